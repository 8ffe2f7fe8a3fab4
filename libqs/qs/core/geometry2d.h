#pragma once
// Small geometric pieces shared across modules: the 2D cross product, barycentric coordinates and
// point location in uv triangles, distances to segments and polylines. Header only; each function
// fixes its floating-point operation order, so every caller gets the same bits.

#include <algorithm>
#include <cmath>
#include <utility>
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

/// The squared distance from p to the segment [a, b]. V: Vec2 or Vec3.
template <class V>
double segment_distance2(const V& p, const V& a, const V& b) {
  const V d = b - a;
  return (a + segment_parameter(p, a, b) * d - p).squaredNorm();
}

/// The distance from p to the segment [a, b]. V: Vec2 or Vec3.
template <class V>
double segment_distance(const V& p, const V& a, const V& b) {
  return std::sqrt(segment_distance2(p, a, b));
}

/// The distance from p to the polyline `line` (its segments; one point: that point).
/// \pre line not empty.
inline double polyline_distance(const Vec3& p, const std::vector<Vec3>& line) {
  double best = (line.front() - p).squaredNorm();
  for (size_t k = 0; k + 1 < line.size(); ++k) best = std::min(best, segment_distance2(p, line[k], line[k + 1]));
  return std::sqrt(best);
}

/// polyline_distance to one line for many points: a hierarchy of boxes over runs of its segments
/// prunes the segments that cannot be nearest. The same value as polyline_distance, bit for bit
/// (the same segment_distance2 terms, and a run is skipped only when its box is farther than the
/// best so far by a margin above rounding).
class PolylineDistance {
 public:
  /// \pre line not empty; it must outlive this object.
  explicit PolylineDistance(const std::vector<Vec3>& line) : line_(line) {
    if (line.size() < 2) return;
    nodes_.emplace_back();
    fill(0, 0, static_cast<int>(line.size()) - 1);
  }

  double operator()(const Vec3& p) const {
    double best = (line_.front() - p).squaredNorm();
    if (nodes_.empty()) return std::sqrt(best);
    auto box = [&](const Node& n) { return (n.lo - p).cwiseMax(p - n.hi).cwiseMax(0.0).squaredNorm(); };
    std::pair<double, int> stack[64];  // (box distance^2, node), the nearer child on top
    int top = 0;
    stack[top++] = {box(nodes_[0]), 0};
    while (top > 0) {
      const auto [d2, i] = stack[--top];
      if (d2 > best * (1 + 1e-9)) continue;
      const Node& n = nodes_[i];
      if (n.left < 0) {
        for (int k = n.begin; k < n.end; ++k) best = std::min(best, segment_distance2(p, line_[k], line_[k + 1]));
        continue;
      }
      const double l = box(nodes_[n.left]), r = box(nodes_[n.left + 1]);
      if (l <= r) {
        stack[top++] = {r, n.left + 1};
        stack[top++] = {l, n.left};
      } else {
        stack[top++] = {l, n.left};
        stack[top++] = {r, n.left + 1};
      }
    }
    return std::sqrt(best);
  }

 private:
  static constexpr int kLeaf = 8;  ///< segments per leaf
  struct Node {
    Vec3 lo, hi;
    int begin, end;  ///< segments [begin, end)
    int left;        ///< the first of two consecutive children; -1 for a leaf
  };
  /// Node `at` over segments [begin, end), its subtree appended.
  void fill(int at, int begin, int end) {
    Node n{line_[begin], line_[begin], begin, end, -1};
    for (int k = begin; k <= end; ++k) n.lo = n.lo.cwiseMin(line_[k]), n.hi = n.hi.cwiseMax(line_[k]);
    if (end - begin > kLeaf) {  // two children at consecutive indices
      n.left = static_cast<int>(nodes_.size());
      nodes_.resize(nodes_.size() + 2);
      const int mid = begin + (end - begin) / 2;
      fill(n.left, begin, mid);
      fill(n.left + 1, mid, end);
    }
    nodes_[at] = n;
  }
  const std::vector<Vec3>& line_;
  std::vector<Node> nodes_;
};

}  // namespace qs
