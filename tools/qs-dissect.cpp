// qs-dissect: quinary-subdivision dissection of a mesh into quad patches, each parameterized onto
// the unit square. Writes OUTDIR/dissection.json and OUTDIR/<stem>.chart.ply.
//
// Exit codes: 0 done (patches left over tau are listed with their reasons), 1 usage, 2 invalid
// mesh or landmarks, 3 i/o, 4 solver failure, 70 internal error.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

#include "mesh_input.h"
#include "qs/core/atomic_file.h"
#include "qs/core/output_folder.h"
#include "qs/dissect/chart_io.h"
#include "qs/dissect/dissection.h"
#include "qs/dissect/dissection_json.h"
#include "qs/maprefine/map_refine.h"
#include "tool_main.h"

namespace fs = std::filesystem;

namespace {

// Seeds as surface points: qs-dissect inserts a seed that is not on a vertex into the mesh, so that
// it is exactly a corner of the two seed patches.
std::array<qs::landmarks::SurfacePoint, 4> seeds_from_landmarks(const qs::landmarks::Landmarks& lm) {
  std::array<qs::landmarks::SurfacePoint, 4> seeds;
  for (int i = 0; i < 4; ++i) seeds[i] = lm.seeds[i].where;
  return seeds;
}

std::string default_outdir(const std::vector<std::string>& files) {
  std::string d;
  for (size_t i = 0; i < files.size() && i < 3; ++i) d += (i ? "_" : "") + fs::path(files[i]).stem().string();
  if (files.size() > 3) d += "_etc";
  return d + ".dissection";
}

// Chart file names: <stem>.chart.ply, with -2, -3 ... for repeated stems.
std::vector<std::string> chart_names(const std::vector<std::string>& files) {
  std::vector<std::string> names;
  std::map<std::string, int> seen;
  for (const auto& f : files) {
    const std::string stem = fs::path(f).stem().string();
    const int n = ++seen[stem];
    names.push_back(stem + (n > 1 ? "-" + std::to_string(n) : "") + ".chart.ply");
  }
  return names;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Dissect closed genus-0 meshes into quad patches by quinary subdivision. Several meshes are\n"
               "dissected together: one union quinary tree, the same patches on every mesh, features aligned.\n"
               "Exit codes: 0 ok, 1 usage, 2 invalid input, 3 i/o, 4 solver, 70 internal.",
               "qs-dissect"};
  std::vector<std::string> meshes, landmark_files;
  std::string outdir, report_file;
  bool quiet = false;
  qs::dissect::DissectOptions opt;
  app.add_option("meshes", meshes, "The meshes (.obj .off .ply .stl); seeds correspond by order, features by name")
      ->required();
  app.add_option("--landmarks", landmark_files,
                 "Landmark files (.json or MeshLab .pp), one per mesh in the same order; default "
                 "<stem>.landmarks.json or <stem>.pp beside each mesh, else seeds are chosen automatically")
      ->expected(1, -1);
  app.add_option("--tau", opt.tau, "Largest accepted patch L2 stretch (1 = isometric)")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1e6));
  app.add_option("--max-depth", opt.max_depth, "Deepest quinary split")->capture_default_str()->check(CLI::Range(0, 12));
  app.add_option("--min-faces", opt.min_faces_to_split, "Smallest patch (in faces) that may be split")
      ->capture_default_str()
      ->check(CLI::Range(10, 1 << 30));
  app.add_option("--relax", opt.relax_rounds, "Rounds of seed-curve relaxation (paper 3.3; off by default, see README)")
      ->capture_default_str()
      ->check(CLI::Range(0, 16));
  // Issue 13/17: geodesic seed curves and intrinsic cotangent weights are the defaults; the old
  // maps stay one flag away. The former opt-in flags are still accepted (they ask for the default).
  bool edge_paths = false, mean_value = false, geodesic_flag = false, cotan_flag = false;
  app.add_flag("--edge-seed-paths", edge_paths,
               "Keep the seed curves as the shortest edge paths instead of straightening them into geodesics "
               "(the default before issue 17; depends on the tessellation)");
  app.add_flag("--mean-value", mean_value,
               "Floater mean-value weights for every patch map instead of cotangent weights on the patch's "
               "intrinsic Delaunay triangulation (the default before issue 17; depends on the tessellation)");
  app.add_flag("--geodesic-seed-curves", geodesic_flag, "Geodesic seed curves (the default; kept for old scripts)");
  app.add_flag("--cotan", cotan_flag, "Intrinsic cotangent weights (the default; kept for old scripts)");
  app.get_option("--edge-seed-paths")->excludes("--geodesic-seed-curves");
  app.get_option("--mean-value")->excludes("--cotan");
  bool no_fallback = false;
  app.add_flag("--no-fallback-maps", no_fallback,
               "Keep the result of the default maps even when it ends with folded leaves (by default the set is "
               "then dissected again with --edge-seed-paths --mean-value, and that result kept if it folds less)");
  app.add_flag("--predict-split", opt.predict_split,
               "Choose each split by the children's stretch predicted from the parent's map (experimental, see README)");
  app.add_option("--optimize-stretch", opt.stretch_iterations,
                 "Rounds of stretch minimization of each final patch map (better remesh and normal-map sampling; "
                 "the patches do not change)")
      ->capture_default_str()
      ->check(CLI::Range(0, 50));
  app.add_option("--max-area", opt.max_patch_area,
                 "Also split every patch larger than this fraction of its mesh's area (0: off, fewer patches; "
                 "evens out remesh sampling)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--split-stretch", opt.split_stretch_rounds,
                 "Stretch-minimization rounds for a patch over tau before it is split (fewer splits on limbs)")
      ->capture_default_str()
      ->check(CLI::Range(0, 50));
  // Issue 13/17: on by default for a set (it does nothing for one mesh).
  bool refine_flag = false, no_refine = false;
  qs::maprefine::RefineOptions refine_opt;
  app.add_flag("--no-refine-maps", no_refine,
               "Keep the dissection's own maps: by default, for two or more meshes, each mesh's chart (u,v) is "
               "moved inside its patches so that its map to the first mesh has low isometric distortion "
               "(issue 17; patch borders, seeds and features stay; see README)");
  app.add_flag("--refine-maps", refine_flag, "Refine the maps between the meshes (the default; kept for old scripts)");
  app.get_option("--no-refine-maps")->excludes("--refine-maps");
  app.add_option("--refine-iterations", refine_opt.iterations, "Newton steps per patch of --refine-maps")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000));
  app.add_flag("--refine-slide-borders", refine_opt.slide_borders,
               "With --refine-maps: let patch-side vertices slide along their sides too (slower; see README)");
  bool across_flag = false, no_across = false;
  app.add_flag("--refine-across-borders", across_flag,
               "Refine maps across patch borders too (the default since issue 13; implies --refine-maps): move the "
               "patch curves of every mesh but the first (adds chart vertices where the new curves cross edges; see "
               "README)");
  app.add_flag("--no-refine-across-borders", no_across,
               "Refine the maps inside the patches only: the patch curves on the surface stay as dissected");
  app.get_option("--no-refine-across-borders")->excludes("--refine-across-borders");
  app.add_option("--refine-border-sweeps", refine_opt.border_sweeps,
                 "Passes over the shared patch sides of --refine-across-borders")
      ->capture_default_str()
      ->check(CLI::Range(0, 20));
  app.add_option("--refine-border-iterations", refine_opt.border_iterations,
                 "Newton steps per glued pair of patches of --refine-across-borders (default 1; 5 for meshes in "
                 "one pose, with the pull)")
      ->check(CLI::Range(0, 1000));
  app.add_flag("--refine-corners", refine_opt.move_corners,
               "Refine maps around the patch corners too: move the corners of every mesh but the first on cone "
               "charts of their patches (implies --refine-maps; adds chart vertices; see README)");
  app.add_option("--refine-corner-sweeps", refine_opt.corner_sweeps, "Passes over the corners of --refine-corners")
      ->capture_default_str()
      ->check(CLI::Range(0, 20));
  app.add_option("--refine-corner-iterations", refine_opt.corner_iterations,
                 "Newton steps per corner star of --refine-corners")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000));
  std::string corner_chart = "sector";
  app.add_option("--refine-corner-chart", corner_chart,
                 "Chart of a corner's patches for --refine-corners: sector (an affine map per patch) or power "
                 "(z^(4/k)); see README")
      ->capture_default_str()
      ->check(CLI::IsMember({"sector", "power"}));
  bool no_refine_before_split = false;
  app.add_flag("--refine-before-split")
      ->description("Before a patch is split, refine every mesh's map of it against the first mesh's, so that the "
                    "split points (equal (u,v) in every mesh) correspond better (the default; see README, \"Map "
                    "refinement\")");
  app.add_flag("--no-refine-before-split", no_refine_before_split,
               "Split every patch at equal (u,v) of each mesh's own map (the default before issue 17's measurement)");
  app.get_option("--no-refine-before-split")->excludes("--refine-before-split");
  app.add_flag("--same-pose", opt.same_pose,
               "The meshes are in one pose (registered scans, re-tessellations of one surface): place every split's "
               "inner corners in each mesh at its points nearest the first mesh's, after the landmarks' similarity, "
               "and pull the refined maps toward nearest points. Found by itself when the surfaces lie within 1% of "
               "the diagonal of each other after that similarity (see README, \"Same pose\")");
  bool no_same_pose = false;
  app.add_flag("--no-same-pose", no_same_pose, "Never treat the meshes as one pose (no detection)");
  app.get_option("--no-same-pose")->excludes("--same-pose");
  bool no_untangle = false;
  app.add_flag("--no-same-pose-untangle", no_untangle,
               "For meshes in one pose: a node whose taken-over map folds keeps its own map instead of being "
               "untangled toward it, and a repaired one is not polished (see README, \"Same pose\")");
  double pose_pull = -1;
  app.add_option("--refine-pose-pull", pose_pull,
                 "For meshes in one pose: weight of the refinement's pull of every vertex toward the first mesh's "
                 "point nearest to it (default 10; 0: off; see README, \"Same pose\")")
      ->check(CLI::Range(0.0, 1e6));
  std::string before_split_metric = "composition";
  app.add_option("--refine-before-split-metric", before_split_metric,
                 "How the refinement before a split sees the first mesh's map: composition (the composed map "
                 "itself), vertex (refine-maps's clamped, vertex-averaged metric) or face (its face's metric, "
                 "unclamped); see README")
      ->capture_default_str()
      ->check(CLI::IsMember({"vertex", "face", "composition"}))
      ->excludes("--no-refine-before-split");
  app.add_option("--min-split-area", opt.min_split_area,
                 "Do not split a patch over tau (bijective) that holds less than this fraction of its mesh's area; "
                 "the leaf repair takes it (0: off; fewer slivers along limbs)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--force-split-area", opt.force_split_area,
                 "Split a patch still over tau after repair that holds at least this fraction of its mesh's area, "
                 "even when splitting made no progress (0: off)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--area-extra-depth", opt.area_extra_depth,
                 "A patch over tau that holds at least --force-split-area of its mesh's area may be split this "
                 "many levels past --max-depth (0: off)")
      ->capture_default_str()
      ->check(CLI::Range(0, 12));
  app.add_option("--protrusion-stretch", opt.protrusion_stretch,
                 "Split a patch whose stretch exceeds this (a squeezed protrusion) with its stretch peak inside the "
                 "centre child, so that the protrusion is not left in an outer child among strips (0: off; see README)")
      ->capture_default_str()
      ->check([](const std::string& v) {
        return std::strtod(v.c_str(), nullptr) < 0 ? "must be at least 0 (0: off), got " + v : std::string();
      });
  app.add_option("-o,--output", outdir, "Output folder (default: <stem>.dissection, or <stem1>_<stem2>....dissection)");
  app.add_option("--report", report_file, "Also write the text report (with timings) to this file");
  app.add_flag("-q,--quiet", quiet, "Print nothing but errors");

  return qs::tools::run_tool(app, argc, argv, [&] {
    if (!landmark_files.empty() && landmark_files.size() != meshes.size())
      throw qs::UsageError("--landmarks got " + std::to_string(landmark_files.size()) + " files for " +
                           std::to_string(meshes.size()) + " meshes; give one per mesh, in the same order");
    if (std::isnan(opt.tau) || std::isnan(opt.max_patch_area))
      throw qs::UsageError(std::string(std::isnan(opt.tau) ? "--tau" : "--max-area") + " must be a number, not nan");
    if (std::isnan(opt.protrusion_stretch))
      throw qs::UsageError("--protrusion-stretch must be a number, not nan");
    if (std::isnan(opt.min_split_area) || std::isnan(opt.force_split_area))
      throw qs::UsageError(std::string(std::isnan(opt.min_split_area) ? "--min-split-area" : "--force-split-area") +
                           " must be a number, not nan");
    refine_opt.corner_chart =
        corner_chart == "power" ? qs::maprefine::CornerChart::Power : qs::maprefine::CornerChart::Sector;
    refine_opt.across_borders = !no_across;
    opt.same_pose_detect = no_same_pose ? 0.0 : qs::dissect::kSamePoseDetect;
    const bool refine_maps = !no_refine || across_flag || refine_opt.move_corners;  // implied
    opt.geodesic_seed_curves = !edge_paths;
    opt.intrinsic_cotan = !mean_value;
    opt.fallback_maps = !no_fallback;
    const bool refine_before_split = !no_refine_before_split;  // --refine-before-split says the default
    if (refine_before_split) {
      qs::maprefine::NodeRefineOptions node;
      node.metric = before_split_metric == "face"          ? qs::maprefine::NodeMetric::Face
                    : before_split_metric == "composition" ? qs::maprefine::NodeMetric::Composition
                                                           : qs::maprefine::NodeMetric::Vertex;
      opt.refine_before_split = qs::maprefine::node_refiner(refine_opt, node);
    }
    if (!no_untangle) opt.same_pose_untangle = qs::maprefine::untangler(refine_opt);
    if (outdir.empty()) outdir = default_outdir(meshes);
    // No output may replace an input: the report file, or the folder's files.
    std::vector<fs::path> input_paths(meshes.begin(), meshes.end());
    input_paths.insert(input_paths.end(), landmark_files.begin(), landmark_files.end());
    if (!report_file.empty()) qs::check_not_an_input(report_file, input_paths, "--report");
    // Checked (and staged) before the work, so that a bad -o fails at once; written on success only.
    qs::OutputFolder folder(outdir);
    const auto t0 = std::chrono::steady_clock::now();
    std::ostringstream text;
    std::vector<qs::tools::MeshInput> inputs;
    for (size_t i = 0; i < meshes.size(); ++i)
      inputs.push_back(qs::tools::load_mesh_input(
          meshes[i], landmark_files.empty() ? std::nullopt : std::optional(landmark_files[i])));

    std::vector<qs::dissect::MeshToDissect> set(inputs.size());
    std::vector<std::string> seed_source(inputs.size(), "automatic");
    int with_seeds = 0;
    for (size_t i = 0; i < inputs.size(); ++i) {
      const auto& in = inputs[i];
      set[i].mesh = &in.valid.mesh;
      set[i].name = in.file;
      if (!in.landmarks) continue;
      if (in.landmarks->seeds.size() == 4) {
        set[i].seed_points = seeds_from_landmarks(*in.landmarks);
        seed_source[i] = in.landmark_file;
        ++with_seeds;
      }
      for (const auto& l : in.landmarks->features) {
        qs::dissect::Feature f;
        f.name = l.name;
        f.vertex = l.vertex;
        f.where = l.where;
        set[i].features.push_back(f);
      }
    }
    if (with_seeds != 0 && with_seeds != static_cast<int>(inputs.size())) {
      std::string which;
      for (size_t i = 0; i < inputs.size(); ++i)
        if (!set[i].seed_points) which += (which.empty() ? "" : ", ") + inputs[i].file;
      throw qs::InvalidInput("seeds correspond by order across the set, so every mesh needs them: " + which +
                             " has no seeds (give a landmark file with 4 seeds for each mesh, or for none)");
    }
    if (inputs.size() > 1 && with_seeds == 0 && !quiet)
      std::cerr << "qs-dissect: warning: no seeds given; each mesh gets automatic seeds from its own principal "
                   "axes, which correspond only for similar poses. Give seeds for a reliable correspondence.\n";

    qs::Context ctx;
    // Each stage once at its start, then at every quarter it passes, never backwards or twice.
    std::string last_stage;
    int last_quarter = -1;
    if (!quiet)
      ctx.progress = [&](const std::string& stage, double f) {
        const int pct = static_cast<int>(std::floor(std::clamp(f, 0.0, 1.0) * 100));
        const int quarter = pct / 25;
        if (stage == last_stage && quarter <= last_quarter) return;
        if (stage != last_stage) last_quarter = -1;
        std::cerr << "qs-dissect: " << stage << " " << pct << "%\n";
        last_stage = stage;
        last_quarter = quarter;
      };
    const auto t1 = std::chrono::steady_clock::now();
    qs::dissect::DissectionSet result = qs::dissect::dissect_set(set, opt, ctx);
    const auto t2 = std::chrono::steady_clock::now();
    // Which maps were used, and why (the safety net of the new maps: DissectOptions::fallback_maps).
    std::string maps = qs::dissect::maps_name(result.geodesic_seed_curves, result.intrinsic_cotan);
    if (!result.maps_fallback.empty()) maps += " (fallback: " + result.maps_fallback + ")";
    qs::dissect::DissectOptions used = opt;  // dissection.json records the options of the result
    used.geodesic_seed_curves = result.geodesic_seed_curves;
    used.intrinsic_cotan = result.intrinsic_cotan;
    // One pose (told or found): posed splits (unless they fell back) and the refinement's pull.
    const bool one_pose = opt.same_pose || result.same_pose_detected;
    used.same_pose = one_pose && result.same_pose_fallback.empty();
    used.same_pose_folded_maps = result.posed_corners_fallback.empty();
    refine_opt.pose_pull = !one_pose ? 0 : pose_pull >= 0 ? pose_pull : qs::maprefine::kDefaultPosePull;
    if (refine_opt.pose_pull > 0 && app.count("--refine-border-iterations") == 0)
      refine_opt.border_iterations = qs::maprefine::kPoseBorderIterations;
    const double seconds = std::chrono::duration<double>(t2 - t1).count();
    double refine_seconds = 0;
    qs::maprefine::RefineReport refine_report;
    if (refine_maps && result.meshes.size() > 1) {
      refine_report = qs::maprefine::refine_maps(result.meshes, refine_opt, ctx);
      refine_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t2).count();
      result.max_stretch = 0;
      for (const auto& m : result.meshes) result.max_stretch = std::max(result.max_stretch, m.max_stretch);
    }
    const auto charts = chart_names(meshes);
    std::vector<qs::dissect::DissectedMesh> out(inputs.size());
    int flipped = 0;
    std::ostringstream folded;  // the patches left folded, for the error
    for (size_t i = 0; i < inputs.size(); ++i) {
      auto& dm = out[i];
      dm.dissection = std::move(result.meshes[i]);
      dm.file = inputs[i].file;
      dm.chart_file = charts[i];
      dm.seed_source = seed_source[i];
      dm.input_vertices = inputs[i].valid.report.vertices;
      dm.input_faces = inputs[i].valid.report.faces;
      dm.seconds = seconds;
      const auto& d = dm.dissection;
      if (!d.base.closed_conforming || d.base.euler_characteristic != 2 ||
          d.base.quads != out[0].dissection.base.quads)
        throw qs::InternalError("the base domain of " + dm.file +
                                " is not a closed conforming quad mesh of Euler characteristic 2 shared by the set");
      text << dm.file << ": " << d.chart.patches.size() << " patches (base domain V=" << d.base.vertices.size()
           << " E=" << d.base.edges << " F=" << d.base.quads.size() << "), max stretch " << std::setprecision(4)
           << d.max_stretch << " (tau " << opt.tau << "), seeds " << dm.seed_source << " [" << d.seeds[0] << " "
           << d.seeds[1] << " " << d.seeds[2] << " " << d.seeds[3] << "]\n";
      int mesh_flipped = 0;
      for (const auto& p : d.chart.patches) {
        mesh_flipped += p.flipped_faces + p.zero_area_faces;
        if (p.stop != qs::dissect::StopReason::None)
          text << "  patch " << p.name << ": stretch " << p.stretch << " over tau, left as is: "
               << qs::dissect::stop_reason_name(p.stop) << (p.stop_detail.empty() ? "" : " (" + p.stop_detail + ")")
               << ", " << p.faces << " faces\n";
      }
      text << "  bijective: " << (mesh_flipped == 0 ? "yes" : "NO") << " (" << mesh_flipped
           << " flipped or zero-area uv faces)\n";
      if (i < refine_report.meshes.size()) {
        const auto& r = refine_report.meshes[i];
        if (r.identity)
          text << "  refine maps: the same chart as mesh " << refine_opt.reference
               << " (the identity map), left as dissected\n";
        else if (r.reference)
          text << "  refine maps: reference (not moved)\n";
        else
          text << "  refine maps: distortion to mesh " << refine_opt.reference << " " << std::setprecision(4)
               << r.energy_before << " -> " << r.energy_after << " (1 = isometric), " << r.patches_refined
               << " patches refined, " << r.patches_skipped << " left as they were, " << r.free_vertices
               << " vertices moved freely, " << r.newton_steps << " Newton steps, "
               << r.flipped_faces + r.zero_area_faces << " flipped or zero-area uv faces\n";
        if (!r.reference && !r.identity && refine_opt.pose_pull > 0)
          text << "  refine maps: pulled toward mesh " << refine_opt.reference
               << "'s nearest points (one pose), weight " << refine_opt.pose_pull << "\n";
        if (!r.reference && refine_opt.across_borders)
          text << "  refine across borders: " << r.sides_refined << " side refinements kept, " << r.sides_skipped
               << " sides left as they were, " << r.cut_vertices << " chart vertices added by the cuts (Newton steps per side: at most "
               << refine_opt.border_iterations << ")\n";
        if (!r.reference && refine_opt.move_corners)
          text << "  refine corners: " << r.corners_moved << " corner moves kept, " << r.corners_irregular
               << " irregular corners and " << r.corners_skipped << " others left as they were, "
               << r.corner_cut_vertices << " chart vertices added by the cuts\n";
      }
      for (const auto& n : d.tree)
        if (i < n.refined_faces.size() && n.refined_faces[i] > 0)
          text << "  refined patch " << n.name << ": +" << n.refined_faces[i]
               << " faces (edges split at their midpoints; the surface is unchanged)\n";
      for (size_t pi = 0; pi < d.chart.patches.size(); ++pi) {
        const auto& p = d.chart.patches[pi];
        if (p.flipped_faces + p.zero_area_faces == 0) continue;
        std::string feats;
        for (const auto& f : d.features)
          if (f.patch == static_cast<int>(pi)) feats += (feats.empty() ? "'" : ", '") + f.name + "'";
        folded << "patch " << p.name << " of " << dm.file << " (" << p.faces << " faces, "
               << p.flipped_faces + p.zero_area_faces << " folded"
               << (feats.empty() ? "" : ", features " + feats) << ", " << qs::dissect::stop_reason_name(p.stop)
               << "); ";
      }
      for (const auto& f : d.features)
        text << "  feature " << f.name << ": patch " << d.chart.patches[f.patch].name << " uv (" << std::setprecision(6)
             << f.uv.x() << ", " << f.uv.y() << ")\n";
      flipped += mesh_flipped;
    }
    if (refine_flag && inputs.size() == 1)
      text << "refine maps: one mesh, no map between meshes to refine (the chart is as dissected)\n";
    text << "maps: " << maps << "\n";
    if (inputs.size() > 1)
      text << "set: " << inputs.size() << " meshes, " << out[0].dissection.chart.patches.size()
           << " common patches, " << result.tree.size() << " tree nodes, " << result.warp_events
           << " warp flip events, max stretch " << std::setprecision(4) << result.max_stretch << "\n";
    if (result.pose_distance >= 0) {
      const bool near = result.pose_distance <= qs::dissect::kSamePoseDetect;
      text << "pose: the surfaces lie " << std::setprecision(3) << 100 * result.pose_distance
           << "% of the diagonal apart after the landmarks' similarity (mean), " << (near ? "at most " : "over ")
           << 100 * qs::dissect::kSamePoseDetect << "%: "
           << (result.same_pose_detected ? "one pose (as --same-pose)"
               : near                    ? "one mesh given again (its map is the identity)"
                                         : "not one pose")
           << "\n";
    }
    if (one_pose && inputs.size() > 1) {
      if (result.same_pose_fallback.empty())
        text << "same pose: " << result.same_pose_loops << " of " << inputs.size() - 1 << " seed loops routed by pose, "
             << result.same_pose_splits << " splits with inner corners placed by pose, " << result.same_pose_common
             << " at the common (u,v); " << result.same_pose_maps
             << " node maps taken over from the first mesh by nearest points, " << result.same_pose_own_maps
             << " kept their own (folded); of those taken over " << result.same_pose_polished
             << " polished after the repair, " << result.same_pose_untangled << " untangled from their own"
             << (result.posed_corners_fallback.empty()
                     ? std::string()
                     : "; posed corners from unfolded node maps only (" + result.posed_corners_fallback + ")")
             << "\n";
      else
        text << "same pose: not used (" << result.same_pose_fallback << "; the common (u,v) fold less)\n";
    }
    if (refine_before_split && !used.same_pose && inputs.size() > 1)
      text << "refine before split: split nodes' maps of every mesh but the first refined against the first's, seen as "
           << before_split_metric << ": " << result.before_split_refined << " refined, " << result.before_split_own
           << " kept their own\n";

    for (const auto& dm : out) {
      qs::check_not_an_input(fs::path(outdir) / dm.chart_file, input_paths, "-o");
      qs::dissect::write_chart_ply(folder.staging() / dm.chart_file, dm.dissection.chart);
    }
    qs::check_not_an_input(fs::path(outdir) / "dissection.json", input_paths, "-o");
    qs::write_file_atomically(folder.staging() / "dissection.json", qs::dissect::dissection_to_json(out, used, false, maps));
    const auto t3 = std::chrono::steady_clock::now();
    text << "  wrote " << (fs::path(outdir) / "dissection.json").string() << " and " << out.size() << " chart file"
         << (out.size() > 1 ? "s" : "") << "\n";
    std::ostringstream times;
    times << std::fixed << std::setprecision(3) << "  time: read+validate "
          << std::chrono::duration<double>(t1 - t0).count() << " s, dissect " << seconds << " s, ";
    if (refine_maps && out.size() > 1) times << "refine maps " << refine_seconds << " s, ";
    times << "write " << std::chrono::duration<double>(t3 - t2).count() - refine_seconds << " s\n";
    if (!quiet) std::cout << text.str() << times.str();
    std::ostringstream full;
    full << text.str() << times.str();
    for (const auto& dm : out)
      for (const auto& p : dm.dissection.chart.patches)
        full << "  " << dm.file << " " << p.name << ": " << p.faces << " faces, stretch " << p.stretch
             << ", flipped " << p.flipped_faces << "\n";
    if (!report_file.empty()) qs::write_file_atomically(report_file, full.str());
    if (flipped > 0) {
      // The folder is written (the report refers to it); the advice depends on why splitting stopped.
      folder.commit();
      bool split_failed = false, limits = false;
      for (const auto& dm : out)
        for (const auto& p : dm.dissection.chart.patches)
          if (p.flipped_faces + p.zero_area_faces > 0) {
            split_failed |= p.stop == qs::dissect::StopReason::SplitFailed || p.stop == qs::dissect::StopReason::NoProgress;
            limits |= p.stop == qs::dissect::StopReason::MaxDepth || p.stop == qs::dissect::StopReason::TooFewFaces;
          }
      std::string advice;
      if (limits) advice = "try a larger --max-depth or a smaller --min-faces";
      if (split_failed)
        advice += std::string(advice.empty() ? "" : "; ") +
                  "a split failed (see its reason above): try other seeds, --relax, or a cleaner mesh";
      if (out.size() > 1)
        advice += std::string(advice.empty() ? "" : "; ") +
                  "check that the landmarks correspond (features in the same order around each other on every "
                  "mesh, seeds at the same places)";
      if (advice.empty()) advice = "see the report above";
      throw qs::SolverError(std::to_string(flipped) + " uv faces stay flipped or of zero area after splitting, " +
                            "local refinement and repair: " + folded.str() + advice);
    }
    folder.commit();
    return 0;
  });
}
