// The dissection pipeline: inputs -> dissect_set (with the map hooks) -> refine_maps -> report ->
// the dissection folder.

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/core/json_strict.h"
#include "qs/dissect/chart_io.h"
#include "qs/pipeline/pipeline.h"

namespace qs::pipeline {

namespace fs = std::filesystem;

namespace {

// A mesh stem as a chart file name that dissection.json (JSON: UTF-8) can hold and its reader
// accepts: a stem that is not clean UTF-8 text, or holds a backslash, has those bytes (and '%')
// written %XX.
std::string chart_stem_of(const std::string& stem) {
  if (json_strict::is_clean_text(stem) && stem.find('\\') == std::string::npos) return stem;
  std::string out;
  for (const char ch : stem) {
    const auto c = static_cast<unsigned char>(ch);
    if (c < 0x20 || c >= 0x7f || c == '\\' || c == '%') {
      static const char* const kHex = "0123456789ABCDEF";
      out += '%';
      out += kHex[c >> 4];
      out += kHex[c & 15];
    } else {
      out += ch;
    }
  }
  return out;
}

// Chart file names: <stem>.chart.ply, with -2, -3 ... for repeated stems.
std::vector<std::string> chart_names(const std::vector<Input>& inputs) {
  std::vector<std::string> names;
  std::map<std::string, int> seen;
  for (const auto& in : inputs) {
    const std::string stem = chart_stem_of(fs::path(in.file).stem().string());
    const int n = ++seen[stem];
    std::string name = stem;
    if (n > 1) name += '-' + std::to_string(n);
    names.push_back(name + ".chart.ply");
  }
  return names;
}

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

Input load_input(const std::string& mesh_file, const std::optional<std::string>& landmark_file) {
  Input in;
  in.file = mesh_file;
  in.read = io::read_mesh(mesh_file);
  in.valid = mesh::validate(in.read.mesh);
  if (!in.valid.report.accepted)
    throw InvalidInput("mesh rejected:\n" + mesh::format_report(mesh_file, in.valid.report));
  const std::optional<fs::path> lm =
      landmark_file ? std::optional<fs::path>(*landmark_file) : landmarks::find_landmarks_beside(mesh_file);
  if (lm) {
    in.landmarks = landmarks::read_landmarks(*lm, in.valid);
    in.landmark_file = lm->string();
  }
  return in;
}

std::string default_dissection_folder(const std::vector<std::string>& files) {
  std::string d;
  for (size_t i = 0; i < files.size() && i < 3; ++i) {
    if (i) d += '_';
    d += fs::path(files[i]).stem().string();
  }
  if (files.size() > 3) d += "_etc";
  return d + ".dissection";
}

std::vector<std::string> check_inputs(const std::vector<Input>& inputs) {
  auto has_seeds = [](const Input& in) { return in.landmarks && in.landmarks->seeds.size() == 4; };
  const auto with_seeds = std::count_if(inputs.begin(), inputs.end(), has_seeds);
  if (with_seeds != 0 && with_seeds != static_cast<long>(inputs.size())) {
    std::string which;
    for (const auto& in : inputs)
      if (!has_seeds(in)) which += (which.empty() ? "" : ", ") + in.file;
    throw InvalidInput("seeds correspond by order across the set, so every mesh needs them: " + which +
                       " has no seeds (give a landmark file with 4 seeds for each mesh, or for none)");
  }
  std::vector<std::string> warnings;
  if (inputs.size() > 1 && with_seeds == 0)
    warnings.push_back("no seeds given; each mesh gets automatic seeds from its own principal axes, which "
                       "correspond only for similar poses. Give seeds for a reliable correspondence.");
  return warnings;
}

SetResult dissect_meshes(const std::vector<dissect::MeshToDissect>& meshes, const DissectConfig& config,
                         const Context& ctx) {
  validate_config(config);
  SetResult out;
  // The options with the map hooks (the dissect module does not depend on maprefine).
  dissect::DissectOptions opt = config.dissect;
  maprefine::RefineOptions& refine_opt = out.refine_options;
  refine_opt = config.refine;
  refine_opt.threads = ctx.threads;
  opt.refine_before_split = nullptr;
  if (config.refine_before_split) opt.refine_before_split = maprefine::node_refiner(refine_opt);
  opt.same_pose_untangle = maprefine::untangler(refine_opt);
  const auto t1 = std::chrono::steady_clock::now();
  out.set = dissect::dissect_set(meshes, opt, ctx);
  out.dissect_seconds = seconds_since(t1);
  // One pose (told or found): posed splits (unless they fell back) and the refinement's pull.
  out.one_pose = opt.same_pose || out.set.same_pose_detected;
  refine_opt.pose_pull = out.one_pose ? config.pose_pull : 0;
  refine_opt.poses = out.set.poses;
  if (refine_opt.pose_pull > 0) {
    refine_opt.border_iterations = config.pose_border_iterations;
    const bool registered =
        std::any_of(out.set.poses.begin(), out.set.poses.end(), [](const auto& p) { return p.registered(); });
    if (registered) {
      refine_opt.pose_pull *= maprefine::kRegisteredPullScale;
      refine_opt.border_iterations *= maprefine::kRegisteredStepScale;
      if (refine_opt.border_sweeps > 0)
        refine_opt.border_sweeps = std::max(refine_opt.border_sweeps, maprefine::kRegisteredBorderSweeps);
    }
  }
  if (config.refine_maps && out.set.meshes.size() > 1) {
    const auto t2 = std::chrono::steady_clock::now();
    out.refine = maprefine::refine_maps(out.set.meshes, refine_opt, ctx);
    out.refine_seconds = seconds_since(t2);
    out.set.max_stretch = 0;
    for (const auto& m : out.set.meshes) out.set.max_stretch = std::max(out.set.max_stretch, m.max_stretch);
  }
  return out;
}

DissectResult dissect(const std::vector<Input>& inputs, const DissectConfig& config, const Context& ctx) {
  validate_config(config);
  if (inputs.empty()) throw InvalidInput("no mesh to dissect");
  DissectResult result;
  result.config = config;
  for (const auto& in : inputs) {
    result.inputs.emplace_back(in.file);
    if (!in.landmark_file.empty()) result.inputs.emplace_back(in.landmark_file);
  }

  std::vector<dissect::MeshToDissect> set(inputs.size());
  std::vector<std::string> seed_source(inputs.size(), "automatic");
  for (size_t i = 0; i < inputs.size(); ++i) {
    const auto& in = inputs[i];
    set[i].mesh = &in.valid.mesh;
    set[i].name = in.file;
    if (!in.landmarks) continue;
    if (in.landmarks->seeds.size() == 4) {
      // Seeds as surface points: a seed not on a vertex is inserted, so that it is exactly a
      // corner of the two seed patches.
      std::array<landmarks::SurfacePoint, 4> seeds;
      for (int k = 0; k < 4; ++k) seeds[k] = in.landmarks->seeds[k].where;
      set[i].seed_points = seeds;
      seed_source[i] = in.landmark_file;
    }
    for (const auto& l : in.landmarks->features) {
      dissect::Feature f;
      f.name = l.name;
      f.vertex = l.vertex;
      f.where = l.where;
      set[i].features.push_back(f);
    }
  }
  check_inputs(inputs);

  SetResult run = dissect_meshes(set, config, ctx);
  dissect::DissectionSet& sets = run.set;
  const maprefine::RefineReport& refine_report = run.refine;
  const maprefine::RefineOptions& refine_opt = run.refine_options;
  const dissect::DissectOptions& opt = config.dissect;
  result.dissect_seconds = run.dissect_seconds;
  result.refine_seconds = run.refine_seconds;
  // Which maps were used, and why (the safety net of the new maps: DissectOptions::fallback_maps).
  std::string maps = dissect::maps_name(sets.geodesic_seed_curves, sets.intrinsic_cotan);
  if (!sets.maps_fallback.empty()) maps += " (fallback: " + sets.maps_fallback + ")";
  result.maps = maps;
  const bool one_pose = run.one_pose;
  const bool posed = one_pose && sets.same_pose_fallback.empty();

  const auto charts = chart_names(inputs);
  auto& out = result.meshes;
  out.resize(inputs.size());
  std::ostringstream text;
  int flipped = 0;
  std::ostringstream folded;  // the patches left folded, for the error
  for (size_t i = 0; i < inputs.size(); ++i) {
    auto& dm = out[i];
    dm.dissection = std::move(sets.meshes[i]);
    dm.file = inputs[i].file;
    dm.chart_file = charts[i];
    dm.seed_source = seed_source[i];
    dm.input_vertices = inputs[i].valid.report.vertices;
    dm.input_faces = inputs[i].valid.report.faces;
    dm.seconds = result.dissect_seconds;
    const auto& d = dm.dissection;
    if (!d.base.closed_conforming || d.base.euler_characteristic != 2 || d.base.quads != out[0].dissection.base.quads)
      throw InternalError("the base domain of " + dm.file +
                          " is not a closed conforming quad mesh of Euler characteristic 2 shared by the set");
    text << dm.file << ": " << d.chart.patches.size() << " patches (base domain V=" << d.base.vertices.size()
         << " E=" << d.base.edges << " F=" << d.base.quads.size() << "), max stretch " << std::setprecision(4)
         << d.max_stretch << " (tau " << opt.tau << "), seeds " << dm.seed_source << " [" << d.seeds[0] << " "
         << d.seeds[1] << " " << d.seeds[2] << " " << d.seeds[3] << "]\n";
    int mesh_flipped = 0;
    for (const auto& p : d.chart.patches) {
      mesh_flipped += p.flipped_faces + p.zero_area_faces;
      if (p.stop != dissect::StopReason::None)
        text << "  patch " << p.name << ": stretch " << p.stretch << " over tau, left as is: "
             << dissect::stop_reason_name(p.stop) << (p.stop_detail.empty() ? "" : " (" + p.stop_detail + ")") << ", "
             << p.faces << " faces\n";
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
             << " vertices moved freely, " << r.newton_steps << " Newton steps, " << r.flipped_faces + r.zero_area_faces
             << " flipped or zero-area uv faces\n";
      if (!r.reference && !r.identity && refine_opt.pose_pull > 0)
        text << "  refine maps: pulled toward mesh " << refine_opt.reference << "'s nearest points (one pose), weight "
             << refine_opt.pose_pull << "\n";
      if (!r.reference && refine_opt.across_borders)
        text << "  refine across borders: " << r.sides_refined << " side refinements kept, " << r.sides_skipped
             << " sides left as they were, " << r.cut_vertices
             << " chart vertices added by the cuts (Newton steps per side: at most " << refine_opt.border_iterations
             << ")\n";
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
             << p.flipped_faces + p.zero_area_faces << " folded" << (feats.empty() ? "" : ", features " + feats) << ", "
             << dissect::stop_reason_name(p.stop) << "); ";
    }
    for (const auto& f : d.features)
      text << "  feature " << f.name << ": patch " << d.chart.patches[f.patch].name << " uv (" << std::setprecision(6)
           << f.uv.x() << ", " << f.uv.y() << ")\n";
    flipped += mesh_flipped;
  }
  text << "maps: " << maps << "\n";
  if (sets.seed_order != std::array<int, 4>{0, 1, 2, 3}) {
    const auto& o = sets.seed_order;
    const auto& len = sets.seed_loop_lengths;
    const double best = std::min({len[0], len[1], len[2]});
    text << "seed order: the seeds taken as s" << o[0] << " s" << o[1] << " s" << o[2] << " s" << o[3]
         << " in every mesh, the set's shortest loop (in the given order the loop is " << std::setprecision(3)
         << 100 * (len[0] / best - 1) << "% longer and winds around the shape)\n";
  }
  if (inputs.size() > 1 && !posed && opt.intrinsic_loops && !sets.landmark_discrepancy.empty()) {
    const auto& d = sets.landmark_discrepancy;
    text << "seed loops: " << sets.intrinsic_loops << " of " << inputs.size() - 1
         << " routed along the first mesh's in geodesic coordinates of the landmarks (the landmarks' geodesic "
            "distances differ from the first mesh's by "
         << std::setprecision(3) << 100 * *std::min_element(d.begin() + 1, d.end()) << "-"
         << 100 * *std::max_element(d.begin() + 1, d.end())
         << "%; a mesh over 5%, not the first's shape in another pose, or whose loop would move a feature to the "
            "other side keeps its own shortest loop)\n";
  }
  if (inputs.size() > 1)
    text << "set: " << inputs.size() << " meshes, " << out[0].dissection.chart.patches.size() << " common patches, "
         << sets.tree.size() << " tree nodes, " << sets.warp_events << " warp flip events, max stretch "
         << std::setprecision(4) << sets.max_stretch << "\n";
  if (sets.pose_distance >= 0) {
    const double limit = opt.same_pose_detect, tail = dissect::kSamePoseTail * limit;
    text << "pose: the surfaces lie " << std::setprecision(3) << 100 * sets.pose_distance
         << "% of the diagonal apart after the landmarks' similarity (mean; 99% of the area within "
         << 100 * sets.pose_distance_p99 << "%; one pose: at most " << 100 * limit << "% and " << 100 * tail
         << "%): ";
    if (sets.pose_part_moved)
      text << "within both, but the 99% quantile is " << std::setprecision(2)
           << sets.pose_distance_p99 / sets.pose_distance << " times the mean (over " << dissect::kPartMoved
           << ": a part moved in place, as a limb turned about itself): "
           << (sets.poses.empty() ? "one pose (as --same-pose), the registration not fitting" : "registered") << "\n";
    else
      text << (sets.same_pose_detected && sets.poses.empty() ? "one pose (as --same-pose)" : "not one pose") << "\n";
  }
  if (sets.registration_fit >= 0) {
    const std::string more = std::to_string(sets.registration_tips) + " more points held";
    text << "registration: the first mesh deformed onto the others as rigidly as possible lies within "
         << std::setprecision(3) << 100 * sets.registration_fit << "% of the diagonal on 99% of the area, distortion "
         << std::setprecision(4) << sets.registration_distortion << " (one pose: at most "
         << 100 * dissect::kRegisteredFit << "% and " << dissect::kRegisteredDistortion << "): ";
    if (sets.poses.empty())
      text << "not used" << (sets.registration_tips > 0 ? ", nor with " + more : "")
           << " (a landmark at the tip of every limb that moved helps it fit)\n";
    else
      text << "one pose through the registrations"
           << (sets.registration_tips > 0 ? ", with " + more +
                                                " (the first mesh's points farthest from the landmarks, matched by "
                                                "their distances along the surface to them)"
                                          : "")
           << "\n";
  }
  if (sets.retried_splits > 0)
    text << "splits tried again with cuts kept on their segments (the first cuts crossed): " << sets.retried_splits
         << "\n";
  if (one_pose && inputs.size() > 1) {
    if (sets.same_pose_fallback.empty())
      text << "same pose: " << sets.same_pose_loops << " of " << inputs.size() - 1 << " seed loops routed by pose, "
           << sets.same_pose_splits << " splits with inner corners placed by pose, " << sets.same_pose_common
           << " at the common (u,v); " << sets.same_pose_maps
           << " node maps taken over from the first mesh by nearest points, " << sets.same_pose_own_maps
           << " kept their own; of those taken over " << sets.same_pose_folded_taken
           << " left folded (the cuts follow the first mesh's), " << sets.same_pose_polished
           << " polished after the repair, " << sets.same_pose_untangled << " untangled from their own; "
           << sets.same_pose_leaves << " leaf maps taken over"
           << (sets.posed_corners_fallback.empty()
                   ? std::string()
                   : "; posed corners from unfolded node maps only (" + sets.posed_corners_fallback + ")")
           << "\n";
    else
      text << "same pose: not used (" << sets.same_pose_fallback << "; the common (u,v) fold less)\n";
  }
  if (config.refine_before_split && !posed && inputs.size() > 1)
    text << "refine before split: split nodes' maps of every mesh but the first refined against the first's, seen as "
            "composition: "
         << sets.before_split_refined << " refined, " << sets.before_split_own << " kept their own\n";
  result.report = text.str();

  std::ostringstream patches;
  for (const auto& dm : out)
    for (const auto& p : dm.dissection.chart.patches)
      patches << "  " << dm.file << " " << p.name << ": " << p.faces << " faces, stretch " << p.stretch << ", flipped "
              << p.flipped_faces << "\n";
  result.patch_report = patches.str();

  result.folded_faces = flipped;
  if (flipped > 0) {
    // The advice depends on why splitting stopped.
    bool split_failed = false, limits = false;
    for (const auto& dm : out)
      for (const auto& p : dm.dissection.chart.patches)
        if (p.flipped_faces + p.zero_area_faces > 0) {
          split_failed |= p.stop == dissect::StopReason::SplitFailed || p.stop == dissect::StopReason::NoProgress;
          limits |= p.stop == dissect::StopReason::MaxDepth || p.stop == dissect::StopReason::TooFewFaces;
        }
    std::string advice;
    if (limits) advice = "try a larger --max-depth or a smaller --min-faces";
    if (split_failed)
      advice += std::string(advice.empty() ? "" : "; ") +
                "a split failed (see its reason above): try other seeds or a cleaner mesh";
    if (out.size() > 1)
      advice += std::string(advice.empty() ? "" : "; ") +
                "check that the landmarks correspond (features in the same order around each other on every "
                "mesh, seeds at the same places)";
    if (advice.empty()) advice = "see the report above";
    result.folded_message = std::to_string(flipped) + " uv faces stay flipped or of zero area after splitting, " +
                            "local refinement and repair: " + folded.str() + advice;
  }
  return result;
}

void write_dissection(const DissectResult& result, OutputFolder& folder) {
  for (const auto& dm : result.meshes) {
    check_not_an_input(folder.target() / dm.chart_file, result.inputs, "output");
    dissect::write_chart_ply(folder.staging() / dm.chart_file, dm.dissection.chart);
  }
  check_not_an_input(folder.target() / "dissection.json", result.inputs, "output");
  write_file_atomically(folder.staging() / "dissection.json",
                        dissect::dissection_to_json(result.meshes, config_to_json(result.config), false, result.maps));
}

void write_dissection(const DissectResult& result, const fs::path& folder) {
  OutputFolder out(folder);
  write_dissection(result, out);
  out.commit();
}

void check_bijective(const DissectResult& result) {
  if (result.folded_faces > 0) throw SolverError(result.folded_message);
}

dissect::LoadedDissection read_dissection(const fs::path& folder) { return dissect::read_dissection(folder); }

}  // namespace qs::pipeline
