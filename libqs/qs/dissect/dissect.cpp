// The dissect module's entry points (paper 3.2-3.4). The work is spread over files by role:
// mesh_dissector.cpp (one mesh's cut mesh and leaves), quinary_split.cpp (cutting one patch),
// split_choice.cpp (where to split), feature_alignment.cpp (the warp of features across a set),
// leaf_repair.cpp (untangling, stretch minimization), set_dissector.cpp (the union tree).
//
// The working state is one CutMesh whose faces carry a patch label (one label per quinary-tree
// node). A split only ever inserts vertices strictly inside the parent patch (its cuts start at
// the parent's corners and otherwise stay in its interior), so neighbouring patches never change
// and every patch side stays shared by exactly two patches: the base domain is conforming by
// construction, and checked anyway.

#include <algorithm>
#include <optional>
#include <string>

#include "qs/core/error.h"
#include "qs/dissect/dissect_detail.h"
#include "qs/dissect/dissection.h"
#include "qs/dissect/loop_guide.h"
#include "qs/dissect/seed_order.h"
#include "qs/metro/metro.h"

namespace qs::dissect {

namespace {

// A mesh's landmarks by name ("seed0".."seed3", then its features): each its 3D point and a vertex
// (a landmark inside a face: the face's corner nearest to it); empty without seeds.
struct NamedLandmark {
  std::string name;
  Vec3 position;
  int vertex = -1;
};
std::vector<NamedLandmark> mesh_landmarks(const MeshToDissect& m) {
  std::vector<NamedLandmark> out;
  const TriMesh& mesh = *m.mesh;
  auto add = [&](std::string name, int vertex, const landmarks::SurfacePoint& where) {
    if (vertex >= 0 && vertex < mesh.num_vertices()) {
      out.push_back({std::move(name), mesh.positions[vertex], vertex});
      return;
    }
    if (where.face < 0 || where.face >= mesh.num_faces())
      throw InvalidInput((m.name.empty() ? std::string("a mesh") : m.name) + ": a landmark refers to face " +
                         std::to_string(where.face) + ", out of range (0.." + std::to_string(mesh.num_faces() - 1) +
                         ")");
    const Vec3 x = landmarks::position_of(mesh, where);
    int best = mesh.faces[where.face][0];
    for (int v : mesh.faces[where.face])
      if ((mesh.positions[v] - x).squaredNorm() < (mesh.positions[best] - x).squaredNorm()) best = v;
    out.push_back({std::move(name), x, best});
  };
  for (int k = 0; k < 4; ++k) {
    if (m.seed_points) add("seed" + std::to_string(k), -1, (*m.seed_points)[k]);
    else if (m.seeds) add("seed" + std::to_string(k), (*m.seeds)[k], {});
    else return {};
  }
  for (const auto& f : m.features) add(f.name, f.vertex, f.where);
  return out;
}

// mesh_landmarks' names and 3D points.
std::vector<std::pair<std::string, Vec3>> landmark_positions(const MeshToDissect& m) {
  std::vector<std::pair<std::string, Vec3>> out;
  for (NamedLandmark& l : mesh_landmarks(m)) out.emplace_back(std::move(l.name), l.position);
  return out;
}

// matched_extremities for a registration that does not fit: at most this many tips, matched within
// this relative difference of geodesic coordinates (as kIntrinsicLoopIsometry).
constexpr int kExtremities = 16;
constexpr double kExtremityMatch = 0.05;

// DissectOptions::register_poses: the first mesh registered onto every other one, when the set is
// one surface in other poses (landmark_discrepancy within kIntrinsicLoopIsometry) and every
// registration fits (kRegisteredFit, kRegisteredDistortion); nullopt otherwise. A registration that
// does not fit within kRegisteredTight is tried again with the tips of A's protrusions held too
// (matched_extremities), the closer kept. The worst fit and distortion go to `fit` and
// `distortion` (-1 when nothing was registered), the most points held to `tips`: in a kept
// retry, or, when the set is not registered, in any retry.
std::optional<std::vector<registration::Pose>> register_poses(const std::vector<MeshToDissect>& meshes,
                                                              const Context& context, double& fit,
                                                              double& distortion, int& tips) {
  fit = distortion = -1;
  tips = 0;
  std::vector<std::vector<NamedLandmark>> l(meshes.size());
  for (size_t i = 0; i < meshes.size(); ++i) l[i] = mesh_landmarks(meshes[i]);
  if (l[0].empty()) return std::nullopt;
  context.report("registration", 0.0);
  // One surface: the landmarks' geodesic distances, every mesh's against the first's.
  std::vector<int> l0;
  for (const NamedLandmark& x : l[0]) l0.push_back(x.vertex);
  std::vector<GeodesicCoordinates> c(meshes.size());  // kept for the retries below
  c[0] = geodesic_coordinates(*meshes[0].mesh, l0, context);
  for (size_t i = 1; i < meshes.size(); ++i) {
    if (l[i].size() != l[0].size()) return std::nullopt;
    std::vector<int> li;
    for (size_t k = 0; k < l[i].size(); ++k) {
      if (l[i][k].name != l[0][k].name) return std::nullopt;
      li.push_back(l[i][k].vertex);
    }
    c[i] = geodesic_coordinates(*meshes[i].mesh, li, context);
    if (!(landmark_discrepancy(c[0], l0, c[i], li) <= detail::kIntrinsicLoopIsometry)) return std::nullopt;
  }
  std::vector<registration::Pose> poses(meshes.size());
  fit = distortion = 0;
  int tried = 0;  // the most points held in a retry
  auto fits = [](const registration::Registration& r) {
    return r.p99_distance <= kRegisteredFit && r.distortion <= kRegisteredDistortion;
  };
  for (size_t i = 1; i < meshes.size(); ++i) {
    std::vector<registration::LandmarkPair> pairs;
    for (size_t k = 0; k < l[i].size(); ++k) pairs.push_back({l[0][k].position, l[i][k].position});
    registration::Registration r;
    try {
      r = registration::register_surface(*meshes[0].mesh, *meshes[i].mesh, pairs, {}, context);
      // Limbs that the landmarks leave free can bend the wrong way: their tips, matched by
      // geodesic coordinates, are held too, and the closer fit is kept.
      if (r.p99_distance > kRegisteredTight || !fits(r)) {
        const auto matched =
            matched_extremities(*meshes[0].mesh, c[0], *meshes[i].mesh, c[i], kExtremities, kExtremityMatch);
        if (!matched.empty()) {
          std::vector<registration::LandmarkPair> more = pairs;
          for (const auto& [p, q] : matched)
            more.push_back({meshes[0].mesh->positions[p], meshes[i].mesh->positions[q]});
          registration::Registration again =
              registration::register_surface(*meshes[0].mesh, *meshes[i].mesh, more, {}, context);
          tried = std::max(tried, static_cast<int>(matched.size()));
          if (fits(again) && (!fits(r) || again.p99_distance < r.p99_distance)) {
            r = std::move(again);
            tips = std::max(tips, static_cast<int>(matched.size()));
          }
        }
      }
    } catch (const InternalError& e) {  // a solve that failed: the set keeps the path of other poses
      context.info(std::string("registration: ") + e.what());
      tips = tried;
      return std::nullopt;
    }
    fit = std::max(fit, r.p99_distance);
    distortion = std::max(distortion, r.distortion);
    if (!fits(r)) {
      tips = tried;
      return std::nullopt;
    }
    poses[i] = registration::Pose(*meshes[0].mesh, std::move(r), thread_count(0, context));
    context.report("registration", static_cast<double>(i) / static_cast<double>(meshes.size() - 1));
  }
  return poses;
}

// dissect_set after its checks and the pose detection: the dissection and its safety nets. A
// result with folded leaves is dissected again with safer options, in this order of preference:
// the pose with the options' maps, the pose with edge+mean-value, the same two with posed corners
// from unfolded node maps only, the common (u,v) with the options' maps, the common (u,v) with
// edge+mean-value. The first without folds is kept, else the one that folds least (the
// earlier on a tie). The pose goes before the maps: a camel against its re-tessellation with a
// hoof as a feature, 10 choices of its landmarks, folded with the pose and geodesic+cotan in 5 of
// them; with the pose and edge+mean-value 2 of those 5 did not fold (0.45-0.48% mean error), where
// the common (u,v) gave 4.1% (legs swapped, 35% max). Since the seed loops of one pose follow the
// first mesh's (SetDissector::seed_posed), 8 of the 10 keep the pose with geodesic+cotan and the
// other 2 with edge+mean-value. Posed corners from folded node maps lower the error on most sets
// (DissectOptions::same_pose_folded_maps) but folded one of those 10 choices of the camel with
// either maps (250 and 1444 uv faces; the common (u,v) then swapped legs: 4.3% mean), which does
// not fold without them (0.46%).
DissectionSet dissect_with_nets(const std::vector<MeshToDissect>& meshes, const DissectOptions& options,
                                const Context& context) {
  auto folded = [&meshes](const DissectionSet& s, std::string& where) {
    long n = 0;
    for (size_t i = 0; i < s.meshes.size(); ++i)
      for (const auto& p : s.meshes[i].chart.patches) {
        const int f = p.flipped_faces + p.zero_area_faces;
        if (f > 0 && where.empty())
          where = "patch " + p.name + " of " + (meshes[i].name.empty() ? "mesh " + std::to_string(i) : meshes[i].name);
        n += f;
      }
    return n;
  };
  struct Attempt {
    bool pose, options_maps;  // options_maps false: edge paths and mean-value weights
    bool folded_maps;         // posed corners from folded node maps too (with pose)
    long folded = 0;
    std::string where;
  };
  const bool pose = options.same_pose && meshes.size() > 1;
  const bool maps_net = options.fallback_maps && (options.geodesic_seed_curves || options.intrinsic_cotan);
  const bool corners_net = pose && options.same_pose_folded_maps;
  std::vector<Attempt> plan{{pose, true, options.same_pose_folded_maps, 0, {}}};
  if (maps_net) plan.push_back({pose, false, options.same_pose_folded_maps, 0, {}});
  if (corners_net) plan.push_back({pose, true, false, 0, {}});
  if (corners_net && maps_net) plan.push_back({pose, false, false, 0, {}});
  if (pose) plan.push_back({false, true, false, 0, {}});
  if (pose && maps_net) plan.push_back({false, false, false, 0, {}});
  const std::string options_maps = maps_name(options.geodesic_seed_curves, options.intrinsic_cotan);
  auto describe = [&](const Attempt& a) {
    const std::string maps = a.options_maps ? options_maps : "edge+mean-value";
    if (!pose) return maps;
    if (!a.pose) return "the common (u,v) and " + maps;
    return std::string(a.folded_maps || !corners_net ? "the pose (posed corners, node maps)"
                                                     : "the pose with corners from unfolded node maps") +
           " and " + maps;
  };
  DissectionSet out;
  size_t best = 0;
  for (size_t k = 0; k < plan.size(); ++k) {
    Attempt& a = plan[k];
    DissectOptions o = options;
    o.same_pose = a.pose && options.same_pose;
    o.same_pose_folded_maps = a.folded_maps;
    if (!a.options_maps) o.geodesic_seed_curves = o.intrinsic_cotan = false;
    if (k > 0)
      context.info("dissection: " + std::to_string(plan[best].folded) + " folded uv faces with " +
                   describe(plan[best]) + " (" + plan[best].where + "); dissecting again with " + describe(a));
    DissectionSet r = detail::SetDissector(meshes, o, context).run();
    r.geodesic_seed_curves = o.geodesic_seed_curves;
    r.intrinsic_cotan = o.intrinsic_cotan;
    a.folded = folded(r, a.where);
    if (k == 0 || a.folded < plan[best].folded) {
      out = std::move(r);
      best = k;
    }
    if (a.folded == 0) break;
  }
  // Why the result's options differ from those given: the attempts' folds with what was dropped.
  auto folds = [](const Attempt& a) { return std::to_string(a.folded) + " folded uv faces"; };
  const Attempt& used = plan[best];
  if (pose && !used.pose) {
    std::string why;
    for (const Attempt& a : plan)
      if (a.pose)
        why +=
            (why.empty() ? "" : ", ") + folds(a) + " with " + describe(a) + (why.empty() ? " (" + a.where + ")" : "");
    out.same_pose_fallback = why;
  }
  // The tries that differ from the result in one option only, in the plan's order.
  auto find = [&](bool options_maps, bool folded_maps) -> const Attempt* {
    for (const Attempt& a : plan)
      if (a.pose == used.pose && a.options_maps == options_maps && a.folded_maps == folded_maps) return &a;
    return nullptr;
  };
  if (!used.options_maps)
    if (const Attempt* with_maps = find(true, used.folded_maps))
      out.maps_fallback = folds(*with_maps) + " with " + options_maps + " (" + with_maps->where + ")";
  if (used.pose && corners_net && !used.folded_maps)
    if (const Attempt* relaxed = find(used.options_maps, true))
      out.posed_corners_fallback = folds(*relaxed) + " with corners from folded node maps too (" + relaxed->where + ")";
  return out;
}

// dissect_set once the seeds are in their order: the pose detection, then the dissection.
DissectionSet dissect_set_in_order(const std::vector<MeshToDissect>& meshes, const DissectOptions& options,
                                   const Context& context) {
  // Same pose found by measurement (DissectOptions::same_pose_detect).
  std::optional<PoseDistance> measured;
  bool detected = false;
  if (!options.same_pose && options.same_pose_detect > 0 && meshes.size() > 1) {
    measured = pose_distance(meshes, context);
    detected = measured && measured->mean <= options.same_pose_detect &&
               measured->p99 <= kSamePoseTail * options.same_pose_detect;
  }
  DissectOptions used = options;
  double fit = -1, distortion = -1;
  int tips = 0;
  const bool part_moved =
      detected && measured->p99 > kPartMoved * measured->mean && measured->p99 > kPartMovedFloor;
  if (measured && (!detected || part_moved) && options.register_poses && used.pose_registrations.empty()) {
    if (auto poses = register_poses(meshes, context, fit, distortion, tips)) {
      used.pose_registrations = std::move(*poses);
      detected = true;
    }
  }
  used.same_pose = options.same_pose || detected;
  DissectionSet out = dissect_with_nets(meshes, used, context);
  out.poses = used.pose_registrations;
  out.registration_fit = fit;
  out.registration_distortion = distortion;
  out.registration_tips = tips;
  out.pose_distance = measured ? measured->mean : -1;
  out.pose_distance_p99 = measured ? measured->p99 : -1;
  out.same_pose_detected = detected;
  out.pose_part_moved = part_moved;
  return out;
}

}  // namespace

std::optional<PoseDistance> pose_distance(const std::vector<MeshToDissect>& meshes, const Context& context) {
  if (meshes.size() < 2) return std::nullopt;
  const auto first = landmark_positions(meshes[0]);
  if (first.empty()) return std::nullopt;
  const metro::SurfaceDistance to_first(*meshes[0].mesh, "the first mesh", thread_count(0, context));
  PoseDistance worst;
  for (size_t i = 1; i < meshes.size(); ++i) {
    const auto mine = landmark_positions(meshes[i]);
    if (mine.empty()) return std::nullopt;
    std::vector<Vec3> from, to;
    for (const auto& [name, x] : mine)
      for (const auto& [name0, x0] : first)
        if (name == name0) {
          from.push_back(x);
          to.push_back(x0);
        }
    const Eigen::Matrix4d pose = fit_similarity(from, to);
    TriMesh moved = *meshes[i].mesh;
    for (auto& x : moved.positions) x = (pose * x.homogeneous()).head<3>();
    const metro::SurfaceDistance to_moved(moved, "a moved mesh", thread_count(0, context));
    const metro::VertexDistance d = metro::vertex_distance(moved, to_moved, *meshes[0].mesh, to_first, 0.99, context);
    worst.mean = std::max(worst.mean, d.mean);
    worst.p99 = std::max(worst.p99, d.quantile);
  }
  const double diag = bounding_box(meshes[0].mesh->positions).diagonal();
  if (!(diag > 0)) return PoseDistance{};
  return PoseDistance{worst.mean / diag, worst.p99 / diag};
}

DissectionSet dissect_set(const std::vector<MeshToDissect>& meshes, const DissectOptions& options,
                          const Context& context) {
  if (!(options.tau >= 1.0)) throw InvalidInput("--tau must be at least 1 (the stretch of an isometry)");
  if (!(options.min_split_area >= 0 && options.min_split_area <= 1))
    throw InvalidInput("min_split_area is " + std::to_string(options.min_split_area) +
                       "; expected a fraction of the surface in [0, 1] (0: off)");
  if (!(options.force_split_area >= 0 && options.force_split_area <= 1))
    throw InvalidInput("force_split_area is " + std::to_string(options.force_split_area) +
                       "; expected a fraction of the surface in [0, 1] (0: off)");
  if (options.area_extra_depth < 0 || options.area_extra_depth > 12)
    throw InvalidInput("area_extra_depth is " + std::to_string(options.area_extra_depth) +
                       "; expected 0 (off) to 12 levels past max_depth");
  if (!(options.protrusion_stretch >= 0))
    throw InvalidInput("protrusion_stretch is " + std::to_string(options.protrusion_stretch) +
                       "; expected a stretch >= 0 (0: off)");
  if (!(options.same_pose_detect >= 0))
    throw InvalidInput("same_pose_detect is " + std::to_string(options.same_pose_detect) +
                       "; expected a fraction of the diagonal >= 0 (0: off)");
  if (meshes.empty()) throw InvalidInput("no mesh to dissect");
  for (const auto& m : meshes)
    if (m.mesh == nullptr) throw InvalidInput("dissect_set: a mesh is null");
  // The seeds' cyclic order of the set's shortest loop (the same permutation for every mesh).
  const SeedOrderChoice order = shortest_seed_order(meshes, kSeedOrderMargin, context);
  if (order.changed()) {
    std::vector<MeshToDissect> reordered = meshes;
    for (size_t i = 0; i < meshes.size(); ++i)
      for (int k = 0; k < 4; ++k) {
        if (meshes[i].seeds) (*reordered[i].seeds)[k] = (*meshes[i].seeds)[order.order[k]];
        if (meshes[i].seed_points) (*reordered[i].seed_points)[k] = (*meshes[i].seed_points)[order.order[k]];
      }
    DissectionSet out = dissect_set_in_order(reordered, options, context);
    out.seed_order = order.order;
    out.seed_loop_lengths = order.lengths;
    return out;
  }
  DissectionSet out = dissect_set_in_order(meshes, options, context);
  out.seed_loop_lengths = order.lengths;
  return out;
}

std::string maps_name(bool geodesic_seed_curves, bool intrinsic_cotan) {
  return std::string(geodesic_seed_curves ? "geodesic" : "edge") + "+" + (intrinsic_cotan ? "cotan" : "mean-value");
}

Dissection dissect(const TriMesh& mesh, const std::optional<std::array<int, 4>>& seeds,
                   const DissectOptions& options, const Context& context) {
  MeshToDissect m;
  m.mesh = &mesh;
  m.seeds = seeds;
  DissectionSet set = dissect_set({m}, options, context);
  return std::move(set.meshes.front());
}

}  // namespace qs::dissect
