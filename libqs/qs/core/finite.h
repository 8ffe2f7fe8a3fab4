#pragma once
// What counts as a usable number in qs's inputs: finite, and for coordinates small enough that
// squares, cross products and volumes (cubes) of differences stay finite in double precision.

#include <cmath>

#include "qs/core/mesh.h"

namespace qs {

/// The largest coordinate magnitude qs accepts anywhere (meshes, landmark points, remesh files):
/// (2 * 1e100)^3 is far below the largest double, so every length, area and volume is finite.
inline constexpr double kMaxCoordinate = 1e100;

/// True for a finite number of magnitude at most kMaxCoordinate (false for NaN and infinities).
inline bool usable_coordinate(double x) { return std::abs(x) <= kMaxCoordinate; }
inline bool usable_position(const Vec3& p) {
  return usable_coordinate(p.x()) && usable_coordinate(p.y()) && usable_coordinate(p.z());
}

}  // namespace qs
