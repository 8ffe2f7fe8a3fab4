// The anisotropic remesh's trees: refinement by area and aspect, 2:1 balance, and the faces of the
// leaves (docs/algorithms.md).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <unordered_set>
#include <utility>

#include "qs/core/error.h"
#include "qs/remesh/anisotropic_detail.h"
#include "qs/remesh/quality.h"
#include "qs/remesh/uniform.h"

namespace qs::remesh::aniso {

namespace {

// Node rectangles in integer units of 2^-kUnits of the unit square (kUnits > the finest numbering
// level, so that a point half a finest cell outside a side is an integer too).
constexpr int kUnits = kMaxUniformLevel + 2;
constexpr int kSpan = 1 << kUnits;

// A node is split for its aspect alone only while it covers more than this share of max_area, so
// that a map degenerate at a point (every node near it long) cannot refine it to max_level.
constexpr double kAspectAreaFloor = 1.0 / 16;

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

  // 2:1 balance along every leaf side (docs/algorithms.md).
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
    // Never a leaf side across the whole patch (docs/algorithms.md).
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

  // The node's area share and aspect over the set (docs/algorithms.md), measured once.
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

}  // namespace

void build_leaves(const std::vector<ChartSampler>& samplers, const AnisotropicOptions& options,
                  const Context& context, AnisotropicRemesh& out) {
  Builder builder(samplers, options, out.stats);
  const int np = samplers[0].topology().num_patches();
  for (int p = 0; p < np; ++p) {
    context.check_cancel();
    context.report("remesh", 0.6 * p / np);
    builder.refine_patch(p);
  }
  builder.balance();
  builder.leaves(out.leaves, out.leaf_aspect);
}

// Faces of the leaves (docs/algorithms.md), the cells cut in two listed in `cuts`.
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
      push_cell(faces, c, d02);
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

}  // namespace qs::remesh::aniso
