#include "qs/dfi/bones.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "qs/core/parallel.h"
#include "qs/dfi/sdf.h"

namespace qs::dfi {
namespace {

double segment_distance2(const Vec3& a, const Vec3& b, const Vec3& p) {
  const Vec3 ab = b - a;
  const double l2 = ab.squaredNorm();
  const double u = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (a + u * ab - p).squaredNorm();
}


// One bone's transform, its pieces computed once per frame.
struct Frame {
  Vec3 from_a, from_b, centre_from, centre_s;
  Eigen::Matrix3d linear;  // R^s * stretch_s
  double r2 = 0;
};

Frame frame_of(const Bone& b, double s) {
  Frame f;
  f.from_a = b.from_a;
  f.from_b = b.from_b;
  f.r2 = b.radius * b.radius;
  const Vec3 d0 = b.from_b - b.from_a, d1 = b.to_b - b.to_a;
  const double l0 = d0.norm(), l1 = d1.norm();
  f.centre_from = 0.5 * (b.from_a + b.from_b);
  f.centre_s = (1 - s) * f.centre_from + s * 0.5 * (b.to_a + b.to_b);
  Eigen::Matrix3d stretch = Eigen::Matrix3d::Identity();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  const double sigma_r = std::clamp(b.radial_scale, 0.5, 2.0);
  if (l0 > 0 && l1 > 0) {
    const Vec3 a = d0 / l0;
    const double sigma_a = std::clamp(l1 / l0, 0.25, 4.0);
    const Eigen::Matrix3d aa = a * a.transpose();
    stretch += s * ((sigma_r - 1) * (Eigen::Matrix3d::Identity() - aa) + (sigma_a - 1) * aa);
    q = Eigen::Quaterniond::Identity().slerp(s, Eigen::Quaterniond::FromTwoVectors(d0, d1));
  } else {
    stretch *= 1 + s * (sigma_r - 1);
  }
  f.linear = q.toRotationMatrix() * stretch;
  return f;
}

}  // namespace

std::vector<Bone> branch_bones(const Skeleton& s0, const std::vector<Branch>& b0, const Skeleton& s1,
                               const std::vector<Branch>& b1, const SkeletonMatching& m, const Grid& sdf0,
                               const Grid& sdf1, int segments, double min_radius) {
  std::vector<Bone> out;
  segments = std::max(1, segments);
  for (const BranchPair& bp : m.branches) {
    const Branch& p = b0[bp.source];
    const Branch& q = b1[bp.target];
    for (int k = 0; k < segments; ++k) {
      const double f0 = static_cast<double>(k) / segments, f1 = static_cast<double>(k + 1) / segments;
      Bone b;
      b.from_a = p.at(s0, f0);
      b.from_b = p.at(s0, f1);
      b.to_a = q.at(s1, bp.reversed ? 1 - f0 : f0);
      b.to_b = q.at(s1, bp.reversed ? 1 - f1 : f1);
      const Vec3 m0 = 0.5 * (b.from_a + b.from_b), m1 = 0.5 * (b.to_a + b.to_b);
      const double r0 = std::max(min_radius, -sdf0.sample(m0)), r1 = std::max(min_radius, -sdf1.sample(m1));
      b.radius = r0;
      b.radial_scale = r1 / r0;
      out.push_back(b);
    }
  }
  return out;
}

std::vector<Bone> inverse_bones(const std::vector<Bone>& bones) {
  std::vector<Bone> out;
  out.reserve(bones.size());
  for (const Bone& b : bones) {
    Bone i;
    i.from_a = b.to_a;
    i.from_b = b.to_b;
    i.to_a = b.from_a;
    i.to_b = b.from_b;
    i.radius = b.radius * b.radial_scale;
    i.radial_scale = 1 / b.radial_scale;
    out.push_back(i);
  }
  return out;
}

Vec3 bone_transform(const Bone& b, double s, const Vec3& x) {
  const Frame f = frame_of(b, s);
  return f.centre_s + f.linear * (x - f.centre_from);
}

Displacement bone_displacement(const std::vector<Bone>& bones, const Grid& geometry, double s, int threads) {
  Displacement d;
  for (auto& c : d.u) {
    c = geometry;
    c.values.assign(geometry.size(), 0.0f);
  }
  if (bones.empty() || s == 0) return d;
  std::vector<Frame> frames;
  frames.reserve(bones.size());
  for (const Bone& b : bones) frames.push_back(frame_of(b, s));
  const int nx = geometry.dims[0], ny = geometry.dims[1], nz = geometry.dims[2];
  parallel_for(nz, threads, Context{}, [&](int k) {
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const Vec3 x = geometry.point(i, j, k);
        Vec3 sum = Vec3::Zero();
        double wsum = 0;
        for (const Frame& f : frames) {
          const double d2 = segment_distance2(f.from_a, f.from_b, x) + f.r2;
          const double w = 1.0 / (d2 * d2);
          sum += w * (f.centre_s + f.linear * (x - f.centre_from));
          wsum += w;
        }
        const Vec3 u = sum / wsum - x;
        const size_t id = geometry.index(i, j, k);
        for (int c = 0; c < 3; ++c) d.u[c].values[id] = static_cast<float>(u[c]);
      }
  });
  return d;
}

double min_jacobian(const Displacement& d) {
  const Grid& g = d.u[0];
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k + 1 < g.dims[2]; ++k)
    for (int j = 0; j + 1 < g.dims[1]; ++j)
      for (int i = 0; i + 1 < g.dims[0]; ++i) {
        const Eigen::Matrix3d J = cell_gradient(d, i, j, k);
        best = std::min(best, (Eigen::Matrix3d::Identity() + J).determinant());
      }
  return best;
}

FoldRepair repair_folds_locally(Displacement& d, double min_det, int max_rounds) {
  FoldRepair r;
  const Grid& g = d.u[0];
  const int nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
  std::vector<char> mark(g.size());
  for (;; ++r.rounds) {
    std::fill(mark.begin(), mark.end(), 0);
    bool any = false;
    r.min_det = std::numeric_limits<double>::infinity();
    for (int k = 0; k + 1 < nz; ++k)
      for (int j = 0; j + 1 < ny; ++j)
        for (int i = 0; i + 1 < nx; ++i) {
          const double det = (Eigen::Matrix3d::Identity() + cell_gradient(d, i, j, k)).determinant();
          r.min_det = std::min(r.min_det, det);
          if (det < min_det) {
            any = true;
            for (int c = -1; c <= 2; ++c)
              for (int b = -1; b <= 2; ++b)
                for (int a = -1; a <= 2; ++a) {
                  const int x = i + a, y = j + b, z = k + c;
                  if (x >= 0 && y >= 0 && z >= 0 && x < nx && y < ny && z < nz) mark[g.index(x, y, z)] = 1;
                }
          }
        }
    if (!any || r.rounds == max_rounds) return r;
    jacobi_smooth(d, 4, &mark);
  }
}

}  // namespace qs::dfi
