// Even frame times (retime.h): the cumulative-change inversion on known numbers, and on an analytic
// blend whose surface moves unevenly in t (a sphere growing fast early, slowly late).
#include <gtest/gtest.h>

#include <cmath>

#include "qs/core/error.h"
#include "qs/dfi/retime.h"
#include "qs/metro/metro.h"
#include "qs/shapes/shapes.h"
#include "test_meshes.h"

using namespace qs;
using namespace qs::dfi;

TEST(Retime, EqualizeTimesInvertsTheCumulativeChange) {
  const std::vector<double> dense = {0, 0.25, 0.5, 0.75, 1};
  // All the change in the third step, a third of it in the fourth: cumulative 0, 0, 0, 0.75, 1.
  const std::vector<double> t = equalize_times(dense, {0, 0, 3, 1}, 3, 0.0);
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(t[0], 0.0);
  EXPECT_NEAR(t[1], 0.5 + 0.25 * (0.5 / 0.75), 1e-12);
  EXPECT_EQ(t[2], 1.0);
  // Even change: uniform times.
  const std::vector<double> u = equalize_times(dense, {2, 2, 2, 2}, 5, 0.05);
  for (int f = 0; f < 5; ++f) EXPECT_NEAR(u[f], f / 4.0, 1e-12) << f;
  // No change at all: uniform times (no division by zero), monotone with a share of uniform.
  const std::vector<double> z = equalize_times(dense, {0, 0, 0, 0}, 3, 0.0);
  EXPECT_NEAR(z[1], 0.5, 1e-12);
  const std::vector<double> s = equalize_times(dense, {0, 0, 5, 0}, 9, 0.1);
  for (size_t f = 1; f < s.size(); ++f) EXPECT_GT(s[f], s[f - 1]) << f;
  EXPECT_THROW(equalize_times(dense, {1, 1}, 3, 0.0), InvalidInput);
  EXPECT_THROW(equalize_times(dense, {1, 1, 1, 1}, 1, 0.0), InvalidInput);
}

namespace {
// The plain blend of d0 = |p| - 0.3 and d1 = 4 (|p| - 0.9): its zero set is the sphere of radius
// r(t) = (0.3 (1 - t) + 3.6 t) / (1 + 3 t), which covers half its way by t = 0.17.
double radius(double t) { return (0.3 * (1 - t) + 3.6 * t) / (1 + 3 * t); }

PreparedMorph growing_sphere() {
  PreparedMorph m;
  m.source_sdf = test_support::analytic_grid(1.2, 48, [](const Vec3& p) { return p.norm() - 0.3; });
  m.target_sdf = test_support::analytic_grid(1.2, 48, [](const Vec3& p) { return 4 * (p.norm() - 0.9); });
  return m;
}
}  // namespace

TEST(Retime, EvenTimesMakeAnUnevenBlendMoveInEqualSteps) {
  const PreparedMorph m = growing_sphere();
  const int frames = 7;
  const Retiming r = even_frame_times(m, frames);
  ASSERT_EQ(static_cast<int>(r.times.size()), frames);
  EXPECT_EQ(r.times.front(), 0.0);
  EXPECT_EQ(r.times.back(), 1.0);
  for (int f = 1; f < frames; ++f) EXPECT_GT(r.times[f], r.times[f - 1]) << f;
  ASSERT_EQ(r.dense_change.size() + 1, r.dense_times.size());
  // Uniform times step the radius by 0.34 then 0.02; even times by 0.1 each (within the coarse
  // frames' resolution, 0.05 * 2, and the 5% uniform share).
  double largest = 0, smallest = 1;
  for (int f = 1; f < frames; ++f) {
    const double step = radius(r.times[f]) - radius(r.times[f - 1]);
    largest = std::max(largest, step);
    smallest = std::min(smallest, step);
    EXPECT_NEAR(radius(r.times[f]), 0.3 + 0.1 * f, 0.035) << "frame " << f << " t " << r.times[f];
  }
  EXPECT_LT(largest, 2.0 * smallest);
  EXPECT_GT(radius(1.0 / (frames - 1)) - radius(0), 3.0 * (radius(1) - radius(5.0 / 6)));  // what uniform does
}

TEST(Retime, SameTimesOnOneAndTwoThreadsAndOptionsChecked) {
  const PreparedMorph m = growing_sphere();
  RetimeOptions o;
  o.samples_per_frame = 2;
  EXPECT_EQ(even_frame_times(m, 5, o, 1).times, even_frame_times(m, 5, o, 2).times);
  o.coarsen = 0;
  EXPECT_THROW(even_frame_times(m, 5, o), InvalidInput);
  EXPECT_THROW(even_frame_times(m, 1), InvalidInput);
}

// Endpoint frames from the input's own field on a finer grid (pipeline.h endpoint_frame): a plate
// thinner than a morph voxel, which the morph's grid loses in places, is held at 4x.
TEST(EndpointFrame, AFinerGridHoldsAPlateThinnerThanAVoxel) {
  TriMesh plate = shapes::ellipsoid(1.0, 0.8, 0.05, 4);
  for (Vec3& p : plate.positions) p = Eigen::AngleAxisd(0.5, Vec3(1, 1, 0).normalized()) * p;  // off the grid's planes
  const TriMesh ball = shapes::icosphere(3);
  MorphOptions opt;
  opt.grid = 20;  // spacing about 0.1: the plate is 0.1 thick in the middle, thinner towards its rim
  opt.warp = false;
  const PreparedMorph m = prepare_morph(plate, ball, opt);
  const double coarse = metro::metro(frame_mesh(m, blend_field(m, 0.0), 0.0), plate).max;
  const TriMesh fine = endpoint_frame(m, plate, false, 4);
  const MeshStats s = mesh_stats(fine);
  EXPECT_TRUE(s.closed_manifold);
  EXPECT_GT(s.volume, 0);
  EXPECT_EQ(test_support::self_intersections(fine), 0);
  const double refined = metro::metro(fine, plate).max;
  EXPECT_LT(refined, 0.6 * m.spacing()) << "coarse " << coarse;
  EXPECT_LT(refined, coarse);
  // The target's end in its own coordinates (frame_mesh at t = 1 puts it there too).
  EXPECT_LT(metro::metro(endpoint_frame(m, ball, true, 2), ball).max, 0.5 * m.spacing());
  EXPECT_THROW(endpoint_frame(m, ball, true, 0), InvalidInput);
}
