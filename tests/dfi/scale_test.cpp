// Morphs of shapes at any finite scale: the morph runs at unit size and the frames come back in
// the inputs' units; the memory estimate before any grid is allocated.
#include <gtest/gtest.h>

#include <cmath>

#include "qs/core/error.h"
#include "qs/dfi/pipeline.h"
#include "qs/shapes/shapes.h"

namespace qs::dfi {
namespace {

TriMesh scaled(TriMesh m, double s, const Vec3& shift = Vec3::Zero()) {
  for (Vec3& p : m.positions) p = s * p + shift;
  return m;
}

MorphOptions small_warp() {
  MorphOptions o;
  o.grid = 16;
  o.emd_voxels = 100;
  return o;
}

TEST(Scale, APowerOfTwoScaleGivesTheScaledFramesBitForBit) {
  const TriMesh a = shapes::ellipsoid(1.5, 0.6, 0.5, 2), b = shapes::ellipsoid(1.2, 0.5, 0.6, 2);
  const PreparedMorph one = prepare_morph(a, b, small_warp());
  const TriMesh f1 = frame_mesh(one, blend_field(one, 0.5), 0.5);
  ASSERT_GT(f1.positions.size(), 50u);
  for (const double s : {std::ldexp(1.0, 200), std::ldexp(1.0, -200)}) {
    const PreparedMorph m = prepare_morph(scaled(a, s), scaled(b, s), small_warp());
    EXPECT_EQ(m.bones.size(), one.bones.size());
    EXPECT_EQ(m.source_sdf.values, one.source_sdf.values);
    const TriMesh f = frame_mesh(m, blend_field(m, 0.5), 0.5);
    ASSERT_EQ(f.positions.size(), f1.positions.size());
    for (size_t i = 0; i < f.positions.size(); ++i) ASSERT_EQ(f.positions[i], s * f1.positions[i]) << i;
    EXPECT_EQ(m.spacing(), s * one.spacing());
  }
}

TEST(Scale, SimilarityAlignmentAcrossNinetyOrdersOfMagnitude) {
  const TriMesh a = shapes::ellipsoid(1.5, 0.6, 0.5, 2);
  const TriMesh b = scaled(shapes::ellipsoid(0.6, 1.5, 0.5, 2), 1e90, Vec3(3e90, 0, 0));
  MorphOptions o;
  o.grid = 16;
  o.warp = false;
  o.align = Align::Similarity;
  const PreparedMorph m = prepare_morph(a, b, o);
  EXPECT_NEAR(m.target_to_source.scale, 1e-90, 1e-96);
  EXPECT_NEAR(std::cbrt(m.target_volume / m.source_volume), 1e90, 1e84);
  for (const double t : {0.0, 0.5, 1.0}) {
    const TriMesh f = frame_mesh(m, blend_field(m, t), t);
    ASSERT_GT(f.positions.size(), 50u);
    const Box3 box = bounding_box(f.positions);
    // From the source's placement to the target's (placement: the scale 1 / ((1 - t) + t 1e-90),
    // the centre (1 - t) 0 + t 3e90).
    const double size = 1 / ((1 - t) + t * 1e-90);
    // The ends are the shapes; between them the blend of the two turned ellipsoids is rounder.
    EXPECT_NEAR(box.diagonal() / size / bounding_box(a.positions).diagonal(), 1, t == 0.5 ? 0.4 : 0.1) << t;
    EXPECT_NEAR(0.5 * (box.min + box.max).x(), t * 3e90, 0.1 * size) << t;
  }
}

TEST(Scale, TheMemoryEstimateGrowsWithTheGridAndTheFramesAndStaysFinite) {
  const TriMesh a = shapes::icosphere(2), b = shapes::torus(32, 12);
  MorphOptions o;
  const MorphSize s150 = morph_size(a, b, o, 3);
  o.grid = 300;
  const MorphSize s300 = morph_size(a, b, o, 3);
  EXPECT_EQ(s300.grid_dims[0], 307);  // the torus is the wider: 300 cells + 2 x 3 of pad + 1
  EXPECT_GT(s300.source_end_dims[0], 2 * (s150.source_end_dims[0] - 7));
  MemoryRequest r;
  const double e150 = estimate_memory(s150, r, true), e300 = estimate_memory(s300, r, true);
  EXPECT_GT(e150, 0.1e9);
  EXPECT_LT(e150, 4e9);
  EXPECT_GT(e300, 6 * e150);
  r.frames = 100000;
  EXPECT_GT(estimate_memory(s150, r, true), 1000 * e150);
  r.keep_frames = true;
  r.frames = 2000000000;
  EXPECT_TRUE(std::isfinite(estimate_memory(s300, r, true)));
  EXPECT_THROW(morph_size(a, b, o, 9), InvalidInput);
}

}  // namespace
}  // namespace qs::dfi
