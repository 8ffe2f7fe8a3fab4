#pragma once
// The as-rigid-as-possible DFI of Weng et al. as the skeleton-guided DFI paper uses it (section 3):
// corresponding centre pairs (x_i in the source, y_i in the target: the anchors and a sample of
// the dense transport correspondence) get in-between positions p_i(t) that interpolate each
// centre's neighbourhood as rigidly as possible, and every frame's backward warps B_0^t, B_1^t
// (frame space -> source, frame space -> target) are thin-plate radial basis functions with a
// global affine part fitted to p_i(t) -> x_i and p_i(t) -> y_i.
//
// Neighbourhoods: each centre's k nearest centres (by the 6-vector (x, y)). Its local map J_i
// (least squares from the source edges x_j - x_i to the target edges y_j - y_i) is split by the
// polar decomposition J_i = R_i S_i (S's eigenvalues clamped to [0.2, 5]); at t it is A_i(t) = R_i^t ((1 - t) I + t S_i) (rotation
// angle interpolated, stretch linearly). The positions minimize
//   sum_i sum_{j in N(i)} |(p_j - p_i) - (A_i(t) + A_j(t)) / 2 (x_j - x_i)|^2
// with their mean at (1 - t) mean(x) + t mean(y); the residual at the ends is then spread
// linearly in t so that p(0) = x and p(1) = y exactly.
//
// The thin-plate RBF in 3D: f(q) = c + M q + sum_k w_k |q - p_k| (the biharmonic kernel) with
// sum_k w_k = 0 and sum_k w_k p_k^T = 0, smoothed by lambda (K + lambda I): it needs no grid, and
// a centre that moves far carries its surroundings along smoothly. The frame's field is then
// D_t(q) = (1 - t) D_0(B_0^t(q)) + t D_1(B_1^t(q)) (equation 3).

#include <vector>

#include <Eigen/Dense>

#include "qs/dfi/grid.h"
#include "qs/dfi/warp.h"

namespace qs::dfi {

struct ArapInterpolation {
  std::vector<Vec3> source, target;          ///< the centre pairs
  std::vector<std::vector<int>> neighbours;  ///< per centre, its k nearest
  std::vector<Eigen::Matrix3d> rotation, stretch;  ///< polar parts of the local maps
  Eigen::MatrixXd solve;                     ///< the positions' normal matrix, inverted (n x n)
  std::vector<Vec3> residual0, residual1;    ///< x - p(0), y - p(1) before the correction
  bool empty() const { return source.empty(); }
};

/// \pre source.size() == target.size() >= 5. k: neighbours per centre (clamped to n - 1).
ArapInterpolation build_arap(const std::vector<Vec3>& source, const std::vector<Vec3>& target, int k = 8);

/// The in-between centre positions at t in [0, 1] (exactly the sources at 0, the targets at 1).
std::vector<Vec3> arap_positions(const ArapInterpolation& a, double t);

/// A thin-plate RBF with a global affine part from `from` to `to` (same sizes, >= 4 points not
/// all in a plane for an exact affine part), smoothed by lambda.
struct ThinPlate {
  std::vector<Vec3> centres;
  Eigen::MatrixXd weights;  ///< n x 3
  Eigen::Matrix3d linear = Eigen::Matrix3d::Identity();
  Vec3 offset = Vec3::Zero();
  Vec3 operator()(const Vec3& q) const;
};
ThinPlate fit_thin_plate(const std::vector<Vec3>& from, const std::vector<Vec3>& to, double lambda);

/// f(q) - q on the samples of `geometry` (its values unused).
Displacement thin_plate_displacement(const ThinPlate& f, const Grid& geometry, int threads = 0);

/// The field sdf pulled back through q -> q + back(q): the value at q is sdf(q + back(q)).
Grid pulled_field(const Grid& sdf, const Displacement& back, int threads = 0);

/// Up to `count` indices of `points` by farthest-point sampling from the first (deterministic).
std::vector<int> farthest_points(const std::vector<Vec3>& points, int count);

}  // namespace qs::dfi
