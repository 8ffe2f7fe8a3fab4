// qs-dfi: morphs between two closed shapes of any genus by distance-field interpolation
// (skeleton-guided DFI, ../shared/papers/skeleton-guided-dfi-metamorphosis.md): skeletons, branch
// matching, anchors, harmonic fields, per-part transport and a warp, or the plain blend. Writes
// OUTDIR/frame_NNNN.<fmt> (connectivity differs per frame), OUTDIR/dfi.json and optionally a GLB
// that plays the frames (one node per frame, scale animated in steps).
//
// Exit codes: 0 done, 1 usage, 2 invalid input (a mesh that is open, non-manifold, inconsistently
// oriented, in several components, or encloses no volume; genus is reported, never rejected),
// 3 i/o, 4 solver (the warp still folds after smoothing), 70 internal error.

#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <unistd.h>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/dfi/pipeline.h"
#include "qs/dfi/retime.h"
#include "qs/gltf/sequence.h"
#include "qs/io/read_mesh.h"
#include "qs/io/write_mesh.h"
#include "qs/landmarks/landmarks.h"
#include "qs/mesh/validate.h"
#include "tool_main.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

struct Shape {
  std::string file;
  qs::TriMesh mesh;
  qs::mesh::ValidationReport report;
  qs::mesh::ValidationResult valid;
};

// Read and validate: closed, manifold, oriented, one component; any genus (reported).
Shape load(const std::string& file, const char* which) {
  Shape s;
  s.file = file;
  const qs::io::ReadResult read = qs::io::read_mesh(file);
  qs::mesh::ValidateOptions vo;
  vo.allow_any_genus = true;
  qs::mesh::ValidationResult valid = qs::mesh::validate(read.mesh, vo);
  if (!valid.report.accepted)
    throw qs::InvalidInput(std::string(which) + " mesh rejected (qs-dfi needs closed, manifold, consistently "
                           "oriented meshes of one component; any genus):\n" +
                           qs::mesh::format_report(file, valid.report));
  s.mesh = valid.mesh;
  s.report = valid.report;
  s.valid = std::move(valid);
  return s;
}

std::string frame_stem(int f, int frames) {
  int width = 4;
  for (int n = frames - 1; n >= 10000; n /= 10) ++width;
  std::ostringstream s;
  s << "frame_" << std::setw(width) << std::setfill('0') << f;
  return s.str();
}

nlohmann::ordered_json vec_json(const qs::Vec3& v) { return {v.x(), v.y(), v.z()}; }

// A skeleton as JSON, its nodes mapped by `place` (morph space -> the shape's own coordinates).
template <class Place>
nlohmann::ordered_json skeleton_json(const qs::dfi::Skeleton& s, const std::vector<qs::dfi::Branch>& branches,
                                     Place place) {
  nlohmann::ordered_json nodes = nlohmann::ordered_json::array(), edges = nlohmann::ordered_json::array(),
                         br = nlohmann::ordered_json::array();
  for (const qs::Vec3& p : s.nodes) nodes.push_back(vec_json(place(p)));
  for (const auto& e : s.edges) edges.push_back({e[0], e[1]});
  for (const auto& b : branches) br.push_back({{"a", b.a}, {"b", b.b}, {"nodes", b.nodes.size()}, {"length", b.length}});
  return {{"nodes", nodes}, {"edges", edges}, {"branches", br}};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Morphs between two closed shapes of any genus by skeleton-guided distance-field\n"
               "interpolation: the signed distance fields of both shapes on one grid, warped toward\n"
               "each other along a skeleton-guided voxel correspondence, blended frame by frame and\n"
               "polygonized (marching tetrahedra: closed, manifold, outward, no self-intersections).\n"
               "Writes OUTDIR/frame_NNNN.<fmt>, OUTDIR/dfi.json and optionally a GLB.\n"
               "Exit codes: 0 done, 1 usage, 2 invalid input, 3 i/o, 4 solver, 70 internal error.",
               "qs-dfi"};
  std::string source_file, target_file, outdir = "dfi-out", format = "obj", align = "none", timing = "even", volume = "linear";
  std::optional<std::string> glb;
  int frames = 11, grid = 150, threads = 0, band = 3, endpoint_refine = 3;
  double fps = 12;
  bool no_warp = false, no_centring = false, no_topology = false, exact_endpoints = false, quiet = false, global_transport = false;
  int anchors_per_branch = 3, emd_voxels = 1500, bone_segments = 8;
  app.add_option("SOURCE", source_file, "Source mesh (.obj .off .ply .stl), closed, any genus")->required();
  app.add_option("TARGET", target_file, "Target mesh, closed, any genus")->required();
  app.add_option("--frames", frames, "Frames K, from t = 0 to t = 1 inclusive (default 11)")
      ->check(CLI::Range(2, 100000));
  app.add_option("--grid", grid, "Grid cells along the longest side of the common bounding box (default 150)")
      ->check(CLI::Range(8, 1024));
  app.add_option("--align", align, "none (default) or similarity: move and scale the target onto the source "
                                   "(volume centroids, volumes, principal axes of inertia); frames travel from one placement to the other")
      ->check(CLI::IsMember({"none", "similarity"}));
  app.add_flag("--no-warp", no_warp, "The plain distance-field blend (1-t) d0 + t d1 (the ablation); default: "
                                     "the skeleton-guided warp");
  app.add_option("--volume", volume, "Volume of the frames between the ends: linear (default: each frame's iso level "
                                     "shifted, by at most 4 cells, so that its volume follows the linear interpolation "
                                     "of the ends') or free (the blend's zero level)")
      ->check(CLI::IsMember({"linear", "free"}));
  app.add_flag("--no-centring", no_centring, "Skeleton nodes where mean curvature flow left them (default: moved to "
                                             "the centre of their cross-section before the matching)");
  app.add_flag("--no-topology-control", no_topology, "Frames as blended; default: when both inputs are genus 0, "
                                                    "every frame's inside grown by simple points only (one genus-0 piece; "
                                                    "an end frame whose input is genus 0 too)");
  app.add_flag("--global-transport", global_transport, "One transport over all interior voxels instead of one "
                                                       "per matched part (the ablation)");
  std::vector<std::string> landmark_files;
  app.add_option("--landmarks", landmark_files, "Two landmark files (.json or .pp, as qs-dissect reads them), "
                                                "source then target: features of the same name force skeleton "
                                                "matches")->expected(2);
  app.add_option("--anchors-per-branch", anchors_per_branch, "Anchors sampled inside each matched branch "
                                                             "(default 3)")->check(CLI::Range(0, 50));
  app.add_option("--bone-segments", bone_segments, "Segments per matched branch of the rotation-aware part warp "
                                                   "(default 8); 0: the linear warp of the transport displacement")
      ->check(CLI::Range(0, 100));
  app.add_option("--emd-voxels", emd_voxels, "Interior voxels per shape for the correspondence (default 1500)")
      ->check(CLI::Range(50, 20000));
  app.add_option("--timing", timing, "Frame times: even (default: consecutive frames change about equally, from "
                                     "cheap frames on a grid of half the samples) or uniform (t = f / (K - 1))")
      ->check(CLI::IsMember({"even", "uniform"}));
  app.add_option("--endpoint-refine", endpoint_refine, "The first and last frames from the input's own distance "
                                                       "field on a grid R times finer (default 3; 1: the morph's grid)")
      ->check(CLI::Range(1, 8));
  app.add_flag("--exact-endpoints", exact_endpoints, "Write the inputs themselves as the first and last frames");
  app.add_option("-o,--output", outdir, "Output folder (default dfi-out; created)");
  app.add_option("--format", format, "Frame format: obj (default) or ply")->check(CLI::IsMember({"obj", "ply"}));
  app.add_option("--glb", glb, "Also write a GLB that plays the frames (one node per frame, stepped scale)");
  app.add_option("--fps", fps, "Frames per second of the GLB animation (default 12)")->check(CLI::PositiveNumber);
  app.add_option("--band", band, "Cells around the surface with exact distances (default 3; 0: exact "
                                 "everywhere, slow)")->check(CLI::Range(0, 64));
  app.add_option("--threads", threads, "Threads (0: all hardware threads; the output does not depend on it)")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
  app.add_flag("-q,--quiet", quiet, "Print nothing but errors");

  return qs::tools::run_tool(app, argc, argv, [&] {
    const auto t_start = Clock::now();
    const Shape source = load(source_file, "source");
    const Shape target = load(target_file, "target");
    qs::Context ctx;
    ctx.threads = threads;
    qs::dfi::MorphOptions opt;
    opt.grid = grid;
    opt.align = align == "similarity" ? qs::dfi::Align::Similarity : qs::dfi::Align::None;
    opt.sdf.band = band;
    opt.sdf.threads = threads;
    opt.warp = !no_warp;
    opt.centre_skeletons = !no_centring;
    opt.volume = volume == "free" ? qs::dfi::FrameVolume::Free : qs::dfi::FrameVolume::Linear;
    opt.bone_segments = bone_segments;
    opt.topology_control = !no_topology;
    opt.part_transport = !global_transport;
    opt.anchors_per_branch = anchors_per_branch;
    opt.emd_voxels = emd_voxels;
    if (!landmark_files.empty()) {
      const auto la = qs::landmarks::read_landmarks(landmark_files[0], source.valid);
      const auto lb = qs::landmarks::read_landmarks(landmark_files[1], target.valid);
      for (const auto& fa : la.features)
        for (const auto& fb : lb.features)
          if (fa.name == fb.name) opt.landmarks.push_back({fa.name, fa.position, fb.position});
      if (opt.landmarks.empty())
        throw qs::InvalidInput(landmark_files[0] + " and " + landmark_files[1] +
                               ": no feature name in common; name the landmarks that should match alike");
    }
    auto say = [&](const std::string& m) {
      if (!quiet) std::cerr << "qs-dfi: " << m << "\n";
    };
    say("source " + source_file + ": " + std::to_string(source.mesh.num_vertices()) + " vertices, genus " +
        std::to_string(source.report.genus) + "; target " + target_file + ": " +
        std::to_string(target.mesh.num_vertices()) + " vertices, genus " + std::to_string(target.report.genus));
    const qs::dfi::PreparedMorph morph = qs::dfi::prepare_morph(source.mesh, target.mesh, opt, ctx);
    const double prep_s = std::chrono::duration<double>(Clock::now() - t_start).count();
    {
      std::ostringstream m;
      m << "grid " << morph.source_sdf.dims[0] << " x " << morph.source_sdf.dims[1] << " x "
        << morph.source_sdf.dims[2] << " (spacing " << morph.source_sdf.spacing << "), distance fields"
        << (morph.warp ? " and correspondence" : "") << " in "
        << std::fixed << std::setprecision(2) << prep_s << " s";
      say(m.str());
    }
    std::error_code ec;
    fs::create_directories(outdir, ec);
    if (ec || !fs::is_directory(outdir)) throw qs::IoError(outdir + ": cannot create the output folder: " + ec.message());

    // Frame times: uniform, or at equal steps of the change between cheap dense frames.
    std::vector<double> times(frames);
    for (int f = 0; f < frames; ++f) times[f] = static_cast<double>(f) / (frames - 1);
    nlohmann::ordered_json timing_json{{"method", timing}};
    if (timing == "even" && frames > 2) {
      const auto t0 = Clock::now();
      const qs::dfi::RetimeOptions ro;
      const qs::dfi::Retiming r = qs::dfi::even_frame_times(morph, frames, ro, threads);
      times = r.times;
      timing_json["dense_samples"] = r.dense_times.size();
      timing_json["coarsen"] = ro.coarsen;
      timing_json["dense_t"] = r.dense_times;
      timing_json["dense_change"] = r.dense_change;
      std::ostringstream m;
      m << "even frame times from " << r.dense_times.size() << " dense frames in " << std::fixed << std::setprecision(2)
        << std::chrono::duration<double>(Clock::now() - t0).count() << " s";
      say(m.str());
    }
    nlohmann::ordered_json frames_json = nlohmann::ordered_json::array();
    std::vector<qs::gltf::SequenceFrame> seq;
    for (int f = 0; f < frames; ++f) {
      const auto t0 = Clock::now();
      const double t = times[f];
      qs::TriMesh mesh;
      qs::dfi::BlendInfo blend;
      bool exact = false;
      qs::dfi::BallReport ball;
      if (exact_endpoints && (f == 0 || f == frames - 1)) {
        mesh = f == 0 ? source.mesh : target.mesh;
        exact = true;
      } else if (endpoint_refine > 1 && (f == 0 || f == frames - 1)) {
        mesh = qs::dfi::endpoint_frame(morph, f == 0 ? source.mesh : target.mesh, f != 0, endpoint_refine, opt.sdf,
                                       opt.polygonize, &ball);
      } else {
        mesh = qs::dfi::frame_mesh(morph, qs::dfi::blend_field(morph, t, threads, &blend), t, opt.polygonize);
        ball = blend.ball;
      }
      const bool controlled = !exact && qs::dfi::controls_topology(morph, t);
      const qs::dfi::MeshStats st = qs::dfi::mesh_stats(mesh);
      if (!exact && !st.closed_manifold)
        throw qs::InternalError("frame " + std::to_string(f) + " is not a closed oriented surface");
      const std::string file = frame_stem(f, frames) + "." + format;
      qs::io::write_mesh(fs::path(outdir) / file, mesh);
      frames_json.push_back({{"index", f},
                             {"t", t},
                             {"file", file},
                             {"input", exact},
                             {"vertices", st.vertices},
                             {"faces", st.faces},
                             {"components", st.components},
                             {"genus", st.genus},
                             {"volume", st.volume},
                             {"iso_shift", blend.iso_shift / morph.source_sdf.spacing},
                             {"iso_shift_clamped", blend.clamped},
                             {"topology_control", controlled},
                             {"topology_removed", ball.removed},
                             {"topology_pieces_removed", ball.components_removed}});
      if (glb) seq.push_back({frame_stem(f, frames), mesh.positions, mesh.faces});
      std::ostringstream m;
      m << "frame " << f + 1 << "/" << frames << " t=" << std::setprecision(3) << t << ": " << st.vertices
        << " vertices, " << st.components << " component(s), genus " << st.genus << ", ";
      if (controlled) {
        m << ball.removed << " inside sample(s) left out";
        if (ball.components_removed) m << " (" << ball.components_removed << " whole piece(s))";
        m << ", ";
      }
      m
        << std::fixed << std::setprecision(2) << std::chrono::duration<double>(Clock::now() - t0).count() << " s";
      say(m.str());
    }
    const auto shape_json = [](const Shape& s, double volume) {
      return nlohmann::ordered_json{{"file", s.file},
                                    {"vertices", s.mesh.num_vertices()},
                                    {"faces", s.mesh.num_faces()},
                                    {"genus", s.report.genus},
                                    {"volume", volume}};
    };
    const qs::dfi::Grid& g = morph.source_sdf;
    nlohmann::ordered_json report{
        {"format", "qs-dfi"},
        {"version", 1},
        {"method", morph.warp ? (global_transport ? "warp-global-transport" : "warp") : "blend"},
        {"source", shape_json(source, morph.source_volume)},
        {"target", shape_json(target, morph.target_volume)},
        {"options", {{"frames", frames}, {"grid", grid}, {"align", align}, {"band", band},
                     {"exact_endpoints", exact_endpoints}, {"frame_format", format}, {"timing", timing},
                     {"endpoint_refine", endpoint_refine}, {"volume", volume}, {"topology_control", !no_topology}}},
        {"timing", timing_json},
        {"grid", {{"dims", {g.dims[0], g.dims[1], g.dims[2]}}, {"spacing", g.spacing}, {"origin", vec_json(g.origin)}}},
        {"alignment", {{"scale", morph.target_to_source.scale},
                       {"rotation", {morph.target_to_source.rotation.row(0).eval(), morph.target_to_source.rotation.row(1).eval(),
                                     morph.target_to_source.rotation.row(2).eval()}},
                       {"target_centroid", vec_json(morph.target_to_source.from)},
                       {"source_centroid", vec_json(morph.target_to_source.to)}}},
        {"skeletons", nullptr},
        {"matches", nullptr},
        {"anchors", nullptr},
        {"correspondence", nullptr},
        {"frames", frames_json}};
    if (morph.warp) {
      const auto to_target = [&](const qs::Vec3& p) { return qs::dfi::placement(morph.target_to_source, 1.0, p); };
      const auto same = [](const qs::Vec3& p) { return p; };
      report["skeletons"] = {{"source", skeleton_json(morph.source_skeleton, morph.source_branches, same)},
                             {"target", skeleton_json(morph.target_skeleton, morph.target_branches, to_target)}};
      nlohmann::ordered_json nodes = nlohmann::ordered_json::array(), branches = nlohmann::ordered_json::array(),
                             anchors = nlohmann::ordered_json::array();
      for (const auto& n : morph.matching.nodes)
        nodes.push_back({{"source", n.source}, {"target", n.target}, {"forced", n.forced}, {"name", n.name}});
      for (const auto& b : morph.matching.branches)
        branches.push_back({{"source", b.source}, {"target", b.target}, {"reversed", b.reversed}});
      for (const auto& a : morph.anchors) anchors.push_back({{"source", vec_json(a.source)}, {"target", vec_json(to_target(a.target))}});
      report["matches"] = {{"nodes", nodes}, {"branches", branches}};
      report["anchors"] = anchors;
      report["correspondence"] = {{"transport", global_transport ? "global" : "per part"},
                                  {"grid_cells", morph.emd_cells},
                                  {"source_voxels", morph.source_voxels},
                                  {"target_voxels", morph.target_voxels},
                                  {"parts", morph.parts},
                                  {"cost", morph.transport_cost},
                                  {"harmonic_agreement", morph.harmonic_agreement},
                                  {"warp", morph.bones.empty() ? "linear" : "parts"},
                                  {"bones", morph.bones.size()},
                                  {"bones_min_det", morph.bone_min_det},
                                  {"centring", {{"source_moved", morph.source_centring.moved},
                                                {"source_outside", {morph.source_centring.outside_before, morph.source_centring.outside_after}},
                                                {"target_moved", morph.target_centring.moved},
                                                {"target_outside", {morph.target_centring.outside_before, morph.target_centring.outside_after}}}},
                                  {"folds", {{"source_min_det", morph.source_folds.min_det},
                                             {"target_min_det", morph.target_folds.min_det},
                                             {"source_smoothing_steps", morph.source_folds.smoothing_steps},
                                             {"target_smoothing_steps", morph.target_folds.smoothing_steps}}}};
      std::ostringstream m;
      m << "skeletons " << morph.source_skeleton.nodes.size() << " / " << morph.target_skeleton.nodes.size()
        << " nodes, " << morph.matching.nodes.size() << " node and " << morph.matching.branches.size()
        << " branch matches, " << morph.anchors.size() << " anchors, " << morph.parts << " part(s), "
        << morph.source_voxels << " / " << morph.target_voxels << " voxels, fold check min det "
        << (morph.bones.empty() ? std::min(morph.source_folds.min_det, morph.target_folds.min_det) : morph.bone_min_det)
        << (morph.bones.empty() ? ", linear warp" : ", part warp with " + std::to_string(morph.bones.size()) + " bones");
      say(m.str());
    }
    if (glb) {
      qs::gltf::SequenceOptions so;
      so.seconds_per_frame = 1.0 / fps;
      so.name = "dfi";
      qs::gltf::write_sequence_glb(*glb, seq, so);
    }
    qs::write_file_atomically(fs::path(outdir) / "dfi.json", report.dump(2) + "\n");
    std::ostringstream m;
    m << "wrote " << frames << " frames to " << outdir << (glb ? " and " + *glb : std::string()) << " in "
      << std::fixed << std::setprecision(2) << std::chrono::duration<double>(Clock::now() - t_start).count() << " s";
    say(m.str());
    return 0;
  });
}
