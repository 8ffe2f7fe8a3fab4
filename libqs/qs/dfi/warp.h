#pragma once
// The space warp of skeleton-guided DFI: from the dense voxel correspondence, a displacement
// field u over the whole (coarse) grid that moves each interior voxel of one shape to the
// flow-weighted mean position of its partners in the other shape, extended harmonically to the
// rest of the grid. Frame t samples each shape's distance field at the inverse of x -> x + s u(x)
// (s = t for the source, 1 - t for the target), found by fixed-point iteration.
//
// The paper uses the as-rigid-as-possible DFI of Weng et al. for this step; ours is the plain
// linear warp, checked for folds: det(I + s grad u) > 0 in every cell for s in (0, 1], else the
// field is smoothed (Jacobi steps of the Laplacian) until it holds.

#include <array>
#include <vector>

#include "qs/dfi/grid.h"
#include "qs/dfi/harmonic.h"

namespace qs::dfi {

struct Displacement {
  std::array<Grid, 3> u;  ///< x, y, z components on the coarse grid
  Vec3 at(const Vec3& p) const { return Vec3(u[0].sample(p), u[1].sample(p), u[2].sample(p)); }
};

/// Harmonic extension to every coarse-grid sample of the displacements given at interior voxels
/// (`destination[i] - voxels.position(i)`). \throws SolverError if the factorization fails.
Displacement extend_displacement(const VoxelSet& voxels, const std::vector<Vec3>& destination);

struct FoldCheck {
  double min_det = 1;      ///< smallest det(I + s grad u) over cells and the checked s
  double at_s = 0;         ///< where it was reached
  int smoothing_steps = 0; ///< Jacobi steps applied to remove folds
};

/// The gradient of u at the centre of cell (i, j, k) (its lowest sample): averaged forward
/// differences over the cell's 4 edges along each axis; rows are the components.
Eigen::Matrix3d cell_gradient(const Displacement& d, int i, int j, int k);

/// `steps` Jacobi steps of the Laplacian on every component of u: each sample becomes the mean of
/// itself and its (up to 6) grid neighbours; with `only`, just the samples marked there.
void jacobi_smooth(Displacement& d, int steps, const std::vector<char>* only = nullptr);

/// Smallest Jacobian determinant of x -> x + s u(x) over the cells, for s = 0.1, 0.2, ..., 1.
FoldCheck check_folds(const Displacement& d);

/// Smooths until check_folds() finds no fold (min_det >= min_det_wanted) or max_steps were
/// applied; returns the final check. Each step replaces every sample by the mean of itself and
/// its 6 neighbours.
FoldCheck remove_folds(Displacement& d, double min_det_wanted = 0.05, int max_steps = 400);

/// The field sdf warped by s u: value at y = sdf(x) where x + s u(x) = y (fixed point, 6 steps).
Grid warped_field(const Grid& sdf, const Displacement& d, double s, int threads = 0);

/// The field sdf warped by u (s = 1): value at y = sdf(x) where x + u(x) = y, by at most 8 Newton steps
/// with the gradient of u's trilinear interpolation (a plain fixed-point step where I + grad u is
/// nearly singular); converges for displacements that rotate (where the fixed point does not).
Grid warped_field_newton(const Grid& sdf, const Displacement& d, int threads = 0);

}  // namespace qs::dfi
