// qs-dfi: morphs between two closed shapes of any genus by distance-field interpolation
// (skeleton-guided DFI, ../shared/papers/skeleton-guided-dfi-metamorphosis.md): skeletons, branch
// matching, anchors, harmonic fields, per-part transport and a warp, or the plain blend. Writes
// OUTDIR/frame_NNNN.<fmt> (connectivity differs per frame), OUTDIR/dfi.json and optionally a GLB
// that plays the frames (one node per frame, scale animated in steps).
//
// Exit codes: 0 done, 1 usage (also an output that is an input, a request over --max-memory),
// 2 invalid input (a mesh that is open, non-manifold, inconsistently oriented, in several
// components, or encloses no volume; genus is reported, never rejected), 3 i/o, 4 solver (the
// warp still folds after smoothing), 70 internal error.
//
// Every option, every input and the memory estimate are checked before any work; the frames and
// dfi.json are staged beside OUTDIR (qs::OutputFolder) and the GLB written under a temporary name,
// all moved into place only when the whole run succeeded.

#include <algorithm>
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
#include "qs/core/json_strict.h"
#include "qs/core/output_folder.h"
#include "qs/dfi/pipeline.h"
#include "qs/dfi/retime.h"
#include "qs/gltf/sequence.h"
#include "qs/io/read_mesh.h"
#include "qs/io/write_mesh.h"
#include "qs/landmarks/landmarks.h"
#include "qs/mesh/validate.h"
#include "resource_limits.h"
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

// A file name as it may appear in dfi.json or a message: bytes that are not UTF-8 written \xNN.
std::string shown(const std::string& name) { return qs::json_strict::printable(name, std::string::npos); }

// The GLB plays frames at these rates: its key times (float) stay finite, positive and distinct.
constexpr double kMinFps = 0.001, kMaxFps = 1000;
// A GLB stores float positions: inputs of larger coordinates, or smaller sizes, are refused for it.
constexpr double kGlbMaxCoordinate = 1e30, kGlbMinSize = 1e-30;

// Removes the folders it created unless disarmed.
struct CreatedFolders {
  std::vector<fs::path> made;  // deepest last
  bool keep = false;
  ~CreatedFolders() {
    std::error_code ec;
    if (!keep)
      for (auto it = made.rbegin(); it != made.rend(); ++it) fs::remove(*it, ec);
  }
};

// The GLB's folder: its nearest existing ancestor must be a writable folder (checked before any
// work); the missing ones are created only when the GLB is written.
void check_glb_destination(const fs::path& glb) {
  std::error_code ec;
  if (glb.filename().empty()) throw qs::UsageError("--glb " + shown(glb.string()) + ": expected a file name");
  if (fs::is_directory(glb, ec)) throw qs::IoError("--glb " + shown(glb.string()) + ": is a folder; expected a file name");
  fs::path p = glb.parent_path();
  if (p.empty()) p = ".";
  while (!fs::exists(fs::symlink_status(p, ec))) {
    fs::path up = p.parent_path();
    if (up.empty()) up = ".";
    if (up == p) break;
    p = up;
  }
  if (!fs::is_directory(p, ec))
    throw qs::IoError("--glb " + shown(glb.string()) + ": " + shown(p.string()) + " is not a folder");
  if (::access(p.c_str(), W_OK | X_OK) != 0)
    throw qs::IoError("--glb " + shown(glb.string()) + ": the folder " + shown(p.string()) + " is not writable");
}

void make_glb_folder(const fs::path& glb, CreatedFolders& created) {
  std::error_code ec;
  std::vector<fs::path> missing;
  for (fs::path p = glb.parent_path(); !p.empty() && !fs::exists(fs::symlink_status(p, ec)); p = p.parent_path()) {
    missing.push_back(p);
    if (p == p.parent_path()) break;
  }
  for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
    if (!fs::create_directory(*it, ec) || ec)
      throw qs::IoError("--glb " + shown(glb.string()) + ": cannot create the folder " + shown(it->string()) +
                        (ec ? " (" + ec.message() + ")" : std::string()));
    created.made.push_back(*it);
  }
}

std::string num(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

double largest_coordinate(const qs::TriMesh& m) {
  double c = 0;
  for (const qs::Vec3& p : m.positions) c = std::max(c, p.cwiseAbs().maxCoeff());
  return c;
}

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
  std::string source_file, target_file, outdir = "dfi-out", format = "obj", align = "none", timing = "even", volume = "linear",
              matching = "voting", interpolation = "parts";
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
  app.add_option("--matching", matching, "Skeleton feature nodes matched by voting (default: centricity, path "
                                         "length, topology, spatial configuration and position) or nearest (nearest-first)")
      ->check(CLI::IsMember({"voting", "nearest"}));
  app.add_option("--interpolation", interpolation, "In-between positions of the correspondence: parts (default: the "
                                                   "rotation-aware part warp along matched branches) or arap (as-rigid-as-possible "
                                                   "centres and thin-plate RBF backward warps with a global affine part)")
      ->check(CLI::IsMember({"parts", "arap"}));
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
  app.add_option("-o,--output", outdir, "Output folder (default dfi-out; written beside it and moved into place when the whole run succeeded)");
  app.add_option("--format", format, "Frame format: obj (default) or ply")->check(CLI::IsMember({"obj", "ply"}));
  app.add_option("--glb", glb, "Also write a GLB that plays the frames (one node per frame, stepped scale)");
  app.add_option("--fps", fps, "Frames per second of the GLB animation, 0.001 to 1000 (default 12)");
  app.add_option("--band", band, "Cells around the surface with exact distances (default 3; 0: exact "
                                 "everywhere, slow)")->check(CLI::Range(0, 64));
  app.add_option("--threads", threads, "Threads (0: all hardware threads; the output does not depend on it)")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
  app.add_flag("-q,--quiet", quiet, "Print nothing but errors");
  double max_memory = qs::tools::kDefaultMaxMemoryGiB;
  qs::tools::add_max_memory_option(app, max_memory);

  return qs::tools::run_tool(app, argc, argv, [&] {
    const auto t_start = Clock::now();
    // Options first: nothing is read or written before they all hold.
    if (!(fps >= kMinFps && fps <= kMaxFps))
      throw qs::UsageError("--fps " + num(fps) + ": expected 0.001 to 1000 frames per second");
    if (!(max_memory >= 0.001 && max_memory <= 1e6))
      throw qs::UsageError("--max-memory " + num(max_memory) + ": expected 0.001 to 1e6 GiB");
    if (!exact_endpoints && static_cast<long>(grid) * endpoint_refine > 2048)
      throw qs::UsageError("--grid " + std::to_string(grid) + " with --endpoint-refine " + std::to_string(endpoint_refine) +
                           ": the end frames' grid would exceed 2048 cells; expected grid x refine <= 2048");
    if (outdir.empty()) throw qs::UsageError("-o: expected a folder name");
    // No output replaces an input (under any spelling, through links).
    std::vector<fs::path> inputs = {source_file, target_file};
    for (const auto& l : landmark_files) inputs.push_back(l);
    std::vector<std::string> outputs{"dfi.json"};  // names this run writes into OUTDIR
    for (int f = 0; f < frames; ++f) outputs.push_back(frame_stem(f, frames) + "." + format);
    const auto ours = [&](const std::string& name) {
      return name == "dfi.json" || (name.rfind("frame_", 0) == 0 && std::find(outputs.begin(), outputs.end(), name) != outputs.end());
    };
    if (glb) {
      qs::check_not_an_input(*glb, inputs, "--glb");
      std::error_code ec;
      const fs::path g = fs::weakly_canonical(fs::absolute(*glb), ec);
      if (!ec && g.parent_path() == fs::weakly_canonical(fs::absolute(outdir), ec) && ours(g.filename().string()))
        throw qs::UsageError("--glb " + shown(*glb) + " is a file this run writes into " + shown(outdir) +
                             "; name the GLB otherwise");
      check_glb_destination(*glb);
    }
    {
      // An input can only be one of the outputs if it already exists in OUTDIR.
      std::error_code ec;
      const fs::path dir = fs::weakly_canonical(fs::absolute(outdir), ec);  // "x/../in" names "in"
      if (!ec && fs::is_directory(dir, ec))
        for (const auto& e : fs::directory_iterator(dir, ec))
          if (ours(e.path().filename().string())) qs::check_not_an_input(e.path(), inputs, "-o");
    }
    const Shape source = load(source_file, "source");
    const Shape target = load(target_file, "target");
    if (glb)
      for (const Shape* s : {&source, &target}) {
        const double big = largest_coordinate(s->mesh), size = qs::bounding_box(s->mesh.positions).diagonal();
        if (!(big <= kGlbMaxCoordinate) || !(size >= kGlbMinSize)) {
          std::ostringstream m;
          m << "--glb: " << shown(s->file) << " has coordinates up to " << big << " and size " << size
            << "; a GLB stores 32-bit floats, so its inputs need coordinates up to " << kGlbMaxCoordinate
            << " and a size of at least " << kGlbMinSize << " (scale the meshes, or leave out --glb)";
          throw qs::InvalidInput(m.str());
        }
      }
    qs::Context ctx;
    ctx.threads = threads;
    qs::dfi::MorphOptions opt;
    opt.grid = grid;
    opt.align = align == "similarity" ? qs::dfi::Align::Similarity : qs::dfi::Align::None;
    opt.sdf.band = band;
    opt.sdf.threads = threads;
    opt.warp = !no_warp;
    opt.centre_skeletons = !no_centring;
    opt.voting = matching == "voting";
    opt.interpolation = interpolation == "arap" ? qs::dfi::Interpolation::Arap : qs::dfi::Interpolation::Parts;
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
        throw qs::InvalidInput(shown(landmark_files[0]) + " and " + shown(landmark_files[1]) +
                               ": no feature name in common; name the landmarks that should match alike");
    }
    // The memory estimate, before anything large is allocated.
    {
      qs::dfi::MemoryRequest req;
      req.frames = frames;
      req.endpoint_refine = exact_endpoints ? 1 : endpoint_refine;
      const qs::dfi::MorphSize size = qs::dfi::morph_size(source.mesh, target.mesh, opt, req.endpoint_refine);
      req.even_timing = timing == "even";
      req.keep_frames = glb.has_value();
      const double bytes = qs::dfi::estimate_memory(size, req, !no_warp);
      std::ostringstream what;
      what << "--grid " << grid << " (" << size.grid_dims[0] << " x " << size.grid_dims[1] << " x " << size.grid_dims[2]
           << " samples";
      if (req.endpoint_refine > 1)
        what << ", end frames on up to " << std::max(size.source_end_dims[0], size.target_end_dims[0]) << " x "
             << std::max(size.source_end_dims[1], size.target_end_dims[1]) << " x "
             << std::max(size.source_end_dims[2], size.target_end_dims[2]);
      what << ") with --frames " << frames << (req.even_timing ? " (even timing)" : "") << (glb ? " and --glb" : "");
      qs::tools::check_memory(bytes, max_memory, what.str());
    }
    auto say = [&](const std::string& m) {
      if (!quiet) std::cerr << "qs-dfi: " << m << "\n";
    };
    // The output folder is staged: nothing appears in OUTDIR before the run succeeded.
    qs::OutputFolder out_folder(outdir);
    const fs::path staging = out_folder.staging();
    say("source " + shown(source_file) + ": " + std::to_string(source.mesh.num_vertices()) + " vertices, genus " +
        std::to_string(source.report.genus) + "; target " + shown(target_file) + ": " +
        std::to_string(target.mesh.num_vertices()) + " vertices, genus " + std::to_string(target.report.genus));
    const qs::dfi::PreparedMorph morph = qs::dfi::prepare_morph(source.mesh, target.mesh, opt, ctx);
    const double prep_s = std::chrono::duration<double>(Clock::now() - t_start).count();
    const double unit = 1 / morph.source_to_morph.scale;  // morph space -> source units, for lengths
    {
      std::ostringstream m;
      m << "grid " << morph.source_sdf.dims[0] << " x " << morph.source_sdf.dims[1] << " x "
        << morph.source_sdf.dims[2] << " (spacing " << morph.spacing() << "), distance fields"
        << (morph.warp ? " and correspondence" : "") << " in "
        << std::fixed << std::setprecision(2) << prep_s << " s";
      say(m.str());
    }

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
      std::vector<double> change = r.dense_change;
      for (double& c : change) c *= unit;  // in the source's units
      timing_json["dense_change"] = change;
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
      qs::io::write_mesh(staging / file, mesh);
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
      return nlohmann::ordered_json{{"file", shown(s.file)},
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
        {"grid", {{"dims", {g.dims[0], g.dims[1], g.dims[2]}},
                  {"spacing", morph.spacing()},
                  {"origin", vec_json(morph.source_to_morph.inverse().apply(g.origin))}}},
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
      // Morph space -> the source's and the target's own coordinates.
      const qs::dfi::Similarity to_source = morph.source_to_morph.inverse(), to_target_units = morph.target_to_morph.inverse();
      const auto to_target = [&](const qs::Vec3& p) { return to_target_units.apply(p); };
      const auto same = [&](const qs::Vec3& p) { return to_source.apply(p); };
      report["skeletons"] = {{"source", skeleton_json(morph.source_skeleton, morph.source_branches, same)},
                             {"target", skeleton_json(morph.target_skeleton, morph.target_branches, to_target)}};
      nlohmann::ordered_json nodes = nlohmann::ordered_json::array(), branches = nlohmann::ordered_json::array(),
                             anchors = nlohmann::ordered_json::array();
      for (const auto& n : morph.matching.nodes)
        nodes.push_back({{"source", n.source}, {"target", n.target}, {"forced", n.forced}, {"name", n.name}, {"votes", n.votes}});
      for (const auto& b : morph.matching.branches)
        branches.push_back({{"source", b.source}, {"target", b.target}, {"reversed", b.reversed}});
      for (const auto& a : morph.anchors) anchors.push_back({{"source", vec_json(same(a.source))}, {"target", vec_json(to_target(a.target))}});
      report["matches"] = {{"method", matching}, {"nodes", nodes}, {"branches", branches}};
      report["anchors"] = anchors;
      report["correspondence"] = {{"transport", global_transport ? "global" : "per part"},
                                  {"grid_cells", morph.emd_cells},
                                  {"source_voxels", morph.source_voxels},
                                  {"target_voxels", morph.target_voxels},
                                  {"parts", morph.parts},
                                  {"cost", morph.transport_cost},
                                  {"harmonic_agreement", morph.harmonic_agreement},
                                  {"warp", !morph.arap.empty() ? "arap" : morph.bones.empty() ? "linear" : "parts"},
                                  {"arap_centres", morph.arap.source.size()},
                                  {"arap_smoothing", morph.arap_lambda},
                                  {"arap_min_det", morph.arap_min_det},
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
        << (!morph.arap.empty() ? morph.arap_min_det
            : morph.bones.empty() ? std::min(morph.source_folds.min_det, morph.target_folds.min_det) : morph.bone_min_det)
        << (!morph.arap.empty() ? ", ARAP warp with " + std::to_string(morph.arap.source.size()) + " centres"
            : morph.bones.empty() ? ", linear warp" : ", part warp with " + std::to_string(morph.bones.size()) + " bones");
      say(m.str());
    }
    // dfi.json staged, then the GLB (written under a temporary name and renamed), then the folder
    // moved into place: a failure before the last step leaves OUTDIR and the GLB as they were.
    qs::write_file_atomically(staging / "dfi.json",
                              report.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n");
    CreatedFolders glb_folders;
    if (glb) {
      qs::gltf::SequenceOptions so;
      so.seconds_per_frame = 1.0 / fps;
      so.name = "dfi";
      make_glb_folder(*glb, glb_folders);
      qs::gltf::write_sequence_glb(*glb, seq, so);
    }
    out_folder.commit();
    glb_folders.keep = true;
    std::ostringstream m;
    m << "wrote " << frames << " frames to " << shown(outdir) << (glb ? " and " + shown(*glb) : std::string()) << " in "
      << std::fixed << std::setprecision(2) << std::chrono::duration<double>(Clock::now() - t_start).count() << " s";
    say(m.str());
    return 0;
  });
}
