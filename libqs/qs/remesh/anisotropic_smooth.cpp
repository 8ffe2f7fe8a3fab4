// The anisotropic remesh's smoothing: the interior vertices move within their patch, the side
// vertices along their side, one uv for the whole set (docs/algorithms.md).

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "qs/core/error.h"
#include "qs/core/geometry2d.h"
#include "qs/mesh/connectivity.h"
#include "qs/remesh/anisotropic_detail.h"

namespace qs::remesh::aniso {

// The interior smoothing keeps a move that raises its ring's summed angle quality while the ring's
// worst angle keeps at least this share of its sine (docs/algorithms.md).
constexpr double kSmoothWorstSlack = 0.9;

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

namespace {

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

}  // namespace

// A 3-triangle template cell (A, M, B, C, D counter-clockwise, M the hanging vertex between A and
// B), emitted as (A, M, D), (M, B, C), (M, C, D): re-cut as the fan from C, (C, D, A), (C, A, M),
// (C, M, B), or from D, (D, A, M), (D, M, B), (D, B, C), when that raises the smallest angle over
// the set. Every inner edge of the three joins at most one point of the patch border (see the
// header), so no other patch can emit it. With `accept`, only the present cut and the cuts it
// accepts are candidates.
void recut_template_best_angle(Tri* f, const std::array<int, 5>& amcbd, const std::vector<std::vector<Vec3>>& positions,
                               const std::function<bool(const std::array<Tri, 3>&)>& accept) {
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

namespace {

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

}  // namespace

// Tangential smoothing of the patch-interior vertices (docs/algorithms.md): Gauss-Seidel in vertex
// order, one uv per vertex for the whole set. Returns the number of accepted moves.
// With `active` (#V flags), only the flagged vertices and, sweep after sweep, the neighbours of
// the moved ones are tried (the flipped rings after a round of flips: the others are where the
// previous smoothing left them).
int smooth_interior(const std::vector<ChartSampler>& samplers, SemiRegularConnectivity& c,
                    std::vector<std::vector<Vec3>>& positions, int iterations, double below_degrees,
                    std::vector<char>* active) {
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

namespace {

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

}  // namespace

// Sliding of the patch-side vertices along their side (docs/algorithms.md): like smooth_interior, but
// a side vertex has one unknown, its fraction along the side, shared by the two patches of the
// side (its (patch, u, v) stays on that side of its patch, so both patches still evaluate it on
// the side's polyline, bit-identical). Only vertices whose every ring face has a patch-interior
// corner in one of the side's two (distinct) patches move. Returns the number of accepted moves.
// With `active` (#V flags), only the flagged vertices are tried (the flipped rings of a round).
int slide_sides(const std::vector<ChartSampler>& samplers, SemiRegularConnectivity& c,
                std::vector<std::vector<Vec3>>& positions, int iterations, double below_degrees,
                const std::vector<char>* active) {
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

}  // namespace qs::remesh::aniso
