// The quinary split of one patch in one mesh (paper 3.2, fig. 4): inner corners inserted at
// (1-w) p_i + w peak, the 8 straight cuts traced through the parent's parameter domain, and the
// five children flood-filled between them.

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>
#include <unordered_set>

#include "qs/core/error.h"
#include "qs/dissect/dissect_detail.h"

namespace qs::dissect::detail {

int MeshDissector::insert_point(int label, const Vec2& q, bool snap) {
  const std::vector<int>& faces = patch_faces_[label];
  const auto [i, best_b] = best_uv_face(q, faces.size(), [&](size_t k) {
    const Tri& t = cm_.face(faces[k]);
    return std::array<Vec2, 3>{uv_of_[t[0]], uv_of_[t[1]], uv_of_[t[2]]};
  });
  if (i < 0) throw SplitFailure("no face contains an inner corner");
  const int best_f = faces[i];
  const Tri t = cm_.face(best_f);
  int kmax, kmin;
  best_b.maxCoeff(&kmax);
  best_b.minCoeff(&kmin);
  if (snap && best_b[kmax] > 0.8 && flag_[t[kmax]] == kFree) return t[kmax];
  const Vec3 bary = best_b.cwiseMax(0.0) / best_b.cwiseMax(0.0).sum();
  if (!bary.allFinite()) throw SplitFailure("an inner corner fell on a degenerate parameter triangle");
  if (bary[kmin] < 0.1) {
    const int h = 3 * best_f + (kmin + 1) % 3;  // the edge opposite corner kmin
    if (interior_edge(h, label)) {
      const int i = (kmin + 1) % 3, j = (kmin + 2) % 3;
      const double s = bary[j] / (bary[i] + bary[j]);
      const int m = split_edge(h, s);
      uv_of_[m] = (1 - s) * uv_of_[t[i]] + s * uv_of_[t[j]];
      return m;
    }
  }
  const int m = split_face(best_f, bary);
  uv_of_[m] = bary[0] * uv_of_[t[0]] + bary[1] * uv_of_[t[1]] + bary[2] * uv_of_[t[2]];
  return m;
}

// Moves vertex v's uv to q (onto a segment being cut) unless that folds a face around it.
void MeshDissector::project_onto_segment(int label, int v, const Vec2& q) {
  const Vec2 old = uv_of_[v];
  uv_of_[v] = q;
  const int h0 = cm_.out_halfedge(v);
  int h = h0;
  do {
    if (cm_.patch(CutMesh::face_of(h)) == label) {
      const Vec2 &a = uv_of_[v], &b = uv_of_[cm_.head(h)], &c = uv_of_[cm_.head(CutMesh::next(h))];
      if (!(signed_area(a, b, c) > param::kZeroUvArea)) {
        uv_of_[v] = old;
        return;
      }
    }
    h = cm_.rotate_ccw(h);
  } while (h != h0);
}

// Cuts the straight parameter-domain segment from vertex a to vertex b into the mesh: walks from
// vertex to vertex, splitting each crossed edge (or passing through a free vertex when the
// crossing is within `snap` of it). Returns the path's vertices, a and b included.
std::vector<int> MeshDissector::trace(int label, int a, int b, double snap, bool project) {
  std::vector<int> path = {a};
  const Vec2 target = uv_of_[b];
  const size_t limit = 4 * patch_faces_[label].size() + 16;
  for (int cur = a; cur != b;) {
    if (path.size() > limit) throw SplitFailure("a cut did not reach its end");
    const Vec2 p = uv_of_[cur];
    const Vec2 d = target - p;
    const double dn = d.norm();
    // The face around `cur` whose corner wedge holds the direction d.
    int best_h = -1;
    double best = -std::numeric_limits<double>::infinity();
    const int h0 = cm_.out_halfedge(cur);
    int h = h0;
    do {
      if (cm_.patch(CutMesh::face_of(h)) == label) {
        const int x = cm_.head(h), y = cm_.head(CutMesh::next(h));
        const Vec2 ex = uv_of_[x] - p, ey = uv_of_[y] - p;
        const double score = std::min(cross2(ex, d) / (ex.norm() * dn), cross2(d, ey) / (ey.norm() * dn));
        if (score > best) {
          best = score;
          best_h = h;
        }
      }
      h = cm_.rotate_ccw(h);
    } while (h != h0);
    if (best_h < 0 || best < -1e-6) throw SplitFailure("a cut left its patch");
    const int x = cm_.head(best_h), y = cm_.head(CutMesh::next(best_h));
    int next;
    if (x == b || y == b) {
      next = b;
    } else {
      const Vec2 ux = uv_of_[x], e = uv_of_[y] - ux;
      const double denom = cross2(e, d);
      if (std::abs(denom) < 1e-300) throw SplitFailure("a cut is parallel to an edge");
      const double t = std::clamp(cross2(p - ux, d) / denom, 0.0, 1.0);
      if (!std::isfinite(t)) throw SplitFailure("a cut met a degenerate parameter triangle");
      const double s = cross2(ux - p, e) / cross2(d, e);
      if (s >= 1.0) throw SplitFailure("a cut missed its end vertex");
      if (t < snap && flag_[x] == kFree) {
        next = x;
        if (project) project_onto_segment(label, x, ux + t * e);
      } else if (t > 1 - snap && flag_[y] == kFree) {
        next = y;
        if (project) project_onto_segment(label, y, ux + t * e);
      } else {
        const int hxy = CutMesh::next(best_h);
        if (!interior_edge(hxy, label)) throw SplitFailure("a cut crossed its patch's boundary");
        if (cut_edges_.count(edge_key(x, y))) throw SplitFailure("a cut crossed another cut");
        next = split_edge(hxy, t);
        uv_of_[next] = (1 - t) * ux + t * uv_of_[y];
      }
    }
    if (next != b) flag_[next] = kOnPath;
    cut_edges_.insert(edge_key(cur, next));
    path.push_back(next);
    cur = next;
  }
  return path;
}

std::array<Node, 5> MeshDissector::split(const Node& node, const Param& p, const Vec2& peak_uv, double w,
                                         double snap) {
  return split(node, p, inner_corners(peak_uv, w), snap);
}

std::array<Node, 5> MeshDissector::split(const Node& node, const Param& p, const std::array<Vec2, 4>& inner,
                                         double snap) {
  const Extracted& ex = p.ex;
  const int nv = static_cast<int>(ex.verts.size());
  for (int i = 0; i < nv; ++i) {
    uv_of_[ex.verts[i]] = p.sp.uv[i];
    flag_[ex.verts[i]] = kFree;
  }
  for (int v : ex.pm.boundary) flag_[ex.verts[v]] = kBoundary;
  for (const auto& f : p.features) flag_[ex.verts[f.second]] = kFeature;  // cuts never snap to features

  // Inner corners p4..p7 and the 8 cuts.
  cut_edges_.clear();
  std::array<int, 8> c;
  for (int i = 0; i < 4; ++i) c[i] = node.corners[i];
  for (int i = 0; i < 4; ++i) {
    // With features in the patch the inner corners never snap to a vertex: the cuts must be the
    // same segments in every mesh, or a feature near one could change sides.
    c[i + 4] = insert_point(node.label, inner[i], p.features.empty());
    flag_[c[i + 4]] = kCorner;
  }
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < i; ++j)
      if (c[i + 4] == c[j + 4]) throw SplitFailure("two inner corners fell on one vertex");
  std::vector<std::vector<int>> paths;
  for (int i = 0; i < 4; ++i) paths.push_back(trace(node.label, c[i], c[i + 4], snap, false));
  for (int i = 0; i < 4; ++i) paths.push_back(trace(node.label, c[i + 4], c[(i + 1) % 4 + 4], snap, false));

  // Flood the parent's faces into the 5 regions the cuts bound.
  std::vector<char> cut(3 * cm_.num_faces(), 0);
  for (const auto& path : paths)
    for (size_t i = 0; i + 1 < path.size(); ++i) {
      const int h = cm_.find_halfedge(path[i], path[i + 1]);
      if (h < 0) throw SplitFailure("a cut is not an edge path");
      cut[h] = cut[cm_.opposite(h)] = 1;
    }
  std::array<Node, 5> kids;
  std::array<int, 5> seed_face;
  for (int k = 0; k < 4; ++k) {
    // The parent's boundary edge leaving corner k lies on side k, in child k.
    const int a = ex.verts[ex.pm.boundary[ex.pm.corner_index[k]]];
    const int bidx = (ex.pm.corner_index[k] + 1) % static_cast<int>(ex.pm.boundary.size());
    seed_face[k] = CutMesh::face_of(cm_.find_halfedge(a, ex.verts[ex.pm.boundary[bidx]]));
    kids[k].corners = {c[k], c[(k + 1) % 4], c[(k + 1) % 4 + 4], c[k + 4]};
  }
  seed_face[4] = CutMesh::face_of(cm_.find_halfedge(paths[4][0], paths[4][1]));
  kids[4].corners = {c[4], c[5], c[6], c[7]};
  std::vector<int> parent_faces = patch_faces_[node.label];
  for (int k = 0; k < 5; ++k) {
    kids[k].name = node.name + "." + std::to_string(k);
    kids[k].depth = node.depth + 1;
    kids[k].label = new_label();
    if (cm_.patch(seed_face[k]) != node.label) throw SplitFailure("two children share a region");
    std::vector<int> stack = {seed_face[k]};
    cm_.set_patch(seed_face[k], kids[k].label);
    while (!stack.empty()) {
      const int f = stack.back();
      stack.pop_back();
      patch_faces_[kids[k].label].push_back(f);
      for (int j = 0; j < 3; ++j) {
        const int h = 3 * f + j;
        if (cut[h]) continue;
        const int g = CutMesh::face_of(cm_.opposite(h));
        if (cm_.patch(g) != node.label) continue;
        cm_.set_patch(g, kids[k].label);
        stack.push_back(g);
      }
    }
  }
  for (int f : parent_faces)
    if (cm_.patch(f) == node.label) throw SplitFailure("a region is bounded by no child's corners");
  return kids;  // the parent's face list stays until the whole set has split (restore needs it)
}

// cut_segments: crossings this near a free vertex (in edge parameter) pass through it.
constexpr double kSegmentSnap = 0.02;

void MeshDissector::cut_segments(const Node& node, Param& p, const std::vector<std::array<int, 2>>& segments) {
  const Extracted& ex = p.ex;
  for (size_t i = 0; i < ex.verts.size(); ++i) {
    uv_of_[ex.verts[i]] = p.sp.uv[i];
    flag_[ex.verts[i]] = kFree;
  }
  for (int v : ex.pm.boundary) flag_[ex.verts[v]] = kBoundary;
  for (const auto& f : p.features) flag_[ex.verts[f.second]] = kFeature;
  std::vector<std::array<int, 2>> global;
  for (const auto& s : segments) global.push_back({ex.verts[s[0]], ex.verts[s[1]]});
  cut_edges_.clear();
  // A crossing within 2% of an edge's length of a free vertex passes through it: the segment moves
  // by that little, and no sliver is cut into the surface (a split 1e-6 from a vertex makes 3D
  // slivers that fold later mean-value maps, and midpoint refinement keeps their shape).
  std::string failure;
  try {
    for (const auto& s : global) trace(node.label, s[0], s[1], kSegmentSnap, true);
  } catch (const SplitFailure& e) {
    failure = e.what();
  }
  cut_edges_.clear();
  // The same map on the refined patch: new vertices got their uv on the split edges.
  Param q;
  q.weights = p.weights;
  q.ex = extract(node);
  q.sp.uv.resize(q.ex.verts.size());
  for (size_t i = 0; i < q.ex.verts.size(); ++i) q.sp.uv[i] = uv_of_[q.ex.verts[i]];
  param::count_uv_faces(q.ex.pm.faces, q.sp);
  q.st = param::l2_stretch(q.ex.pm.positions, q.ex.pm.faces, q.sp.uv);
  collect_features(q);
  p = std::move(q);
  if (!failure.empty()) throw SplitFailure(failure);
}

}  // namespace qs::dissect::detail
