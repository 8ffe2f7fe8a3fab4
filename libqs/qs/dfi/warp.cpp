#include "qs/dfi/warp.h"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>

#include "qs/core/error.h"
#include "qs/core/parallel.h"
#include "qs/dfi/sdf.h"

namespace qs::dfi {

Displacement extend_displacement(const VoxelSet& v, const std::vector<Vec3>& destination) {
  const Grid& g = v.grid;
  const int nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
  const int n = static_cast<int>(g.size());
  std::vector<int> unknown(n, -1);
  int nu = 0;
  for (int s = 0; s < n; ++s)
    if (v.local[s] < 0) unknown[s] = nu++;
  Displacement d;
  for (auto& c : d.u) {
    c = g;
    c.values.assign(n, 0.0f);
  }
  Eigen::MatrixXd fixed(n, 3);
  for (int s = 0; s < n; ++s) {
    const int i = v.local[s];
    const Vec3 u = i >= 0 ? Vec3(destination[i] - v.position(i)) : Vec3::Zero();
    fixed.row(s) = u.transpose();
  }
  if (nu > 0) {
    std::vector<Eigen::Triplet<double>> trip;
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(nu, 3);
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          const int s = static_cast<int>(g.index(i, j, k));
          if (unknown[s] < 0) continue;
          const int nb[6][3] = {{i - 1, j, k}, {i + 1, j, k}, {i, j - 1, k}, {i, j + 1, k}, {i, j, k - 1}, {i, j, k + 1}};
          int degree = 0;
          for (const auto& q : nb) {
            if (q[0] < 0 || q[1] < 0 || q[2] < 0 || q[0] >= nx || q[1] >= ny || q[2] >= nz) continue;
            const int t = static_cast<int>(g.index(q[0], q[1], q[2]));
            ++degree;
            if (unknown[t] >= 0) trip.emplace_back(unknown[s], unknown[t], -1.0);
            else rhs.row(unknown[s]) += fixed.row(t);
          }
          trip.emplace_back(unknown[s], unknown[s], degree + 1e-9);
        }
    Eigen::SparseMatrix<double> L(nu, nu);
    L.setFromTriplets(trip.begin(), trip.end());
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(L);
    if (solver.info() != Eigen::Success) throw SolverError("warp: the displacement extension could not be factorized");
    const Eigen::MatrixXd x = solver.solve(rhs);
    for (int s = 0; s < n; ++s)
      if (unknown[s] >= 0) fixed.row(s) = x.row(unknown[s]);
  }
  for (int s = 0; s < n; ++s)
    for (int c = 0; c < 3; ++c) d.u[c].values[s] = static_cast<float>(fixed(s, c));
  return d;
}

Eigen::Matrix3d cell_gradient(const Displacement& d, int i, int j, int k) {
  const Grid& g = d.u[0];
  Eigen::Matrix3d J;
  for (int c = 0; c < 3; ++c) {
    const auto& u = d.u[c].values;
    auto at = [&](int a, int b, int e) { return static_cast<double>(u[g.index(i + a, j + b, k + e)]); };
    J(c, 0) = (at(1, 0, 0) - at(0, 0, 0) + at(1, 1, 0) - at(0, 1, 0) + at(1, 0, 1) - at(0, 0, 1) + at(1, 1, 1) - at(0, 1, 1)) / 4;
    J(c, 1) = (at(0, 1, 0) - at(0, 0, 0) + at(1, 1, 0) - at(1, 0, 0) + at(0, 1, 1) - at(0, 0, 1) + at(1, 1, 1) - at(1, 0, 1)) / 4;
    J(c, 2) = (at(0, 0, 1) - at(0, 0, 0) + at(1, 0, 1) - at(1, 0, 0) + at(0, 1, 1) - at(0, 1, 0) + at(1, 1, 1) - at(1, 1, 0)) / 4;
  }
  J /= g.spacing;
  return J;
}

FoldCheck check_folds(const Displacement& d) {
  const Grid& g = d.u[0];
  FoldCheck f;
  f.min_det = std::numeric_limits<double>::infinity();
  for (int k = 0; k + 1 < g.dims[2]; ++k)
    for (int j = 0; j + 1 < g.dims[1]; ++j)
      for (int i = 0; i + 1 < g.dims[0]; ++i) {
        const Eigen::Matrix3d J = cell_gradient(d, i, j, k);
        for (int q = 1; q <= 10; ++q) {
          const double s = q / 10.0;
          const double det = (Eigen::Matrix3d::Identity() + s * J).determinant();
          if (det < f.min_det) {
            f.min_det = det;
            f.at_s = s;
          }
        }
      }
  return f;
}

void jacobi_smooth(Displacement& d, int steps, const std::vector<char>* only) {
  const Grid& g = d.u[0];
  const int nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
  for (int step = 0; step < steps; ++step)
    for (auto& comp : d.u) {
      std::vector<float> next = comp.values;
      for (int k = 0; k < nz; ++k)
        for (int j = 0; j < ny; ++j)
          for (int i = 0; i < nx; ++i) {
            const size_t at = g.index(i, j, k);
            if (only && !(*only)[at]) continue;
            double sum = comp.values[at];
            int cnt = 1;
            if (i > 0) sum += comp.values[g.index(i - 1, j, k)], ++cnt;
            if (i + 1 < nx) sum += comp.values[g.index(i + 1, j, k)], ++cnt;
            if (j > 0) sum += comp.values[g.index(i, j - 1, k)], ++cnt;
            if (j + 1 < ny) sum += comp.values[g.index(i, j + 1, k)], ++cnt;
            if (k > 0) sum += comp.values[g.index(i, j, k - 1)], ++cnt;
            if (k + 1 < nz) sum += comp.values[g.index(i, j, k + 1)], ++cnt;
            next[at] = static_cast<float>(sum / cnt);
          }
      comp.values.swap(next);
    }
}

FoldCheck remove_folds(Displacement& d, double wanted, int max_steps) {
  FoldCheck f = check_folds(d);
  int steps = 0;
  while (f.min_det < wanted && steps < max_steps) {
    jacobi_smooth(d, 5);
    steps += 5;
    f = check_folds(d);
  }
  f.smoothing_steps = steps;
  return f;
}

namespace {

// The three components at p with one set of trilinear weights (Grid::sample's rule: clamped).
Vec3 displacement_at(const Displacement& d, const Vec3& p) {
  const Grid& g = d.u[0];
  int c[3];
  double f[3];
  g.locate(p, c, f);
  Vec3 v = Vec3::Zero();
  for (int corner = 0; corner < 8; ++corner) {
    const int dx = corner & 1, dy = (corner >> 1) & 1, dz = (corner >> 2) & 1;
    const double w = (dx ? f[0] : 1 - f[0]) * (dy ? f[1] : 1 - f[1]) * (dz ? f[2] : 1 - f[2]);
    if (w == 0) continue;
    const size_t id = g.index(c[0] + dx, c[1] + dy, c[2] + dz);
    v += w * Vec3(d.u[0].values[id], d.u[1].values[id], d.u[2].values[id]);
  }
  return v;
}

// The displacement at p and its gradient (rows: components) within p's cell.
Vec3 displacement_and_gradient(const Displacement& d, const Vec3& p, Eigen::Matrix3d& grad) {
  const Grid& g = d.u[0];
  int c[3];
  double f[3];
  g.locate(p, c, f);
  Vec3 v = Vec3::Zero();
  grad.setZero();
  for (int corner = 0; corner < 8; ++corner) {
    const int dx = corner & 1, dy = (corner >> 1) & 1, dz = (corner >> 2) & 1;
    const double wx = dx ? f[0] : 1 - f[0], wy = dy ? f[1] : 1 - f[1], wz = dz ? f[2] : 1 - f[2];
    const size_t id = g.index(c[0] + dx, c[1] + dy, c[2] + dz);
    const Vec3 u(d.u[0].values[id], d.u[1].values[id], d.u[2].values[id]);
    v += wx * wy * wz * u;
    const Vec3 dw((dx ? 1 : -1) * wy * wz, (dy ? 1 : -1) * wx * wz, (dz ? 1 : -1) * wx * wy);
    grad += u * dw.transpose();
  }
  grad /= g.spacing;
  return v;
}

}  // namespace

Grid warped_field_newton(const Grid& sdf, const Displacement& d, int threads) {
  Grid out = sdf;
  const int nx = sdf.dims[0], ny = sdf.dims[1], nz = sdf.dims[2];
  const double tol2 = 1e-8 * sdf.spacing * sdf.spacing;
  parallel_for(nz, threads, Context{}, [&](int k) {
    Eigen::Matrix3d grad;
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const Vec3 y = sdf.point(i, j, k);
        Vec3 x = y;
        for (int it = 0; it < 8; ++it) {
          const Vec3 r = x + displacement_and_gradient(d, x, grad) - y;
          if (r.squaredNorm() < tol2) break;
          const Eigen::Matrix3d a = Eigen::Matrix3d::Identity() + grad;
          const double det = a.determinant();
          x -= det > 0.05 ? Vec3(a.inverse() * r) : r;
        }
        out.values[sdf.index(i, j, k)] = static_cast<float>(sdf.sample(x));
      }
  });
  return out;
}

Grid warped_field(const Grid& sdf, const Displacement& d, double s, int threads) {
  Grid out = sdf;
  if (s == 0) return out;
  const int nx = sdf.dims[0], ny = sdf.dims[1], nz = sdf.dims[2];
  parallel_for(nz, threads, Context{}, [&](int k) {
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const Vec3 y = sdf.point(i, j, k);
        Vec3 x = y;
        for (int it = 0; it < 6; ++it) x = y - s * displacement_at(d, x);
        out.values[sdf.index(i, j, k)] = static_cast<float>(sdf.sample(x));
      }
  });
  return out;
}

}  // namespace qs::dfi
