#include "qs/family/sphere_hull.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/convex_hull_3.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <string>
#include <tuple>

#include "qs/core/error.h"

namespace qs::family::detail {

std::vector<Tri> sphere_hull(const std::vector<Vec3>& points) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using P = K::Point_3;
  std::vector<P> in;
  in.reserve(points.size());
  for (const Vec3& p : points) in.emplace_back(p.x(), p.y(), p.z());
  std::vector<P> hull_points;
  std::vector<std::array<std::size_t, 3>> hull_faces;
  CGAL::convex_hull_3(in.begin(), in.end(), hull_points, hull_faces);
  if (hull_points.size() != points.size())
    throw InternalError("sphere_hull: " + std::to_string(points.size() - hull_points.size()) + " of " +
                        std::to_string(points.size()) + " parameter points are not hull vertices");
  // Hull vertices are copies of input points: map them back by exact coordinates.
  auto key = [](const P& p) { return std::make_tuple(p.x(), p.y(), p.z()); };
  std::vector<std::pair<std::tuple<double, double, double>, int>> order;
  order.reserve(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) order.emplace_back(key(in[i]), static_cast<int>(i));
  std::sort(order.begin(), order.end());
  std::vector<int> id(hull_points.size(), -1);
  for (std::size_t h = 0; h < hull_points.size(); ++h) {
    auto it = std::lower_bound(order.begin(), order.end(), std::make_pair(key(hull_points[h]), -1));
    if (it == order.end() || it->first != key(hull_points[h]))
      throw InternalError("sphere_hull: a hull vertex is not one of the input points");
    id[h] = it->second;
  }
  std::vector<Tri> faces;
  faces.reserve(hull_faces.size());
  for (const auto& f : hull_faces) faces.push_back({id[f[0]], id[f[1]], id[f[2]]});
  if (faces.size() != 2 * points.size() - 4)
    throw InternalError("sphere_hull: the hull has " + std::to_string(faces.size()) + " faces, expected " +
                        std::to_string(2 * points.size() - 4));
  // Orient outward (CGAL's hull faces outward already; make it explicit and independent of that).
  for (Tri& t : faces) {
    const Vec3& a = points[t[0]];
    if ((points[t[1]] - a).cross(points[t[2]] - a).dot(a + points[t[1]] + points[t[2]]) < 0) std::swap(t[1], t[2]);
  }
  // A canonical order: the hull's own face order is an implementation detail.
  for (Tri& t : faces) std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
  std::sort(faces.begin(), faces.end());
  return faces;
}

}  // namespace qs::family::detail
