// Metro distance: sampling, and exact closest-point queries in our own bounding-volume hierarchy
// (binned-SAH binary tree, child boxes stored in the parent as outward-rounded floats, nearest
// child first, the previous sample's triangle as the first guess). Measured on venus_100k
// (100k faces, 200k queries from the faces of another mesh, one thread): 2-4x faster than
// CGAL's AABB_tree with AABB_triangle_primitive over Simple_cartesian<double> and its kd-tree
// hints, with the same distances (sums agree to 1e-9). So CGAL is not used here.
#include "qs/metro/metro.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/core/parallel.h"
#include "qs/core/weighted.h"

namespace qs::metro {

namespace {

// ---- Random numbers: splitmix64 (Steele, Lea, Flood 2014), the same on every platform --------

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/// Uniform in [0, 1) from the top 53 bits.
double unit_double(std::uint64_t x) { return static_cast<double>(x >> 11) * 0x1.0p-53; }

// ---- Input checks ----------------------------------------------------------------------------

std::string first_ids(const std::vector<long long>& ids, long long count) {
  std::string s;
  for (size_t i = 0; i < ids.size(); ++i) s += (i ? ", " : "") + std::to_string(ids[i]);
  if (count > static_cast<long long>(ids.size())) s += ", ...";
  return s;
}

/// Checks what measuring needs, collecting every problem. Returns the per-vertex "used" flags.
std::vector<char> check_mesh(const TriMesh& mesh, const std::string& name) {
  if (mesh.faces.empty())
    throw InvalidInput(name + ": the mesh has no faces (" + std::to_string(mesh.num_vertices()) +
                       " vertices); metro measures distances between surfaces, so each mesh "
                       "needs at least one triangle");
  const int nv = mesh.num_vertices();
  std::vector<char> used(static_cast<size_t>(nv), 0);
  std::vector<long long> bad_faces, bad_vertices;
  long long n_bad_faces = 0, n_bad_vertices = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    bool ok = true;
    for (int v : mesh.faces[static_cast<size_t>(f)]) ok = ok && v >= 0 && v < nv;
    if (!ok) {
      if (bad_faces.size() < 10) bad_faces.push_back(f);
      ++n_bad_faces;
      continue;
    }
    for (int v : mesh.faces[static_cast<size_t>(f)]) used[static_cast<size_t>(v)] = 1;
  }
  for (int v = 0; v < nv; ++v)
    if (used[static_cast<size_t>(v)] && !mesh.positions[static_cast<size_t>(v)].allFinite()) {
      if (bad_vertices.size() < 10) bad_vertices.push_back(v);
      ++n_bad_vertices;
    }
  std::string problems;
  if (n_bad_faces > 0)
    problems += "\n  " + std::to_string(n_bad_faces) + " faces with a vertex index outside [0, " +
                std::to_string(nv) + ") (faces " + first_ids(bad_faces, n_bad_faces) + ")";
  if (n_bad_vertices > 0)
    problems += "\n  " + std::to_string(n_bad_vertices) +
                " vertices used by faces have a NaN or infinite coordinate (vertices " +
                first_ids(bad_vertices, n_bad_vertices) + ")";
  if (!problems.empty())
    throw InvalidInput(name + ": cannot measure distances on this mesh:" + problems +
                       "\n  fix or remove these elements (qs-inspect lists them)");
  return used;
}

// ---- Closest point on a triangle (Ericson, Real-Time Collision Detection, 5.1.5) ------------

struct P3 {
  double x, y, z;
};
inline P3 operator-(const P3& a, const P3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline P3 operator+(const P3& a, const P3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline P3 operator*(double s, const P3& a) { return {s * a.x, s * a.y, s * a.z}; }
inline double dot(const P3& a, const P3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline P3 cross(const P3& a, const P3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline P3 to_p3(const Vec3& v) { return {v.x(), v.y(), v.z()}; }

struct Triangle {
  P3 a, b, c;
  P3 n;  ///< unit normal (zero for a degenerate triangle)
  int face;
  bool degenerate;  ///< (nearly) zero area: measured as its three edges
};

inline P3 closest_on_segment(const P3& p, const P3& a, const P3& b) {
  const P3 ab = b - a;
  const double len2 = dot(ab, ab);
  if (!(len2 > 0)) return a;
  const double t = std::clamp(dot(p - a, ab) / len2, 0.0, 1.0);
  return a + t * ab;
}

inline P3 closest_on_triangle(const P3& p, const Triangle& t) {
  const P3& a = t.a;
  const P3& b = t.b;
  const P3& c = t.c;
  if (t.degenerate) {
    P3 best = closest_on_segment(p, a, b);
    P3 d = p - best;
    double best_d2 = dot(d, d);
    for (const P3& q : {closest_on_segment(p, b, c), closest_on_segment(p, c, a)}) {
      d = p - q;
      const double d2 = dot(d, d);
      if (d2 < best_d2) best_d2 = d2, best = q;
    }
    return best;
  }
  const P3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const P3 bp = p - b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + (d1 / (d1 - d3)) * ab;
  const P3 cp = p - c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + (d2 / (d2 - d6)) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + (vb * denom) * ab + (vc * denom) * ac;
}

// ---- Bounding-volume hierarchy ---------------------------------------------------------------

/// An inner node of the hierarchy holds the boxes of both children (in floats rounded outward,
/// so one node is one 64-byte cache line and a child is only fetched when it must be searched).
struct alignas(64) Node {
  float lo[2][3], hi[2][3];
  int child[2];  ///< inner child: node index; leaf child: first triangle
  int count[2];  ///< leaf child: number of triangles (>= 1); inner child: 0
};

constexpr int kLeafSize = 4;
/// Meshes of at least this many faces build their tree on several threads.
constexpr size_t kParallelBuildFaces = 20000;
constexpr int kMaxSahDepth = 40;  ///< deeper, median splits: the depth stays below 40 + 32

inline float round_down(double x) {
  if (x > std::numeric_limits<float>::max()) return std::numeric_limits<float>::max();
  if (x < -std::numeric_limits<float>::max()) return -std::numeric_limits<float>::infinity();
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}
inline float round_up(double x) {
  if (x > std::numeric_limits<float>::max()) return std::numeric_limits<float>::infinity();
  if (x < -std::numeric_limits<float>::max()) return -std::numeric_limits<float>::max();
  float f = static_cast<float>(x);
  if (static_cast<double>(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

/// Squared distance from p to child c's box (computed in double: a true lower bound).
inline double box_distance2(const Node& n, int c, const P3& p) {
  const double dx = std::max({static_cast<double>(n.lo[c][0]) - p.x, 0.0, p.x - static_cast<double>(n.hi[c][0])});
  const double dy = std::max({static_cast<double>(n.lo[c][1]) - p.y, 0.0, p.y - static_cast<double>(n.hi[c][1])});
  const double dz = std::max({static_cast<double>(n.lo[c][2]) - p.z, 0.0, p.z - static_cast<double>(n.hi[c][2])});
  return dx * dx + dy * dy + dz * dz;
}

}  // namespace

struct SurfaceDistance::Impl {
  std::vector<Triangle> tris;  ///< in leaf order
  std::vector<Node> nodes;     ///< inner nodes, depth first
  /// The root, as a child of a parent node that is not stored: box in [0], and whether it is a
  /// leaf (a mesh of at most kLeafSize faces) or node 0.
  Node root;

  struct Hit {
    double d2 = std::numeric_limits<double>::infinity();
    P3 point{0, 0, 0};
    int tri = -1;  ///< index into tris
  };

  /// What the build needs per face: its box and the centre of the box.
  struct Prim {
    double lo[3], hi[3], c[3];
  };

  /// Face f of `mesh` as a triangle: corners, unit normal, degeneracy.
  static Triangle triangle(const TriMesh& mesh, size_t f) {
    const Tri& t = mesh.faces[f];
    Triangle tr;
    tr.a = to_p3(mesh.positions[static_cast<size_t>(t[0])]);
    tr.b = to_p3(mesh.positions[static_cast<size_t>(t[1])]);
    tr.c = to_p3(mesh.positions[static_cast<size_t>(t[2])]);
    tr.face = static_cast<int>(f);
    const P3 ab = tr.b - tr.a, ac = tr.c - tr.a, n = cross(ab, ac);
    // Relative test: |ab x ac| = |ab| |ac| sin(angle); below ~1e-10 of that the interior
    // branch of the closest-point routine would divide by (almost) zero.
    tr.degenerate = !(dot(n, n) > 1e-20 * dot(ab, ab) * dot(ac, ac));
    tr.n = tr.degenerate ? P3{0, 0, 0} : (1 / std::sqrt(dot(n, n))) * n;
    return tr;
  }

  /// The same faces at the positions of `mesh`: every triangle and box again, the tree kept.
  void refit(const TriMesh& mesh) {
    for (Triangle& tr : tris) tr = triangle(mesh, static_cast<size_t>(tr.face));
    auto leaf_box = [&](int first, int count, float* lo, float* hi) {
      double l[3], h[3];
      for (int k = 0; k < 3; ++k) l[k] = std::numeric_limits<double>::infinity(), h[k] = -l[k];
      for (int i = first; i < first + count; ++i) {
        const Triangle& t = tris[static_cast<size_t>(i)];
        const double cs[3][3] = {{t.a.x, t.b.x, t.c.x}, {t.a.y, t.b.y, t.c.y}, {t.a.z, t.b.z, t.c.z}};
        for (int k = 0; k < 3; ++k)
          l[k] = std::min({l[k], cs[k][0], cs[k][1], cs[k][2]}), h[k] = std::max({h[k], cs[k][0], cs[k][1], cs[k][2]});
      }
      for (int k = 0; k < 3; ++k) lo[k] = round_down(l[k]), hi[k] = round_up(h[k]);
    };
    // A parent's boxes from its children's: children come after their parent in `nodes`.
    auto refit_child = [&](Node& parent, int c) {
      if (parent.count[c] > 0) return leaf_box(parent.child[c], parent.count[c], parent.lo[c], parent.hi[c]);
      const Node& n = nodes[static_cast<size_t>(parent.child[c])];
      for (int k = 0; k < 3; ++k)
        parent.lo[c][k] = std::min(n.lo[0][k], n.lo[1][k]), parent.hi[c][k] = std::max(n.hi[0][k], n.hi[1][k]);
    };
    for (size_t i = nodes.size(); i-- > 0;)
      for (int c = 0; c < 2; ++c) refit_child(nodes[i], c);
    refit_child(root, 0);
  }

  /// `threads`: the build's (0: all hardware threads); the same tree on any count.
  void build(const TriMesh& mesh, int threads) {
    const size_t nf = mesh.faces.size();
    const int count = nf < kParallelBuildFaces || inside_parallel_loop() ? 1 : thread_count(threads, Context{});
    std::vector<Triangle> in(nf);
    std::vector<Prim> prims(nf);
    const int chunks = count > 1 ? 4 * count : 1;
    parallel_for(chunks, count, Context{}, [&](int k) {
      for (size_t f = nf * static_cast<size_t>(k) / chunks; f < nf * static_cast<size_t>(k + 1) / chunks; ++f)
        prim(mesh, f, in[f], prims[f]);
    });
    std::vector<int> order(nf), scratch(nf);
    for (size_t i = 0; i < nf; ++i) order[i] = static_cast<int>(i);
    nodes.clear();
    nodes.reserve(nf / 2 + 8);
    // Subtrees down to this depth are built at once, 2^depth of them on `count` threads.
    int fork_depth = 0;
    while ((1 << fork_depth) < count) ++fork_depth;
    build_node(prims, order, scratch, 0, static_cast<int>(nf), 0, root, 0, nodes, fork_depth);
    tris.resize(nf);
    for (size_t i = 0; i < nf; ++i) tris[i] = in[static_cast<size_t>(order[i])];
  }

  /// Face f as a triangle and its box and centre.
  static void prim(const TriMesh& mesh, size_t f, Triangle& tr, Prim& p) {
    tr = triangle(mesh, f);
    const double xs[3] = {tr.a.x, tr.b.x, tr.c.x}, ys[3] = {tr.a.y, tr.b.y, tr.c.y},
                 zs[3] = {tr.a.z, tr.b.z, tr.c.z};
    const double* cs[3] = {xs, ys, zs};
    for (int k = 0; k < 3; ++k) {
      p.lo[k] = std::min({cs[k][0], cs[k][1], cs[k][2]});
      p.hi[k] = std::max({cs[k][0], cs[k][1], cs[k][2]});
      p.c[k] = 0.5 * (p.lo[k] + p.hi[k]);
    }
  }

  /// Builds the subtree over order[begin, end) into `out` (depth first) and records it as child
  /// `slot` of `parent`. Above `fork` levels the two children are built at once, the second into
  /// a vector of its own appended after the first's: the same nodes in the same order.
  void build_node(const std::vector<Prim>& prims, std::vector<int>& order, std::vector<int>& scratch,
                  int begin, int end, int depth, Node& parent, int slot, std::vector<Node>& out, int fork) {
    double lo[3], hi[3], clo[3], chi[3];
    for (int k = 0; k < 3; ++k) {
      lo[k] = clo[k] = std::numeric_limits<double>::infinity();
      hi[k] = chi[k] = -std::numeric_limits<double>::infinity();
    }
    for (int i = begin; i < end; ++i) {
      const Prim& p = prims[static_cast<size_t>(order[static_cast<size_t>(i)])];
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], p.lo[k]), hi[k] = std::max(hi[k], p.hi[k]);
        clo[k] = std::min(clo[k], p.c[k]), chi[k] = std::max(chi[k], p.c[k]);
      }
    }
    for (int k = 0; k < 3; ++k) parent.lo[slot][k] = round_down(lo[k]), parent.hi[slot][k] = round_up(hi[k]);
    if (end - begin <= kLeafSize) {
      // Leaf contents in face order, whatever order the partitions left them in.
      std::sort(order.begin() + begin, order.begin() + end);
      parent.child[slot] = begin;
      parent.count[slot] = end - begin;
      return;
    }
    const int index = static_cast<int>(out.size());
    parent.child[slot] = index;
    parent.count[slot] = 0;
    out.emplace_back();  // filled in below, once both children are known
    const int mid = depth < kMaxSahDepth ? split(prims, order, scratch, begin, end, clo, chi)
                                         : median_split(prims, order, begin, end, clo, chi);
    Node node;
    if (fork <= 0) {
      build_node(prims, order, scratch, begin, mid, depth + 1, node, 0, out, 0);
      build_node(prims, order, scratch, mid, end, depth + 1, node, 1, out, 0);
      out[static_cast<size_t>(index)] = node;
      return;
    }
    std::vector<Node> second;
    parallel_for(2, 2, Context{}, [&](int c) {
      build_node(prims, order, scratch, c ? mid : begin, c ? end : mid, depth + 1, node, c, c ? second : out, fork - 1);
    });
    // The second subtree's node indices follow the first's.
    const int offset = static_cast<int>(out.size());
    for (Node& n : second)
      for (int c = 0; c < 2; ++c)
        if (n.count[c] == 0) n.child[c] += offset;
    if (node.count[1] == 0) node.child[1] += offset;
    out.insert(out.end(), second.begin(), second.end());
    out[static_cast<size_t>(index)] = node;
  }

  /// Halves order[begin, end) at the median box centre along the longest axis of the centres.
  static int median_split(const std::vector<Prim>& prims, std::vector<int>& order, int begin, int end,
                          const double* clo, const double* chi) {
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (chi[k] - clo[k] > chi[axis] - clo[axis]) axis = k;
    const int mid = begin + (end - begin) / 2;
    // Ties broken by face id: the halves do not depend on the nth_element implementation.
    std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end, [&](int l, int r) {
      const double kl = prims[static_cast<size_t>(l)].c[axis], kr = prims[static_cast<size_t>(r)].c[axis];
      return kl < kr || (kl == kr && l < r);
    });
    return mid;
  }

  /// Binned surface-area-heuristic split (Wald 2007) of order[begin, end) by box centres; returns
  /// the first index of the right part. Falls back to a split by face id when the centres cannot
  /// be told apart. Deterministic: stable partitions, ties broken by face id.
  static int split(const std::vector<Prim>& prims, std::vector<int>& order, std::vector<int>& scratch,
                   int begin, int end, const double* clo, const double* chi) {
    constexpr int kBins = 16;
    constexpr double inf = std::numeric_limits<double>::infinity();
    struct Bin {
      double lo[3] = {inf, inf, inf}, hi[3] = {-inf, -inf, -inf};
      int n = 0;
    };
    auto half_area = [](const double* lo, const double* hi) {
      const double dx = hi[0] - lo[0], dy = hi[1] - lo[1], dz = hi[2] - lo[2];
      return dx < 0 ? 0.0 : dx * dy + dy * dz + dz * dx;
    };
    double scale[3];
    for (int k = 0; k < 3; ++k) scale[k] = chi[k] > clo[k] ? kBins / (chi[k] - clo[k]) : 0.0;
    auto bin_of = [&](const Prim& p, int axis) {
      return std::clamp(static_cast<int>((p.c[axis] - clo[axis]) * scale[axis]), 0, kBins - 1);
    };
    Bin bins[3][kBins];
    for (int i = begin; i < end; ++i) {
      const Prim& p = prims[static_cast<size_t>(order[static_cast<size_t>(i)])];
      for (int axis = 0; axis < 3; ++axis) {
        Bin& b = bins[axis][bin_of(p, axis)];
        ++b.n;
        for (int k = 0; k < 3; ++k) b.lo[k] = std::min(b.lo[k], p.lo[k]), b.hi[k] = std::max(b.hi[k], p.hi[k]);
      }
    }
    double best_cost = inf;
    int best_axis = -1, best_bin = -1;
    for (int axis = 0; axis < 3; ++axis) {
      if (scale[axis] == 0) continue;
      double right_area[kBins];
      int right_n[kBins];
      Bin acc;
      for (int b = kBins - 1; b > 0; --b) {
        const Bin& x = bins[axis][b];
        for (int k = 0; k < 3; ++k) acc.lo[k] = std::min(acc.lo[k], x.lo[k]), acc.hi[k] = std::max(acc.hi[k], x.hi[k]);
        acc.n += x.n;
        right_area[b] = half_area(acc.lo, acc.hi);
        right_n[b] = acc.n;
      }
      acc = Bin{};
      for (int b = 1; b < kBins; ++b) {  // left = bins [0, b)
        const Bin& x = bins[axis][b - 1];
        for (int k = 0; k < 3; ++k) acc.lo[k] = std::min(acc.lo[k], x.lo[k]), acc.hi[k] = std::max(acc.hi[k], x.hi[k]);
        acc.n += x.n;
        if (acc.n == 0 || right_n[b] == 0) continue;
        const double cost = half_area(acc.lo, acc.hi) * acc.n + right_area[b] * right_n[b];
        if (cost < best_cost) best_cost = cost, best_axis = axis, best_bin = b;
      }
    }
    if (best_axis < 0) {  // every centre at one point: split by face id
      std::sort(order.begin() + begin, order.begin() + end);
      return begin + (end - begin) / 2;
    }
    // Stable partition through the scratch buffer (its own range: subtrees may be built at once).
    int left = begin, right = begin;
    for (int i = begin; i < end; ++i) {
      const int f = order[static_cast<size_t>(i)];
      if (bin_of(prims[static_cast<size_t>(f)], best_axis) < best_bin) order[static_cast<size_t>(left++)] = f;
      else scratch[static_cast<size_t>(right++)] = f;
    }
    std::copy(scratch.begin() + begin, scratch.begin() + right, order.begin() + left);
    return left;
  }

  /// The nearest surface point to p. `hint` (an index into tris, or -1) is tried first: a good
  /// one (the previous sample's triangle) prunes most of the tree. With `facing`, only triangles
  /// whose normal n has dot(n, *facing) >= min_cos count (none: tri -1).
  Hit closest(const P3& p, int hint, const P3* facing = nullptr, double min_cos = 0) const {
    Hit best;
    auto try_tri = [&](int i) {
      if (facing && !(dot(tris[static_cast<size_t>(i)].n, *facing) >= min_cos)) return;
      const P3 q = closest_on_triangle(p, tris[static_cast<size_t>(i)]);
      const P3 d = p - q;
      const double d2 = dot(d, d);
      if (d2 < best.d2) best.d2 = d2, best.point = q, best.tri = i;
    };
    if (hint >= 0) try_tri(hint);
    struct Entry {
      double d2;
      int child, count;  ///< as in Node
    };
    Entry stack[160];  // depth < kMaxSahDepth + 32, and a pop pushes at most two
    int top = 0;
    const double root_d2 = box_distance2(root, 0, p);
    if (root_d2 < best.d2) stack[top++] = {root_d2, root.child[0], root.count[0]};
    while (top > 0) {
      const Entry e = stack[--top];
      if (e.d2 >= best.d2) continue;
      if (e.count > 0) {
        for (int i = e.child; i < e.child + e.count; ++i)
          if (i != hint) try_tri(i);
        continue;
      }
      const Node& n = nodes[static_cast<size_t>(e.child)];
      const double d0 = box_distance2(n, 0, p), d1 = box_distance2(n, 1, p);
      // Push the farther child first so that the nearer one is searched first.
      const int near = d1 < d0 ? 1 : 0, far = 1 - near;
      const double dn = near ? d1 : d0, df = near ? d0 : d1;
      if (df < best.d2) stack[top++] = {df, n.child[far], n.count[far]};
      if (dn < best.d2) stack[top++] = {dn, n.child[near], n.count[near]};
    }
    return best;
  }
};

SurfaceDistance::SurfaceDistance(const TriMesh& mesh, const char* name, int threads)
    : impl_(std::make_unique<Impl>()) {
  check_mesh(mesh, name);
  impl_->build(mesh, threads);
}
void SurfaceDistance::refit(const TriMesh& mesh) {
  if (mesh.faces.size() != impl_->tris.size())
    throw InvalidInput("SurfaceDistance::refit: " + std::to_string(mesh.faces.size()) + " faces, the tree has " +
                       std::to_string(impl_->tris.size()));
  check_mesh(mesh, "the moved mesh");
  impl_->refit(mesh);
}
SurfaceDistance::~SurfaceDistance() = default;
SurfaceDistance::SurfaceDistance(SurfaceDistance&&) noexcept = default;
SurfaceDistance& SurfaceDistance::operator=(SurfaceDistance&&) noexcept = default;

SurfaceDistance::Closest SurfaceDistance::closest(const Vec3& query) const {
  const Impl::Hit h = impl_->closest(to_p3(query), -1);
  Closest c;
  c.distance = std::sqrt(h.d2);
  c.point = Vec3(h.point.x, h.point.y, h.point.z);
  c.face = impl_->tris[static_cast<size_t>(h.tri)].face;
  return c;
}

SurfaceDistance::Closest SurfaceDistance::closest_facing(const Vec3& query, const Vec3& facing,
                                                         double min_cos) const {
  int hint = -1;
  return closest_facing(query, facing, min_cos, hint);
}

SurfaceDistance::Closest SurfaceDistance::closest_facing(const Vec3& query, const Vec3& facing, double min_cos,
                                                         int& hint) const {
  const double len = facing.norm();
  Closest c;
  c.face = -1;
  c.distance = std::numeric_limits<double>::infinity();
  if (!(len > 0)) return c;
  const P3 f = to_p3(facing / len);
  const Impl::Hit h = impl_->closest(to_p3(query), hint, &f, min_cos);
  if (h.tri < 0) return c;
  hint = h.tri;
  c.distance = std::sqrt(h.d2);
  c.point = Vec3(h.point.x, h.point.y, h.point.z);
  c.face = impl_->tris[static_cast<size_t>(h.tri)].face;
  return c;
}

namespace {

/// Samples per unit of work: 4096, or more for very large counts so that there are at most
/// ~65536 units. It depends on the count only, never on the threads, so neither do the results.
long chunk_size(long n) { return std::max(4096L, n / 65536 + 1); }

struct ChunkResult {
  double sum = 0, sum2 = 0, max = -1;
  P3 max_at{0, 0, 0};
};

/// The sampled mesh, prepared once: positions, faces of positive area, and the running area.
struct SampledMesh {
  const TriMesh* mesh = nullptr;
  std::vector<double> cumulative;  ///< #F + 1, cumulative[f] = area of faces before f
  std::vector<int> used_vertices;  ///< vertices referenced by faces, ascending
  double area = 0;
  double diagonal = 0;             ///< of the used vertices
};

SampledMesh prepare(const TriMesh& mesh, const std::vector<char>& used, const std::string& name) {
  SampledMesh s;
  s.mesh = &mesh;
  s.cumulative.resize(mesh.faces.size() + 1);
  s.cumulative[0] = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    s.cumulative[f + 1] = s.cumulative[f] + face_area(mesh, static_cast<int>(f));
  s.area = s.cumulative.back();
  if (!(s.area > 0))
    throw InvalidInput(name + ": every face has zero area (" + std::to_string(mesh.num_faces()) +
                       " faces); there is no surface to sample");
  if (!std::isfinite(s.area))
    throw InvalidInput(name + ": the surface area overflows (coordinates too large); scale the "
                       "mesh down");
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (size_t v = 0; v < used.size(); ++v)
    if (used[v]) {
      s.used_vertices.push_back(static_cast<int>(v));
      lo = lo.cwiseMin(mesh.positions[v]);
      hi = hi.cwiseMax(mesh.positions[v]);
    }
  s.diagonal = (hi - lo).norm();
  return s;
}

/// Measures one direction: samples on `from`, distances to the surface in `to`.
OneSided measure(const SampledMesh& from, const SurfaceDistance::Impl& to, long n_samples,
                 bool sample_vertices, std::uint64_t seed, int threads, const Context& ctx,
                 const std::string& stage) {
  const TriMesh& mesh = *from.mesh;
  const long n_vertex = sample_vertices ? static_cast<long>(from.used_vertices.size()) : 0;
  const long surface_chunk = chunk_size(n_samples), vertex_chunk = chunk_size(n_vertex);
  const long surface_chunks = (n_samples + surface_chunk - 1) / surface_chunk;
  const long vertex_chunks = (n_vertex + vertex_chunk - 1) / vertex_chunk;
  const long n_chunks = surface_chunks + vertex_chunks;
  std::vector<ChunkResult> results(static_cast<size_t>(n_chunks));
  // Systematic sampling: sample k sits at arc-area (k + offset) * area / n along the faces.
  const double offset = unit_double(splitmix64(seed));
  const double step = from.area / static_cast<double>(n_samples);
  const double last = std::nextafter(from.area, 0.0);

  auto run_chunk = [&](long c) {
    ChunkResult r;
    int hint = -1;
    auto add = [&](const P3& p, bool surface) {
      const SurfaceDistance::Impl::Hit h = to.closest(p, hint);
      hint = h.tri;
      const double d = std::sqrt(h.d2);
      if (surface) r.sum += d, r.sum2 += h.d2;
      if (d > r.max) r.max = d, r.max_at = p;
    };
    if (c < surface_chunks) {
      const long k0 = c * surface_chunk, k1 = std::min(n_samples, k0 + surface_chunk);
      auto face_of = [&](double t) {
        const auto it = std::upper_bound(from.cumulative.begin(), from.cumulative.end(), t);
        return static_cast<size_t>(it - from.cumulative.begin()) - 1;
      };
      size_t f = face_of(std::min((static_cast<double>(k0) + offset) * step, last));
      for (long k = k0; k < k1; ++k) {
        const double t = std::min((static_cast<double>(k) + offset) * step, last);
        while (from.cumulative[f + 1] <= t) ++f;
        const std::uint64_t h1 = splitmix64(seed ^ (0xD1B54A32D192ED03ull * static_cast<std::uint64_t>(k + 1)));
        const std::uint64_t h2 = splitmix64(h1);
        const double s = std::sqrt(unit_double(h1)), r2 = unit_double(h2);
        const Tri& tri = mesh.faces[f];
        const P3 a = to_p3(mesh.positions[static_cast<size_t>(tri[0])]);
        const P3 b = to_p3(mesh.positions[static_cast<size_t>(tri[1])]);
        const P3 cc = to_p3(mesh.positions[static_cast<size_t>(tri[2])]);
        add((1 - s) * a + (s * (1 - r2)) * b + (s * r2) * cc, true);
      }
    } else {
      const long k0 = (c - surface_chunks) * vertex_chunk, k1 = std::min(n_vertex, k0 + vertex_chunk);
      for (long k = k0; k < k1; ++k)
        add(to_p3(mesh.positions[static_cast<size_t>(from.used_vertices[static_cast<size_t>(k)])]), false);
    }
    results[static_cast<size_t>(c)] = r;
  };

  ctx.report(stage, 0.0);
  parallel_for(static_cast<int>(n_chunks), threads, ctx, run_chunk, stage);  // the calling thread reports

  OneSided out;
  double sum = 0, sum2 = 0;
  for (const ChunkResult& r : results) sum += r.sum, sum2 += r.sum2;  // in chunk order
  double best = -1;  // the first chunk with the largest value wins ties
  for (const ChunkResult& r : results)
    if (r.max > best) best = r.max, out.max_at = Vec3(r.max_at.x, r.max_at.y, r.max_at.z);
  out.max = std::max(best, 0.0);
  out.samples = n_samples;
  out.vertex_samples = n_vertex;
  out.mean = sum / static_cast<double>(n_samples);
  out.rms = std::sqrt(sum2 / static_cast<double>(n_samples));
  return out;
}

}  // namespace

MetroResult metro(const TriMesh& a, const TriMesh& b, const MetroOptions& options, const Context& ctx) {
  if (options.face_samples < 0)
    throw InvalidInput("metro: face_samples is " + std::to_string(options.face_samples) +
                       "; give a positive count, or 0 for the automatic one");
  if (!std::isfinite(options.samples_per_face) || options.samples_per_face < 0)
    throw InvalidInput("metro: samples_per_face is " + std::to_string(options.samples_per_face) +
                       "; expected a finite number >= 0");
  if (options.min_samples < 1)
    throw InvalidInput("metro: min_samples is " + std::to_string(options.min_samples) + "; expected >= 1");
  if (options.threads < 0)
    throw InvalidInput("metro: threads is " + std::to_string(options.threads) +
                       "; expected >= 0 (0 = one per hardware thread)");

  const std::vector<char> used_a = check_mesh(a, "A");
  const std::vector<char> used_b = check_mesh(b, "B");
  const SampledMesh sa = prepare(a, used_a, "A");
  const SampledMesh sb = prepare(b, used_b, "B");

  long n = options.face_samples;
  if (n == 0) {
    const double automatic =
        std::ceil(options.samples_per_face * static_cast<double>(std::max(a.num_faces(), b.num_faces())));
    n = std::max(options.min_samples, static_cast<long>(std::min(automatic, 1e15)));
  }
  // The two trees are independent: build them side by side.
  SurfaceDistance::Impl tree_a, tree_b;
  const int threads = thread_count(options.threads, ctx);
  parallel_for(2, options.threads, ctx, [&](int i) { i == 0 ? tree_a.build(a, threads) : tree_b.build(b, threads); });

  MetroResult res;
  const std::uint64_t seed = splitmix64(options.seed);
  res.a_to_b = measure(sa, tree_b, n, options.sample_vertices, splitmix64(seed ^ 0xA), options.threads, ctx,
                       "metro A -> B");
  res.b_to_a = measure(sb, tree_a, n, options.sample_vertices && options.sample_vertices_b, splitmix64(seed ^ 0xB),
                       options.threads, ctx, "metro B -> A");
  res.max = std::max(res.a_to_b.max, res.b_to_a.max);
  res.mean = 0.5 * (res.a_to_b.mean + res.b_to_a.mean);
  res.rms = std::sqrt(0.5 * (res.a_to_b.rms * res.a_to_b.rms + res.b_to_a.rms * res.b_to_a.rms));
  res.diagonal = sa.diagonal;
  res.area_a = sa.area;
  res.area_b = sb.area;
  return res;
}

namespace {

// Each vertex of `mesh` with a positive area share: (its distance to `to`, its share).
std::vector<std::pair<double, double>> weighted_vertex_distances(const TriMesh& mesh, const SurfaceDistance& to,
                                                                 const Context& ctx) {
  const size_t n = mesh.positions.size();
  std::vector<double> area(n, 0.0), distance(n, 0.0);
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const double third = face_area(mesh, f) / 3;
    for (int v : mesh.faces[f]) area[static_cast<size_t>(v)] += third;
  }
  constexpr int kBlock = 1024;
  parallel_for(static_cast<int>((n + kBlock - 1) / kBlock), ctx, [&](int block) {
    const size_t end = std::min(n, static_cast<size_t>(block + 1) * kBlock);
    for (size_t v = static_cast<size_t>(block) * kBlock; v < end; ++v)
      if (area[v] > 0) distance[v] = to.distance(mesh.positions[v]);
  });
  std::vector<std::pair<double, double>> out;
  for (size_t v = 0; v < n; ++v)
    if (area[v] > 0) out.emplace_back(distance[v], area[v]);
  return out;
}

}  // namespace

VertexDistance vertex_distance(const TriMesh& a, const SurfaceDistance& to_a, const TriMesh& b,
                               const SurfaceDistance& to_b, double fraction, const Context& ctx) {
  std::vector<std::pair<double, double>> ab = weighted_vertex_distances(a, to_b, ctx);
  std::vector<std::pair<double, double>> ba = weighted_vertex_distances(b, to_a, ctx);
  auto total = [](const std::vector<std::pair<double, double>>& v) {
    double t = 0;
    for (const auto& dw : v) t += dw.second;
    return t;
  };
  const double ta = total(ab), tb = total(ba);
  if (!(ta > 0) || !(tb > 0)) return {};
  for (auto& dw : ab) dw.second /= 2 * ta;
  for (auto& dw : ba) dw.second /= 2 * tb;
  ab.insert(ab.end(), ba.begin(), ba.end());
  std::sort(ab.begin(), ab.end());
  VertexDistance out;
  for (const auto& [d, w] : ab) out.mean += w * d;
  out.quantile = value_at_weight(ab, fraction);
  return out;
}

}  // namespace qs::metro
