// The union quinary tree (paper 3.4): walks the tree over every mesh of the set at once; a node over
// tau in any mesh is split in every mesh at one point of the aligned parameter domain.

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <deque>
#include <iterator>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "qs/core/error.h"
#include "qs/dissect/dissect_detail.h"
#include "qs/dissect/loop_guide.h"
#include "qs/dissect/seed_loop.h"
#include "qs/dissect/seed_routing_detail.h"
#include "qs/landmarks/landmarks.h"
#include "qs/metro/metro.h"

namespace qs::dissect::detail {

// Levels past max_depth that a node whose map folds may still be split (see run()).
constexpr int kFoldExtraDepth = 3;

// Whether the folds of a node are those of a squeezed protrusion tip: every folded uv face, in
// every mesh, lies within kTipReach of the same feature (measured on the cat/lion tail tip: all
// folds within 4e-4 of it; folds elsewhere, left by a warp or a cut, spread over 0.02-0.5).
// Local refinement only adds rings to such a tip (measured: 6 -> 24 -> 52 -> 155 folds in three
// rounds); a split brings the tip closer to a patch of its own.
constexpr double kTipReach = 0.01;

bool squeezed_tip(const std::vector<Param>& ps) {
  int tip = -1;
  for (const auto& q : ps) {
    if (q.sp.bijective()) continue;
    const auto& F = q.ex.pm.faces;
    for (const Tri& t : F) {
      if (signed_area(q.sp.uv[t[0]], q.sp.uv[t[1]], q.sp.uv[t[2]]) > param::kZeroUvArea) continue;
      int nearest = -1;
      double reach = INFINITY;
      for (const auto& [k, local] : q.features) {
        double r = 0;
        for (int v : t) r = std::max(r, (q.sp.uv[v] - q.sp.uv[local]).norm());
        if (r < reach) reach = r, nearest = k;
      }
      if (nearest < 0 || reach > kTipReach || (tip >= 0 && nearest != tip)) return false;
      tip = nearest;
    }
  }
  return tip >= 0;
}

// DissectOptions::replace_node_maps (measurement only), with the maps' counts and stretch updated.
void replace_node_maps(const DissectOptions& opt, std::vector<Param>& ps, bool before_split) {
  if (!opt.replace_node_maps) return;
  std::vector<DissectOptions::NodeMapRef> maps;
  for (Param& p : ps) maps.push_back({&p.ex.verts, &p.sp.uv});
  opt.replace_node_maps(maps, before_split);
  for (Param& p : ps) {
    param::count_uv_faces(p.ex.pm.faces, p.sp);
    p.st = param::l2_stretch(p.ex.pm.positions, p.ex.pm.faces, p.sp.uv);
  }
}

bool wants_mean_value(const param::SquareParam& cot, const param::SquareParam& mv, bool one_tessellation) {
  if (cot.bijective()) return false;
  const bool fewer = mv.flipped_faces + mv.zero_area_faces < cot.flipped_faces + cot.zero_area_faces;
  return fewer && (one_tessellation || cot.flipped_faces > 0 || mv.bijective());
}

std::vector<char> joint_weights(const std::vector<double>& discrepancy) {
  std::vector<char> joint(discrepancy.size(), 0);
  for (size_t i = 0; i < discrepancy.size(); ++i) joint[i] = i == 0 || discrepancy[i] <= kIntrinsicLoopIsometry;
  if (std::count(joint.begin(), joint.end(), 1) < 2) std::fill(joint.begin(), joint.end(), 0);
  return joint;
}

SetDissector::SetDissector(const std::vector<MeshToDissect>& in, const DissectOptions& options,
                           const Context& context)
    : in_(in), opt_(options), ctx_(context) {
  // Features correspond by name: every mesh must have the same names, each once.
  for (size_t i = 0; i < in.size(); ++i) {
    std::vector<std::string> names;
    for (const auto& f : in[i].features) names.push_back(f.name);
    std::sort(names.begin(), names.end());
    const auto dup = std::adjacent_find(names.begin(), names.end());
    if (dup != names.end())
      throw InvalidInput((in[i].name.empty() ? "mesh " + std::to_string(i) : in[i].name) + ": feature '" + *dup +
                         "' is given twice");
    if (i == 0) {
      feature_names_ = names;
      continue;
    }
    std::vector<std::string> missing, extra;
    std::set_difference(feature_names_.begin(), feature_names_.end(), names.begin(), names.end(),
                        std::back_inserter(missing));
    std::set_difference(names.begin(), names.end(), feature_names_.begin(), feature_names_.end(),
                        std::back_inserter(extra));
    if (!missing.empty() || !extra.empty()) {
      std::string m = "features must have the same names in every mesh of the set;";
      auto list = [](const std::vector<std::string>& v) {
        std::string r;
        for (const auto& x : v) r += (r.empty() ? "'" : ", '") + x + "'";
        return r;
      };
      if (!missing.empty()) m += " " + in[i].name + " lacks " + list(missing) + " (found in " + in[0].name + ");";
      if (!extra.empty()) m += " " + in[i].name + " has " + list(extra) + " that " + in[0].name + " lacks;";
      throw InvalidInput(m);
    }
  }
  meshes_.reserve(in.size());
  for (size_t i = 0; i < in.size(); ++i)
    meshes_.emplace_back(in[i], static_cast<int>(i), feature_names_, opt_, ctx_);
}

std::vector<Param> SetDissector::evaluate(const std::vector<Node>& nodes, TreeNode& tn) {
  const Node& node = nodes[0];
  // The meshes of a set are independent here: one thread each for large nodes (the results do
  // not depend on it).
  std::vector<Param> ps(meshes_.size());
  size_t faces = 0;
  for (size_t i = 0; i < meshes_.size(); ++i) faces += meshes_[i].node_faces(nodes[i]);
  const int par = faces >= kParallelFaces ? 0 : 1;
  parallel_for(meshes_.size(), par, ctx_, [&](size_t i) { ps[i] = meshes_[i].parameterize(nodes[i]); });
  // Cotangent weights guarantee a bijection of the intrinsic Delaunay triangulation only: where a
  // patch's own triangles fold (slivers of the cuts) or a protrusion is squeezed to zero uv area,
  // the node may take mean-value weights instead (wants_mean_value). Those depend on the
  // tessellation, so meshes of one surface (other poses, other tessellations) choose together,
  // mean-value for all of them or for none: a mesh falling back alone would map a re-tessellation
  // by another rule than its source. Meshes of other shapes choose alone, where the fallback is
  // what holds a squeezed node (docs/pose-pairs.md has the measurements).
  auto joint = [&](size_t i) { return i < joint_weights_.size() && joint_weights_[i]; };
  std::vector<param::SquareParam> mv(ps.size());
  std::vector<char> wants(ps.size(), 0);
  parallel_for(ps.size(), par, ctx_, [&](size_t i) {
    if (ps[i].weights == param::InteriorWeights::MeanValue || ps[i].sp.bijective()) return;
    mv[i] = meshes_[i].mean_value_map(ps[i]);
    wants[i] = wants_mean_value(ps[i].sp, mv[i], !joint(i) || one_tessellation_);
  });
  bool together = false;
  for (size_t i = 0; i < ps.size(); ++i) together = together || (joint(i) && wants[i]);
  parallel_for(ps.size(), par, ctx_, [&](size_t i) {
    if ((joint(i) ? together : wants[i]) && ps[i].weights != param::InteriorWeights::MeanValue)
      meshes_[i].use_mean_value(ps[i], mv[i].uv.empty() ? meshes_[i].mean_value_map(ps[i]) : std::move(mv[i]));
    // A map squeezed to zero area (a long protrusion) that holds features is spread out by
    // stretch minimization, so that the features can be aligned (measured: it changes the tree of
    // a mesh without features for the worse as often as for the better).
    if (!ps[i].sp.bijective() && !ps[i].features.empty()) meshes_[i].spread(ps[i]);
  });
  replace_node_maps(opt_, ps, false);
  // The same features must lie inside the node in every mesh: they are aligned before every split,
  // so only the seed loops (traced on each mesh independently) can separate them.
  for (size_t i = 1; i < ps.size(); ++i) {
    if (ps[i].features.size() == ps[0].features.size() &&
        std::equal(ps[i].features.begin(), ps[i].features.end(), ps[0].features.begin(),
                   [](const auto& a, const auto& b) { return a.first == b.first; }))
      continue;
    std::vector<int> a, b, diff;
    for (const auto& f : ps[0].features) a.push_back(f.first);
    for (const auto& f : ps[i].features) b.push_back(f.first);
    std::set_symmetric_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(diff));
    if (node.depth > 0)
      throw SolverError("feature '" + feature_names_[diff.front()] + "' ended in different children of patch " +
                        node.name.substr(0, node.name.rfind('.')) + " across the set (please report this)");
    throw InvalidInput("feature '" + feature_names_[diff.front()] + "' lies in seed patch " + node.name + " of " +
                       (std::binary_search(a.begin(), a.end(), diff.front()) ? meshes_[0].name() : meshes_[i].name()) +
                       " but not of " +
                       (std::binary_search(a.begin(), a.end(), diff.front()) ? meshes_[i].name() : meshes_[0].name()) +
                       ": the seed loop s0-s1-s2-s3 separates the features differently on the two meshes; "
                       "place the seeds so that each feature is on the same side of the loop in every mesh");
  }
  tn.features = static_cast<int>(ps[0].features.size());
  if (meshes_.size() > 1 && !ps[0].features.empty()) align(nodes, ps, tn);
  tn.stretch = 0;
  tn.mesh_stretch.clear();
  for (const auto& p : ps) {
    tn.mesh_stretch.push_back(p.st.patch);
    tn.stretch = std::max(tn.stretch, p.st.patch);
  }
  return ps;
}

void SetDissector::fit_poses(const std::vector<SeedLoop>& loops) {
  const size_t nm = meshes_.size();
  pose_.assign(nm, registration::Pose());
  pose_diagonal_.assign(nm, 0.0);
  pose_diagonal_[0] = bounding_box(in_[0].mesh->positions).diagonal();
  const std::vector<Vec3> from = meshes_[0].landmark_points(loops[0].seeds);
  for (size_t i = 1; i < nm; ++i) {
    pose_[i] = i < opt_.pose_registrations.size() && opt_.pose_registrations[i].registered()
                   ? opt_.pose_registrations[i]
                   : registration::Pose(fit_similarity(from, meshes_[i].landmark_points(loops[i].seeds)));
    pose_diagonal_[i] = bounding_box(in_[i].mesh->positions).diagonal();
  }
}

std::array<std::vector<Vec3>, 4> SetDissector::in_pose(size_t i, const std::array<std::vector<Vec3>, 4>& curves) const {
  std::array<std::vector<Vec3>, 4> moved;
  for (int k = 0; k < 4; ++k)
    for (const Vec3& x : curves[k]) moved[k].push_back(pose_[i].forward(x));
  return moved;
}

std::optional<SeedLoop> SetDissector::pose_loop(size_t i, const SeedLoop& own, const std::vector<int>& want,
                                                const std::array<std::vector<Vec3>, 4>& guide) const {
  const std::array<std::vector<Vec3>, 4> moved = in_pose(i, guide);
  const TriMesh mi = meshes_[i].trimesh();
  try {
    SeedLoop guided =
        trace_guided_loop(mi, own.seeds, moved, kPoseLoopSigma * pose_diagonal_[i], meshes_[i].feature_vertices());
    // A feature next to mesh 0's loop can fall on the other side of the guided one (a limb turned
    // about its axis, which the pose does not see): the nearest path is routed around it.
    if (sides_of_vertices(mi, guided, meshes_[i].feature_vertices()) != want)
      guided = meshes_[i].reroute_loop(guided, want, {});
    return guided;
  } catch (const InvalidInput&) {
    return std::nullopt;
  }
}

namespace {

// The mean distance between two sets of four curves (3D polylines, curve k against curve k),
// both ways: how far one seed loop runs from another.
double curves_apart(const std::array<std::vector<Vec3>, 4>& a, const std::array<std::vector<Vec3>, 4>& b) {
  double sum = 0;
  int n = 0;
  for (int k = 0; k < 4; ++k) {
    if (a[k].empty() || b[k].empty()) return std::numeric_limits<double>::infinity();
    for (const Vec3& p : a[k]) sum += polyline_distance(p, b[k]), ++n;
    for (const Vec3& p : b[k]) sum += polyline_distance(p, a[k]), ++n;
  }
  return sum / n;
}

}  // namespace

void SetDissector::seed_posed(std::vector<SeedLoop>& loops, std::array<std::vector<Node>, 2>& roots,
                              DissectionSet& out) {
  const size_t nm = meshes_.size();
  fit_poses(loops);
  // Through a registration the leaves' maps are taken over too (run()): their Params are kept.
  bool registered = false;
  for (size_t i = 1; i < nm; ++i) registered = registered || pose_[i].registered();
  if (opt_.same_pose_maps && registered)
    for (size_t i = 0; i < nm; ++i)
      if (i == 0 || pose_[i].registered()) meshes_[i].keep_leaf_params();
  const std::vector<int> want = meshes_[0].feature_sides(loops[0]);
  // Mesh 0's loop as traced (edge paths), then as cut into it (geodesics, by default).
  std::array<std::vector<Vec3>, 4> traced;
  for (int k = 0; k < 4; ++k)
    for (int v : loops[0].paths[k]) traced[k].push_back(meshes_[0].positions()[v]);
  const auto r = meshes_[0].seed(std::move(loops[0]));
  for (int k = 0; k < 2; ++k) roots[k].push_back(r[k]);
  ctx_.report("seed loops", 1.0 / static_cast<double>(nm));
  const std::array<std::vector<Vec3>, 4>& cut = meshes_[0].seed_curves();
  // Mesh i's candidates: its loop routed along mesh 0's traced paths and along its cut curves,
  // each straightened on mesh i as the options ask, and (with geodesic curves) the latter kept as
  // routed. Each mesh straightens its own loop, and two nearby edge paths can straighten into
  // curves far apart (the cow against its re-tessellation: 0.84% of the diagonal apart on
  // average, 7% at most, from paths 0.26% apart); the candidate whose curves lie nearest mesh 0's
  // is kept. None routes: the mesh's own loop. The two guides of each mesh are routed and
  // straightened in parallel (tasks mesh-major, traced first); the choice goes through the
  // candidates in that order and keeps the first of equal distances.
  struct Choice {
    SeedLoop loop;
    std::optional<GeodesicLoop> straightened;
    double distance = std::numeric_limits<double>::infinity();
  };
  const std::array<const std::array<std::vector<Vec3>, 4>*, 2> guides{&traced, &cut};
  std::vector<std::array<std::vector<Vec3>, 4>> reference(nm);  // mesh 0's cut curves in mesh i's pose
  for (size_t i = 1; i < nm; ++i) reference[i] = in_pose(i, cut);
  std::vector<std::vector<Choice>> candidates(2 * (nm - 1));
  parallel_for(
      candidates.size(), ctx_,
      [&](size_t task) {
        const size_t i = task / 2 + 1, g = task % 2;
        if (g == 1 && !opt_.geodesic_seed_curves) return;  // edge paths: traced and cut are the same curves
        std::optional<SeedLoop> loop = pose_loop(i, loops[i], want, *guides[g]);
        if (!loop) return;
        auto add = [&](SeedLoop l, std::optional<GeodesicLoop> gl) {
          std::array<std::vector<Vec3>, 4> curves;
          const bool straight = gl && gl->any_straightened();
          for (int c = 0; c < 4; ++c)
            for (int v : straight ? gl->loop.paths[c] : l.paths[c])
              curves[c].push_back(straight ? gl->mesh.positions[v] : meshes_[i].positions()[v]);
          const double d = curves_apart(curves, reference[i]);
          candidates[task].push_back(Choice{std::move(l), std::move(gl), d});
        };
        if (!opt_.geodesic_seed_curves) {
          add(std::move(*loop), std::nullopt);
          return;
        }
        add(*loop, meshes_[i].straighten(*loop));
        if (g == 1) add(std::move(*loop), GeodesicLoop{});  // routed along the geodesics, kept
      });
  std::vector<std::optional<Choice>> chosen(nm);
  for (size_t task = 0; task < candidates.size(); ++task)
    for (Choice& c : candidates[task]) {
      auto& best = chosen[task / 2 + 1];
      if (!best || c.distance < best->distance) best = std::move(c);
    }
  for (size_t i = 1; i < nm; ++i)
    if (!chosen[i] && own_loops_failure_) throw *own_loops_failure_;
  for (size_t i = 1; i < nm; ++i) {
    out.same_pose_loops += chosen[i].has_value();
    const auto ri = chosen[i] ? meshes_[i].seed(std::move(chosen[i]->loop), std::move(chosen[i]->straightened))
                              : meshes_[i].seed(std::move(loops[i]));
    for (int k = 0; k < 2; ++k) roots[k].push_back(ri[k]);
    ctx_.report("seed loops", static_cast<double>(i + 1) / static_cast<double>(nm));
  }
}

std::vector<std::array<Vec2, 4>> SetDissector::posed_corners(const std::vector<Param>& ps, const Vec2& peak,
                                                            double w) const {
  const size_t nm = ps.size();
  const std::array<Vec2, 4> common = inner_corners(peak, w);
  std::vector<std::array<Vec2, 4>> out(nm, common);
  // Mesh 0's inner corners on its surface: the point of its node at that (u, v).
  const param::PatchMesh& pm0 = ps[0].ex.pm;
  const std::vector<Vec2>& uv0 = ps[0].sp.uv;
  std::array<Vec3, 4> x0, n0;  // mesh 0's corner points and the normals of their faces
  for (int c = 0; c < 4; ++c) {
    const auto [f, bary] = best_uv_face(common[c], pm0.faces.size(), [&](size_t k) {
      const Tri& t = pm0.faces[k];
      return std::array<Vec2, 3>{uv0[t[0]], uv0[t[1]], uv0[t[2]]};
    });
    if (f < 0) return out;
    const Tri& t = pm0.faces[f];
    const Vec3 l = bary.cwiseMax(0.0) / bary.cwiseMax(0.0).sum();
    x0[c] = l[0] * pm0.positions[t[0]] + l[1] * pm0.positions[t[1]] + l[2] * pm0.positions[t[2]];
    n0[c] = (pm0.positions[t[1]] - pm0.positions[t[0]]).cross(pm0.positions[t[2]] - pm0.positions[t[0]]).normalized();
  }
  for (size_t i = 1; i < nm; ++i) {
    // Mesh i's point nearest to mesh 0's corner moved by the landmarks' similarity, within its
    // node; its (u, v) by mesh i's map.
    const param::PatchMesh& pm = ps[i].ex.pm;
    const std::vector<Vec2>& uv = ps[i].sp.uv;
    // A map folded here and there (a face by a feature the alignment moved) still places the
    // corners by its other faces; a split that its folds spoil (cuts that cross) falls back to the
    // common (u, v) as any failed posed split does.
    if (!opt_.same_pose_folded_maps && !ps[i].sp.bijective()) continue;
    std::array<Vec2, 4> posed;
    std::vector<Vec3> normal(pm.faces.size());  // unnormalized: the test below scales by the length
    for (size_t k = 0; k < pm.faces.size(); ++k) {
      const Tri& t = pm.faces[k];
      normal[k] = (pm.positions[t[1]] - pm.positions[t[0]]).cross(pm.positions[t[2]] - pm.positions[t[0]]);
    }
    bool near = true;
    for (int c = 0; c < 4 && near; ++c) {
      const auto [target, turned] = pose_[i].forward(x0[c], n0[c]);
      const Vec3 facing = turned.normalized();
      double best = INFINITY;
      for (size_t k = 0; k < pm.faces.size(); ++k) {
        const Tri& t = pm.faces[k];
        // Only faces that face as mesh 0's does (kSamePoseFacingCos): not the next finger's back.
        if (!(normal[k].dot(facing) >= kSamePoseFacingCos * normal[k].norm())) continue;
        const auto l = landmarks::closest_on_triangle(target, pm.positions[t[0]], pm.positions[t[1]], pm.positions[t[2]]);
        const Vec3 x = l[0] * pm.positions[t[0]] + l[1] * pm.positions[t[1]] + l[2] * pm.positions[t[2]];
        const double d = (x - target).squaredNorm();
        if (d < best) {
          best = d;
          posed[c] = l[0] * uv[t[0]] + l[1] * uv[t[1]] + l[2] * uv[t[2]];
        }
      }
      near = std::sqrt(best) <= kSamePoseReach * pose_diagonal_[i];
    }
    if (!near) continue;
    // As far toward the posed corners as still makes a split (a posed corner on the node's
    // border, where the nodes of the two meshes differ, or a quad folded by a squeezed map) and
    // keeps the features clear of the cuts, as the common split keeps them (feature_cut_margin).
    std::vector<Vec2> fuv;
    for (const auto& [k, local] : ps[i].features) fuv.push_back(uv[local]);
    for (const double t : {1.0, 0.75, 0.5, 0.25}) {
      std::array<Vec2, 4> q;
      for (int c = 0; c < 4; ++c) q[c] = (1 - t) * common[c] + t * posed[c];
      if (inner_quad_ok(q, kSamePoseMargin) && feature_clearance(fuv, q) >= opt_.feature_cut_margin) {
        out[i] = q;
        break;
      }
    }
  }
  return out;
}

int SetDissector::route_intrinsic(std::vector<SeedLoop>& loops, std::vector<double>& discrepancy) const {
  const size_t nm = meshes_.size();
  // The landmarks every mesh has: the four seeds, then the features present in all meshes.
  std::vector<size_t> common;
  for (size_t k = 0; k < feature_names_.size(); ++k) {
    bool all = true;
    for (size_t i = 0; i < nm && all; ++i) all = meshes_[i].feature_vertices()[k] >= 0;
    if (all) common.push_back(k);
  }
  auto landmarks = [&](size_t i) {
    std::vector<int> l(loops[i].seeds.begin(), loops[i].seeds.end());
    for (size_t k : common) l.push_back(meshes_[i].feature_vertices()[k]);
    return l;
  };
  const TriMesh m0 = meshes_[0].trimesh();
  const std::vector<int> l0 = landmarks(0);
  const GeodesicCoordinates c0 = geodesic_coordinates(m0, l0, ctx_);
  const auto reference = loop_coordinates(c0, loops[0]);
  const std::vector<int> want = meshes_[0].feature_sides(loops[0]);
  std::vector<char> routed(nm, 0);
  discrepancy.assign(nm, 0.0);
  parallel_for(static_cast<int>(nm) - 1, ctx_, [&](int t) {
    const size_t i = static_cast<size_t>(t) + 1;
    const TriMesh mi = meshes_[i].trimesh();
    const std::vector<int> li = landmarks(i);
    const GeodesicCoordinates ci = geodesic_coordinates(mi, li, ctx_);
    // Geodesic coordinates correspond only between near-isometric surfaces (one shape in two
    // poses); other shapes keep their own shortest loops.
    discrepancy[i] = landmark_discrepancy(c0, l0, ci, li);
    if (!(discrepancy[i] <= kIntrinsicLoopIsometry)) return;
    try {
      SeedLoop l = trace_intrinsic_loop(mi, loops[i].seeds, ci, reference, kIntrinsicLoopSigma,
                                        meshes_[i].feature_vertices());
      // A feature next to the first mesh's loop may fall on the other side of this one: the loop
      // is routed around it there (reroute_loop), the rest still follows the first mesh's.
      if (meshes_[i].feature_sides(l) != want) l = meshes_[i].reroute_loop(l, want);
      if (meshes_[i].feature_sides(l) != want) return;
      loops[i] = std::move(l);
      routed[i] = 1;
    } catch (const InvalidInput&) {
      // the mesh keeps its own loop
    }
  });
  return static_cast<int>(std::count(routed.begin(), routed.end(), 1));
}

DissectionSet SetDissector::run() {
  ctx_.report("seed loops", 0.0);
  const size_t nm = meshes_.size();
  // The shortest loop of every mesh (in parallel: the meshes are independent here).
  std::vector<SeedLoop> loops(nm);
  parallel_for(nm, ctx_, [&](size_t i) {
    if (meshes_[i].inserted_seeds || in_[i].seeds) {
      loops[i] = meshes_[i].trace_loop(meshes_[i].inserted_seeds ? *meshes_[i].inserted_seeds : *in_[i].seeds);
      return;
    }
    routing::Graph g;  // the automatic seeds' graph of the input, routed on again
    const std::array<int, 4> s = routing::choose_seeds(*in_[i].mesh, ctx_, g);
    loops[i] = meshes_[i].trace_loop(s, &g);
  });
  // Consistent loops: every feature on the same side in every mesh. The side each feature takes
  // in most meshes (ties: the first mesh's) is required of all; a mesh whose shortest loop puts a
  // feature on the other side is routed again around it. When some mesh cannot be, the meshes'
  // own arrangements are tried in turn (most common first): a feature near a seed may fit only one.
  if (nm > 1 && !feature_names_.empty()) {
    std::vector<std::vector<int>> sides(nm);
    parallel_for(nm, ctx_, [&](size_t i) { sides[i] = meshes_[i].feature_sides(loops[i]); });
    const size_t nf = feature_names_.size();
    std::vector<int> majority(nf);
    for (size_t k = 0; k < nf; ++k) {
      size_t zeros = 0;
      for (size_t i = 0; i < nm; ++i) zeros += sides[i][k] == 0;
      majority[k] = 2 * zeros > nm ? 0 : 2 * zeros < nm ? 1 : sides[0][k];
    }
    std::vector<std::vector<int>> candidates{majority};
    std::vector<std::vector<int>> own = sides;  // the meshes' arrangements, most common first
    std::stable_sort(own.begin(), own.end(), [&](const auto& a, const auto& b) {
      return std::count(sides.begin(), sides.end(), a) > std::count(sides.begin(), sides.end(), b);
    });
    for (const auto& a : own)
      if (std::find(candidates.begin(), candidates.end(), a) == candidates.end()) candidates.push_back(a);
    std::optional<InvalidInput> first_failure;
    for (const std::vector<int>& want : candidates) {
      std::vector<SeedLoop> routed = loops;
      std::vector<std::string> failure(nm);
      parallel_for(nm, ctx_, [&](size_t i) {
        if (sides[i] == want) return;
        try {
          routed[i] = meshes_[i].reroute_loop(loops[i], want);
        } catch (const InvalidInput& e) {
          failure[i] = e.what();
        }
      });
      const auto bad = std::find_if(failure.begin(), failure.end(), [](const std::string& f) { return !f.empty(); });
      if (bad == failure.end()) {
        loops = std::move(routed);
        first_failure.reset();
        break;
      }
      if (first_failure) continue;
      const size_t i = static_cast<size_t>(bad - failure.begin());
      std::string names;
      for (size_t k = 0; k < nf; ++k)
        if (sides[i][k] != want[k]) names += (names.empty() ? "'" : ", '") + feature_names_[k] + "'";
      first_failure = InvalidInput(meshes_[i].name() + ": feature " + names +
                                   " lies on the other side of the seed loop s0-s1-s2-s3 than in most meshes of the set, "
                                   "and no loop through its seeds puts it on the same side (" + *bad +
                                   "); move the seeds so that each feature is on the same side of the loop in every mesh");
    }
    // In one pose the loops follow mesh 0's (seed_posed), each with the features on mesh 0's sides;
    // the own loops are only the fallback there.
    if (first_failure && opt_.same_pose) own_loops_failure_ = std::move(first_failure);
    else if (first_failure) throw *first_failure;
  }
  DissectionSet out;
  if (nm > 1 && !opt_.same_pose && opt_.intrinsic_loops)
    out.intrinsic_loops = route_intrinsic(loops, out.landmark_discrepancy);
  joint_weights_ = joint_weights(out.landmark_discrepancy);
  one_tessellation_ = true;
  for (size_t i = 1; i < joint_weights_.size(); ++i)
    if (joint_weights_[i]) one_tessellation_ = one_tessellation_ && in_[i].mesh->faces == in_[0].mesh->faces;
  std::vector<std::optional<GeodesicLoop>> straightened(nm);
  if (opt_.replace_seed_loops) {
    std::vector<GeodesicLoop> g(nm);
    for (size_t i = 0; i < nm; ++i) {
      if (opt_.geodesic_seed_curves) {
        g[i] = meshes_[i].straighten(loops[i]);
      } else {
        g[i].mesh = meshes_[i].trimesh();
        g[i].loop = loops[i];
      }
    }
    opt_.replace_seed_loops(g);
    for (auto& gi : g) {  // the hook may have changed the loops
      gi.face_patches.clear();
      gi.cut.reset();
    }
    for (size_t i = 0; i < nm; ++i) {
      loops[i] = g[i].loop;
      if (opt_.geodesic_seed_curves) straightened[i] = std::move(g[i]);
    }
  }
  std::array<std::vector<Node>, 2> roots;  // the same names, labels and corner roles in every mesh
  if (opt_.same_pose && nm > 1) {
    seed_posed(loops, roots, out);
  } else {
    for (size_t i = 0; i < nm; ++i) {
      const auto r = meshes_[i].seed(std::move(loops[i]), std::move(straightened[i]));
      for (int k = 0; k < 2; ++k) roots[k].push_back(r[k]);
      ctx_.report("seed loops", static_cast<double>(i + 1) / static_cast<double>(nm));
    }
  }
  std::map<std::string, std::vector<int>> refined_faces;  // node name -> faces added per mesh
  std::vector<size_t> refined_total(nm, 0);                // faces added per mesh
  std::deque<std::vector<Node>> queue(roots.begin(), roots.end());
  ctx_.report("quinary subdivision", 0.0);  // the roots' maps and splits are this stage's
  // Progress: the share of the surface area in finished leaves (cuts add faces, not area).
  double total_area = 0, done_area = 0;
  std::vector<double> max_area;   // per mesh: opt_.max_patch_area times its surface area
  std::vector<double> mesh_area;  // per mesh: its surface area
  for (const auto& m : in_) {
    const double area = surface_area(*m.mesh);
    total_area += area;
    max_area.push_back(opt_.max_patch_area > 0 ? opt_.max_patch_area * area : INFINITY);
    mesh_area.push_back(area);
  }
  while (!queue.empty()) {
    ctx_.check_cancel();
    const std::vector<Node> nodes = queue.front();
    queue.pop_front();
    const Node& node = nodes[0];
    TreeNode tn;
    tn.name = node.name;
    tn.depth = node.depth;
    std::vector<Param> ps = evaluate(nodes, tn);
    // A long protrusion shrinks exponentially under a Floater map, down to UV triangles of zero
    // area in floating point: such a patch is over tau whatever its RMS stretch, and splitting
    // it around its peak is exactly the cure. Only a leaf must be bijective.
    std::vector<bool> over(ps.size());
    bool any_over = false;
    int biggest_over = 0;
    for (size_t i = 0; i < ps.size(); ++i) {
      over[i] = ps[i].st.patch > opt_.tau || !ps[i].sp.bijective() || ps[i].st.area3d > max_area[i];
      if (over[i]) {
        any_over = true;
        biggest_over = std::max(biggest_over, static_cast<int>(ps[i].ex.faces.size()));
      }
    }
    // No progress: a bijective patch at least as stretched as its parent in every mesh that is
    // over (a corner whose 3D angle the square cannot take: every split hands it to a smaller
    // child, whose stretch only grows). Splitting again would not help; the leaf is repaired
    // instead. A strongly stretched parent (over 2 tau: a protrusion) gets one more generation
    // when it had improved on its own parent, since the first split of a protrusion can raise
    // the stretch of the child that holds its tip.
    bool progress = false;
    for (size_t i = 0; i < ps.size() && !progress; ++i) {
      const double parent = nodes[i].parent_stretch, grandparent = nodes[i].grandparent_stretch;
      progress = over[i] && (!ps[i].sp.bijective() || ps[i].st.area3d > max_area[i] || ps[i].st.patch < parent ||
                             (parent > 2 * opt_.tau && parent < grandparent));
    }
    // Small patches: a node over tau only by its stretch (bijective in every mesh, under the area
    // cap) in every mesh that is over, holding less than min_split_area of that mesh's surface,
    // is not split; the leaf repair takes it. Along limbs whose tips are patch corners (seeds at
    // finger and toe tips) these are lengthwise strips, and a quinary split, whose children each
    // keep a whole side of the parent, only shaves thinner strips off them.
    bool small = any_over && opt_.min_split_area > 0;
    for (size_t i = 0; i < ps.size() && small; ++i)
      if (over[i])
        small = ps[i].sp.bijective() && ps[i].st.area3d <= max_area[i] &&
                ps[i].st.area3d < opt_.min_split_area * mesh_area[i];
    // Large patches: a node that made no progress but holds at least force_split_area of a mesh
    // whose patch is still over tau after the leaf repair is split all the same (a large
    // over-tau leaf is what a user sees; its children usually do better than the no-progress
    // rule predicts).
    if (any_over && !progress && !small && opt_.force_split_area > 0 && node.depth < opt_.max_depth &&
        biggest_over >= opt_.min_faces_to_split) {
      std::vector<char> force(ps.size(), 0);
      Context quiet = ctx_.without_progress();
      quiet.log = nullptr;
      parallel_for(ps.size(), ctx_, [&](size_t i) {
        if (!over[i] || !ps[i].sp.bijective() || ps[i].st.area3d < opt_.force_split_area * mesh_area[i]) return;
        const param::SquareParam m = minimized_leaf(ps[i], std::max(opt_.stretch_iterations, kRepairRounds), quiet);
        const double repaired =
            m.uv.empty() ? ps[i].st.patch : param::l2_stretch(ps[i].ex.pm.positions, ps[i].ex.pm.faces, m.uv).patch;
        force[i] = repaired > opt_.tau;
      });
      progress = std::find(force.begin(), force.end(), 1) != force.end();
    }
    // Folds outrank the depth bound for a squeezed protrusion tip (see squeezed_tip): such a node
    // is split up to kFoldExtraDepth levels past max_depth instead of being refined. A feature
    // deep in a long protrusion with no seed at its tip (a tail tip) stays in the centre child of
    // every split, squeezed by the mean-value map, and a warp that moves it to its counterparts'
    // position folds the rings around it; each split cuts the protrusion across a little closer
    // to the tip, until the feature's patch is small enough to align and untangle. Below the
    // extra levels a folded node keeps splitting (it exists only for its folds); at the last
    // one, local refinement is the last resort as everywhere else.
    bool folded = false;
    for (const auto& p : ps) folded = folded || !p.sp.bijective();
    // Large over-tau patches outrank the depth bound too (area_extra_depth): a patch over tau (by its
    // stretch, or folded) that holds at least force_split_area of its mesh's surface may be split
    // up to area_extra_depth levels past max_depth. With seeds on a belt around a body, each limb
    // is a protrusion of a seed patch that every split hands to its centre child, one level deeper.
    bool large_over = false;
    for (size_t i = 0; i < ps.size() && opt_.force_split_area > 0 && opt_.area_extra_depth > 0; ++i)
      large_over = large_over || (over[i] && (ps[i].st.patch > opt_.tau || !ps[i].sp.bijective()) &&
                                  ps[i].st.area3d >= opt_.force_split_area * mesh_area[i]);
    const int depth_limit =
        opt_.max_depth + (folded && (node.depth > opt_.max_depth || squeezed_tip(ps)) ? kFoldExtraDepth : 0) +
        (large_over ? opt_.area_extra_depth : 0);
    StopReason stop = StopReason::None;
    std::string detail;
    if (small) {
      stop = StopReason::SmallArea;
    } else if (any_over && !progress) {
      stop = StopReason::NoProgress;
    } else if (any_over && node.depth < depth_limit && biggest_over >= opt_.min_faces_to_split) {
      const size_t first_new_label = meshes_[0].labels();
      const auto [peak, w] = choose_split(node, ps, tn, over);
      // DissectOptions::refine_before_split (the pipeline's default): the split points are taken at equal
      // (u, v) in every mesh, so each mesh's map of the node is refined against mesh 0's before
      // the cuts (border, corners and features held). The split (peak, w) and the children's
      // parent stretch stay those of the dissection's own maps, so only where the cuts run on
      // each surface changes. A refined map is bijective (the refiner keeps only positive uv
      // faces, checked again here).
      size_t node_faces = 0;
      for (const auto& p : ps) node_faces += p.ex.faces.size();
      // The refined map is kept only when it does not raise the children's predicted stretch
      // above tau and its own map's (a cut that would leave a thin strip of a child on the surface:
      // the example set's slivers). Skipped in one pose, where the maps are taken over below.
      if (opt_.refine_before_split && nm > 1 && !(opt_.same_pose && opt_.same_pose_maps)) {
        std::vector<char> refined(nm, 0);
        parallel_for(nm - 1, node_faces >= kParallelFaces ? 0 : 1, ctx_, [&](size_t k) {
          Param& p = ps[k + 1];
          if (!p.sp.bijective() || !ps[0].sp.bijective()) return;
          const double own_children = predicted_children_stretch(p, peak, w);
          param::SquareParam own = p.sp;
          const bool changed = opt_.refine_before_split(ps[0].ex.pm, ps[0].sp.uv, p.ex.pm, p.sp.uv, feature_mask(p));
          if (changed) param::count_uv_faces(p.ex.pm.faces, p.sp);
          if (!changed || !p.sp.bijective() || predicted_children_stretch(p, peak, w) > std::max(opt_.tau, own_children)) {
            p.sp = std::move(own);
            return;
          }
          refined[k + 1] = 1;
        });
        for (size_t i = 1; i < nm; ++i) ++(refined[i] ? out.before_split_refined : out.before_split_own);
      }
      // DissectOptions::same_pose_maps: every mesh's map of the node taken over from mesh 0's, also
      // where mesh 0's folds (a leg squeezed to zero uv area): the split cuts every mesh at equal
      // (u, v), so the others must follow mesh 0's map as it is (a camel against its
      // re-tessellation: a hoof in another leg's patch, 31% of the diagonal). In another pose,
      // where no bijective map follows it, the nearest points' (u, v) as they are, folded, still
      // cut where mesh 0 is cut (see transfer_node_map).
      if (opt_.same_pose && opt_.same_pose_maps && nm > 1) {
        const TriMesh ref_mesh{ps[0].ex.pm.positions, ps[0].ex.pm.faces};
        const metro::SurfaceDistance on_ref(ref_mesh, "the first mesh's node", thread_count(0, ctx_));
        std::vector<Transfer> taken(nm, Transfer::Own);
        Context quiet = ctx_.without_progress();
        quiet.log = nullptr;
        // Also where mesh i's own map of the node folds.
        parallel_for(nm - 1, node_faces >= kParallelFaces ? 0 : 1, ctx_, [&](size_t k) {
          Param& p = ps[k + 1];
          taken[k + 1] = transfer_node_map(ps[0], on_ref, pose_[k + 1], kSamePoseReach * pose_diagonal_[0],
                                           opt_.same_pose_untangle, quiet, p);
        });
        for (size_t i = 1; i < nm; ++i) {
          ++(taken[i] == Transfer::Own ? out.same_pose_own_maps : out.same_pose_maps);
          out.same_pose_folded_taken += taken[i] == Transfer::Folded;
          out.same_pose_polished += taken[i] == Transfer::Polished;
          out.same_pose_untangled += taken[i] == Transfer::Untangled;
        }
      }
      replace_node_maps(opt_, ps, true);
      std::vector<std::array<Node, 5>> kids(meshes_.size());
      // DissectOptions::same_pose: every mesh's inner corners where mesh 0's lie on its surface;
      // when that fails (no such quad, or the split fails with it), the common (u, v) after all.
      std::vector<std::array<Vec2, 4>> posed;
      if (opt_.same_pose && nm > 1) {
        posed = posed_corners(ps, peak, w);
        bool moved = false;
        for (size_t i = 1; i < nm; ++i) moved = moved || posed[i] != posed[0];
        if (!moved) {
          posed.clear();
          ++out.same_pose_common;
        }
      }
      Vec2 common_peak = peak;
      double common_w = w;
      auto split_all = [&](bool use_posed, double snap) {
        parallel_for(meshes_.size(), node_faces >= kParallelFaces ? 0 : 1, ctx_, [&](size_t i) {
          try {
            kids[i] = use_posed ? meshes_[i].split(nodes[i], ps[i], posed[i], snap)
                                : meshes_[i].split(nodes[i], ps[i], common_peak, common_w, snap);
          } catch (const SplitFailure& e) {
            throw SplitFailure(meshes_.size() > 1 ? meshes_[i].name() + ": " + e.what() : std::string(e.what()));
          }
        });
        // Counterparts must land in the same child. They do when every mesh's map is bijective
        // (the cuts are the same segments of the aligned domain); a folded map can break that.
        for (const auto& [k, local] : ps[0].features)
          for (size_t i = 1; i < meshes_.size(); ++i)
            if (meshes_[i].feature_label(k) != meshes_[0].feature_label(k))
              throw SplitFailure("feature '" + feature_names_[k] + "' would land in different children (a folded map)");
      };
      // After a failed attempt (which cut the meshes: new vertices), the node is put back and
      // parameterized again.
      auto start_over = [&]() {
        for (size_t i = 0; i < meshes_.size(); ++i) meshes_[i].restore(nodes[i], first_new_label);
        tn = TreeNode{};
        tn.name = node.name;
        tn.depth = node.depth;
        ps = evaluate(nodes, tn);
      };
      try {
        bool done = false;
        if (!posed.empty()) {
          try {
            split_all(true, kSplitSnap);
            done = true;
            tn.posed = true;
            ++out.same_pose_splits;
          } catch (const SplitFailure&) {
            start_over();
            ++out.same_pose_common;
            std::tie(common_peak, common_w) = choose_split(node, ps, tn, over);
          }
        }
        if (!done) {
          try {
            split_all(false, kSplitSnap);
          } catch (const SplitFailure&) {
            // Cuts that crossed where they passed through vertices near them: once more, with
            // (almost) no such detours.
            start_over();
            std::tie(common_peak, common_w) = choose_split(node, ps, tn, over);
            split_all(false, kSplitRetrySnap);
            ++out.retried_splits;
          }
        }
      } catch (const SplitFailure& e) {
        start_over();
        stop = StopReason::SplitFailed;
        detail = e.what();
      }
      if (stop == StopReason::None) {
        for (size_t i = 0; i < meshes_.size(); ++i) {
          meshes_[i].commit_split(nodes[i]);
          for (int k = 0; k < 5; ++k)
            if (kids[i][k].label != kids[0][k].label) throw InternalError("tree labels differ across the set");
        }
        tn.split = true;
        if (auto it = refined_faces.find(node.name); it != refined_faces.end()) tn.refined_faces = it->second;
        out.tree.push_back(tn);
        for (int k = 0; k < 5; ++k) {
          std::vector<Node> child;
          for (size_t i = 0; i < kids.size(); ++i) {
            child.push_back(kids[i][k]);
            child.back().parent_stretch = ps[i].st.patch;
            child.back().grandparent_stretch = nodes[i].parent_stretch;
          }
          queue.push_back(std::move(child));
        }
        continue;
      }
    } else if (any_over) {
      stop = node.depth >= depth_limit ? StopReason::MaxDepth : StopReason::TooFewFaces;
    }
    // No dead ends: a leaf whose map would stay folded in some mesh even after the repair that
    // finish() tries has the region of its folds refined there (edges split at their midpoints:
    // the surface is unchanged, only its sampling), and a node whose split failed has its whole
    // patch refined (at most kRefineFaces faces); then the node is evaluated again. Finer faces
    // follow the alignment warp more closely, give the repair room, and let a split through.
    // At most max(2 F, 20000) faces are added to a mesh of F input faces.
    if (auto it = refined_faces.find(node.name); it != refined_faces.end()) tn.refined_faces = it->second;
    if (node.refinements < kMaxRefinements) {
      enum Mode : char { kNone, kFolds, kWhole };
      std::vector<char> mode(nm, kNone);
      Context quiet = ctx_.without_progress();
      quiet.log = nullptr;
      parallel_for(nm, ctx_, [&](size_t i) {
        const size_t faces = ps[i].ex.faces.size();
        const size_t budget = std::max<size_t>(2 * in_[i].mesh->faces.size(), 20000);
        if (refined_total[i] >= budget) return;
        if (!ps[i].sp.bijective()) {
          // Local folds only: a map folded over much of its patch (a degenerate fan, say) is not
          // a sampling problem.
          const size_t folded = static_cast<size_t>(ps[i].sp.flipped_faces + ps[i].sp.zero_area_faces);
          if (folded <= std::max<size_t>(50, faces / 20) &&
              minimized_leaf(ps[i], std::max(opt_.stretch_iterations, kRepairRounds), quiet).uv.empty())
            mode[i] = kFolds;
        } else if (stop == StopReason::SplitFailed && faces <= kRefineFaces && refined_total[i] + 3 * faces <= budget) {
          mode[i] = kWhole;
        }
      });
      if (std::find_if(mode.begin(), mode.end(), [](char m) { return m != kNone; }) != mode.end()) {
        std::vector<int>& added = refined_faces[node.name];
        added.resize(nm, 0);
        std::vector<Node> again = nodes;
        for (size_t i = 0; i < nm; ++i) {
          if (mode[i] != kNone) {
            const int n = meshes_[i].refine(nodes[i], mode[i] == kFolds ? &ps[i] : nullptr);
            added[i] += n;
            refined_total[i] += static_cast<size_t>(n);
          }
          ++again[i].refinements;
        }
        queue.push_front(std::move(again));
        continue;
      }
    }
    out.tree.push_back(tn);
    for (size_t i = 0; i < meshes_.size(); ++i) {
      PatchInfo info;
      const bool over_i = ps[i].st.patch > opt_.tau || !ps[i].sp.bijective();
      if (over_i) {
        info.stop = stop;
        info.stop_detail = detail;
      }
      meshes_[i].keep_leaf(nodes[i], ps[i], info);
      done_area += ps[i].st.area3d;
    }
    ctx_.report("quinary subdivision", std::min(1.0, done_area / std::max(total_area, 1e-300)));
  }
  std::stable_sort(out.tree.begin(), out.tree.end(), [](const TreeNode& a, const TreeNode& b) {
    return a.depth != b.depth ? a.depth < b.depth : a.name < b.name;
  });
  for (size_t i = 0; i < meshes_.size(); ++i) {
    MeshDissector& m = meshes_[i];
    ctx_.report("leaf repairs", static_cast<double>(out.meshes.size()) / static_cast<double>(meshes_.size()));
    // Through a registration, each leaf's map follows the first mesh's (as repaired in its
    // finish()), as the node maps did before every split: each mesh's own stretch-minimized map of
    // a squeezed leaf (a camel's tail) runs its own way inside the leaf.
    if (i > 0 && opt_.same_pose && opt_.same_pose_maps && pose_[i].registered()) {
      out.same_pose_leaves += m.take_over_leaves(meshes_[0], pose_[i], kSamePoseReach * pose_diagonal_[0],
                                                 opt_.same_pose_untangle);
    }
    out.meshes.push_back(m.finish(out.tree));
    out.max_stretch = std::max(out.max_stretch, out.meshes.back().max_stretch);
    for (size_t k = 0; k < feature_names_.size(); ++k) out.meshes.back().features[k].name = feature_names_[k];
  }
  for (const auto& n : out.tree) out.warp_events += n.warp_events;
  return out;
}

}  // namespace qs::dissect::detail
