// Recursive quinary subdivision of one mesh (paper 3.2-3.3).
//
// The working state is one CutMesh whose faces carry a patch label (one label per quinary-tree
// node). A split only ever inserts vertices strictly inside the parent patch (its cuts start at
// the parent's corners and otherwise stay in its interior), so neighbouring patches never change
// and every patch side stays shared by exactly two patches: the base domain is conforming by
// construction, and checked anyway.

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_set>
#include <cstdint>

#include "qs/core/error.h"
#include "qs/dissect/cut_mesh.h"
#include "qs/dissect/dissection.h"
#include "qs/dissect/seed_loop.h"
#include "qs/param/square_param.h"

namespace qs::dissect {

const char* stop_reason_name(StopReason r) {
  switch (r) {
    case StopReason::None: return "none";
    case StopReason::MaxDepth: return "max_depth";
    case StopReason::TooFewFaces: return "too_few_faces";
    case StopReason::SplitFailed: return "split_failed";
  }
  return "none";
}

namespace {

// A split that could not be completed; the parent is restored and kept as a leaf.
struct SplitFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::uint64_t edge_key(int a, int b) {
  return (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint64_t>(std::max(a, b));
}

double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

const std::array<Vec2, 4> kSquare = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};

struct Node {
  std::string name;
  int depth = 0;
  int label = 0;
  std::array<int, 4> corners{};
};

// A patch as a PatchMesh, with its local -> global maps.
struct Extracted {
  param::PatchMesh pm;
  std::vector<int> verts;  // local -> global vertex
  std::vector<int> faces;  // local -> global face
};

enum Flag : char { kFree = 0, kBoundary = 1, kOnPath = 2, kCorner = 3 };

class Dissector {
 public:
  Dissector(const TriMesh& mesh, const DissectOptions& options, const Context& context)
      : mesh_(mesh), cm_(mesh), opt_(options), ctx_(context) {}

  Dissection run(const std::array<int, 4>& seeds);

 private:
  void grow() {
    const size_t n = cm_.num_vertices();
    if (local_of_.size() < n) {
      local_of_.resize(n, -1);
      uv_of_.resize(n, Vec2::Zero());
      flag_.resize(n, kFree);
    }
    face_uv_.resize(cm_.num_faces());
  }
  int split_edge(int h, double t) {
    const int m = cm_.split_edge(h, t);
    const int nf = cm_.num_faces();
    patch_faces_[cm_.patch(nf - 2)].push_back(nf - 2);
    patch_faces_[cm_.patch(nf - 1)].push_back(nf - 1);
    grow();
    return m;
  }
  int split_face(int f, const Vec3& bary) {
    const int m = cm_.split_face(f, bary);
    const int nf = cm_.num_faces();
    patch_faces_[cm_.patch(f)].push_back(nf - 2);
    patch_faces_[cm_.patch(f)].push_back(nf - 1);
    grow();
    return m;
  }
  int new_label() {
    patch_faces_.emplace_back();
    return static_cast<int>(patch_faces_.size()) - 1;
  }
  bool interior_edge(int h, int label) const {
    return cm_.patch(CutMesh::face_of(h)) == label && cm_.patch(CutMesh::face_of(cm_.opposite(h))) == label;
  }

  Extracted extract(const Node& node);
  struct Param {
    Extracted ex;
    param::SquareParam sp;
    param::Stretch st;
  };
  Param parameterize(const Node& node);
  std::array<Node, 5> split(const Node& node, const Param& p, TreeNode& tn);
  int insert_point(int label, const Vec2& q);
  std::vector<int> trace(int label, int a, int b);

  const TriMesh& mesh_;  // the input, before any cut
  CutMesh cm_;
  DissectOptions opt_;
  const Context& ctx_;
  std::vector<std::vector<int>> patch_faces_;  // by label
  std::vector<int> local_of_;                  // scratch: global vertex -> local, -1
  std::vector<Vec2> uv_of_;                    // scratch: uv of the patch being split
  std::vector<char> flag_;                     // scratch: Flag of the patch being split
  std::vector<std::array<Vec2, 3>> face_uv_;   // leaves' wedge uv, by global face
  std::unordered_set<std::uint64_t> cut_edges_;  // edges of the cuts of the split under way
};

Extracted Dissector::extract(const Node& node) {
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

Dissector::Param Dissector::parameterize(const Node& node) {
  Param p;
  for (int round = 0;; ++round) {
    p.ex = extract(node);
    const auto bad = param::border_degeneracies(p.ex.pm);
    if (bad.empty() || round == 3) break;
    for (const auto& e : bad) {
      const int h = cm_.find_halfedge(p.ex.verts[e[0]], p.ex.verts[e[1]]);
      if (h >= 0 && interior_edge(h, node.label)) split_edge(h, 0.5);
    }
  }
  Context quiet = ctx_;  // the per-patch solve's own progress would drown the dissection's
  quiet.progress = nullptr;
  p.sp = param::parameterize_square(p.ex.pm, {}, quiet);
  p.st = param::l2_stretch(p.ex.pm.positions, p.ex.pm.faces, p.sp.uv);
  return p;
}

// Inserts (or reuses) a vertex at parameter point q inside patch `label`, whose vertices have
// their uv in uv_of_. Crossings near an existing free vertex snap to it; near an edge split it.
int Dissector::insert_point(int label, const Vec2& q) {
  int best_f = -1;
  Vec3 best_b(0, 0, 0);
  double best_min = -std::numeric_limits<double>::infinity();
  for (int f : patch_faces_[label]) {
    const Tri& t = cm_.face(f);
    const Vec2 &a = uv_of_[t[0]], &b = uv_of_[t[1]], &c = uv_of_[t[2]];
    const double area = cross2(b - a, c - a);
    if (!(area > 0)) continue;
    const Vec3 bary(cross2(b - q, c - q) / area, cross2(c - q, a - q) / area, cross2(a - q, b - q) / area);
    if (bary.minCoeff() > best_min) {
      best_min = bary.minCoeff();
      best_b = bary;
      best_f = f;
    }
  }
  if (best_f < 0) throw SplitFailure("no face contains an inner corner");
  const Tri t = cm_.face(best_f);
  int kmax, kmin;
  best_b.maxCoeff(&kmax);
  best_b.minCoeff(&kmin);
  if (best_b[kmax] > 0.8 && flag_[t[kmax]] == kFree) return t[kmax];
  const Vec3 bary = best_b.cwiseMax(0.0) / best_b.cwiseMax(0.0).sum();
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

// Cuts the straight parameter-domain segment from vertex a to vertex b into the mesh: walks from
// vertex to vertex, splitting each crossed edge (or passing through a free vertex when the
// crossing is within 5% of it). Returns the path's vertices, a and b included.
std::vector<int> Dissector::trace(int label, int a, int b) {
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
      const double s = cross2(ux - p, e) / cross2(d, e);
      if (s >= 1.0) throw SplitFailure("a cut missed its end vertex");
      if (t < 0.05 && flag_[x] == kFree) {
        next = x;
      } else if (t > 0.95 && flag_[y] == kFree) {
        next = y;
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

std::array<Node, 5> Dissector::split(const Node& node, const Param& p, TreeNode& tn) {
  const Extracted& ex = p.ex;
  const int nv = static_cast<int>(ex.verts.size());
  for (int i = 0; i < nv; ++i) {
    uv_of_[ex.verts[i]] = p.sp.uv[i];
    flag_[ex.verts[i]] = kFree;
  }
  for (int v : ex.pm.boundary) flag_[ex.verts[v]] = kBoundary;

  // Peak: the face of greatest stretch after smoothing over the faces around its corners, so
  // that one sliver cannot decide.
  std::vector<double> vs(nv, 0.0), va(nv, 0.0);
  const auto& F = ex.pm.faces;
  for (size_t f = 0; f < F.size(); ++f) {
    const Tri& t = F[f];
    const Vec3& q0 = ex.pm.positions[t[0]];
    const double area = 0.5 * (ex.pm.positions[t[1]] - q0).cross(ex.pm.positions[t[2]] - q0).norm() + 1e-300;
    const double s = std::min(p.st.face[f], 1e6);
    for (int v : t) {
      vs[v] += s * area;
      va[v] += area;
    }
  }
  int peak = 0;
  double peak_s = -1;
  for (size_t f = 0; f < F.size(); ++f) {
    const Tri& t = F[f];
    const double s = (vs[t[0]] + vs[t[1]] + vs[t[2]]) / (va[t[0]] + va[t[1]] + va[t[2]]);
    if (s > peak_s) {
      peak_s = s;
      peak = static_cast<int>(f);
    }
  }
  const Tri& pt = F[peak];
  Vec2 peak_uv = (p.sp.uv[pt[0]] + p.sp.uv[pt[1]] + p.sp.uv[pt[2]]) / 3.0;
  peak_uv = peak_uv.cwiseMax(opt_.peak_margin).cwiseMin(1 - opt_.peak_margin);
  const double w = std::clamp(opt_.w_bias + std::log10(std::max(peak_s, 1e-12)), opt_.w_min, opt_.w_max);
  tn.peak_uv = peak_uv;
  tn.w = w;

  // Inner corners p4..p7 and the 8 cuts.
  cut_edges_.clear();
  std::array<int, 8> c;
  for (int i = 0; i < 4; ++i) c[i] = node.corners[i];
  for (int i = 0; i < 4; ++i) {
    c[i + 4] = insert_point(node.label, (1 - w) * kSquare[i] + w * peak_uv);
    flag_[c[i + 4]] = kCorner;
  }
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < i; ++j)
      if (c[i + 4] == c[j + 4]) throw SplitFailure("two inner corners fell on one vertex");
  std::vector<std::vector<int>> paths;
  for (int i = 0; i < 4; ++i) paths.push_back(trace(node.label, c[i], c[i + 4]));
  for (int i = 0; i < 4; ++i) paths.push_back(trace(node.label, c[i + 4], c[(i + 1) % 4 + 4]));

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
  patch_faces_[node.label].clear();
  return kids;
}

Dissection Dissector::run(const std::array<int, 4>& seeds) {
  Dissection out;
  out.seeds = seeds;
  ctx_.report("seed loop", 0.0);
  const SeedLoop loop = trace_seed_loop(mesh_, seeds, ctx_);
  grow();

  // Seed patches: "0" left of the loop s0->s1->s2->s3, "1" right of it.
  std::array<Node, 2> roots;
  roots[0] = {"0", 0, new_label(), {seeds[0], seeds[1], seeds[2], seeds[3]}};
  roots[1] = {"1", 0, new_label(), {seeds[0], seeds[3], seeds[2], seeds[1]}};
  const std::vector<int> side = seed_patch_of_faces(mesh_, loop);
  for (int f = 0; f < cm_.num_faces(); ++f) {
    cm_.set_patch(f, roots[side[f]].label);
    patch_faces_[roots[side[f]].label].push_back(f);
  }

  std::deque<Node> queue(roots.begin(), roots.end());
  std::vector<Node> leaves;
  std::vector<PatchInfo> infos;
  const double total_faces = cm_.num_faces();
  double done_faces = 0;
  while (!queue.empty()) {
    ctx_.check_cancel();
    Node node = queue.front();
    queue.pop_front();
    Param p = parameterize(node);
    TreeNode tn;
    tn.name = node.name;
    tn.depth = node.depth;
    tn.stretch = p.st.patch;
    PatchInfo info;
    info.stretch = p.st.patch;
    // A long protrusion shrinks exponentially under a Floater map, down to UV triangles of zero
    // area in floating point: such a patch is over tau whatever its RMS stretch, and splitting
    // it around its peak is exactly the cure. Only a leaf must be bijective.
    const bool over = p.st.patch > opt_.tau || !p.sp.bijective();
    const int nfaces = static_cast<int>(p.ex.faces.size());
    if (over && node.depth < opt_.max_depth && nfaces >= opt_.min_faces_to_split) {
      const size_t first_new_label = patch_faces_.size();
      try {
        const auto kids = split(node, p, tn);
        tn.split = true;
        out.tree.push_back(tn);
        for (const auto& k : kids) queue.push_back(k);
        continue;
      } catch (const SplitFailure& e) {
        // Restore the parent (its mesh is refined, which is harmless) and keep it as a leaf.
        // patch_faces_[node.label] still lists all its faces, those the cuts added included.
        for (int f : patch_faces_[node.label]) cm_.set_patch(f, node.label);
        patch_faces_.resize(first_new_label);
        p = parameterize(node);
        info.stretch = tn.stretch = p.st.patch;
        info.stop = StopReason::SplitFailed;
        info.stop_detail = e.what();
      }
    } else if (over) {
      info.stop = node.depth >= opt_.max_depth ? StopReason::MaxDepth : StopReason::TooFewFaces;
    }
    out.tree.push_back(tn);
    info.name = node.name;
    info.corners = node.corners;
    info.faces = static_cast<int>(p.ex.faces.size());
    info.flipped_faces = p.sp.flipped_faces;
    info.zero_area_faces = p.sp.zero_area_faces;
    info.uv_area_sum = p.sp.uv_area_sum;
    for (size_t lf = 0; lf < p.ex.faces.size(); ++lf)
      for (int k = 0; k < 3; ++k) face_uv_[p.ex.faces[lf]][k] = p.sp.uv[p.ex.pm.faces[lf][k]];
    leaves.push_back(node);
    infos.push_back(info);
    done_faces += info.faces;
    ctx_.report("quinary subdivision", done_faces / total_faces);
  }

  // Leaves sorted by name; the chart's face labels index them.
  std::vector<int> order(leaves.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return leaves[a].name < leaves[b].name; });
  std::vector<int> leaf_of_label(patch_faces_.size(), -1);
  for (size_t i = 0; i < order.size(); ++i) {
    leaf_of_label[leaves[order[i]].label] = static_cast<int>(i);
    out.chart.patches.push_back(infos[order[i]]);
    out.max_stretch = std::max(out.max_stretch, infos[order[i]].stretch);
  }
  out.chart.mesh = cm_.to_trimesh();
  out.chart.face_patch.resize(cm_.num_faces());
  for (int f = 0; f < cm_.num_faces(); ++f) out.chart.face_patch[f] = leaf_of_label[cm_.patch(f)];
  out.chart.face_uv = face_uv_;
  out.chart.face_uv.resize(cm_.num_faces());
  std::stable_sort(out.tree.begin(), out.tree.end(), [](const TreeNode& a, const TreeNode& b) {
    return a.depth != b.depth ? a.depth < b.depth : a.name < b.name;
  });
  out.base = build_base_domain(out.chart.patches);
  return out;
}

}  // namespace

BaseDomain build_base_domain(const std::vector<PatchInfo>& patches) {
  BaseDomain bd;
  std::vector<int> ids;
  for (const auto& p : patches) ids.insert(ids.end(), p.corners.begin(), p.corners.end());
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  bd.vertices = ids;
  std::vector<std::pair<int, int>> sides;
  for (const auto& p : patches) {
    std::array<int, 4> q;
    for (int k = 0; k < 4; ++k) q[k] = static_cast<int>(std::lower_bound(ids.begin(), ids.end(), p.corners[k]) - ids.begin());
    bd.quads.push_back(q);
    for (int k = 0; k < 4; ++k) sides.emplace_back(q[k], q[(k + 1) % 4]);
  }
  std::sort(sides.begin(), sides.end());
  bool ok = std::adjacent_find(sides.begin(), sides.end()) == sides.end();  // no side twice one way
  for (const auto& [a, b] : sides) ok = ok && std::binary_search(sides.begin(), sides.end(), std::make_pair(b, a));
  bd.closed_conforming = ok;
  bd.edges = static_cast<int>(sides.size()) / 2;
  bd.euler_characteristic = static_cast<int>(bd.vertices.size()) - bd.edges + static_cast<int>(bd.quads.size());
  return bd;
}

Dissection dissect(const TriMesh& mesh, const std::optional<std::array<int, 4>>& seeds,
                   const DissectOptions& options, const Context& context) {
  if (!(options.tau >= 1.0)) throw InvalidInput("--tau must be at least 1 (the stretch of an isometry)");
  const std::array<int, 4> s = seeds ? *seeds : choose_seeds(mesh);
  Dissector d(mesh, options, context);
  return d.run(s);
}

}  // namespace qs::dissect
