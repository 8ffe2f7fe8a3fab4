// The frames' volume (FrameVolume::Linear): the field volume estimator, the iso level for a wanted
// volume, and a blend that loses volume half-way brought back to the linear interpolation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "qs/core/error.h"
#include "qs/dfi/pipeline.h"
#include "qs/shapes/shapes.h"
#include "test_meshes.h"

using namespace qs;
using namespace qs::dfi;

namespace {
double ball(double r) { return 4.0 / 3.0 * M_PI * r * r * r; }
}  // namespace

TEST(FrameVolume, VolumeBelowMeasuresOffsetsOfASphere) {
  const Grid g = test_support::analytic_grid(2.0, 48, [](const Vec3& p) { return test_support::sphere_sd(p, Vec3::Zero(), 1.0); });
  EXPECT_NEAR(volume_below(g), ball(1.0), 0.01 * ball(1.0));
  EXPECT_NEAR(volume_below(g, 0.2), ball(1.2), 0.01 * ball(1.2));
  EXPECT_NEAR(volume_below(g, -0.3), ball(0.7), 0.01 * ball(0.7));
  double last = 0;
  for (int q = -20; q <= 20; ++q) {  // non-decreasing in the level
    const double v = volume_below(g, q * 0.013);
    EXPECT_GE(v, last);
    last = v;
  }
}

TEST(FrameVolume, IsoForVolumeInvertsVolumeBelowAndClamps) {
  const Grid g = test_support::analytic_grid(2.0, 48, [](const Vec3& p) { return test_support::sphere_sd(p, Vec3::Zero(), 1.0); });
  const double max_shift = 4 * g.spacing;
  for (double c : {-0.17, -0.05, 0.0, 0.08, 0.15}) {
    const double found = iso_for_volume(g, volume_below(g, c), max_shift);
    EXPECT_NEAR(found, c, 1e-4 * g.spacing) << c;
  }
  EXPECT_EQ(iso_for_volume(g, 100.0, max_shift), max_shift);  // more than 4 cells can give
  EXPECT_EQ(iso_for_volume(g, 0.0, max_shift), -max_shift);
  EXPECT_EQ(iso_for_volume(g, volume_below(g, 0.1), 0.0), 0.0);
}

// Two balls side by side: the plain blend half-way is the set where the mean of the distances to
// the two centres is below the radius, an ellipsoid of under half the volume; with the volume
// following the ends', the middle frame holds the balls' volume and stays one closed genus-0
// surface without self-intersections, and the ends are untouched.
TEST(FrameVolume, LinearVolumeRestoresTheMiddleFrameOfABlendThatShrinks) {
  TriMesh a = shapes::icosphere(4), b = shapes::icosphere(4);
  for (Vec3& p : a.positions) p = 0.8 * p + Vec3(-0.6, 0, 0);
  for (Vec3& p : b.positions) p = 0.8 * p + Vec3(0.6, 0, 0);
  MorphOptions opt;
  opt.grid = 40;
  opt.warp = false;
  opt.volume = FrameVolume::Free;
  const PreparedMorph free = prepare_morph(a, b, opt);
  const double ends = 0.5 * (free.source_volume + free.target_volume);
  const MeshStats shrunk = mesh_stats(frame_mesh(free, blend_field(free, 0.5), 0.5));
  EXPECT_LT(shrunk.volume, 0.6 * ends);  // what the plain blend does

  opt.volume = FrameVolume::Linear;
  const PreparedMorph m = prepare_morph(a, b, opt);
  EXPECT_EQ(blend_field(m, 0.0).values, m.source_sdf.values);  // the ends are not shifted
  for (double t : {0.25, 0.5, 0.75}) {
    BlendInfo info;
    const TriMesh mesh = frame_mesh(m, blend_field(m, t, 0, &info), t);
    const MeshStats s = mesh_stats(mesh);
    EXPECT_GT(info.iso_shift, 0) << t;  // grown
    EXPECT_FALSE(info.clamped) << t;
    EXPECT_LT(info.volume_blended, info.volume_wanted) << t;
    EXPECT_NEAR(s.volume, ends, 0.03 * ends) << t;
    EXPECT_TRUE(s.closed_manifold) << t;
    EXPECT_EQ(s.components, 1) << t;
    EXPECT_EQ(s.genus, 0) << t;
    EXPECT_EQ(test_support::self_intersections(mesh), 0) << t;
  }
}

TEST(FrameVolume, OptionsOutOfRangeAreRejected) {
  const TriMesh a = shapes::icosphere(2);
  MorphOptions opt;
  opt.grid = 16;
  opt.warp = false;
  opt.max_iso_shift = -1;
  EXPECT_THROW(prepare_morph(a, a, opt), InvalidInput);
  opt.max_iso_shift = 65;
  EXPECT_THROW(prepare_morph(a, a, opt), InvalidInput);
}

// Between the ends, a piece under 0.2% of the frame's inside samples (what a part thinner than the
// grid leaves when the blend thins it) is dropped; a larger piece that comes off is kept.
TEST(FrameCleanup, PiecesUnderAShareOfTheVolumeAreDroppedLargerOnesKept) {
  for (double r : {0.11, 0.3}) {
    const auto two_balls = [r](const Vec3& p) {
      return std::min(test_support::sphere_sd(p, Vec3(-0.4, 0, 0), 1.0), test_support::sphere_sd(p, Vec3(1.5, 0, 0), r));
    };
    PreparedMorph m;  // built by hand: the plain blend of one field with itself
    m.source_sdf = m.target_sdf = test_support::analytic_grid(2.0, 96, two_balls);
    size_t small = 0, inside = 0;
    for (int k = 0; k < m.source_sdf.dims[2]; ++k)
      for (int j = 0; j < m.source_sdf.dims[1]; ++j)
        for (int i = 0; i < m.source_sdf.dims[0]; ++i) {
          const float v = m.source_sdf.values[m.source_sdf.index(i, j, k)];
          inside += v < 0;
          small += v < 0 && m.source_sdf.point(i, j, k).x() > 0.8;
        }
    ASSERT_GT(small, 8u);  // more than a speck either way
    const bool under = small <= 0.002 * inside;
    EXPECT_EQ(under, r < 0.2) << small << " of " << inside;
    EXPECT_EQ(mesh_stats(polygonize(blend_field(m, 0.0))).components, 2) << r;  // the ends as they are
    EXPECT_EQ(mesh_stats(polygonize(blend_field(m, 0.5))).components, under ? 1 : 2) << r;
  }
}
