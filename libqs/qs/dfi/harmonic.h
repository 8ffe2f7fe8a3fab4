#pragma once
// Harmonic fields on the interior voxels of a shape (skeleton-guided DFI, equation 4): for each
// anchor i, h_i = 1 at the anchor's voxel, 0 at the other anchors' voxels, and at every other
// interior voxel the mean of its face-adjacent interior neighbours.

#include <Eigen/Core>
#include <vector>

#include "qs/dfi/grid.h"

namespace qs::dfi {

/// The samples of a coarse grid that lie inside a shape (its signed distance, sampled
/// trilinearly, is negative there).
struct VoxelSet {
  Grid grid;                 ///< geometry of the coarse grid (values unused)
  std::vector<int> sample;   ///< per interior voxel, its sample index in grid
  std::vector<int> local;    ///< per grid sample, its interior voxel index or -1
  Vec3 position(int voxel) const;
};

/// Interior voxels of the shape whose signed distance is `sdf`, on the coarse grid `coarse`.
VoxelSet interior_voxels(const Grid& sdf, const Grid& coarse);

/// The interior voxel nearest to p (lowest index on ties), or -1 when there is none.
int nearest_voxel(const VoxelSet& v, const Vec3& p);

/// #voxels x K fields for the K anchor voxels (distinct voxel indices). Components of interior
/// voxels without an anchor get 0 (a 1e-9 diagonal regularization keeps the system definite).
/// \throws InvalidInput for a repeated or out-of-range anchor voxel; SolverError if the
/// factorization fails.
Eigen::MatrixXd harmonic_fields(const VoxelSet& v, const std::vector<int>& anchor_voxels);

}  // namespace qs::dfi
