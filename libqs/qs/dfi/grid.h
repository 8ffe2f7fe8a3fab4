#pragma once
// A regular 3D grid of scalar samples: the common domain of every distance field of a morph.

#include <array>
#include <cstddef>
#include <vector>

#include "qs/core/mesh.h"

namespace qs::dfi {

/// Sample (i, j, k) sits at origin + spacing * (i, j, k); values are stored x fastest.
struct Grid {
  Vec3 origin = Vec3::Zero();
  double spacing = 1.0;
  std::array<int, 3> dims{0, 0, 0};  ///< samples per axis
  std::vector<float> values;         ///< dims[0] * dims[1] * dims[2], or empty

  size_t size() const { return static_cast<size_t>(dims[0]) * dims[1] * dims[2]; }
  size_t index(int i, int j, int k) const {
    return (static_cast<size_t>(k) * dims[1] + j) * dims[0] + i;
  }
  Vec3 point(int i, int j, int k) const { return origin + spacing * Vec3(i, j, k); }
  /// The cell that holds p (clamped to the grid: its lowest corner c) and p's fractions f in it,
  /// the cell the trilinear rules below interpolate in.
  void locate(const Vec3& p, int c[3], double f[3]) const;
  /// Trilinear interpolation; points outside the grid are clamped to its boundary.
  double sample(const Vec3& p) const;
};

/// A grid over `box` (in world units) with `cells` cells along its longest side plus `pad` cells
/// of margin on every side; values empty. \throws InvalidInput when cells < 4 or the box is empty.
Grid grid_over(const Box3& box, int cells, int pad);

}  // namespace qs::dfi
