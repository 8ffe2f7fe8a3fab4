#pragma once
// Internal to qs::family: the convex hull of points on the unit sphere (their spherical Delaunay
// triangulation), behind a plain interface so that CGAL stays in one .cpp file.

#include <vector>

#include "qs/core/mesh.h"

namespace qs::family::detail {

/// Faces (ids into `points`, counter-clockwise seen from outside) of the convex hull of points
/// that lie on the unit sphere. \throws InternalError if a point is not a hull vertex (points
/// closer than about 1e-12 to each other) or the hull is not a closed triangulation.
std::vector<Tri> sphere_hull(const std::vector<Vec3>& points);

}  // namespace qs::family::detail
