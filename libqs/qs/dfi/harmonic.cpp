#include "qs/dfi/harmonic.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <limits>
#include <string>

#include "qs/core/error.h"

namespace qs::dfi {

Vec3 VoxelSet::position(int voxel) const {
  const int s = sample[voxel];
  const int nx = grid.dims[0], ny = grid.dims[1];
  return grid.point(s % nx, (s / nx) % ny, s / (nx * ny));
}

VoxelSet interior_voxels(const Grid& sdf, const Grid& coarse) {
  VoxelSet v;
  v.grid = coarse;
  v.grid.values.clear();
  v.local.assign(coarse.size(), -1);
  for (int k = 0; k < coarse.dims[2]; ++k)
    for (int j = 0; j < coarse.dims[1]; ++j)
      for (int i = 0; i < coarse.dims[0]; ++i)
        if (sdf.sample(coarse.point(i, j, k)) < 0) {
          const int s = static_cast<int>(coarse.index(i, j, k));
          v.local[s] = static_cast<int>(v.sample.size());
          v.sample.push_back(s);
        }
  return v;
}

int nearest_voxel(const VoxelSet& v, const Vec3& p) {
  int best = -1;
  double bd = std::numeric_limits<double>::infinity();
  for (int i = 0; i < static_cast<int>(v.sample.size()); ++i) {
    const double d = (v.position(i) - p).squaredNorm();
    if (d < bd) {
      bd = d;
      best = i;
    }
  }
  return best;
}

Eigen::MatrixXd harmonic_fields(const VoxelSet& v, const std::vector<int>& anchors) {
  const int n = static_cast<int>(v.sample.size()), K = static_cast<int>(anchors.size());
  std::vector<int> anchor_of(n, -1);
  for (int a = 0; a < K; ++a) {
    if (anchors[a] < 0 || anchors[a] >= n)
      throw InvalidInput("harmonic fields: anchor " + std::to_string(a) + " has voxel " + std::to_string(anchors[a]) +
                         ", out of range (" + std::to_string(n) + " interior voxels)");
    if (anchor_of[anchors[a]] >= 0)
      throw InvalidInput("harmonic fields: anchors " + std::to_string(anchor_of[anchors[a]]) + " and " +
                         std::to_string(a) + " share voxel " + std::to_string(anchors[a]));
    anchor_of[anchors[a]] = a;
  }
  // Unknowns: the non-anchor voxels.
  std::vector<int> unknown(n, -1);
  int nu = 0;
  for (int i = 0; i < n; ++i)
    if (anchor_of[i] < 0) unknown[i] = nu++;
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(n, K);
  for (int a = 0; a < K; ++a) h(anchors[a], a) = 1.0;
  if (nu == 0 || K == 0) return h;
  const int nx = v.grid.dims[0], ny = v.grid.dims[1], nz = v.grid.dims[2];
  std::vector<Eigen::Triplet<double>> trip;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(nu, K);
  for (int i = 0; i < n; ++i) {
    if (unknown[i] < 0) continue;
    const int s = v.sample[i];
    const int x = s % nx, y = (s / nx) % ny, z = s / (nx * ny);
    const int nb[6][3] = {{x - 1, y, z}, {x + 1, y, z}, {x, y - 1, z}, {x, y + 1, z}, {x, y, z - 1}, {x, y, z + 1}};
    int degree = 0;
    for (const auto& q : nb) {
      if (q[0] < 0 || q[1] < 0 || q[2] < 0 || q[0] >= nx || q[1] >= ny || q[2] >= nz) continue;
      const int j = v.local[v.grid.index(q[0], q[1], q[2])];
      if (j < 0) continue;
      ++degree;
      if (unknown[j] >= 0) trip.emplace_back(unknown[i], unknown[j], -1.0);
      else rhs(unknown[i], anchor_of[j]) += 1.0;
    }
    trip.emplace_back(unknown[i], unknown[i], degree + 1e-9);
  }
  Eigen::SparseMatrix<double> L(nu, nu);
  L.setFromTriplets(trip.begin(), trip.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(L);
  if (solver.info() != Eigen::Success) throw SolverError("harmonic fields: the factorization failed");
  const Eigen::MatrixXd x = solver.solve(rhs);
  for (int i = 0; i < n; ++i)
    if (unknown[i] >= 0) h.row(i) = x.row(unknown[i]);
  return h;
}

}  // namespace qs::dfi
