#include "qs/remesh/anisotropic.h"

#include <algorithm>
#include <functional>
#include <array>
#include <cmath>
#include <cstdint>
#include <utility>
#include <limits>
#include <string>
#include <unordered_set>

#include "qs/core/error.h"
#include "qs/core/geometry2d.h"
#include "qs/mesh/connectivity.h"
#include "qs/remesh/chart_sampler.h"
#include "qs/remesh/quality.h"
#include "qs/remesh/uniform.h"

namespace qs::remesh {

namespace {

// Node rectangles in integer units of 2^-kUnits of the unit square (kUnits > the finest numbering
// level, so that a point half a finest cell outside a side is an integer too).
constexpr int kUnits = kMaxUniformLevel + 2;
constexpr int kSpan = 1 << kUnits;

// A node is split for its aspect alone only while it covers more than this share of max_area, so
// that a map degenerate at a point (every node near it long) cannot refine it to max_level.
constexpr double kAspectAreaFloor = 1.0 / 16;

// The interior smoothing keeps a move that raises its ring's summed angle quality while the ring's
// worst angle keeps at least this share of its sine (see the header).
constexpr double kSmoothWorstSlack = 0.9;

// A flip's new edge may lie this share of its length off the surface (at its midpoint) where the
// old edge lay closer (see flip_for_angles).
constexpr double kFlipChordSlack = 0.005;
// ... and its two triangles may cover this much more area than the old two (a flip across a fold
// of a squeezed map does much more: polygirl_20k's level-5 vertex spread 33.8 -> 50 without it).
constexpr double kFlipAreaGrowth = 1.05;

constexpr double kHalfLog2 = 0.34657359027997264;  // log(2) / 2

enum Split : int { kNone = 0, kU = 1, kV = 2, kUV = 3 };

struct TreeNode {
  int lu = 0, lv = 0, i = 0, j = 0;
  int split = kNone;
  int child = -1;  // first child's index in the patch's node list
  double area = -1;  // A_C, or -1 when not measured
  double log_aspect = 0;  // log r(q): the midrange of log(Su / Sv) over the meshes
  double log_spread = 0;  // half the range of log(Su / Sv) over the meshes
  int x0() const { return i << (kUnits - lu); }
  int x1() const { return (i + 1) << (kUnits - lu); }
  int y0() const { return j << (kUnits - lv); }
  int y1() const { return (j + 1) << (kUnits - lv); }
};

class Builder {
 public:
  Builder(const std::vector<ChartSampler>& samplers, const AnisotropicOptions& o, AnisotropicStats& stats)
      : samplers_(samplers), o_(o), stats_(stats), t_(samplers[0].topology()), nodes_(t_.num_patches()),
        hints_(samplers.size(), -1), log_max_(std::log(o.max_aspect)) {
    for (const auto& s : samplers) {
      double area = 0;
      for (int f = 0; f < s.chart().mesh.num_faces(); ++f) area += face_area(s.chart().mesh, f);
      inv_area_.push_back(area > 0 ? 1.0 / area : 0.0);
    }
    for (int p = 0; p < t_.num_patches(); ++p) nodes_[p].push_back(TreeNode{});
  }

  void refine_patch(int p) { refine(p, 0); }

  // 2:1 balance along every leaf side (see the header).
  void balance() {
    std::vector<std::pair<int, int>> work;
    for (int p = 0; p < t_.num_patches(); ++p) collect_leaves(p, 0, work);
    for (size_t w = 0; w < work.size(); ++w) {
      const auto [p, a] = work[w];
      if (nodes_[p][a].split != kNone) continue;
      for (int d = 0; d < 4; ++d) {
        const TreeNode na = nodes_[p][a];
        int q, b, side;
        neighbour(p, na, d, q, b, side);
        const TreeNode& nb = nodes_[q][b];
        const int res_a = d % 2 == 0 ? na.lu : na.lv;
        const int res_b = side % 2 == 0 ? nb.lu : nb.lv;
        if (res_b >= res_a - 1) continue;
        const TreeNode& mb = measured(q, b);  // no reallocation: nb is still valid
        const double r = mb.log_aspect, half = 0.5 * log_max_;
        // Along the needed direction alone when it is the long one (or the other is at max_level).
        int kind;
        if (side % 2 == 0) kind = r > half || mb.lv + 1 > o_.max_level ? kU : kUV;
        else kind = r < -half || mb.lu + 1 > o_.max_level ? kV : kUV;
        split(q, b, kind);
        ++stats_.balance_splits;
        const int c = nodes_[q][b].child;
        for (int k = 0; k < (nodes_[q][b].split == kUV ? 4 : 2); ++k) work.push_back({q, c + k});
        work.push_back({p, a});  // its neighbour may still be too coarse
        break;
      }
    }
  }

  // Leaves of every patch, depth first; their aspects measured.
  void leaves(std::vector<AnisoNode>& out, std::vector<double>& aspect) {
    for (int p = 0; p < t_.num_patches(); ++p) {
      std::vector<std::pair<int, int>> l;
      collect_leaves(p, 0, l);
      for (const auto& [q, k] : l) {
        const TreeNode& n = measured(q, k);
        out.push_back({q, n.lu, n.lv, n.i, n.j});
        aspect.push_back(std::exp(std::abs(n.log_aspect) + n.log_spread));
      }
    }
  }

 private:
  void collect_leaves(int p, int k, std::vector<std::pair<int, int>>& out) const {
    const TreeNode& n = nodes_[p][k];
    if (n.split == kNone) {
      out.push_back({p, k});
      return;
    }
    const int count = n.split == kUV ? 4 : 2;
    for (int c = 0; c < count; ++c) collect_leaves(p, n.child + c, out);
  }

  void split(int p, int k, int kind) {
    const TreeNode n = nodes_[p][k];
    // Never a leaf side across the whole patch (see the header).
    if ((kind == kU && n.lv == 0) || (kind == kV && n.lu == 0)) kind = kUV;
    const int first = static_cast<int>(nodes_[p].size());
    if (kind == kU) {
      for (int a = 0; a < 2; ++a) nodes_[p].push_back({n.lu + 1, n.lv, 2 * n.i + a, n.j});
    } else if (kind == kV) {
      for (int b = 0; b < 2; ++b) nodes_[p].push_back({n.lu, n.lv + 1, n.i, 2 * n.j + b});
    } else {
      for (int c = 0; c < 4; ++c) nodes_[p].push_back({n.lu + 1, n.lv + 1, 2 * n.i + (c & 1), 2 * n.j + (c >> 1)});
    }
    nodes_[p][k].split = kind;
    nodes_[p][k].child = first;
  }

  // The node's area share and aspect over the set (see the header), measured once.
  const TreeNode& measured(int p, int k) {
    TreeNode& n = nodes_[p][k];
    if (n.area >= 0) return n;
    const double su = 1.0 / (1 << n.lu), sv = 1.0 / (1 << n.lv);
    const double u0 = n.i * su, v0 = n.j * sv;
    double area = 0, log_lo = 0, log_hi = 0;
    int logs = 0;
    auto tri = [](const Vec3& a, const Vec3& b, const Vec3& c) { return 0.5 * (b - a).cross(c - a).norm(); };
    for (size_t m = 0; m < samplers_.size(); ++m) {
      std::array<Vec3, 9> x;  // row by row: (a, b) at (u0 + a su / 2, v0 + b sv / 2)
      for (int b = 0; b < 3; ++b)
        for (int a = 0; a < 3; ++a)
          x[3 * b + a] = samplers_[m].point(p, Vec2(u0 + 0.5 * a * su, v0 + 0.5 * b * sv), hints_[m]);
      double ar = 0;
      for (int b = 0; b < 2; ++b)
        for (int a = 0; a < 2; ++a) {
          const Vec3 &p00 = x[3 * b + a], &p10 = x[3 * b + a + 1], &p01 = x[3 * (b + 1) + a],
                     &p11 = x[3 * (b + 1) + a + 1];
          ar += tri(p00, p10, p11) + tri(p00, p11, p01);
        }
      area = std::max(area, ar * inv_area_[m]);
      auto row = [&](int b) { return (x[3 * b + 1] - x[3 * b]).norm() + (x[3 * b + 2] - x[3 * b + 1]).norm(); };
      auto col = [&](int a) { return (x[3 + a] - x[a]).norm() + (x[6 + a] - x[3 + a]).norm(); };
      const double lu = 0.25 * (row(0) + 2 * row(1) + row(2)), lv = 0.25 * (col(0) + 2 * col(1) + col(2));
      if (lu > 0 && lv > 0 && std::isfinite(lu) && std::isfinite(lv)) {
        const double l = std::log(lu / lv);
        log_lo = logs == 0 ? l : std::min(log_lo, l);
        log_hi = logs == 0 ? l : std::max(log_hi, l);
        ++logs;
      }
    }
    n.area = area;
    n.log_aspect = 0.5 * (log_lo + log_hi);  // a degenerate node in every mesh: square
    n.log_spread = 0.5 * (log_hi - log_lo);
    return n;
  }

  void refine(int p, int k) {
    const TreeNode& n = measured(p, k);
    const double area = n.area, r = n.log_aspect, worst = std::abs(r) + n.log_spread;
    const bool too_big = area > o_.max_area;
    // Too long in some mesh, and a split along the long direction makes the worst mesh better.
    const bool too_long = worst > log_max_ && std::abs(r) > kHalfLog2 && area > kAspectAreaFloor * o_.max_area;
    if (!too_big && !too_long) return;
    const double half = 0.5 * log_max_;
    const bool can_u = n.lu < o_.max_level, can_v = n.lv < o_.max_level;
    int kind = kNone;
    if (too_big) {
      kind = r > half ? kU : r < -half ? kV : kUV;
      // A direction at max_level: the other one alone (the area bound first).
      if (kind == kUV && !can_u) kind = kV;
      if (kind == kUV && !can_v) kind = kU;
      if (kind == kU && !can_u) kind = kV;
      if (kind == kV && !can_v) kind = can_u ? kU : kNone;
    } else {
      kind = r > 0 ? (can_u ? kU : kNone) : (can_v ? kV : kNone);
    }
    if (kind == kNone) {
      ++stats_.unresolved_leaves;
      return;
    }
    ++(too_big ? stats_.area_splits : stats_.aspect_splits);
    split(p, k, kind);
    const int first = nodes_[p][k].child;
    for (int c = 0; c < (nodes_[p][k].split == kUV ? 4 : 2); ++c) refine(p, first + c);
  }

  // The leaf across side d of leaf n of patch p (in the twin patch across a patch side): its
  // patch, index, and the side of it that faces n.
  void neighbour(int p, const TreeNode& n, int d, int& q, int& k, int& side) const {
    const int xm = (n.x0() + n.x1()) / 2, ym = (n.y0() + n.y1()) / 2;
    int x = d == 0 || d == 2 ? xm : d == 1 ? n.x1() + 1 : n.x0() - 1;
    int y = d == 1 || d == 3 ? ym : d == 0 ? n.y0() - 1 : n.y1() + 1;
    q = p;
    side = (d + 2) % 4;
    if (x <= 0 || x >= kSpan || y <= 0 || y >= kSpan) {
      const int t = d == 0 ? xm : d == 1 ? ym : d == 2 ? kSpan - xm : kSpan - ym;  // along side d from corner d
      const PatchSide tw = t_.twin(p, d);
      const int r = kSpan - t;
      q = tw.patch;
      side = tw.side;
      switch (tw.side) {
        case 0: x = r, y = 1; break;
        case 1: x = kSpan - 1, y = r; break;
        case 2: x = kSpan - r, y = kSpan - 1; break;
        default: x = 1, y = kSpan - r; break;
      }
    }
    k = locate(q, x, y);
  }

  // The leaf of patch p containing the point (x, y) (not on a leaf side).
  int locate(int p, int x, int y) const {
    int k = 0;
    while (nodes_[p][k].split != kNone) {
      const TreeNode& n = nodes_[p][k];
      const int a = x >= (n.x0() + n.x1()) / 2, b = y >= (n.y0() + n.y1()) / 2;
      k = n.child + (n.split == kU ? a : n.split == kV ? b : a + 2 * b);
    }
    return k;
  }

  const std::vector<ChartSampler>& samplers_;
  const AnisotropicOptions& o_;
  AnisotropicStats& stats_;
  const BaseTopology& t_;
  std::vector<std::vector<TreeNode>> nodes_;
  std::vector<int> hints_;
  std::vector<double> inv_area_;
  double log_max_;
};

struct LeafCut {
  size_t first_face;
  bool diag02;
};

// Faces of the leaves (see the header), the cells cut in two listed in `cuts`.
SemiRegularConnectivity leaf_connectivity(const BaseTopology& t, const std::vector<AnisoNode>& leaves,
                                          std::vector<LeafCut>& cuts, std::vector<size_t>& templates,
                                          int& fan_leaves, std::vector<int>& face_leaf) {
  int finest = 0;
  for (const auto& n : leaves) finest = std::max({finest, n.lu, n.lv});
  const int top = finest + 1;  // leaf centres
  const UniformNumbering num(t, top);
  const int span = 1 << top;
  std::unordered_set<std::int64_t> corners;
  corners.reserve(4 * leaves.size());
  auto rect = [top](const AnisoNode& n, int& x0, int& x1, int& y0, int& y1) {
    x0 = n.i << (top - n.lu), x1 = (n.i + 1) << (top - n.lu);
    y0 = n.j << (top - n.lv), y1 = (n.j + 1) << (top - n.lv);
  };
  for (const auto& n : leaves) {
    int x0, x1, y0, y1;
    rect(n, x0, x1, y0, y1);
    corners.insert(num.vertex(n.patch, x0, y0));
    corners.insert(num.vertex(n.patch, x1, y0));
    corners.insert(num.vertex(n.patch, x1, y1));
    corners.insert(num.vertex(n.patch, x0, y1));
  }
  // Leaf corners strictly inside the segment (ax, ay)-(bx, by) of patch p, in order from a to b.
  // The segment is a leaf side (dyadic), so a corner inside it implies one at its midpoint.
  std::vector<std::int64_t> ring;
  auto hanging = [&](auto&& self, int p, int ax, int ay, int bx, int by) -> void {
    if (std::abs(bx - ax) + std::abs(by - ay) < 2) return;
    const int mx = (ax + bx) / 2, my = (ay + by) / 2;
    const std::int64_t id = num.vertex(p, mx, my);
    if (!corners.count(id)) return;
    self(self, p, ax, ay, mx, my);
    ring.push_back(id);
    self(self, p, mx, my, bx, by);
  };
  std::vector<std::array<std::int64_t, 3>> faces;
  faces.reserve(2 * leaves.size() + leaves.size() / 2);
  fan_leaves = 0;
  face_leaf.clear();
  for (size_t leaf = 0; leaf < leaves.size(); ++leaf) {
    face_leaf.resize(faces.size(), static_cast<int>(leaf) - 1);
    const AnisoNode& n = leaves[leaf];
    int x0, x1, y0, y1;
    rect(n, x0, x1, y0, y1);
    const int p = n.patch;
    const std::array<std::int64_t, 4> c = {num.vertex(p, x0, y0), num.vertex(p, x1, y0), num.vertex(p, x1, y1),
                                           num.vertex(p, x0, y1)};
    ring.clear();
    std::array<size_t, 4> at{};  // ring position of corner d; side d's hanging vertices follow it
    for (int d = 0; d < 4; ++d) {
      at[d] = ring.size();
      ring.push_back(c[d]);
      const int ax = d == 0 || d == 3 ? x0 : x1, ay = d <= 1 ? y0 : y1;
      const int bx = d == 0 || d == 1 ? x1 : x0, by = d == 0 || d == 3 ? y0 : y1;
      hanging(hanging, p, ax, ay, bx, by);
    }
    // Sides on the patch's border: 0 bottom, 1 right, 2 top, 3 left.
    const std::array<bool, 4> on = {y0 == 0, x1 == span, y1 == span, x0 == 0};
    const int border_sides = on[0] + on[1] + on[2] + on[3];
    // A corner leaf (two adjacent border sides, at patch corner k): k, else -1.
    int corner = -1;
    for (int k = 0; k < 4 && border_sides == 2; ++k)
      if (on[(k + 3) % 4] && on[k]) corner = k;
    if (ring.size() == 4 && (border_sides <= 1 || corner >= 0)) {
      // The quadrant pattern: a leaf that touches at most one patch side lies in one quadrant, and
      // a corner leaf is cut through the patch corner. The other diagonal of a corner leaf joins two
      // border points, which another patch may join too only at a base vertex of valence 2.
      const bool d02 = corner >= 0 ? corner % 2 == 0 : (x0 + x1 < span) == (y0 + y1 < span);
      if (corner < 0 || t.valence[t.quads[p][corner]] >= 3) cuts.push_back({faces.size(), d02});
      if (d02) {
        faces.push_back({c[0], c[1], c[2]});
        faces.push_back({c[0], c[2], c[3]});
      } else {
        faces.push_back({c[0], c[1], c[3]});
        faces.push_back({c[1], c[2], c[3]});
      }
      continue;
    }
    if (ring.size() == 5 && border_sides <= 1) {
      // One hanging vertex M on side d: (C_d, M, C_d+3), (M, C_d+1, C_d+2), (M, C_d+2, C_d+3). Its
      // two inner edges join M to the opposite side's corners, at most one of them on the border.
      int d = 0;
      while ((d < 3 ? at[d + 1] : ring.size()) != at[d] + 2) ++d;
      const std::int64_t m = ring[at[d] + 1];
      templates.push_back(faces.size());
      faces.push_back({c[d], m, c[(d + 3) % 4]});
      faces.push_back({m, c[(d + 1) % 4], c[(d + 2) % 4]});
      faces.push_back({m, c[(d + 2) % 4], c[(d + 3) % 4]});
      continue;
    }
    ++fan_leaves;
    const std::int64_t centre = num.vertex(p, (x0 + x1) / 2, (y0 + y1) / 2);
    for (size_t r = 0; r < ring.size(); ++r) faces.push_back({centre, ring[r], ring[(r + 1) % ring.size()]});
  }

  face_leaf.resize(faces.size(), static_cast<int>(leaves.size()) - 1);
  int used_bits = 0;
  SemiRegularConnectivity out = compact_connectivity(t, num, faces, "the anisotropic remesh", &used_bits);
  // The finest grid level that any vertex needs.
  int level = top;
  while (level > 0 && (used_bits & ((1 << (top - level + 1)) - 1)) == 0) --level;
  out.level = level;
  return out;
}


// The uv of vertex v in patch p's frame: its own (patch, uv) when that is p, else (a patch corner
// or a side sample recorded in another patch) the point of p's border that it is, the nearest one
// to `near` when several are (a patch that meets itself).
Vec2 uv_in_patch(const BaseTopology& t, const SemiRegularConnectivity& c, int v, int p, const Vec2& near) {
  if (c.vertex_patch[v] == p) return c.vertex_uv[v];
  std::vector<Vec2> cand;
  static const std::array<Vec2, 4> corner_uv = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};
  if (v < c.num_base_vertices) {
    for (int k = 0; k < 4; ++k)
      if (t.quads[p][k] == v) cand.push_back(corner_uv[k]);
  } else {
    const int q = c.vertex_patch[v];
    const Vec2 uv = c.vertex_uv[v];
    // Sides of q through uv, with the fraction t along side s from corner s.
    const std::array<bool, 4> on = {uv.y() == 0, uv.x() == 1, uv.y() == 1, uv.x() == 0};
    const std::array<double, 4> frac = {uv.x(), uv.y(), 1 - uv.x(), 1 - uv.y()};
    for (int s = 0; s < 4; ++s) {
      if (!on[s]) continue;
      const PatchSide tw = t.twin(q, s);
      if (tw.patch != p) continue;
      const double r = 1 - frac[s];  // along the twin side from its corner
      switch (tw.side) {
        case 0: cand.push_back(Vec2(r, 0)); break;
        case 1: cand.push_back(Vec2(1, r)); break;
        case 2: cand.push_back(Vec2(1 - r, 1)); break;
        default: cand.push_back(Vec2(0, 1 - r)); break;
      }
    }
  }
  if (cand.empty()) throw InternalError("remesh: a vertex next to a patch's interior vertex is not on that patch's border");
  Vec2 best = cand[0];
  for (const Vec2& x : cand)
    if ((x - near).squaredNorm() < (best - near).squaredNorm()) best = x;
  return best;
}

// sin of the smallest angle of triangle (a, b, c) (0 when degenerate).
double sin_min_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double lab = (b - a).squaredNorm(), lbc = (c - b).squaredNorm(), lca = (a - c).squaredNorm();
  const double twice_area = (b - a).cross(c - a).norm();
  const double denom2 = lab <= lbc && lab <= lca ? lbc * lca : lbc <= lca ? lab * lca : lab * lbc;
  return denom2 > 0 ? twice_area / std::sqrt(denom2) : 0.0;
}

// A remesh vertex strictly inside its patch's square (not a base vertex, not on a side).
bool patch_interior(const SemiRegularConnectivity& c, int v) {
  const Vec2& uv = c.vertex_uv[v];
  return v >= c.num_base_vertices && uv.x() > 0 && uv.x() < 1 && uv.y() > 0 && uv.y() < 1;
}

// The quality of a vertex's ring over the set: the worst sin(smallest angle) of its triangles and
// their sum, each capped at `cap`. at(m): the vertex's point in mesh m; ends(r): the ring
// triangle r's two other corners.
struct RingQuality {
  double worst = 1, sum = 0;
  // A move is kept when the ring's worst angle rises, or when the sum rises and the worst keeps
  // at least kSmoothWorstSlack of its sine.
  bool better_than(const RingQuality& before) const {
    if (worst < 0) return false;
    return worst > before.worst || (worst >= kSmoothWorstSlack * before.worst && sum > before.sum);
  }
};

template <class At, class Ends>
RingQuality ring_quality(const std::vector<std::vector<Vec3>>& positions, int b, int e, double cap, At&& at,
                         Ends&& ends) {
  RingQuality q;
  for (size_t m = 0; m < positions.size(); ++m)
    for (int r = b; r < e; ++r) {
      const auto [w1, w2] = ends(r);
      const double x = sin_min_angle(at(m), positions[m][w1], positions[m][w2]);
      q.worst = std::min(q.worst, x);
      q.sum += std::min(x, cap);
    }
  return q;
}

// A 3-triangle template cell (A, M, B, C, D counter-clockwise, M the hanging vertex between A and
// B), emitted as (A, M, D), (M, B, C), (M, C, D): re-cut as the fan from C, (C, D, A), (C, A, M),
// (C, M, B), or from D, (D, A, M), (D, M, B), (D, B, C), when that raises the smallest angle over
// the set. Every inner edge of the three joins at most one point of the patch border (see the
// header), so no other patch can emit it. With `accept`, only the present cut and the cuts it
// accepts are candidates.
void recut_template_best_angle(Tri* f, const std::array<int, 5>& amcbd, const std::vector<std::vector<Vec3>>& positions,
                               const std::function<bool(const std::array<Tri, 3>&)>& accept = {}) {
  const int a = amcbd[0], m = amcbd[1], b = amcbd[2], c = amcbd[3], d = amcbd[4];
  const std::array<std::array<Tri, 3>, 3> cuts = {{{Tri{a, m, d}, Tri{m, b, c}, Tri{m, c, d}},
                                                   {Tri{c, d, a}, Tri{c, a, m}, Tri{c, m, b}},
                                                   {Tri{d, a, m}, Tri{d, m, b}, Tri{d, b, c}}}};
  int best = 0;
  double best_q = -1;
  for (int k = 0; k < 3; ++k) {
    const bool present = cuts[k][0] == f[0] && cuts[k][1] == f[1] && cuts[k][2] == f[2];
    if (accept && !present && !accept(cuts[k])) continue;
    double q = 1;
    for (const auto& x : positions)
      for (const Tri& t : cuts[k]) q = std::min(q, sin_min_angle(x[t[0]], x[t[1]], x[t[2]]));
    if (q > best_q) best_q = q, best = k;
  }
  for (int i = 0; i < 3; ++i) f[i] = cuts[best][i];
}

// Tangential smoothing of the patch-interior vertices (see the header): Gauss-Seidel in vertex
// order, one uv per vertex for the whole set. Returns the number of accepted moves.
// The area-weighted centroid of a vertex's ring triangles in one mesh (x: its points, xv: the
// vertex's, ends(r): ring triangle r's two other corners) and their total area.
template <class Ends>
std::pair<Vec3, double> ring_centroid(const std::vector<Vec3>& x, const Vec3& xv, int b, int e, Ends&& ends) {
  Vec3 target(0, 0, 0);
  double area = 0;
  for (int r = b; r < e; ++r) {
    const auto [w1, w2] = ends(r);
    const Vec3 &x1 = x[w1], &x2 = x[w2];
    const double a = 0.5 * (x1 - xv).cross(x2 - xv).norm();
    target += a * (xv + x1 + x2) / 3;
    area += a;
  }
  return {target, area};
}

// With `active` (#V flags), only the flagged vertices and, sweep after sweep, the neighbours of
// the moved ones are tried (the flipped rings after a round of flips: the others are where the
// previous smoothing left them).
int smooth_interior(const std::vector<ChartSampler>& samplers, SemiRegularConnectivity& c,
                    std::vector<std::vector<Vec3>>& positions, int iterations, double below_degrees,
                    std::vector<char>* active = nullptr) {
  if (iterations <= 0) return 0;
  const BaseTopology& t = samplers[0].topology();
  const int nv = c.num_vertices();
  auto interior = [&](int x) { return patch_interior(c, x); };
  // Incident faces of every interior vertex, as the two other corners in CCW order.
  std::vector<int> offset(nv + 1, 0);
  for (const Tri& f : c.faces)
    for (int k = 0; k < 3; ++k)
      if (interior(f[k])) ++offset[f[k] + 1];
  for (int v = 0; v < nv; ++v) offset[v + 1] += offset[v];
  std::vector<std::array<int, 2>> ring(offset[nv]);
  {
    std::vector<int> fill(offset.begin(), offset.end() - 1);
    for (const Tri& f : c.faces)
      for (int k = 0; k < 3; ++k)
        if (interior(f[k])) ring[fill[f[k]]++] = {f[(k + 1) % 3], f[(k + 2) % 3]};
  }
  // The uv (in the vertex's patch) of its fixed neighbours, ring entry by ring entry.
  std::vector<std::array<Vec2, 2>> fixed_uv(ring.size());
  for (int v = 0; v < nv; ++v) {
    if (!interior(v)) continue;
    const int p = c.vertex_patch[v];
    for (int r = offset[v]; r < offset[v + 1]; ++r)
      for (int k = 0; k < 2; ++k) {
        const int w = ring[r][k];
        if (!interior(w)) fixed_uv[r][k] = uv_in_patch(t, c, w, p, c.vertex_uv[v]);
        else if (c.vertex_patch[w] != p) throw InternalError("remesh: a face joins the interiors of two patches");
      }
  }
  const double threshold = std::sin(below_degrees * M_PI / 180);
  const size_t meshes = samplers.size();
  std::vector<int> hints(meshes, -1);
  std::vector<Vec3> moved(meshes);
  int accepted = 0;
  for (int it = 0; it < iterations; ++it) {
    int moves = 0;
    for (int v = 0; v < nv; ++v) {
      if (!interior(v) || offset[v + 1] == offset[v] || (active && !(*active)[v])) continue;
      const int b = offset[v], e = offset[v + 1];
      auto nb_uv = [&](int r, int k) { const int w = ring[r][k]; return interior(w) ? c.vertex_uv[w] : fixed_uv[r][k]; };
      // The ring's worst smallest angle over the set, with v at x[m] in mesh m.
      // Also the sum over the set of the ring's angles' sines up to the bound.
      auto worst = [&](auto&& at) {
        return ring_quality(positions, b, e, threshold, at, [&](int r) { return std::make_pair(ring[r][0], ring[r][1]); });
      };
      const RingQuality before = worst([&](size_t m) -> const Vec3& { return positions[m][v]; });
      if (before.worst >= threshold) continue;
      // Per mesh: the 3D target (area-weighted centroid of the ring's triangles), mapped back to uv
      // through the least-squares affine map of the ring's edges; the set moves by the mean step.
      const Vec2 uv = c.vertex_uv[v];
      Vec2 step(0, 0);
      int used = 0;
      for (size_t m = 0; m < meshes; ++m) {
        const auto& x = positions[m];
        const Vec3 xv = x[v];
        const auto [target, area] = ring_centroid(x, xv, b, e, [&](int r) { return std::make_pair(ring[r][0], ring[r][1]); });
        Eigen::Matrix2d dd = Eigen::Matrix2d::Zero();
        Eigen::Matrix<double, 3, 2> ed = Eigen::Matrix<double, 3, 2>::Zero();
        for (int r = b; r < e; ++r)
          for (int k = 0; k < 2; ++k) {
            const Vec2 d = nb_uv(r, k) - uv;
            const Vec3 ex = x[ring[r][k]] - xv;
            dd += d * d.transpose();
            ed += ex * d.transpose();
          }
        if (!(area > 0) || std::abs(dd.determinant()) <= 0) continue;
        const Eigen::Matrix<double, 3, 2> jac = ed * dd.inverse();
        const Eigen::Matrix2d jtj = jac.transpose() * jac;
        if (!(std::abs(jtj.determinant()) > 0)) continue;
        const Vec2 s = jtj.ldlt().solve(jac.transpose() * (target / area - xv));
        if (!s.allFinite()) continue;
        step += s;
        ++used;
      }
      // The ring's worst angle with v at uv + d, or -1 when a ring face would flip or shrink to
      // under 5% of its uv area; `moved` then holds the 3D points.
      auto trial = [&](const Vec2& d) {
        const Vec2 nuv = uv + d;
        if (!(nuv.x() > 0 && nuv.x() < 1 && nuv.y() > 0 && nuv.y() < 1)) return RingQuality{-1, 0};
        for (int r = b; r < e; ++r) {
          const Vec2 a1 = nb_uv(r, 0), a2 = nb_uv(r, 1);
          const double before_uv = cross2(a1 - uv, a2 - uv), after_uv = cross2(a1 - nuv, a2 - nuv);
          if (!(after_uv * before_uv > 0) || std::abs(after_uv) < 0.05 * std::abs(before_uv)) return RingQuality{-1, 0};
        }
        for (size_t m = 0; m < meshes; ++m) moved[m] = samplers[m].point(c.vertex_patch[v], nuv, hints[m]);
        return worst([&](size_t m) -> const Vec3& { return moved[m]; });
      };
      auto take = [&](const Vec2& d) {
        c.vertex_uv[v] = uv + d;
        for (size_t m = 0; m < meshes; ++m) positions[m][v] = moved[m];
        ++moves;
        if (active)
          for (int r = offset[v]; r < offset[v + 1]; ++r) (*active)[ring[r][0]] = (*active)[ring[r][1]] = 1;
      };
      // The centroid step, or its half, quarter, when the ring's worst angle rises.
      if (used == 0) continue;
      step /= used;
      for (int tries = 0; tries < 3; ++tries, step *= 0.5)
        if (trial(step).better_than(before)) {
          take(step);
          break;
        }
    }
    accepted += moves;
    if (moves == 0) break;
  }
  return accepted;
}

// The side of patch p that (u,v) lies on (0 bottom, 1 right, 2 top, 3 left), or -1 inside or at a
// corner; and the fraction along side s from corner s, and back.
int side_of(const Vec2& uv) {
  const int on = (uv.y() == 0) + (uv.x() == 1) + (uv.y() == 1) + (uv.x() == 0);
  if (on != 1) return -1;
  return uv.y() == 0 ? 0 : uv.x() == 1 ? 1 : uv.y() == 1 ? 2 : 3;
}
double side_fraction(int s, const Vec2& uv) {
  return s == 0 ? uv.x() : s == 1 ? uv.y() : s == 2 ? 1 - uv.x() : 1 - uv.y();
}
Vec2 side_point(int s, double f) {
  return s == 0 ? Vec2(f, 0) : s == 1 ? Vec2(1, f) : s == 2 ? Vec2(1 - f, 1) : Vec2(0, 1 - f);
}

// The (u,v) in the twin patch across side s of patch p of the point uv on that side.
Vec2 twin_side_uv(const BaseTopology& t, int p, int s, const Vec2& uv) {
  const PatchSide tw = t.twin(p, s);
  const double r = 1 - side_fraction(s, uv);  // along the twin side from its corner
  switch (tw.side) {
    case 0: return Vec2(r, 0);
    case 1: return Vec2(1, r);
    case 2: return Vec2(1 - r, 1);
    default: return Vec2(0, 1 - r);
  }
}

// Sliding of the patch-side vertices along their side (see the header): like smooth_interior, but
// a side vertex has one unknown, its fraction along the side, shared by the two patches of the
// side (its (patch, u, v) stays on that side of its patch, so both patches still evaluate it on
// the side's polyline, bit-identical). Only vertices whose every ring face has a patch-interior
// corner in one of the side's two (distinct) patches move. Returns the number of accepted moves.
// With `active` (#V flags), only the flagged vertices are tried (the flipped rings of a round).
int slide_sides(const std::vector<ChartSampler>& samplers, SemiRegularConnectivity& c,
                std::vector<std::vector<Vec3>>& positions, int iterations, double below_degrees,
                const std::vector<char>* active = nullptr) {
  if (iterations <= 0) return 0;
  const BaseTopology& t = samplers[0].topology();
  const int nv = c.num_vertices();
  auto interior = [&](int x) { return patch_interior(c, x); };
  auto slidable_side = [&](int v) { return v >= c.num_base_vertices ? side_of(c.vertex_uv[v]) : -1; };
  // Ring faces of every side vertex: the two other corners (CCW) and the face's patch.
  struct RingFace {
    int w1, w2, patch;
  };
  std::vector<int> offset(nv + 1, 0);
  for (const Tri& f : c.faces)
    for (int k = 0; k < 3; ++k)
      if (slidable_side(f[k]) >= 0) ++offset[f[k] + 1];
  for (int v = 0; v < nv; ++v) offset[v + 1] += offset[v];
  std::vector<RingFace> ring(offset[nv]);
  std::vector<char> ok(nv, 0);
  {
    std::vector<int> fill(offset.begin(), offset.end() - 1);
    for (const Tri& f : c.faces) {
      int patch = -1;
      for (int w : f)
        if (interior(w)) patch = c.vertex_patch[w];
      for (int k = 0; k < 3; ++k)
        if (slidable_side(f[k]) >= 0) ring[fill[f[k]]++] = {f[(k + 1) % 3], f[(k + 2) % 3], patch};
    }
    for (int v = 0; v < nv; ++v) {
      const int s = slidable_side(v);
      if (s < 0 || offset[v + 1] == offset[v]) continue;
      const int p = c.vertex_patch[v], q = t.twin(p, s).patch;
      bool good = p != q;
      for (int r = offset[v]; r < offset[v + 1] && good; ++r) good = ring[r].patch == p || ring[r].patch == q;
      ok[v] = good;
    }
  }
  const double threshold = std::sin(below_degrees * M_PI / 180);
  const size_t meshes = samplers.size();
  std::vector<int> hints(meshes, -1);
  std::vector<Vec3> moved(meshes);
  std::vector<std::array<Vec2, 3>> ring_uv;  // per ring face: v, w1, w2 in the face's patch
  int accepted = 0;
  for (int it = 0; it < iterations; ++it) {
    int moves = 0;
    for (int v = 0; v < nv; ++v) {
      if (!ok[v] || (active && !(*active)[v])) continue;
      const int b = offset[v], e = offset[v + 1];
      auto worst = [&](auto&& at) {
        return ring_quality(positions, b, e, threshold, at, [&](int r) { return std::make_pair(ring[r].w1, ring[r].w2); });
      };
      const RingQuality before = worst([&](size_t m) -> const Vec3& { return positions[m][v]; });
      if (before.worst >= threshold) continue;
      const int p = c.vertex_patch[v];
      const Vec2 uv = c.vertex_uv[v];
      const int s = side_of(uv);
      const double f0 = side_fraction(s, uv);
      // The ring in its faces' patches, and the nearest ring vertices on the side (fractions).
      ring_uv.resize(e - b);
      double lo = 0, hi = 1;
      for (int r = b; r < e; ++r) {
        const int patch = ring[r].patch;
        ring_uv[r - b][0] = uv_in_patch(t, c, v, patch, uv);
        for (int k = 0; k < 2; ++k) {
          const int w = k == 0 ? ring[r].w1 : ring[r].w2;
          ring_uv[r - b][k + 1] = uv_in_patch(t, c, w, patch, ring_uv[r - b][0]);
          if (patch != p) continue;
          const Vec2& wu = ring_uv[r - b][k + 1];
          const bool on_side = s == 0 ? wu.y() == 0 : s == 1 ? wu.x() == 1 : s == 2 ? wu.y() == 1 : wu.x() == 0;
          if (!on_side) continue;
          const double fw = side_fraction(s, wu);
          if (fw < f0) lo = std::max(lo, fw);
          if (fw > f0) hi = std::min(hi, fw);
        }
      }
      const double room = std::min(f0 - lo, hi - f0);
      if (!(room > 0)) continue;
      // Per mesh: the step along the side toward the ring's area-weighted centroid (its projection
      // on the side's tangent); the set moves by the mean.
      const double h = 0.25 * room;
      double step = 0;
      int used = 0;
      for (size_t m = 0; m < meshes; ++m) {
        const auto& x = positions[m];
        const Vec3 xv = x[v];
        const auto [target, area] = ring_centroid(x, xv, b, e, [&](int r) { return std::make_pair(ring[r].w1, ring[r].w2); });
        const Vec3 tangent = (samplers[m].point(p, side_point(s, f0 + h)) - samplers[m].point(p, side_point(s, f0 - h))) / (2 * h);
        const double tt = tangent.squaredNorm();
        if (!(area > 0) || !(tt > 0)) continue;
        const double ds = tangent.dot(target / area - xv) / tt;
        if (!std::isfinite(ds)) continue;
        step += ds;
        ++used;
      }
      if (used == 0) continue;
      step = std::clamp(step / used, -0.5 * room, 0.5 * room);
      auto trial = [&](double ds) {
        const double f = f0 + ds;
        if (!(f > lo && f < hi)) return RingQuality{-1, 0};
        const Vec2 nuv = side_point(s, f);
        for (int r = b; r < e; ++r) {
          const int patch = ring[r].patch;
          const Vec2 vn = patch == p ? nuv : twin_side_uv(t, p, s, nuv);
          const Vec2 &a1 = ring_uv[r - b][1], &a2 = ring_uv[r - b][2], &vo = ring_uv[r - b][0];
          const double before_uv = cross2(a1 - vo, a2 - vo), after_uv = cross2(a1 - vn, a2 - vn);
          if (!(after_uv * before_uv > 0) || std::abs(after_uv) < 0.05 * std::abs(before_uv))
            return RingQuality{-1, 0};
        }
        for (size_t m = 0; m < meshes; ++m) moved[m] = samplers[m].point(p, nuv, hints[m]);
        return worst([&](size_t m) -> const Vec3& { return moved[m]; });
      };
      for (int tries = 0; tries < 3; ++tries, step *= 0.5)
        if (trial(step).better_than(before)) {
          c.vertex_uv[v] = side_point(s, f0 + step);
          for (size_t m = 0; m < meshes; ++m) positions[m][v] = moved[m];
          ++moves;
          break;
        }
    }
    accepted += moves;
    if (moves == 0) break;
  }
  return accepted;
}

// How far the chord from xa to xb (the 3D points of (u,v) ua, ub of patch p) passes from the
// surface, along n: the distance of its 3D midpoint from the chart's point at its (u,v) midpoint.
double chord_gap(const ChartSampler& s, int p, const Vec2& ua, const Vec2& ub, const Vec3& xa, const Vec3& xb,
                 const Vec3& n, int& hint) {
  return std::abs(n.dot(0.5 * (xa + xb) - s.point(p, 0.5 * (ua + ub), hint)));
}

// Edge flips on the surface (see the header): an edge whose two triangles lie in one patch is
// flipped when that raises the smallest angle of the two over the set, their worst angle is under
// below_degrees, the new edge has a patch-interior end and is no edge yet, and the two new
// triangles are counter-clockwise in the patch's (u,v). Half-edge he = 3 f + k runs from corner k
// of face f to corner k + 1; faces are replaced in place, edges visited from a stack (last in,
// first out), so the result is a function of the input alone. Returns the number of flips.
// `touched` (#V) flags the four corners of every flipped pair.
int flip_for_angles(const std::vector<ChartSampler>& samplers, SemiRegularConnectivity& c,
                    const std::vector<std::vector<Vec3>>& positions, double below_degrees,
                    std::vector<char>& touched) {
  const BaseTopology& t = samplers[0].topology();
  auto interior = [&](int x) { return patch_interior(c, x); };
  auto& faces = c.faces;
  const int nf = c.num_faces();
  auto from = [&](int he) { return faces[he / 3][he % 3]; };
  auto to = [&](int he) { return faces[he / 3][(he % 3 + 1) % 3]; };
  auto next = [](int he) { return he - he % 3 + (he % 3 + 1) % 3; };
  auto prev = [](int he) { return he - he % 3 + (he % 3 + 2) % 3; };
  // Twins (the same half-edge numbering as qs::mesh::Connectivity), kept up to date by the flips.
  std::vector<int> twin = mesh::build_connectivity(TriMesh{positions[0], faces}).opposite;
  // Whether an edge joins v and w: around v through the twins (the mesh is closed and manifold).
  auto joined = [&](int start, int w) {  // start: a half-edge leaving v
    int he = start;
    for (int guard = 0; guard < nf; ++guard) {
      if (to(he) == w) return true;
      he = twin[prev(he)];
      if (he < 0 || he == start) return false;
    }
    return false;
  };
  auto patch_of = [&](int f) {
    for (int v : faces[f])
      if (interior(v)) return c.vertex_patch[v];
    return -1;
  };
  auto quality = [&](const Tri& f, const Tri& g) {
    double q = 1;
    for (const auto& x : positions)
      q = std::min({q, sin_min_angle(x[f[0]], x[f[1]], x[f[2]]), sin_min_angle(x[g[0]], x[g[1]], x[g[2]])});
    return q;
  };
  const double threshold = std::sin(below_degrees * M_PI / 180);
  std::vector<int> hints(samplers.size(), -1);
  std::vector<int> work;
  work.reserve(3 * static_cast<size_t>(nf));
  for (int he = 3 * nf - 1; he >= 0; --he) work.push_back(he);
  int flips = 0;
  const long budget = 20L * nf;  // visits; flips raise the sorted angles, so this is a guard only
  for (long visit = 0; !work.empty() && visit < budget; ++visit) {
    const int h = work.back();
    work.pop_back();
    const int g_he = twin[h];
    if (g_he < 0) continue;
    const int f = h / 3, g = g_he / 3;
    if (f == g) continue;
    const int a = from(h), b = to(h), cc = to(next(h)), d = to(next(g_he));
    if (cc == d || (!interior(cc) && !interior(d))) continue;
    const int p = patch_of(f);
    if (p < 0 || patch_of(g) != p) continue;
    const double before = quality(faces[f], faces[g]);
    if (!(before < threshold)) continue;
    const Tri f_new = {cc, a, d}, g_new = {d, b, cc};
    if (!(quality(f_new, g_new) > before * (1 + 1e-9))) continue;
    if (joined(prev(h), d)) continue;  // prev(h) leaves cc
    // Counter-clockwise in the patch's (u,v), with a margin against rounding.
    const Vec2 near = c.vertex_uv[interior(cc) ? cc : d];
    const Vec2 ua = uv_in_patch(t, c, a, p, near), ub = uv_in_patch(t, c, b, p, near),
               uc = uv_in_patch(t, c, cc, p, near), ud = uv_in_patch(t, c, d, p, near);
    const double total = std::abs(cross2(ub - ua, uc - ua)) + std::abs(cross2(ua - ub, ud - ub));
    if (!(cross2(ua - uc, ud - uc) > 1e-6 * total && cross2(ub - ud, uc - ud) > 1e-6 * total)) continue;
    // The new edge stays as close to the surface as the old one (in every mesh): the distance of
    // its 3D midpoint from the chart's point at its (u,v) midpoint, along the normal of the two
    // old triangles (the map's tangential distortion does not count), at most the old edge's or
    // kFlipChordSlack of its length, and the pair's area grows by kFlipAreaGrowth at most, so
    // that a flip across a bend or a fold does not cut the surface.
    bool near_surface = true;
    const bool set = samplers.size() > 1;
    for (size_t m = 0; m < samplers.size() && near_surface; ++m) {
      const auto& x = positions[m];
      Vec3 n = (x[b] - x[a]).cross(x[cc] - x[a]) + (x[a] - x[b]).cross(x[d] - x[b]);
      const double nn = n.norm();
      if (!(nn > 0)) continue;
      n /= nn;
      const double old_gap = chord_gap(samplers[m], p, ua, ub, x[a], x[b], n, hints[m]);
      const double new_gap = chord_gap(samplers[m], p, uc, ud, x[cc], x[d], n, hints[m]);
      double allowed = std::max(old_gap, kFlipChordSlack * (x[cc] - x[d]).norm());
      // The pair's four sides, only when needed (in a set, a mesh sampled more coarsely than the
      // remesh has chords off its surface everywhere: its old diagonal happening to lie on one
      // chart face must not block a flip that another mesh needs).
      const std::array<std::pair<int, Vec2>, 4> quad = {{{a, ua}, {d, ud}, {b, ub}, {cc, uc}}};
      for (int k = 0; k < 4 && set && new_gap > allowed; ++k) {
        const auto& [v0, w0] = quad[k];
        const auto& [v1, w1] = quad[(k + 1) % 4];
        allowed = std::max(allowed, chord_gap(samplers[m], p, w0, w1, x[v0], x[v1], n, hints[m]));
      }
      const double old_area = (x[b] - x[a]).cross(x[cc] - x[a]).norm() + (x[a] - x[b]).cross(x[d] - x[b]).norm();
      const double new_area = (x[a] - x[cc]).cross(x[d] - x[cc]).norm() + (x[b] - x[d]).cross(x[cc] - x[d]).norm();
      near_surface = new_gap <= allowed && new_area <= kFlipAreaGrowth * old_area;
    }
    if (!near_surface) continue;
    // The outer half-edges' twins, then the two faces and their six half-edges.
    const int t_bc = twin[next(h)], t_ca = twin[prev(h)], t_ad = twin[next(g_he)], t_db = twin[prev(g_he)];
    faces[f] = f_new;  // 3f: c->a, 3f+1: a->d, 3f+2: d->c
    faces[g] = g_new;  // 3g: d->b, 3g+1: b->c, 3g+2: c->d
    auto link = [&](int x, int y) {
      twin[x] = y;
      if (y >= 0) twin[y] = x;
    };
    link(3 * f, t_ca), link(3 * f + 1, t_ad), link(3 * g, t_db), link(3 * g + 1, t_bc), link(3 * f + 2, 3 * g + 2);
    ++flips;
    touched[a] = touched[b] = touched[cc] = touched[d] = 1;
    for (int k = 0; k < 2; ++k) work.push_back(3 * f + k), work.push_back(3 * g + k);
  }
  return flips;
}

}  // namespace

AnisotropicRemesh remesh_anisotropic(const std::vector<const dissect::Chart*>& charts, const AnisotropicOptions& options,
                                     const Context& context) {
  if (!(options.max_area > 0) || !std::isfinite(options.max_area))
    throw InvalidInput("remesh: the anisotropic remesh's area bound must be a positive share of the surface, got " +
                       std::to_string(options.max_area));
  if (!(options.max_aspect >= 1.5) || !std::isfinite(options.max_aspect))
    throw InvalidInput("remesh: the anisotropic remesh's aspect bound must be a finite number >= 1.5 (a cell's "
                       "longer side over its shorter on the surface), got " + std::to_string(options.max_aspect));
  if (options.max_level < 0 || options.max_level > kMaxAnisotropicLevel)
    throw InvalidInput("remesh: max level " + std::to_string(options.max_level) + " is out of range; expected 0.." +
                       std::to_string(kMaxAnisotropicLevel));
  if (options.flip_rounds < 0 || options.flip_rounds > 10)
    throw InvalidInput("remesh: flip rounds " + std::to_string(options.flip_rounds) + " are out of range; expected 0..10");
  if (options.smooth_iterations < 0 || options.smooth_iterations > 100)
    throw InvalidInput("remesh: smoothing sweeps " + std::to_string(options.smooth_iterations) +
                       " are out of range; expected 0..100");
  if (!(options.smooth_below >= 0 && options.smooth_below <= 60))
    throw InvalidInput("remesh: the smoothing's angle bound must be 0..60 degrees, got " +
                       std::to_string(options.smooth_below));
  if (charts.empty()) throw InvalidInput("remesh: no charts to remesh");
  const std::vector<ChartSampler> samplers = set_samplers(charts, context);
  const BaseTopology& topology = samplers[0].topology();

  AnisotropicRemesh out;
  Builder builder(samplers, options, out.stats);
  const int np = topology.num_patches();
  for (int p = 0; p < np; ++p) {
    context.check_cancel();
    context.report("remesh", 0.6 * p / np);
    builder.refine_patch(p);
  }
  builder.balance();
  builder.leaves(out.leaves, out.leaf_aspect);
  for (double r : out.leaf_aspect) out.stats.max_leaf_aspect = std::max({out.stats.max_leaf_aspect, r, 1.0 / r});
  for (const auto& n : out.leaves) out.stats.finest_level = std::max({out.stats.finest_level, n.lu, n.lv});

  std::vector<LeafCut> cuts;
  std::vector<size_t> templates;
  out.remesh.connectivity = leaf_connectivity(topology, out.leaves, cuts, templates, out.stats.fan_leaves,
                                                  out.face_leaf);
  for (size_t m = 0; m < samplers.size(); ++m) {
    context.report("remesh", 0.7 + 0.3 * m / samplers.size());
    out.remesh.positions.push_back(sample_positions(samplers[m], out.remesh.connectivity, context));
  }
  auto& faces = out.remesh.connectivity.faces;
  for (const auto& cut : cuts)
    recut_cell_best_angle(faces[cut.first_face], faces[cut.first_face + 1], cut.diag02, out.remesh.positions);
  // The template cells' corners A, M, B, C, D (emitted as (A, M, D), (M, B, C), (M, C, D)).
  std::vector<std::array<int, 5>> pentagons;
  pentagons.reserve(templates.size());
  for (size_t first : templates) {
    const Tri &f0 = faces[first], &f1 = faces[first + 1];
    pentagons.push_back({f0[0], f0[1], f1[1], f1[2], f0[2]});
  }
  for (size_t k = 0; k < templates.size(); ++k)
    recut_template_best_angle(&faces[templates[k]], pentagons[k], out.remesh.positions);
  // The sides slide in a set only (see the header).
  const bool slide = options.slide_sides && samplers.size() > 1;
  if (options.smooth_iterations > 0) {
    context.check_cancel();
    out.stats.smoothed_moves = smooth_interior(samplers, out.remesh.connectivity, out.remesh.positions,
                                               options.smooth_iterations, options.smooth_below);
    if (slide)
      out.stats.slid_moves += slide_sides(samplers, out.remesh.connectivity, out.remesh.positions,
                                          options.smooth_iterations, options.smooth_below);
    // The cells' diagonals and templates again for the moved vertices. A moved cell need not be
    // convex in (u,v) any more, so a new cut is kept only where every corner is inside one patch
    // (one uv frame) and its triangles stay counter-clockwise there; elsewhere the cut the
    // smoothing checked stays.
    const auto& conn = out.remesh.connectivity;
    auto ccw_in_one_patch = [&](const Tri* f, int n) {
      const int patch = conn.vertex_patch[f[0][0]];
      for (int i = 0; i < n; ++i) {
        for (int v : f[i])
          if (conn.vertex_patch[v] != patch || !patch_interior(conn, v)) return false;
        const Vec2 &a = conn.vertex_uv[f[i][0]], &b = conn.vertex_uv[f[i][1]], &c = conn.vertex_uv[f[i][2]];
        if (!(cross2(b - a, c - a) > 0)) return false;
      }
      return true;
    };
    // (f1 starts at f0's first corner: cut 0-2.) A cell has two cuts: the other one is taken only
    // where it is accepted.
    for (const auto& cut : cuts) {
      Tri &f0 = faces[cut.first_face], &f1 = faces[cut.first_face + 1];
      const Tri k0 = f0, k1 = f1;
      recut_cell_best_angle(f0, f1, f1[0] == f0[0], out.remesh.positions);
      const Tri both[2] = {f0, f1};
      if ((f0 != k0 || f1 != k1) && !ccw_in_one_patch(both, 2)) f0 = k0, f1 = k1;
    }
    for (size_t k = 0; k < templates.size(); ++k)
      recut_template_best_angle(&faces[templates[k]], pentagons[k], out.remesh.positions,
                                [&](const std::array<Tri, 3>& cut) { return ccw_in_one_patch(cut.data(), 3); });
  }
  // Rounds of edge flips on the surface, each but the last followed by the interior smoothing of
  // the flipped rings.
  for (int r = 0; r < options.flip_rounds; ++r) {
    context.check_cancel();
    std::vector<char> touched(out.remesh.connectivity.num_vertices(), 0);
    out.stats.flips +=
        flip_for_angles(samplers, out.remesh.connectivity, out.remesh.positions, options.smooth_below, touched);
    if (r + 1 < options.flip_rounds) {
      out.stats.smoothed_moves += smooth_interior(samplers, out.remesh.connectivity, out.remesh.positions,
                                                  options.smooth_iterations, options.smooth_below, &touched);
      if (slide)
        out.stats.slid_moves += slide_sides(samplers, out.remesh.connectivity, out.remesh.positions,
                                            options.smooth_iterations, options.smooth_below, &touched);
    }
  }
  context.report("remesh", 1.0);
  return out;
}

AnisotropicOptions anisotropic_options(int level, int patches, double share_sum) {
  if (level < 0 || level > kMaxAnisotropicLevel)
    throw InvalidInput("remesh: level " + std::to_string(level) + " is out of range for the anisotropic remesh; "
                       "expected 0.." + std::to_string(kMaxAnisotropicLevel));
  if (patches < 1) throw InvalidInput("remesh: " + std::to_string(patches) + " patches; expected at least 1");
  if (!(share_sum >= 1) || !std::isfinite(share_sum))
    throw InvalidInput("remesh: the patches' largest shares of the surface add up to " + std::to_string(share_sum) +
                       "; expected a finite number >= 1");
  AnisotropicOptions o;
  o.max_area = kAnisoAreaFactor * share_sum / (static_cast<double>(patches) * std::ldexp(1.0, 2 * level));
  o.max_level = std::min(level + 6, kMaxAnisotropicLevel);
  return o;
}

AnisotropicRemesh remesh_even_anisotropic(const std::vector<const dissect::Chart*>& charts, int level,
                                          const Context& context) {
  if (charts.empty() || charts.front() == nullptr) throw InvalidInput("remesh: no charts to remesh");
  double sum = 0;
  for (double a : patch_area_shares(charts)) sum += a;
  return remesh_anisotropic(
      charts, anisotropic_options(level, static_cast<int>(charts.front()->patches.size()), std::max(sum, 1.0)), context);
}

}  // namespace qs::remesh
