#pragma once
// Small geometric pieces shared across modules: the 2D cross product, barycentric coordinates and
// point location in uv triangles, distances to segments and polylines. Header only; each function
// fixes its floating-point operation order, so every caller gets the same bits.

#include <algorithm>
#include <cmath>
#include <vector>

#include "qs/core/mesh.h"

namespace qs {

/// The 2D cross product a.x b.y - a.y b.x (twice the signed area of (0, a, b)).
inline double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

/// Barycentric coordinates of q in the uv triangle (a, b, c), given area = cross2(b - a, c - a)
/// (twice its signed area). \pre area != 0.
inline Vec3 barycentric(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& q, double area) {
  return Vec3(cross2(b - q, c - q) / area, cross2(c - q, a - q) / area, cross2(a - q, b - q) / area);
}

/// Point location by the best barycentric score: when the uv triangle (a, b, c) is positive and q's
/// smallest barycentric coordinate in it beats `score`, takes it (best = id, bary and score updated)
/// and returns true. Scanning candidates with score starting at -infinity leaves q's own triangle,
/// else the one q is least outside of; ties keep the earlier candidate.
inline bool try_uv_triangle(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& q, int id, int& best,
                            Vec3& bary, double& score) {
  const double area = cross2(b - a, c - a);
  if (!(area > 0)) return false;
  const Vec3 w = barycentric(a, b, c, q, area);
  const double s = w.minCoeff();
  if (!(s > score)) return false;
  score = s;
  bary = w;
  best = id;
  return true;
}

/// The parameter t in [0, 1] of the point of segment [a, b] nearest to p (0 for a degenerate
/// segment). V: Vec2 or Vec3.
template <class V>
double segment_parameter(const V& p, const V& a, const V& b) {
  const V d = b - a;
  return std::clamp((p - a).dot(d) / std::max(d.squaredNorm(), 1e-300), 0.0, 1.0);
}

/// The distance from p to the segment [a, b]. V: Vec2 or Vec3.
template <class V>
double segment_distance(const V& p, const V& a, const V& b) {
  const V d = b - a;
  return (a + segment_parameter(p, a, b) * d - p).norm();
}

/// The distance from p to the polyline `line` (its segments; one point: that point).
/// \pre line not empty.
inline double polyline_distance(const Vec3& p, const std::vector<Vec3>& line) {
  double best = (line.front() - p).squaredNorm();
  for (size_t k = 0; k + 1 < line.size(); ++k) {
    const Vec3 d = line[k + 1] - line[k];
    best = std::min(best, (line[k] + segment_parameter(p, line[k], line[k + 1]) * d - p).squaredNorm());
  }
  return std::sqrt(best);
}

}  // namespace qs
