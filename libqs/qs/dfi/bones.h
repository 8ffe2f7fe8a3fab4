#pragma once
// The rotation-aware warp of skeleton-guided DFI: every matched skeleton branch pair is cut into
// segments at equal arc-length fractions (the paper's anchors along matched branches), and each
// source segment gets the transform that carries it onto its target segment:
//
//   x -> T + R (sigma_r (I - a a^T) + sigma_a a a^T) (x - S)
//
// S, T the segment midpoints, a the source segment's direction, R the smallest rotation taking it
// to the target's, sigma_a the length ratio, sigma_r the ratio of the shapes' radii there (the
// distance fields at the skeleton). Frame s interpolates each transform as-rigidly-as-possible:
// the rotation by angle s theta about its axis (not the linear blend, which shrinks what turns),
// the stretch linearly from I, the centre linearly from S to T. A point moves by the blend of the
// segments' interpolated transforms with weights 1 / (d^2 + r^2)^2 (d its distance to the source
// segment, r the segment's radius): a leg matched to a leg moves with it nearly rigidly, so its
// warped field keeps its thickness and meets the other shape's leg warped the other way.
//
// The inverse transforms (target segments onto source ones) warp the target's field the same
// way; at s and 1 - s the two agree where the transforms are exact.

#include <vector>

#include "qs/dfi/grid.h"
#include "qs/dfi/matching.h"
#include "qs/dfi/skeleton.h"
#include "qs/dfi/warp.h"

namespace qs::dfi {

struct Bone {
  Vec3 from_a, from_b;                                  ///< the segment in the space it moves out of
  Vec3 to_a, to_b;                                      ///< where it goes
  double radius = 0;                                    ///< shape radius around from_a..from_b (>= one spacing)
  double radial_scale = 1;                              ///< sigma_r, clamped to [0.5, 2]
};

/// Segments along every matched branch pair: `segments` per branch at equal arc-length fractions,
/// source -> target. Radii are -sdf at the skeleton points (at least `min_radius`).
std::vector<Bone> branch_bones(const Skeleton& source, const std::vector<Branch>& source_branches, const Skeleton& target,
                               const std::vector<Branch>& target_branches, const SkeletonMatching& matching,
                               const Grid& source_sdf, const Grid& target_sdf, int segments, double min_radius);

/// The same segments the other way round (target -> source).
std::vector<Bone> inverse_bones(const std::vector<Bone>& bones);

/// The interpolated transform of one bone at s in [0, 1] applied to x (s = 0: x, s = 1: the
/// full transform).
Vec3 bone_transform(const Bone& b, double s, const Vec3& x);

/// The displacement x_s - x on the samples of `geometry` (its values unused), x_s the weighted
/// blend of the bones' transforms at s. \pre bones not empty.
Displacement bone_displacement(const std::vector<Bone>& bones, const Grid& geometry, double s, int threads = 0);

/// Smallest Jacobian determinant of x -> x + u(x) over the cells of u's grid.
double min_jacobian(const Displacement& d);

struct FoldRepair {
  double min_det = 1;  ///< smallest det(I + grad u) over the cells at the last check
  int rounds = 0;      ///< rounds of local smoothing applied
};

/// Repairs folds where they are: while a cell has det(I + grad u) < min_det and fewer than
/// max_rounds rounds were applied, the samples of such cells and their neighbours (a 4^3 block per
/// cell) get 4 Jacobi steps (each the mean of itself and its 6 neighbours); samples away from
/// every fold are left exactly as they were. Used on every frame of the part warp (0.1, 40), so a
/// fold where two parts' transforms meet does not send the whole morph to the linear warp.
FoldRepair repair_folds_locally(Displacement& d, double min_det = 0.1, int max_rounds = 40);

}  // namespace qs::dfi
