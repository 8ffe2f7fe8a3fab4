// The ARAP interpolation of centre pairs and the thin-plate backward warps (arap.h).
#include <gtest/gtest.h>

#include <cmath>

#include "qs/dfi/arap.h"
#include "qs/dfi/pipeline.h"
#include "qs/shapes/shapes.h"

using namespace qs;
using namespace qs::dfi;

namespace {

std::vector<Vec3> cloud(int n) {
  std::vector<Vec3> p;
  for (int i = 0; i < n; ++i) {  // a deterministic cloud in a 2 x 1 x 0.5 box
    const double a = std::fmod(i * 0.618034, 1.0), b = std::fmod(i * 0.414214, 1.0), c = std::fmod(i * 0.732051, 1.0);
    p.push_back(Vec3(2 * a - 1, b - 0.5, 0.5 * c - 0.25));
  }
  return p;
}

}  // namespace

// A rigid rotation by 90 degrees about z: half-way, every centre is rotated by 45 degrees (the
// linear blend would shrink the cloud by cos 45), and the ends are exact.
TEST(Arap, RigidMotionIsInterpolatedRigidly) {
  const std::vector<Vec3> x = cloud(60);
  const Eigen::Matrix3d r = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()).toRotationMatrix();
  const Eigen::Matrix3d half = Eigen::AngleAxisd(M_PI / 4, Vec3::UnitZ()).toRotationMatrix();
  const Vec3 move(0.3, -0.2, 0.1);
  std::vector<Vec3> y;
  for (const Vec3& p : x) y.push_back(r * p + move);
  const ArapInterpolation a = build_arap(x, y);
  const std::vector<Vec3> p0 = arap_positions(a, 0), p1 = arap_positions(a, 1), mid = arap_positions(a, 0.5);
  Vec3 cx = Vec3::Zero(), cm = Vec3::Zero();
  for (size_t i = 0; i < x.size(); ++i) {
    EXPECT_EQ(p0[i], x[i]);
    EXPECT_EQ(p1[i], y[i]);
    cx += x[i] / x.size();
    cm += mid[i] / x.size();
  }
  for (size_t i = 0; i < x.size(); ++i)
    EXPECT_LT((mid[i] - cm - half * (x[i] - cx)).norm(), 1e-6) << i;
}

// The thin-plate warp reproduces an affine map exactly (its global part) and interpolates the
// centres; pulled_field samples a field through it.
TEST(Arap, ThinPlateHasAnExactAffinePart) {
  const std::vector<Vec3> x = cloud(30);
  Eigen::Matrix3d m;
  m << 1.2, 0.1, 0, -0.2, 0.9, 0.05, 0, 0, 1.1;
  const Vec3 c(0.1, 0.2, -0.3);
  std::vector<Vec3> y;
  for (const Vec3& p : x) y.push_back(m * p + c);
  const ThinPlate f = fit_thin_plate(x, y, 0);
  for (const Vec3& q : {Vec3(0, 0, 0), Vec3(0.5, -0.3, 0.1), Vec3(3, 2, 1)})
    EXPECT_LT((f(q) - (m * q + c)).norm(), 1e-8) << q.transpose();
  std::vector<Vec3> bent = y;
  bent[3] += Vec3(0.05, 0, 0);
  const ThinPlate g = fit_thin_plate(x, bent, 0);
  for (size_t i = 0; i < x.size(); ++i) EXPECT_LT((g(x[i]) - bent[i]).norm(), 1e-8);
  EXPECT_EQ(farthest_points(x, 5).size(), 5u);
  EXPECT_EQ(farthest_points(x, 5)[0], 0);
}

// The ARAP warp in the pipeline: an ellipsoid to the same ellipsoid moved along x. The middle
// frame is the ellipsoid half-way (one piece, its volume, its centre), the ends are the inputs'.
TEST(Arap, MiddleFrameOfAMovedShapeIsTheShapeHalfWay) {
  const TriMesh a = shapes::ellipsoid(1.0, 0.5, 0.4, 2);
  TriMesh b = a;
  for (Vec3& p : b.positions) p += Vec3(1.0, 0, 0);
  MorphOptions opt;
  opt.grid = 28;
  opt.emd_voxels = 200;
  opt.arap_centres = 60;
  opt.interpolation = Interpolation::Arap;
  const PreparedMorph m = prepare_morph(a, b, opt);
  ASSERT_FALSE(m.arap.empty());
  EXPECT_GT(m.arap_min_det, 0);
  EXPECT_EQ(blend_field(m, 0).values, m.source_sdf.values);
  EXPECT_EQ(blend_field(m, 1).values, m.target_sdf.values);
  const MeshStats mid = mesh_stats(frame_mesh(m, blend_field(m, 0.5), 0.5));
  EXPECT_EQ(mid.components, 1);
  const double volume = 4.0 / 3.0 * M_PI * 1.0 * 0.5 * 0.4;
  EXPECT_NEAR(mid.volume, volume, 0.08 * volume);
  const Box3 box = bounding_box(frame_mesh(m, blend_field(m, 0.5), 0.5).positions);
  EXPECT_NEAR(0.5 * (box.min.x() + box.max.x()), 0.5, 2 * m.spacing());
}
