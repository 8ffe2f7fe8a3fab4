// The dissection state of one mesh of a set: its cut mesh, the faces of every tree node, its leaves
// and their maps (paper 3.2). The set driver asks it to parameterize, split, restore or keep nodes.

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>
#include "qs/dissect/geodesic_loop.h"
#include "qs/dissect/seed_loop.h"
#include "qs/dissect/seed_routing_detail.h"
#include "qs/warp/warp.h"

#include "qs/core/error.h"
#include "qs/dissect/dissect_detail.h"

namespace qs::dissect::detail {

Extracted MeshDissector::extract(const Node& node) {
  Extracted ex;
  std::vector<int>& faces = patch_faces_[node.label];
  std::sort(faces.begin(), faces.end());
  ex.faces = faces;
  ex.pm.faces.reserve(faces.size());
  for (int f : faces) {
    Tri lt;
    for (int k = 0; k < 3; ++k) {
      const int v = cm_.face(f)[k];
      if (local_of_[v] < 0) {
        local_of_[v] = static_cast<int>(ex.verts.size());
        ex.verts.push_back(v);
        ex.pm.positions.push_back(cm_.position(v));
      }
      lt[k] = local_of_[v];
    }
    ex.pm.faces.push_back(lt);
  }
  const int nv = static_cast<int>(ex.verts.size());
  std::vector<int> next_b(nv, -1);
  int boundary_edges = 0;
  std::string error;
  for (int f : faces)
    for (int k = 0; k < 3; ++k) {
      const int h = 3 * f + k;
      if (cm_.patch(CutMesh::face_of(cm_.opposite(h))) == node.label) continue;
      const int a = local_of_[cm_.tail(h)];
      if (next_b[a] >= 0 && error.empty())
        error = "vertex " + std::to_string(cm_.tail(h)) + " is on its boundary twice (not a disk)";
      next_b[a] = local_of_[cm_.head(h)];
      ++boundary_edges;
    }
  const int start = local_of_[node.corners[0]];
  if (error.empty() && (start < 0 || next_b[start] < 0))
    error = "corner vertex " + std::to_string(node.corners[0]) + " is not on its boundary";
  if (error.empty()) {
    for (int v = start, guard = 0; guard <= boundary_edges; ++guard) {
      ex.pm.boundary.push_back(v);
      v = next_b[v];
      if (v == start) break;
    }
    if (static_cast<int>(ex.pm.boundary.size()) != boundary_edges)
      error = "its boundary is not one loop (" + std::to_string(boundary_edges) + " boundary edges, loop of " +
              std::to_string(ex.pm.boundary.size()) + ")";
  }
  if (error.empty()) {
    int last = -1;
    for (int c = 0; c < 4; ++c) {
      const int lc = local_of_[node.corners[c]];
      const auto it = lc < 0 ? ex.pm.boundary.end() : std::find(ex.pm.boundary.begin(), ex.pm.boundary.end(), lc);
      const int idx = static_cast<int>(it - ex.pm.boundary.begin());
      if (it == ex.pm.boundary.end() || idx <= last) {
        error = "corner " + std::to_string(c) + " (vertex " + std::to_string(node.corners[c]) +
                ") is not on its boundary in counter-clockwise order";
        break;
      }
      ex.pm.corner_index[c] = last = idx;
    }
  }
  for (int v : ex.verts) local_of_[v] = -1;
  if (!error.empty()) throw SplitFailure("patch " + node.name + ": " + error);
  return ex;
}

std::vector<std::array<int, 2>> MeshDissector::border_degeneracies(const Extracted& ex, int label) const {
  // Half-edge 3 f + c of the cut mesh is the patch's local half-edge 3 lf + c; it is interior
  // when the face across it is in the patch too.
  std::vector<char> interior(3 * ex.faces.size());
  for (size_t lf = 0; lf < ex.faces.size(); ++lf)
    for (int c = 0; c < 3; ++c)
      interior[3 * lf + c] = cm_.patch(CutMesh::face_of(cm_.opposite(3 * ex.faces[lf] + c))) == label;
  return param::border_degeneracies(ex.pm, interior);
}

MeshDissector::MeshDissector(const MeshToDissect& in, int index, const std::vector<std::string>& feature_names,
                             const DissectOptions& options, const Context& context)
    : mesh_(*in.mesh),
      name_(in.name.empty() ? "mesh " + std::to_string(index) : in.name),
      cm_(*in.mesh),
      opt_(options),
      ctx_(context) {
  grow();
  // Features become vertices of the cut mesh (a point on a face splits it), so that cuts can be
  // kept off them and their (u,v) is exact.
  feature_vertex_.assign(feature_names.size(), -1);
  for (const Feature& f : in.features) {
    const auto it = std::lower_bound(feature_names.begin(), feature_names.end(), f.name);
    const int k = static_cast<int>(it - feature_names.begin());
    feature_vertex_[k] = insert_feature(f);
  }
  if (in.seed_points) {
    std::array<int, 4> sv{};
    for (int i = 0; i < 4; ++i) {
      SeedPlacement& sp = seed_placements_[i];
      sp.where = (*in.seed_points)[i];
      sv[i] = sp.vertex = insert_surface_point(sp.where, &sp.inserted);
      sp.position = landmarks::position_of(mesh_, sp.where);
    }
    inserted_seeds = sv;
  }
  feature_of_.assign(cm_.num_vertices(), -1);
  for (size_t k = 0; k < feature_vertex_.size(); ++k) {
    const int v = feature_vertex_[k];
    if (feature_of_[v] >= 0)
      throw InvalidInput(name_ + ": features '" + feature_names[feature_of_[v]] + "' and '" + feature_names[k] +
                         "' are the same point (vertex " + std::to_string(v) + "); give distinct points");
    feature_of_[v] = static_cast<int>(k);
  }
}

int MeshDissector::insert_feature(const Feature& f) {
  if (f.vertex >= 0) {
    if (f.vertex >= cm_.num_vertices())
      throw InvalidInput(name_ + ": feature '" + f.name + "' refers to vertex " + std::to_string(f.vertex) +
                         ", out of range");
    return f.vertex;
  }
  return insert_surface_point(f.where);
}

int MeshDissector::insert_surface_point(const landmarks::SurfacePoint& where, bool* inserted) {
  if (inserted) *inserted = false;
  if (where.face < 0 || where.face >= mesh_.num_faces())
    throw InvalidInput(name_ + ": a landmark refers to face " + std::to_string(where.face) + ", out of range");
  // On a vertex of the input: that vertex (input ids are kept by the cut mesh).
  for (int k = 0; k < 3; ++k)
    if (where.bary[k] > 1 - 1e-12) return mesh_.faces[where.face][k];
  // The face may have been split by an earlier point: find the current face nearest the point.
  const Vec3 p = landmarks::position_of(mesh_, where);
  const landmarks::SurfacePoint sp = landmarks::closest_surface_point(cm_.to_trimesh(), p);
  const Tri t = cm_.face(sp.face);
  const Vec3 b(sp.bary[0], sp.bary[1], sp.bary[2]);
  int kmax, kmin;
  b.maxCoeff(&kmax);
  b.minCoeff(&kmin);
  if (b[kmax] > 1 - 1e-9) return t[kmax];
  if (inserted) *inserted = true;
  if (b[kmin] < 1e-9) {
    const int i = (kmin + 1) % 3, j = (kmin + 2) % 3;
    const int m = cm_.split_edge(3 * sp.face + i, b[j] / (b[i] + b[j]));
    grow();
    return m;
  }
  const int m = cm_.split_face(sp.face, b / b.sum());
  grow();
  return m;
}

SeedLoop MeshDissector::trace_loop(const std::array<int, 4>& seeds, const routing::Graph* input_graph) const {
  for (size_t k = 0; k < feature_vertex_.size(); ++k)
    for (int i = 0; i < 4; ++i)
      if (feature_vertex_[k] == seeds[i])
        throw InvalidInput(name_ + ": a feature is the seed s" + std::to_string(i) + " (vertex " +
                           std::to_string(seeds[i]) + "); seeds are features already, remove it");
  // The cut mesh is the input while nothing has been inserted into it (splits only add faces).
  if (input_graph && cm_.num_faces() == mesh_.num_faces())
    return routing::trace_seed_loop(mesh_, *input_graph, seeds, feature_vertex_, ctx_);
  return trace_seed_loop(cm_.to_trimesh(), seeds, feature_vertex_, ctx_);
}

std::vector<int> MeshDissector::feature_sides(const SeedLoop& loop) const {
  return sides_of_vertices(cm_.to_trimesh(), loop, feature_vertex_);
}

SeedLoop MeshDissector::reroute_loop(const SeedLoop& loop, const std::vector<int>& want,
                                     const std::vector<SideConstraint>& more) const {
  std::vector<SideConstraint> sides;
  for (size_t k = 0; k < want.size(); ++k) sides.push_back({feature_vertex_[k], want[k]});
  sides.insert(sides.end(), more.begin(), more.end());
  return reroute_for_sides(cm_.to_trimesh(), loop, feature_vertex_, sides, ctx_);
}

std::vector<Vec3> MeshDissector::landmark_points(const std::array<int, 4>& seeds) const {
  std::vector<Vec3> out;
  for (int s : seeds) out.push_back(cm_.position(s));
  for (int v : feature_vertex_) out.push_back(cm_.position(v));
  return out;
}

GeodesicLoop MeshDissector::straighten(const SeedLoop& loop) const {
  GeodesicLoopOptions go;
  go.avoid = feature_vertex_;
  return straighten_seed_loop(cm_, loop, go, ctx_);
}

std::array<Node, 2> MeshDissector::seed(SeedLoop loop, std::optional<GeodesicLoop> straightened) {
  const std::array<int, 4> seeds = loop.seeds;
  seeds_ = seeds;
  TriMesh tm = cm_.to_trimesh();
  std::vector<int> side;  // the seed patch of each face of tm
  if (opt_.geodesic_seed_curves) {
    // The four curves become geodesics cut into the mesh, the same curves on the surface
    // for any tessellation. New vertices are appended, so input and feature ids stay valid.
    if (!straightened) straightened = straighten(loop);
    GeodesicLoop& g = *straightened;
    for (const std::string& why : g.why)
      if (!why.empty()) ctx_.info(name_ + ": seed " + why);
    if (g.any_straightened()) {
      tm = std::move(g.mesh);
      loop = std::move(g.loop);
      side = std::move(g.face_patches);
      cm_ = g.cut ? std::move(*g.cut) : CutMesh(tm);
      grow();
      feature_of_.resize(cm_.num_vertices(), -1);
    }
  }
  for (int k = 0; k < 4; ++k) {
    seed_curves_[k].clear();
    for (int v : loop.paths[k]) seed_curves_[k].push_back(tm.positions[v]);
  }
  // Seed patches: "0" left of the loop s0->s1->s2->s3, "1" right of it.
  std::array<Node, 2> roots;
  roots[0] = {"0", 0, new_label(), {seeds[0], seeds[1], seeds[2], seeds[3]}};
  roots[1] = {"1", 0, new_label(), {seeds[0], seeds[3], seeds[2], seeds[1]}};
  if (side.size() != tm.faces.size()) side = seed_patch_of_faces(tm, loop);
  for (int f = 0; f < cm_.num_faces(); ++f) {
    cm_.set_patch(f, roots[side[f]].label);
    patch_faces_[roots[side[f]].label].push_back(f);
  }
  return roots;
}

Param MeshDissector::parameterize(const Node& node) {
  Param p;
  for (int round = 0;; ++round) {
    p.ex = extract(node);
    const auto bad = border_degeneracies(p.ex, node.label);
    if (bad.empty() || round == 3) break;
    for (const auto& e : bad) {
      const int h = cm_.find_halfedge(p.ex.verts[e[0]], p.ex.verts[e[1]]);
      if (h >= 0 && interior_edge(h, node.label)) split_edge(h, 0.5);
    }
  }
  p.weights = opt_.intrinsic_cotan ? param::InteriorWeights::IntrinsicCotan : param::InteriorWeights::MeanValue;
  param::SquareParamOptions base;
  base.weights = p.weights;
  p.sp = param::parameterize_square(p.ex.pm, base, ctx_.without_progress());
  p.weights = p.sp.weights;  // mean-value where the Delaunay flips ran past their budget
  p.plain = {p.sp.uv, std::move(p.sp.cholesky_ordering)};
  p.st = param::l2_stretch(p.ex.pm.positions, p.ex.pm.faces, p.sp.uv);
  collect_features(p);
  for (int b : p.ex.pm.boundary)
    for (const auto& [k, local] : p.features)
      if (local == b)
        throw InternalError(name_ + ": feature vertex " + std::to_string(p.ex.verts[b]) + " is on the border of patch " +
                            node.name);
  return p;
}

param::SquareParam MeshDissector::mean_value_map(const Param& p) const {
  return param::parameterize_square(p.ex.pm, {}, ctx_.without_progress());
}

void MeshDissector::use_mean_value(Param& p, param::SquareParam mv) const {
  p.sp = std::move(mv);
  p.weights = param::InteriorWeights::MeanValue;
  p.plain = {p.sp.uv, {}};
  p.st = param::l2_stretch(p.ex.pm.positions, p.ex.pm.faces, p.sp.uv);
}

void MeshDissector::spread(Param& p) const {
  param::SquareParamOptions po;
  po.weights = p.weights;
  po.stretch_iterations = kRepairRounds;
  po.plain = &p.plain;
  try {
    param::SquareParam sp = param::parameterize_square(p.ex.pm, po, ctx_.without_progress());
    // Kept when it folds less, or, both bijective, when it is less stretched.
    const int bad = sp.flipped_faces + sp.zero_area_faces;
    const int old_bad = p.sp.flipped_faces + p.sp.zero_area_faces;
    if (bad < old_bad || (bad == 0 && old_bad == 0)) {
      param::Stretch st = param::l2_stretch(p.ex.pm.positions, p.ex.pm.faces, sp.uv);
      if (bad < old_bad || st.patch < p.st.patch) {
        p.sp = std::move(sp);
        p.st = std::move(st);
      }
    }
  } catch (const SolverError&) {
    // keep the map
  }
}

void MeshDissector::restore(const Node& node, size_t first_new_label) {
  // patch_faces_[node.label] still lists all its faces, those the cuts added included; the mesh
  // stays refined, which is harmless.
  for (int f : patch_faces_[node.label]) cm_.set_patch(f, node.label);
  if (patch_faces_.size() > first_new_label) patch_faces_.resize(first_new_label);
}

int MeshDissector::refine(const Node& node, const Param* p) {
  std::vector<int>& faces = patch_faces_[node.label];
  std::sort(faces.begin(), faces.end());
  std::vector<char> in_region;  // by global face; empty: the whole patch
  if (p) {
    in_region.assign(cm_.num_faces(), 0);
    const auto& F = p->ex.pm.faces;
    for (size_t f = 0; f < F.size(); ++f)
      if (signed_area(p->sp.uv[F[f][0]], p->sp.uv[F[f][1]], p->sp.uv[F[f][2]]) <= param::kZeroUvArea)
        in_region[p->ex.faces[f]] = 1;
    for (int ring = 0; ring < 2; ++ring) {
      std::vector<char> grown = in_region;
      for (int f : faces)
        if (in_region[f])
          for (int k = 0; k < 3; ++k) {
            const int g = CutMesh::face_of(cm_.opposite(3 * f + k));
            if (cm_.patch(g) == node.label) grown[g] = 1;
          }
      in_region.swap(grown);
    }
  }
  std::vector<std::pair<int, int>> edges;
  for (int f : faces)
    for (int k = 0; k < 3; ++k) {
      const int h = 3 * f + k;
      const int g = CutMesh::face_of(cm_.opposite(h));
      if (!in_region.empty() && !in_region[f] && !in_region[g]) continue;
      if (cm_.tail(h) < cm_.head(h) && interior_edge(h, node.label)) edges.emplace_back(cm_.tail(h), cm_.head(h));
    }
  const int before = cm_.num_faces();
  for (const auto& [a, b] : edges) {
    const int h = cm_.find_halfedge(a, b);
    if (h >= 0) split_edge(h, 0.5);
  }
  return cm_.num_faces() - before;
}

void MeshDissector::keep_leaf(const Node& node, const Param& p, PatchInfo info) {
  info.name = node.name;
  info.corners = node.corners;
  info.faces = static_cast<int>(p.ex.faces.size());
  leaves_.push_back(node);
  infos_.push_back(std::move(info));
  // A leaf left over tau or with zero-area UV faces (a protrusion squeezed below double
  // precision at the depth limit) is repaired by stretch minimization, whatever the option says;
  // the repairs run in finish(), in parallel.
  const bool exception = !p.sp.bijective() || p.st.patch > opt_.tau;
  const int rounds = exception ? std::max(opt_.stretch_iterations, kRepairRounds) : opt_.stretch_iterations;
  if (rounds > 0) repairs_.push_back({infos_.size() - 1, p, rounds});
  if (keep_params_) leaf_params_.push_back(p);
  set_leaf_map(infos_.size() - 1, p, p.sp, p.st);
}

void MeshDissector::set_leaf_map(size_t leaf, const Param& p, const param::SquareParam& sp, const param::Stretch& st) {
  PatchInfo& info = infos_[leaf];
  if (sp.bijective() && st.patch <= opt_.tau) {  // within tau (perhaps repaired): no exception
    info.stop = StopReason::None;
    info.stop_detail.clear();
  }
  info.stretch = st.patch;
  info.flipped_faces = sp.flipped_faces;
  info.zero_area_faces = sp.zero_area_faces;
  info.uv_area_sum = sp.uv_area_sum;
  if (leaf < leaf_params_.size()) {
    leaf_params_[leaf].sp = sp;
    leaf_params_[leaf].st = st;
  }
  for (size_t lf = 0; lf < p.ex.faces.size(); ++lf)
    for (int k = 0; k < 3; ++k) face_uv_[p.ex.faces[lf]][k] = sp.uv[p.ex.pm.faces[lf][k]];
}

Dissection MeshDissector::finish(const std::vector<TreeNode>& tree) {
  run_repairs();
  Dissection out;
  out.seeds = seeds_;
  out.seed_placements = seed_placements_;
  for (int i = 0; i < 4; ++i)
    if (seed_placements_[i].vertex != seeds_[i]) {  // given as vertex ids, or chosen automatically
      SeedPlacement& sp = out.seed_placements[i];
      sp = {};
      sp.vertex = seeds_[i];
      sp.position = cm_.position(seeds_[i]);
    }
  out.tree = tree;
  // Leaves sorted by name; the chart's face labels index them.
  std::vector<int> order(leaves_.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return leaves_[a].name < leaves_[b].name; });
  std::vector<int> leaf_of_label(patch_faces_.size(), -1);
  for (size_t i = 0; i < order.size(); ++i) {
    leaf_of_label[leaves_[order[i]].label] = static_cast<int>(i);
    out.chart.patches.push_back(infos_[order[i]]);
    out.max_stretch = std::max(out.max_stretch, infos_[order[i]].stretch);
  }
  out.chart.mesh = cm_.to_trimesh();
  out.chart.face_patch.resize(cm_.num_faces());
  for (int f = 0; f < cm_.num_faces(); ++f) out.chart.face_patch[f] = leaf_of_label[cm_.patch(f)];
  out.chart.face_uv = face_uv_;
  out.chart.face_uv.resize(cm_.num_faces());
  out.base = build_base_domain(out.chart.patches);
  // Each feature is an interior vertex of one leaf: read its uv from any face around it.
  for (size_t k = 0; k < feature_vertex_.size(); ++k) {
    FeaturePlacement fp;
    fp.vertex = feature_vertex_[k];
    const int h = cm_.out_halfedge(fp.vertex);
    const int f = CutMesh::face_of(h);
    fp.patch = out.chart.face_patch[f];
    fp.uv = out.chart.face_uv[f][h % 3];
    out.features.push_back(fp);
  }
  return out;
}

// Inserts (or reuses) a vertex at parameter point q inside patch `label`, whose vertices have

}  // namespace qs::dissect::detail
