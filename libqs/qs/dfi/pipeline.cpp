#include "qs/dfi/pipeline.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <string>

#include "qs/core/error.h"
#include "qs/metro/metro.h"

namespace qs::dfi {
namespace {

// Volume centroid of a closed outward mesh (signed tetrahedra about the bounding-box centre).
Vec3 volume_centroid(const TriMesh& m, double& volume) {
  const Box3 box = bounding_box(m.positions);
  const Vec3 o = 0.5 * (box.min + box.max);
  Vec3 c = Vec3::Zero();
  double v = 0;
  for (const Tri& t : m.faces) {
    const Vec3 a = m.positions[t[0]] - o, b = m.positions[t[1]] - o, d = m.positions[t[2]] - o;
    const double vol = a.dot(b.cross(d)) / 6.0;
    v += vol;
    c += vol * (a + b + d) / 4.0;
  }
  volume = v;
  return v != 0 ? Vec3(o + c / v) : o;
}

// Principal axes of inertia (columns, ascending moments), a proper rotation.
Eigen::Matrix3d principal_frame(const TriMesh& m, const Vec3& c) {
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  for (const Tri& t : m.faces) {
    const Vec3 a = m.positions[t[0]] - c, b = m.positions[t[1]] - c, d = m.positions[t[2]] - c;
    const double vol = a.dot(b.cross(d)) / 6.0;
    const Vec3 sum = a + b + d;
    second += vol / 20.0 * (a * a.transpose() + b * b.transpose() + d * d.transpose() + sum * sum.transpose());
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(second);
  Eigen::Matrix3d e = eig.eigenvectors();
  if (e.determinant() < 0) e.col(2) = -e.col(2);
  return e;
}

// The 24 rotations that map the coordinate axes onto themselves, in a fixed order.
std::vector<Eigen::Matrix3d> cube_rotations() {
  std::vector<Eigen::Matrix3d> out;
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (const auto& p : perms)
    for (int signs = 0; signs < 8; ++signs) {
      Eigen::Matrix3d r = Eigen::Matrix3d::Zero();
      for (int row = 0; row < 3; ++row) r(row, p[row]) = (signs >> row) & 1 ? -1.0 : 1.0;
      if (r.determinant() > 0) out.push_back(r);
    }
  return out;
}

Eigen::Matrix3d best_rotation(const TriMesh& source, const Vec3& c0, const TriMesh& target, const Vec3& c1,
                              double scale) {
  const Eigen::Matrix3d e0 = principal_frame(source, c0), e1 = principal_frame(target, c1);
  const metro::SurfaceDistance surface(source, "source");
  const int stride = std::max(1, target.num_vertices() / 2000);
  double best = std::numeric_limits<double>::infinity();
  Eigen::Matrix3d best_r = Eigen::Matrix3d::Identity();
  for (const Eigen::Matrix3d& g : cube_rotations()) {
    const Eigen::Matrix3d r = e0 * g * e1.transpose();
    double sum = 0;
    for (int v = 0; v < target.num_vertices(); v += stride)
      sum += surface.distance(scale * (r * (target.positions[v] - c1)) + c0);
    if (sum < best) {
      best = sum;
      best_r = r;
    }
  }
  return best_r;
}

}  // namespace

Vec3 placement(const Similarity& s, double t, const Vec3& y) {
  const double scale = (1 - t) + t * s.scale;
  const Eigen::Quaterniond q = Eigen::Quaterniond::Identity().slerp(t, Eigen::Quaterniond(s.rotation));
  const Vec3 centre = (1 - t) * s.to + t * s.from;
  return centre + q.conjugate() * (y - s.to) / scale;
}

PreparedMorph prepare_morph(const TriMesh& source, const TriMesh& target, const MorphOptions& options,
                            const Context& ctx) {
  if (options.grid < 8 || options.grid > 1024)
    throw InvalidInput("grid is " + std::to_string(options.grid) + " cells; expected 8 to 1024");
  if (options.pad < 2) throw InvalidInput("pad is " + std::to_string(options.pad) + " cells; expected at least 2");
  PreparedMorph m;
  const Vec3 c0 = volume_centroid(source, m.source_volume);
  const Vec3 c1 = volume_centroid(target, m.target_volume);
  if (!(m.source_volume > 0) || !(m.target_volume > 0))
    throw InvalidInput("a shape encloses no volume (source " + std::to_string(m.source_volume) + ", target " +
                       std::to_string(m.target_volume) + ")");
  if (options.align == Align::Similarity) {
    m.target_to_source.scale = std::cbrt(m.source_volume / m.target_volume);
    m.target_to_source.from = c1;
    m.target_to_source.to = c0;
    m.target_to_source.rotation = best_rotation(source, c0, target, c1, m.target_to_source.scale);
  }
  TriMesh moved = target;
  for (Vec3& p : moved.positions) p = m.target_to_source.apply(p);
  Box3 box = bounding_box(source.positions);
  const Box3 b1 = bounding_box(moved.positions);
  box.min = box.min.cwiseMin(b1.min);
  box.max = box.max.cwiseMax(b1.max);
  const Grid domain = grid_over(box, options.grid, options.pad);
  ctx.report("distance fields", 0.0);
  m.source_sdf = signed_distance(source, domain, options.sdf, ctx.without_progress());
  ctx.report("distance fields", 0.5);
  m.target_sdf = signed_distance(moved, domain, options.sdf, ctx.without_progress());
  ctx.report("distance fields", 1.0);
  return m;
}

Grid blend_field(const PreparedMorph& m, double t) {
  Grid g = m.source_sdf;
  for (size_t i = 0; i < g.values.size(); ++i)
    g.values[i] = static_cast<float>((1 - t) * m.source_sdf.values[i] + t * m.target_sdf.values[i]);
  return g;
}

TriMesh frame_mesh(const PreparedMorph& m, const Grid& field, double t, const PolygonizeOptions& options) {
  TriMesh mesh = polygonize(field, options);
  for (Vec3& p : mesh.positions) p = placement(m.target_to_source, t, p);
  return mesh;
}

}  // namespace qs::dfi
