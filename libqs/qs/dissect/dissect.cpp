// Recursive quinary subdivision of one mesh (paper 3.2-3.3).
//
// The working state is one CutMesh whose faces carry a patch label (one label per quinary-tree
// node). A split only ever inserts vertices strictly inside the parent patch (its cuts start at
// the parent's corners and otherwise stay in its interior), so neighbouring patches never change
// and every patch side stays shared by exactly two patches: the base domain is conforming by
// construction, and checked anyway.

#include <algorithm>
#include <exception>
#include <thread>
#include <mutex>
#include <atomic>
#include <cmath>
#include <deque>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <cstdint>

#include "qs/core/error.h"
#include "qs/dissect/cut_mesh.h"
#include "qs/dissect/dissection.h"
#include "qs/dissect/relax.h"
#include "qs/dissect/seed_loop.h"
#include "qs/param/square_param.h"
#include "qs/warp/warp.h"

namespace qs::dissect {

const char* stop_reason_name(StopReason r) {
  switch (r) {
    case StopReason::None: return "none";
    case StopReason::MaxDepth: return "max_depth";
    case StopReason::TooFewFaces: return "too_few_faces";
    case StopReason::SplitFailed: return "split_failed";
    case StopReason::NoProgress: return "no_progress";
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
  double parent_stretch = std::numeric_limits<double>::infinity();  ///< this mesh's, at the parent
  double grandparent_stretch = std::numeric_limits<double>::infinity();
};

// A patch as a PatchMesh, with its local -> global maps.
struct Extracted {
  param::PatchMesh pm;
  std::vector<int> verts;  // local -> global vertex
  std::vector<int> faces;  // local -> global face
};

enum Flag : char { kFree = 0, kBoundary = 1, kOnPath = 2, kCorner = 3, kFeature = 4 };

/// Per-mesh work on a node of a set runs on several threads from this many faces (all meshes).
constexpr size_t kParallelFaces = 8000;
/// Stretch-minimization rounds tried on a leaf left over tau or not bijective.
constexpr int kRepairRounds = 12;

/// Runs f(i) for i in [0, n) on up to hardware_concurrency() threads (one thread when !parallel:
/// starting threads costs more than small work). Every i runs; then the exception of the lowest i
/// that threw is rethrown, so errors do not depend on timing.
template <class F>
void parallel_for(size_t n, F&& f, bool parallel = true) {
  std::vector<std::exception_ptr> errors(n);
  std::atomic<size_t> next{0};
  auto work = [&] {
    for (size_t i; (i = next++) < n;) {
      try {
        f(i);
      } catch (...) {
        errors[i] = std::current_exception();
      }
    }
  };
  const size_t threads = parallel ? std::min<size_t>(std::max(1u, std::thread::hardware_concurrency()), n) : 1;
  std::vector<std::thread> pool;
  for (size_t t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
}

// The per-node result of one mesh: its patch extracted and parameterized (after alignment).
struct Param {
  Extracted ex;
  param::SquareParam sp;
  param::Stretch st;
  std::vector<std::pair<int, int>> features;  // (feature index, local vertex), by feature index
};

// The dissection state of one mesh of the set: the cut mesh and the faces of every tree node.
// The set driver (SetDissector) walks the union tree and asks each mesh to parameterize, split,
// restore or keep a node; labels are handed out in the same order in every mesh.
class MeshDissector {
 public:
  MeshDissector(const MeshToDissect& in, int index, const std::vector<std::string>& feature_names,
                const DissectOptions& options, const Context& context);

  /// Traces the seed loop (avoiding the features) and labels the two seed patches.
  std::array<Node, 2> seed(const std::array<int, 4>& seeds);
  Param parameterize(const Node& node);
  std::array<Node, 5> split(const Node& node, const Param& p, const Vec2& peak_uv, double w);
  /// Puts a node's faces back after a failed split (in any mesh of the set).
  void restore(const Node& node, size_t first_new_label);
  size_t labels() const { return patch_faces_.size(); }
  size_t node_faces(const Node& node) const { return patch_faces_[node.label].size(); }
  /// Drops the parent's face list once every mesh of the set has split it.
  void commit_split(const Node& node) { patch_faces_[node.label].clear(); }
  /// Records a node as a leaf with its (aligned) parameterization.
  void keep_leaf(const Node& node, const Param& p, PatchInfo info);
  Dissection finish(const std::vector<TreeNode>& tree);
  const std::string& name() const { return name_; }
  /// The label of the patch holding feature k (features never lie on a patch border).
  int feature_label(int k) const { return cm_.patch(CutMesh::face_of(cm_.out_halfedge(feature_vertex_[k]))); }

  /// Smoothed per-face stretch peak: (face, value). One sliver cannot decide.
  std::pair<int, double> peak(const Param& p) const;

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
  int insert_feature(const Feature& f);
  Extracted extract(const Node& node);
  /// p.features from p.ex: (feature index, local vertex), sorted.
  void collect_features(Param& p) const {
    p.features.clear();
    for (size_t i = 0; i < p.ex.verts.size(); ++i) {
      const int v = p.ex.verts[i];
      if (v < static_cast<int>(feature_of_.size()) && feature_of_[v] >= 0)
        p.features.emplace_back(feature_of_[v], static_cast<int>(i));
    }
    std::sort(p.features.begin(), p.features.end());
  }
  int insert_point(int label, const Vec2& q, bool snap);
  std::vector<int> trace(int label, int a, int b);

  const TriMesh& mesh_;  // the input, before any cut
  std::string name_;
  CutMesh cm_;
  DissectOptions opt_;
  const Context& ctx_;
  std::vector<int> feature_vertex_;            // by feature index (names sorted)
  std::vector<int> feature_of_;                // by vertex: feature index or -1
  std::vector<std::vector<int>> patch_faces_;  // by label
  std::vector<int> local_of_;                  // scratch: global vertex -> local, -1
  std::vector<Vec2> uv_of_;                    // scratch: uv of the patch being split
  std::vector<char> flag_;                     // scratch: Flag of the patch being split
  std::vector<std::array<Vec2, 3>> face_uv_;   // leaves' wedge uv, by global face
  std::unordered_set<std::uint64_t> cut_edges_;  // edges of the cuts of the split under way
  std::vector<Node> leaves_;
  std::vector<PatchInfo> infos_;
  struct Repair {
    size_t leaf;  // index into leaves_ / infos_
    Param param;  // the leaf as kept
    int rounds;
  };
  std::vector<Repair> repairs_;  // leaves to minimize in finish()
  void set_leaf_map(size_t leaf, const Param& p, const param::SquareParam& sp, const param::Stretch& st);
  void run_repairs();
  std::array<int, 4> seeds_{};
};

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
  // The face may have been split by an earlier feature: find the current face nearest the point.
  const Vec3 p = landmarks::position_of(mesh_, f.where);
  const landmarks::SurfacePoint sp = landmarks::closest_surface_point(cm_.to_trimesh(), p);
  const Tri t = cm_.face(sp.face);
  const Vec3 b(sp.bary[0], sp.bary[1], sp.bary[2]);
  int kmax, kmin;
  b.maxCoeff(&kmax);
  b.minCoeff(&kmin);
  if (b[kmax] > 1 - 1e-9) return t[kmax];
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

std::array<Node, 2> MeshDissector::seed(const std::array<int, 4>& seeds) {
  seeds_ = seeds;
  for (size_t k = 0; k < feature_vertex_.size(); ++k)
    for (int i = 0; i < 4; ++i)
      if (feature_vertex_[k] == seeds[i])
        throw InvalidInput(name_ + ": a feature is the seed s" + std::to_string(i) + " (vertex " +
                           std::to_string(seeds[i]) + "); seeds are features already, remove it");
  TriMesh tm = cm_.to_trimesh();
  SeedLoop loop = trace_seed_loop(tm, seeds, feature_vertex_, ctx_);
  if (opt_.relax_rounds > 0) {
    // Paper 3.3: each seed curve becomes the straight line of the map of the mesh cut along the
    // other three. New vertices are appended, so input and feature ids stay valid.
    RelaxOptions ro;
    ro.rounds = opt_.relax_rounds;
    ro.avoid = feature_vertex_;
    RelaxedLoop r = relax_seed_loop(tm, loop, ro, ctx_);
    tm = std::move(r.mesh);
    loop = std::move(r.loop);
    cm_ = CutMesh(tm);
    grow();
    feature_of_.resize(cm_.num_vertices(), -1);
  }
  // Seed patches: "0" left of the loop s0->s1->s2->s3, "1" right of it.
  std::array<Node, 2> roots;
  roots[0] = {"0", 0, new_label(), {seeds[0], seeds[1], seeds[2], seeds[3]}};
  roots[1] = {"1", 0, new_label(), {seeds[0], seeds[3], seeds[2], seeds[1]}};
  const std::vector<int> side = seed_patch_of_faces(tm, loop);
  for (int f = 0; f < cm_.num_faces(); ++f) {
    cm_.set_patch(f, roots[side[f]].label);
    patch_faces_[roots[side[f]].label].push_back(f);
  }
  return roots;
}

namespace {
double signed_area(const Vec2& a, const Vec2& b, const Vec2& c) { return 0.5 * cross2(b - a, c - a); }
}  // namespace

namespace {
// Local untangling of a folded map: the free vertices of folded faces and two rings around them
// move to the average of their neighbours (Gauss-Seidel), the border and `fixed` vertices stay.
// Repeated while folds remain (at most `rounds` times). Returns the map with fewer folds.
param::SquareParam untangle(const param::PatchMesh& pm, const param::SquareParam& in, const std::vector<char>& fixed,
                            int rounds) {
  const int nv = static_cast<int>(pm.positions.size());
  std::vector<std::vector<int>> nb(nv);
  for (const Tri& t : pm.faces)
    for (int k = 0; k < 3; ++k) nb[t[k]].push_back(t[(k + 1) % 3]), nb[t[k]].push_back(t[(k + 2) % 3]);
  for (auto& n : nb) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  std::vector<char> pinned = fixed;
  pinned.resize(nv, 0);
  for (int b : pm.boundary) pinned[b] = 1;
  param::SquareParam best = in, cur = in;
  for (int r = 0; r < rounds && !best.bijective(); ++r) {
    std::vector<char> mark(nv, 0);
    for (const Tri& t : pm.faces)
      if (signed_area(cur.uv[t[0]], cur.uv[t[1]], cur.uv[t[2]]) <= param::kZeroUvArea)
        for (int v : t) mark[v] = 1;
    for (int ring = 0; ring < 2 + std::min(r, 6); ++ring) {  // a wider region every round
      std::vector<char> grown = mark;
      for (int v = 0; v < nv; ++v)
        if (mark[v])
          for (int w : nb[v]) grown[w] = 1;
      mark.swap(grown);
    }
    for (int sweep = 0; sweep < 10; ++sweep)
      for (int v = 0; v < nv; ++v) {
        if (!mark[v] || pinned[v] || nb[v].empty()) continue;
        Vec2 c = Vec2::Zero();
        for (int w : nb[v]) c += cur.uv[w];
        cur.uv[v] = c / static_cast<double>(nb[v].size());
      }
    param::count_uv_faces(pm.faces, cur);
    if (cur.flipped_faces + cur.zero_area_faces < best.flipped_faces + best.zero_area_faces) best = cur;
  }
  return best;
}
}  // namespace

Param MeshDissector::parameterize(const Node& node) {
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
  p.sp = param::parameterize_square(p.ex.pm, {}, ctx_.without_progress());
  p.st = param::l2_stretch(p.ex.pm.positions, p.ex.pm.faces, p.sp.uv);
  collect_features(p);
  // A map squeezed to zero area (a long protrusion) that holds features is spread out by stretch
  // minimization, so that the features can be aligned (measured: it changes the tree of a mesh
  // without features for the worse as often as for the better). With the option, every patch
  // over tau is judged (and split) by its minimized map.
  const bool squeezed = !p.sp.bijective() && !p.features.empty();
  if (squeezed || (opt_.split_stretch_rounds > 0 && p.st.patch > opt_.tau)) {
    param::SquareParamOptions po;
    po.stretch_iterations = squeezed ? std::max(opt_.split_stretch_rounds, kRepairRounds) : opt_.split_stretch_rounds;
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
      // keep the mean-value map
    }
  }
  for (int b : p.ex.pm.boundary)
    for (const auto& [k, local] : p.features)
      if (local == b)
        throw InternalError(name_ + ": feature vertex " + std::to_string(p.ex.verts[b]) + " is on the border of patch " +
                            node.name);
  return p;
}

std::pair<int, double> MeshDissector::peak(const Param& p) const {
  const Extracted& ex = p.ex;
  const int nv = static_cast<int>(ex.verts.size());
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
  return {peak, peak_s};
}

void MeshDissector::restore(const Node& node, size_t first_new_label) {
  // patch_faces_[node.label] still lists all its faces, those the cuts added included; the mesh
  // stays refined, which is harmless.
  for (int f : patch_faces_[node.label]) cm_.set_patch(f, node.label);
  if (patch_faces_.size() > first_new_label) patch_faces_.resize(first_new_label);
}

namespace {
// A stretch-minimized map of a leaf (see keep_leaf), or an empty map when none is better.
// Pure: it reads the leaf only, so leaves are repaired in parallel.
param::SquareParam minimized_leaf(const Param& p, int rounds, const Context& context) {
  // Minimize without pins (pins inside a squeezed protrusion defeat it), then warp the features
  // back onto their aligned (u,v): the spread-out map folds far less under the warp.
  param::SquareParamOptions po;
  po.stretch_iterations = rounds;
  param::SquareParam min_sp;
  try {
    min_sp = param::parameterize_square(p.ex.pm, po, context);
    if (!p.features.empty()) {
      std::vector<Vec2> from, to;
      for (const auto& [k, local] : p.features) {
        from.push_back(min_sp.uv[local]);
        to.push_back(p.sp.uv[local]);
      }
      min_sp.uv = warp::warp_square(from, to, min_sp.uv, {}, context).points;
      param::count_uv_faces(p.ex.pm.faces, min_sp);
      if (!min_sp.bijective()) {
        std::vector<char> fixed(p.ex.verts.size(), 0);
        for (const auto& f : p.features) fixed[f.second] = 1;
        min_sp = untangle(p.ex.pm, min_sp, fixed, 20);
      }
      if (!min_sp.bijective()) {  // then try minimizing with the features pinned
        for (const auto& [k, local] : p.features) po.pinned.emplace_back(local, p.sp.uv[local]);
        param::SquareParam pinned = param::parameterize_square(p.ex.pm, po, context);
        if (pinned.flipped_faces + pinned.zero_area_faces < min_sp.flipped_faces + min_sp.zero_area_faces)
          min_sp = std::move(pinned);
      }
    }
  } catch (const Error& e) {
    if (e.code() == ErrorCode::Internal) throw;  // cancelled, or a bug
    return {};  // a singular system or features the warp cannot place: keep the given map
  }
  if (!min_sp.bijective()) return {};
  return min_sp;
}
}  // namespace

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
  for (size_t lf = 0; lf < p.ex.faces.size(); ++lf)
    for (int k = 0; k < 3; ++k) face_uv_[p.ex.faces[lf]][k] = sp.uv[p.ex.pm.faces[lf][k]];
}

void MeshDissector::run_repairs() {
  // Independent leaves, one result slot each: the outcome does not depend on the thread count.
  Context quiet = ctx_.without_progress();
  quiet.log = nullptr;  // the minimization's fold warnings are expected; the result is counted
  std::vector<param::SquareParam> result(repairs_.size());
  size_t faces = 0;
  for (const auto& r : repairs_) faces += r.param.ex.faces.size();
  parallel_for(
      repairs_.size(), [&](size_t r) { result[r] = minimized_leaf(repairs_[r].param, repairs_[r].rounds, quiet); },
      faces >= kParallelFaces / 8);
  for (size_t r = 0; r < repairs_.size(); ++r) {
    const Param& p = repairs_[r].param;
    if (result[r].uv.empty()) continue;
    const param::Stretch st = param::l2_stretch(p.ex.pm.positions, p.ex.pm.faces, result[r].uv);
    if (!p.sp.bijective() || st.patch < p.st.patch) set_leaf_map(repairs_[r].leaf, p, result[r], st);
  }
  repairs_.clear();
}

Dissection MeshDissector::finish(const std::vector<TreeNode>& tree) {
  run_repairs();
  Dissection out;
  out.seeds = seeds_;
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
// their uv in uv_of_. Crossings near an existing free vertex snap to it; near an edge split it.
int MeshDissector::insert_point(int label, const Vec2& q, bool snap) {
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
  if (snap && best_b[kmax] > 0.8 && flag_[t[kmax]] == kFree) return t[kmax];
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
std::vector<int> MeshDissector::trace(int label, int a, int b) {
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

std::array<Node, 5> MeshDissector::split(const Node& node, const Param& p, const Vec2& peak_uv, double w) {
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
    c[i + 4] = insert_point(node.label, (1 - w) * kSquare[i] + w * peak_uv, p.features.empty());
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
  return kids;  // the parent's face list stays until the whole set has split (restore needs it)
}

// Distance from q to the segment ab.
double segment_distance(const Vec2& q, const Vec2& a, const Vec2& b) {
  const Vec2 d = b - a;
  const double t = std::clamp((q - a).dot(d) / std::max(d.squaredNorm(), 1e-300), 0.0, 1.0);
  return (a + t * d - q).norm();
}

// The smallest distance from the features to the 8 cuts (and their ends) of a split at (peak, w).
double feature_clearance(const std::vector<Vec2>& features, const Vec2& peak, double w) {
  std::array<Vec2, 8> c;
  for (int i = 0; i < 4; ++i) {
    c[i] = kSquare[i];
    c[i + 4] = (1 - w) * kSquare[i] + w * peak;
  }
  double best = std::numeric_limits<double>::infinity();
  for (const Vec2& q : features)
    for (int i = 0; i < 4; ++i) {
      best = std::min(best, segment_distance(q, c[i], c[i + 4]));
      best = std::min(best, segment_distance(q, c[i + 4], c[(i + 1) % 4 + 4]));
    }
  return best;
}

// The stretch the children of a split at (peak, w) would have if each kept the parent's map,
// carried onto its own square (inner child: a scaling; outer children: the inverse of the
// bilinear map of their trapezoid): the largest over the 5 children. Every child map predicted
// this way is bijective, and the fresh maps are usually better, so it ranks candidate splits.
// Faces are subsampled to about 2000 (deterministic stride); a face folded by the prediction
// counts as stretch 1e3.
double predicted_children_stretch(const Param& p, const Vec2& peak, double w) {
  std::array<Vec2, 8> c;
  for (int i = 0; i < 4; ++i) {
    c[i] = kSquare[i];
    c[i + 4] = (1 - w) * kSquare[i] + w * peak;
  }
  std::array<std::array<Vec2, 4>, 5> quad;
  for (int k = 0; k < 4; ++k) quad[k] = {c[k], c[(k + 1) % 4], c[(k + 1) % 4 + 4], c[k + 4]};
  quad[4] = {c[4], c[5], c[6], c[7]};
  auto inside = [](const std::array<Vec2, 4>& q, const Vec2& x) {
    for (int i = 0; i < 4; ++i)
      if (cross2(q[(i + 1) % 4] - q[i], x - q[i]) < 0) return false;
    return true;
  };
  auto to_child = [](const std::array<Vec2, 4>& q, const Vec2& x) {
    Vec2 st(0.5, 0.5);
    for (int it = 0; it < 8; ++it) {
      const double s = st.x(), t = st.y();
      const Vec2 f = (1 - s) * (1 - t) * q[0] + s * (1 - t) * q[1] + s * t * q[2] + (1 - s) * t * q[3] - x;
      const Vec2 ds = (1 - t) * (q[1] - q[0]) + t * (q[2] - q[3]);
      const Vec2 dt = (1 - s) * (q[3] - q[0]) + s * (q[2] - q[1]);
      const double det = cross2(ds, dt);
      if (std::abs(det) < 1e-300) break;
      st -= Vec2(cross2(f, dt), cross2(ds, f)) / det;
    }
    return st;
  };
  std::array<double, 5> e{}, a3{}, auv{};
  const auto& F = p.ex.pm.faces;
  const auto& P = p.ex.pm.positions;
  const size_t stride = std::max<size_t>(1, F.size() / 2000);
  for (size_t f = 0; f < F.size(); f += stride) {
    const Tri& t = F[f];
    const Vec2 q = (p.sp.uv[t[0]] + p.sp.uv[t[1]] + p.sp.uv[t[2]]) / 3.0;
    int k = 4;
    if (!inside(quad[4], q))
      for (k = 0; k < 3 && !inside(quad[k], q); ++k) {
      }
    std::array<Vec2, 3> u;
    for (int j = 0; j < 3; ++j) u[j] = to_child(quad[k], p.sp.uv[t[j]]);
    const double area3 = 0.5 * (P[t[1]] - P[t[0]]).cross(P[t[2]] - P[t[0]]).norm();
    const double area2 = 0.5 * cross2(u[1] - u[0], u[2] - u[0]);
    double l2sq;
    if (area2 <= 1e-300) {
      l2sq = 1e6;
    } else {
      const Vec3 ss = (P[t[0]] * (u[1].y() - u[2].y()) + P[t[1]] * (u[2].y() - u[0].y()) + P[t[2]] * (u[0].y() - u[1].y())) / (2 * area2);
      const Vec3 st = (P[t[0]] * (u[2].x() - u[1].x()) + P[t[1]] * (u[0].x() - u[2].x()) + P[t[2]] * (u[1].x() - u[0].x())) / (2 * area2);
      l2sq = 0.5 * (ss.squaredNorm() + st.squaredNorm());
    }
    e[k] += l2sq * area3;
    a3[k] += area3;
    auv[k] += std::max(area2, 0.0);
  }
  double worst = 0;
  for (int k = 0; k < 5; ++k)
    if (a3[k] > 0) worst = std::max(worst, std::sqrt(e[k] / a3[k] * auv[k] / a3[k]));
  return worst;
}

// Walks the union quinary tree over every mesh of the set at once.
class SetDissector {
 public:
  SetDissector(const std::vector<MeshToDissect>& in, const DissectOptions& options, const Context& context);
  DissectionSet run();

 private:
  // Parameterizes a node in every mesh and aligns its features to their mean (u,v).
  // `nodes` holds the node of every mesh (same name and label, each mesh's own corner ids).
  std::vector<Param> evaluate(const std::vector<Node>& nodes, TreeNode& tn);
  void align(std::vector<Param>& ps, TreeNode& tn);
  std::pair<Vec2, double> choose_split(const Node& node, const std::vector<Param>& ps, TreeNode& tn,
                                       const std::vector<bool>& over);

  const std::vector<MeshToDissect>& in_;
  DissectOptions opt_;
  const Context& ctx_;
  std::vector<std::string> feature_names_;
  std::vector<MeshDissector> meshes_;
};

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
  parallel_for(meshes_.size(), [&](size_t i) { ps[i] = meshes_[i].parameterize(nodes[i]); }, faces >= kParallelFaces);
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
  if (meshes_.size() > 1 && !ps[0].features.empty()) align(ps, tn);
  tn.stretch = 0;
  tn.mesh_stretch.clear();
  for (const auto& p : ps) {
    tn.mesh_stretch.push_back(p.st.patch);
    tn.stretch = std::max(tn.stretch, p.st.patch);
  }
  return ps;
}

// Moves the features of one node to their mean (u,v) over the set. Features closer than
// feature_group_distance to each other (in any mesh, or as targets) move as one group, by their
// centroid, and so do features that near to the border: a warp cannot separate them at this
// level, and the next split's fresh maps will spread them apart.
void SetDissector::align(std::vector<Param>& ps, TreeNode& tn) {
  const size_t nf = ps[0].features.size(), nm = ps.size();
  auto uv = [&](size_t i, size_t k) -> const Vec2& { return ps[i].sp.uv[ps[i].features[k].second]; };
  std::vector<Vec2> target(nf, Vec2::Zero());
  for (size_t i = 0; i < nm; ++i)
    for (size_t k = 0; k < nf; ++k) target[k] += uv(i, k);
  for (auto& t : target) t /= static_cast<double>(nm);
  const double d = opt_.feature_group_distance;
  std::vector<int> group(nf);
  for (size_t k = 0; k < nf; ++k) group[k] = static_cast<int>(k);
  std::function<int(int)> find = [&](int k) { return group[k] == k ? k : group[k] = find(group[k]); };
  std::vector<std::vector<Vec2>> rep(nm);  // per mesh, per group root: centroid
  std::vector<Vec2> rep_target;
  std::vector<int> roots;
  for (bool merged = true; merged;) {
    merged = false;
    roots.clear();
    for (size_t k = 0; k < nf; ++k)
      if (find(static_cast<int>(k)) == static_cast<int>(k)) roots.push_back(static_cast<int>(k));
    auto centroid = [&](const std::function<Vec2(size_t)>& at, int root) {
      Vec2 c = Vec2::Zero();
      int n = 0;
      for (size_t k = 0; k < nf; ++k)
        if (find(static_cast<int>(k)) == root) {
          c += at(k);
          ++n;
        }
      return Vec2(c / n);
    };
    rep_target.clear();
    for (int r : roots) rep_target.push_back(centroid([&](size_t k) { return target[k]; }, r));
    for (size_t i = 0; i < nm; ++i) {
      rep[i].clear();
      for (int r : roots) rep[i].push_back(centroid([&](size_t k) { return uv(i, k); }, r));
    }
    for (size_t a = 0; a < roots.size() && !merged; ++a)
      for (size_t b = a + 1; b < roots.size() && !merged; ++b) {
        bool close = (rep_target[a] - rep_target[b]).norm() < d;
        for (size_t i = 0; i < nm && !close; ++i) close = (rep[i][a] - rep[i][b]).norm() < d;
        if (close) {
          group[roots[b]] = roots[a];
          merged = true;
        }
      }
  }
  // Groups too near the border stay where they are in this node.
  auto near_border = [&](const Vec2& q) { return q.minCoeff() < d || q.maxCoeff() > 1 - d; };
  std::vector<size_t> moving;
  for (size_t g = 0; g < roots.size(); ++g) {
    bool ok = !near_border(rep_target[g]);
    for (size_t i = 0; i < nm && ok; ++i) ok = !near_border(rep[i][g]);
    if (ok) moving.push_back(g);
  }
  tn.feature_groups = static_cast<int>(roots.size());
  tn.features_held = static_cast<int>(roots.size() - moving.size());
  std::vector<Vec2> to;
  for (size_t g : moving) to.push_back(rep_target[g]);
  std::vector<int> events(nm, 0), pinned_solves(nm, 0);
  size_t faces = 0;
  for (const auto& p : ps) faces += p.ex.faces.size();
  parallel_for(nm, [&](size_t i) {
    Param& p = ps[i];
    std::vector<Vec2> from;
    for (size_t g : moving) from.push_back(rep[i][g]);
    warp::WarpResult wr;
    try {
      wr = warp::warp_square(from, to, p.sp.uv, {}, ctx_.without_progress());
    } catch (const Error& e) {
      const std::string m = "aligning the features of patch " + tn.name + " on " + meshes_[i].name() + ": " + e.what();
      if (e.code() == ErrorCode::InvalidInput) throw InvalidInput(m);
      throw SolverError(m);
    }
    param::SquareParam warped = p.sp;
    warped.uv = std::move(wr.points);
    events[i] = wr.events;
    param::count_uv_faces(p.ex.pm.faces, warped);
    if (!warped.bijective()) {
      // The warp is a bijection of the square, but a mesh face whose corners lie in different
      // warp triangles is mapped by its corners only and can fold where a feature moved far.
      // Then solve the mean-value map again with the features pinned where the warp put them,
      // and keep whichever folds less (ties: the warp).
      param::SquareParamOptions po;
      for (size_t k = 0; k < nf; ++k) po.pinned.emplace_back(p.features[k].second, warped.uv[p.features[k].second]);
      Context quiet = ctx_.without_progress();
      quiet.log = nullptr;  // its fold warning is expected here: the folds are compared below
      const param::SquareParam pinned = param::parameterize_square(p.ex.pm, po, quiet);
      if (pinned.flipped_faces + pinned.zero_area_faces < warped.flipped_faces + warped.zero_area_faces) {
        warped = pinned;
        pinned_solves[i] = 1;
      }
    }
    if (!warped.bijective()) {
      std::vector<char> fixed(p.ex.verts.size(), 0);
      for (const auto& f : p.features) fixed[f.second] = 1;
      warped = untangle(p.ex.pm, warped, fixed, 20);
    }
    p.sp = std::move(warped);
    p.st = param::l2_stretch(p.ex.pm.positions, p.ex.pm.faces, p.sp.uv);
  }, faces >= kParallelFaces);
  for (size_t i = 0; i < nm; ++i) {
    tn.warp_events += events[i];
    tn.pinned_solves += pinned_solves[i];
  }
}

// The split point: the smoothed stretch peak of the most stretched mesh that is over tau, in the
// aligned domain (so the children correspond in every mesh), nudged off the features if needed.
std::pair<Vec2, double> SetDissector::choose_split(const Node& node, const std::vector<Param>& ps, TreeNode& tn,
                                                   const std::vector<bool>& over) {
  int best = -1;
  for (size_t i = 0; i < ps.size(); ++i)
    if (over[i] && (best < 0 || ps[i].st.patch > ps[best].st.patch)) best = static_cast<int>(i);
  const auto [face, peak_s] = meshes_[best].peak(ps[best]);
  const Param& p = ps[best];
  const Tri& t = p.ex.pm.faces[face];
  const Vec2 raw = (p.sp.uv[t[0]] + p.sp.uv[t[1]] + p.sp.uv[t[2]]) / 3.0;
  double w = std::clamp(opt_.w_bias + std::log10(std::max(peak_s, 1e-12)), opt_.w_min, opt_.w_max);
  auto clamp = [&](const Vec2& q) { return Vec2(q.cwiseMax(opt_.peak_margin).cwiseMin(1 - opt_.peak_margin)); };
  Vec2 peak = clamp(raw);
  tn.split_mesh = best;
  if (opt_.predict_split) {
    // Candidates: the rule above first, the raw peak with smaller margins, a 3x3 grid of centres,
    // each with w in {0.5, 0.65, 0.8}; the lowest predicted children's stretch wins (ties: first).
    std::vector<Vec2> centres = {peak};
    for (double m : {0.25, 0.15}) centres.push_back(Vec2(raw.cwiseMax(m).cwiseMin(1 - m)));
    for (double y : {0.3, 0.5, 0.7})
      for (double x : {0.3, 0.5, 0.7}) centres.emplace_back(x, y);
    double best_score = predicted_children_stretch(p, peak, w);
    for (const Vec2& cc : centres)
      for (double ww : {0.5, 0.65, 0.8}) {
        const double sc = predicted_children_stretch(p, cc, ww);
        if (sc < best_score * (1 - 1e-9)) {
          best_score = sc;
          peak = cc;
          w = ww;
        }
      }
  }
  if (!p.features.empty()) {
    // Every mesh's features must clear the cuts (grouped or held features are not aligned).
    std::vector<Vec2> fuv;
    for (const auto& q : ps)
      for (const auto& f : q.features) fuv.push_back(q.sp.uv[f.second]);
    // Candidates: the peak, then rings of 8 around it; the first clear by the margin wins, else
    // the one with the largest clearance.
    Vec2 best_peak = peak;
    double best_clear = feature_clearance(fuv, peak, w);
    for (double r : {0.03, 0.06, 0.1, 0.15}) {
      if (best_clear >= opt_.feature_cut_margin) break;
      for (int k = 0; k < 8 && best_clear < opt_.feature_cut_margin; ++k) {
        const double a = k * M_PI / 4;
        const Vec2 q = clamp(peak + r * Vec2(std::cos(a), std::sin(a)));
        const double c = feature_clearance(fuv, q, w);
        if (c > best_clear) {
          best_clear = c;
          best_peak = q;
        }
      }
    }
    if (best_clear < 1e-6)
      throw InvalidInput("patch " + node.name + ": a feature lies on every candidate cut line (clearance " +
                         std::to_string(best_clear) + "); features too close together or to a patch corner");
    peak = best_peak;
  }
  tn.peak_uv = peak;
  tn.w = w;
  return {peak, w};
}

DissectionSet SetDissector::run() {
  ctx_.report("seed loop", 0.0);
  std::array<std::vector<Node>, 2> roots;  // the same names, labels and corner roles in every mesh
  for (size_t i = 0; i < meshes_.size(); ++i) {
    const std::array<int, 4> s = in_[i].seeds ? *in_[i].seeds : choose_seeds(*in_[i].mesh);
    const auto r = meshes_[i].seed(s);
    for (int k = 0; k < 2; ++k) roots[k].push_back(r[k]);
  }
  DissectionSet out;
  std::deque<std::vector<Node>> queue(roots.begin(), roots.end());
  double total_faces = 0, done_faces = 0;
  std::vector<double> max_area;  // per mesh: opt_.max_patch_area times its surface area
  for (const auto& m : in_) {
    total_faces += static_cast<double>(m.mesh->faces.size());
    double area = 0;
    for (int f = 0; f < m.mesh->num_faces(); ++f) area += face_area(*m.mesh, f);
    max_area.push_back(opt_.max_patch_area > 0 ? opt_.max_patch_area * area : INFINITY);
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
    StopReason stop = StopReason::None;
    std::string detail;
    if (any_over && !progress) {
      stop = StopReason::NoProgress;
    } else if (any_over && node.depth < opt_.max_depth && biggest_over >= opt_.min_faces_to_split) {
      const size_t first_new_label = meshes_[0].labels();
      const auto [peak, w] = choose_split(node, ps, tn, over);
      std::vector<std::array<Node, 5>> kids(meshes_.size());
      size_t node_faces = 0;
      for (const auto& p : ps) node_faces += p.ex.faces.size();
      try {
        parallel_for(meshes_.size(), [&](size_t i) {
          try {
            kids[i] = meshes_[i].split(nodes[i], ps[i], peak, w);
          } catch (const SplitFailure& e) {
            throw SplitFailure(meshes_.size() > 1 ? meshes_[i].name() + ": " + e.what() : std::string(e.what()));
          }
        }, node_faces >= kParallelFaces);
        // Counterparts must land in the same child. They do when every mesh's map is bijective
        // (the cuts are the same segments of the aligned domain); a folded map can break that.
        for (const auto& [k, local] : ps[0].features)
          for (size_t i = 1; i < meshes_.size(); ++i)
            if (meshes_[i].feature_label(k) != meshes_[0].feature_label(k))
              throw SplitFailure("feature '" + feature_names_[k] + "' would land in different children (a folded map)");
      } catch (const SplitFailure& e) {
        for (size_t i = 0; i < meshes_.size(); ++i) meshes_[i].restore(nodes[i], first_new_label);
        tn = TreeNode{};
        tn.name = node.name;
        tn.depth = node.depth;
        ps = evaluate(nodes, tn);
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
      stop = node.depth >= opt_.max_depth ? StopReason::MaxDepth : StopReason::TooFewFaces;
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
      done_faces += static_cast<double>(ps[i].ex.faces.size());
    }
    ctx_.report("quinary subdivision", std::min(1.0, done_faces / total_faces));
  }
  std::stable_sort(out.tree.begin(), out.tree.end(), [](const TreeNode& a, const TreeNode& b) {
    return a.depth != b.depth ? a.depth < b.depth : a.name < b.name;
  });
  for (auto& m : meshes_) {
    out.meshes.push_back(m.finish(out.tree));
    out.max_stretch = std::max(out.max_stretch, out.meshes.back().max_stretch);
    for (size_t k = 0; k < feature_names_.size(); ++k) out.meshes.back().features[k].name = feature_names_[k];
  }
  for (const auto& n : out.tree) out.warp_events += n.warp_events;
  return out;
}
}  // namespace

BaseDomain build_base_domain(const std::vector<PatchInfo>& patches) {
  BaseDomain bd;
  std::unordered_map<int, int> base_of;  // chart vertex -> base vertex, by first appearance
  for (const auto& p : patches)
    for (int c : p.corners)
      if (base_of.emplace(c, static_cast<int>(bd.vertices.size())).second) bd.vertices.push_back(c);
  std::vector<std::pair<int, int>> sides;
  for (const auto& p : patches) {
    std::array<int, 4> q;
    for (int k = 0; k < 4; ++k) q[k] = base_of.at(p.corners[k]);
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

DissectionSet dissect_set(const std::vector<MeshToDissect>& meshes, const DissectOptions& options,
                          const Context& context) {
  if (!(options.tau >= 1.0)) throw InvalidInput("--tau must be at least 1 (the stretch of an isometry)");
  if (meshes.empty()) throw InvalidInput("no mesh to dissect");
  for (const auto& m : meshes)
    if (m.mesh == nullptr) throw InvalidInput("dissect_set: a mesh is null");
  SetDissector d(meshes, options, context);
  return d.run();
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
