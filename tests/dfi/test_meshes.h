#pragma once
// Helpers for the dfi tests: analytic fields on grids and an independent self-intersection check.

#include <algorithm>
#include <cmath>
#include <functional>

#include "qs/core/mesh.h"
#include "qs/dfi/grid.h"

namespace qs::dfi::test_support {

/// A grid over [-extent, extent]^3 with `cells` cells per side, sampled from f.
inline Grid analytic_grid(double extent, int cells, const std::function<double(const Vec3&)>& f) {
  Box3 box;
  box.min = Vec3::Constant(-extent);
  box.max = Vec3::Constant(extent);
  Grid g = grid_over(box, cells, 2);
  g.values.resize(g.size());
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) g.values[g.index(i, j, k)] = static_cast<float>(f(g.point(i, j, k)));
  return g;
}

inline double sphere_sd(const Vec3& p, const Vec3& c, double r) { return (p - c).norm() - r; }
/// Torus about z, tube centre radius R, tube radius r.
inline double torus_sd(const Vec3& p, double R, double r) {
  return std::hypot(std::hypot(p.x(), p.y()) - R, p.z()) - r;
}

/// 2D: does segment pq cross triangle abc (an edge crossed properly, or p or q strictly inside)?
/// Coordinates are the two axes other than `drop`.
inline bool segment_hits_triangle_2d(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c,
                                     int drop) {
  const int x = (drop + 1) % 3, y = (drop + 2) % 3;
  auto o = [&](const Vec3& u, const Vec3& v, const Vec3& w) {
    return (v[x] - u[x]) * (w[y] - u[y]) - (v[y] - u[y]) * (w[x] - u[x]);
  };
  auto inside = [&](const Vec3& r) {
    const double s1 = o(a, b, r), s2 = o(b, c, r), s3 = o(c, a, r);
    return (s1 > 0 && s2 > 0 && s3 > 0) || (s1 < 0 && s2 < 0 && s3 < 0);
  };
  auto crosses = [&](const Vec3& u, const Vec3& v) {
    const double d1 = o(p, q, u), d2 = o(p, q, v), d3 = o(u, v, p), d4 = o(u, v, q);
    return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
  };
  return inside(p) || inside(q) || crosses(a, b) || crosses(b, c) || crosses(c, a);
}

/// Does segment pq cross triangle abc? A proper crossing in 3D; where pq lies in abc's plane (to
/// rounding: both orientations below 1e-9 of the scale's cube, as on the planar patches of a field
/// sampled on grid planes), the 2D test in that plane instead of the noise of the 3D signs.
inline bool segment_hits_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c) {
  auto orient = [](const Vec3& w, const Vec3& x, const Vec3& y, const Vec3& z) { return (x - w).dot((y - w).cross(z - w)); };
  const double sp = orient(a, b, c, p), sq = orient(a, b, c, q);
  const double scale = std::max({(b - a).norm(), (c - a).norm(), (q - p).norm()});
  const double eps = 1e-9 * scale * scale * scale;
  if (std::abs(sp) <= eps && std::abs(sq) <= eps) {
    const Vec3 n = (b - a).cross(c - a).cwiseAbs();
    const int drop = n.x() >= n.y() && n.x() >= n.z() ? 0 : (n.y() >= n.z() ? 1 : 2);
    return segment_hits_triangle_2d(p, q, a, b, c, drop);
  }
  if ((sp > 0 && sq > 0) || (sp < 0 && sq < 0) || sp == 0 || sq == 0) return false;
  const double s1 = orient(p, q, a, b), s2 = orient(p, q, b, c), s3 = orient(p, q, c, a);
  return (s1 > 0 && s2 > 0 && s3 > 0) || (s1 < 0 && s2 < 0 && s3 < 0);
}

/// Pairs of faces sharing no vertex whose edges cross the other face (brute force with boxes).
inline int self_intersections(const TriMesh& m) {
  const int nf = m.num_faces();
  std::vector<Box3> boxes(nf);
  for (int f = 0; f < nf; ++f) {
    boxes[f].min = boxes[f].max = m.positions[m.faces[f][0]];
    for (int v : m.faces[f]) {
      boxes[f].min = boxes[f].min.cwiseMin(m.positions[v]);
      boxes[f].max = boxes[f].max.cwiseMax(m.positions[v]);
    }
  }
  std::vector<int> order(nf);
  for (int f = 0; f < nf; ++f) order[f] = f;
  std::sort(order.begin(), order.end(), [&](int a, int b) { return boxes[a].min.x() < boxes[b].min.x(); });
  int hits = 0;
  for (int ii = 0; ii < nf; ++ii) {
    const int f = order[ii];
    for (int jj = ii + 1; jj < nf && boxes[order[jj]].min.x() <= boxes[f].max.x(); ++jj) {
      const int g = order[jj];
      if ((boxes[f].min.array() > boxes[g].max.array()).any() || (boxes[g].min.array() > boxes[f].max.array()).any())
        continue;
      bool shared = false;
      for (int a : m.faces[f])
        for (int b : m.faces[g]) shared |= a == b;
      if (shared) continue;
      bool hit = false;
      for (int e = 0; e < 3 && !hit; ++e) {
        const auto& F = m.faces[f];
        const auto& G = m.faces[g];
        hit = segment_hits_triangle(m.positions[F[e]], m.positions[F[(e + 1) % 3]], m.positions[G[0]],
                                    m.positions[G[1]], m.positions[G[2]]) ||
              segment_hits_triangle(m.positions[G[e]], m.positions[G[(e + 1) % 3]], m.positions[F[0]],
                                    m.positions[F[1]], m.positions[F[2]]);
      }
      hits += hit;
    }
  }
  return hits;
}

}  // namespace qs::dfi::test_support
