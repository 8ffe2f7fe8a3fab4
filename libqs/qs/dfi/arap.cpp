#include "qs/dfi/arap.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "qs/core/parallel.h"

namespace qs::dfi {
namespace {

Eigen::Matrix3d blend(const ArapInterpolation& a, int i, double t) {
  const Eigen::Quaterniond q = Eigen::Quaterniond::Identity().slerp(t, Eigen::Quaterniond(a.rotation[i]));
  return q.toRotationMatrix() * ((1 - t) * Eigen::Matrix3d::Identity() + t * a.stretch[i]);
}

// The least-squares positions for the local maps at t, mean fixed (before the end correction).
std::vector<Vec3> raw_positions(const ArapInterpolation& a, double t) {
  const int n = static_cast<int>(a.source.size());
  std::vector<Eigen::Matrix3d> at(n);
  for (int i = 0; i < n; ++i) at[i] = blend(a, i, t);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, 3);
  Vec3 mean = Vec3::Zero();
  for (int i = 0; i < n; ++i) mean += (1 - t) * a.source[i] + t * a.target[i];
  mean /= n;
  for (int i = 0; i < n; ++i)
    for (int j : a.neighbours[i]) {
      const Vec3 e = 0.5 * (at[i] + at[j]) * (a.source[j] - a.source[i]);
      rhs.row(j) += e.transpose();
      rhs.row(i) -= e.transpose();
    }
  // The mean constraint enters as the rank-one term (1/n) 1 1^T p = mean (see build_arap).
  for (int i = 0; i < n; ++i) rhs.row(i) += mean.transpose();
  const Eigen::MatrixXd p = a.solve * rhs;
  std::vector<Vec3> out(n);
  for (int i = 0; i < n; ++i) out[i] = p.row(i).transpose();
  return out;
}

}  // namespace

ArapInterpolation build_arap(const std::vector<Vec3>& source, const std::vector<Vec3>& target, int k) {
  ArapInterpolation a;
  a.source = source;
  a.target = target;
  const int n = static_cast<int>(source.size());
  k = std::clamp(k, 1, std::max(1, n - 1));
  a.neighbours.resize(n);
  std::vector<std::pair<double, int>> d(n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j)
      d[j] = {(source[j] - source[i]).squaredNorm() + (target[j] - target[i]).squaredNorm(), j};
    std::partial_sort(d.begin(), d.begin() + std::min(n, k + 1), d.end());
    for (int m = 0, got = 0; m < n && got < k; ++m)
      if (d[m].second != i) a.neighbours[i].push_back(d[m].second), ++got;
  }
  a.rotation.resize(n);
  a.stretch.resize(n);
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix3d xx = Eigen::Matrix3d::Zero(), yx = Eigen::Matrix3d::Zero();
    double scale = 0;
    for (int j : a.neighbours[i]) {
      const Vec3 dx = source[j] - source[i], dy = target[j] - target[i];
      xx += dx * dx.transpose();
      yx += dy * dx.transpose();
      scale += dx.squaredNorm();
    }
    // A tiny ridge term for neighbourhoods that lie in a plane or on a line.
    const double eps = 1e-9 * scale / std::max<size_t>(1, a.neighbours[i].size()) + 1e-300;
    const Eigen::Matrix3d j = yx * (xx + eps * Eigen::Matrix3d::Identity()).inverse();
    Eigen::JacobiSVD<Eigen::Matrix3d> svd(j, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d u = svd.matrixU();
    Eigen::Vector3d s = svd.singularValues();
    const Eigen::Matrix3d v = svd.matrixV();
    if ((u * v.transpose()).determinant() < 0) {  // a reflection: the closest rotation, stretch flipped
      u.col(2) = -u.col(2);
      s(2) = -s(2);
    }
    for (int c = 0; c < 3; ++c) s(c) = std::copysign(std::clamp(std::abs(s(c)), 0.2, 5.0), s(c));  // no collapse
    a.rotation[i] = u * v.transpose();
    a.stretch[i] = v * s.asDiagonal() * v.transpose();
  }
  // Normal matrix of the edge terms (a graph Laplacian, both directions of every edge) plus the
  // mean constraint (1/n) 1 1^T, which makes it invertible on a connected graph.
  Eigen::MatrixXd l = Eigen::MatrixXd::Constant(n, n, 1.0 / n);
  for (int i = 0; i < n; ++i)
    for (int j : a.neighbours[i]) {
      l(i, i) += 1;
      l(j, j) += 1;
      l(i, j) -= 1;
      l(j, i) -= 1;
    }
  a.solve = l.completeOrthogonalDecomposition().pseudoInverse();
  const std::vector<Vec3> p0 = raw_positions(a, 0), p1 = raw_positions(a, 1);
  a.residual0.resize(n);
  a.residual1.resize(n);
  for (int i = 0; i < n; ++i) {
    a.residual0[i] = source[i] - p0[i];
    a.residual1[i] = target[i] - p1[i];
  }
  return a;
}

std::vector<Vec3> arap_positions(const ArapInterpolation& a, double t) {
  if (t <= 0) return a.source;
  if (t >= 1) return a.target;
  std::vector<Vec3> p = raw_positions(a, t);
  for (size_t i = 0; i < p.size(); ++i) p[i] += (1 - t) * a.residual0[i] + t * a.residual1[i];
  return p;
}

Vec3 ThinPlate::operator()(const Vec3& q) const {
  Vec3 out = offset + linear * q;
  for (size_t k = 0; k < centres.size(); ++k) {
    const double r = (q - centres[k]).norm();
    out += r * weights.row(static_cast<Eigen::Index>(k)).transpose();
  }
  return out;
}

ThinPlate fit_thin_plate(const std::vector<Vec3>& from, const std::vector<Vec3>& to, double lambda) {
  const int n = static_cast<int>(from.size());
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n + 4, n + 4), rhs = Eigen::MatrixXd::Zero(n + 4, 3);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) m(i, j) = (from[i] - from[j]).norm();
    m(i, i) += lambda;
    m(i, n) = m(n, i) = 1;
    for (int c = 0; c < 3; ++c) m(i, n + 1 + c) = m(n + 1 + c, i) = from[i][c];
    rhs.row(i) = to[i].transpose();
  }
  const Eigen::MatrixXd x = m.fullPivLu().solve(rhs);
  ThinPlate f;
  f.centres = from;
  f.weights = x.topRows(n);
  f.offset = x.row(n).transpose();
  for (int c = 0; c < 3; ++c) f.linear.col(c) = x.row(n + 1 + c).transpose();
  return f;
}

Displacement thin_plate_displacement(const ThinPlate& f, const Grid& geometry, int threads) {
  Displacement d;
  for (auto& c : d.u) {
    c = geometry;
    c.values.assign(geometry.size(), 0.0f);
  }
  const int nx = geometry.dims[0], ny = geometry.dims[1], nz = geometry.dims[2];
  const int n = static_cast<int>(f.centres.size());
  // Centres and weights as flat arrays for the inner loop.
  std::vector<double> cx(n), cy(n), cz(n), wx(n), wy(n), wz(n);
  for (int k = 0; k < n; ++k) {
    cx[k] = f.centres[k].x(), cy[k] = f.centres[k].y(), cz[k] = f.centres[k].z();
    wx[k] = f.weights(k, 0), wy[k] = f.weights(k, 1), wz[k] = f.weights(k, 2);
  }
  parallel_for(nz, threads, Context{}, [&](int k) {
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const Vec3 q = geometry.point(i, j, k);
        double sx = 0, sy = 0, sz = 0;
        for (int c = 0; c < n; ++c) {
          const double dx = q.x() - cx[c], dy = q.y() - cy[c], dz = q.z() - cz[c];
          const double r = std::sqrt(dx * dx + dy * dy + dz * dz);
          sx += r * wx[c];
          sy += r * wy[c];
          sz += r * wz[c];
        }
        const Vec3 u = f.offset + f.linear * q + Vec3(sx, sy, sz) - q;
        const size_t id = geometry.index(i, j, k);
        for (int c = 0; c < 3; ++c) d.u[c].values[id] = static_cast<float>(u[c]);
      }
  });
  return d;
}

Grid pulled_field(const Grid& sdf, const Displacement& back, int threads) {
  Grid out = sdf;
  const int nx = sdf.dims[0], ny = sdf.dims[1], nz = sdf.dims[2];
  parallel_for(nz, threads, Context{}, [&](int k) {
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const Vec3 q = sdf.point(i, j, k);
        out.values[sdf.index(i, j, k)] = static_cast<float>(sdf.sample(q + back.at(q)));
      }
  });
  return out;
}

std::vector<int> farthest_points(const std::vector<Vec3>& points, int count) {
  std::vector<int> out;
  const int n = static_cast<int>(points.size());
  if (n == 0 || count <= 0) return out;
  std::vector<double> d(n, std::numeric_limits<double>::infinity());
  int next = 0;
  for (int c = 0; c < std::min(count, n); ++c) {
    out.push_back(next);
    int best = -1;
    double far = -1;
    for (int i = 0; i < n; ++i) {
      d[i] = std::min(d[i], (points[i] - points[next]).squaredNorm());
      if (d[i] > far) far = d[i], best = i;
    }
    if (far <= 0) break;
    next = best;
  }
  return out;
}

}  // namespace qs::dfi
