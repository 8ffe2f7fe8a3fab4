// The plain blend end to end on generated shapes: sphere to torus.
#include <gtest/gtest.h>

#include "qs/dfi/pipeline.h"
#include "qs/metro/metro.h"
#include "qs/shapes/shapes.h"
#include "test_meshes.h"

using namespace qs;
using namespace qs::dfi;

TEST(Pipeline, SphereToTorusFramesAreClosedAndEndpointsWithinAVoxel) {
  TriMesh sphere = shapes::icosphere(3);
  for (Vec3& p : sphere.positions) p *= 1.2;
  const TriMesh torus = shapes::torus(64, 24);
  // The plain blend (the warped morph is tested in stages_test), with its zero level as blended
  // and with the iso level shifted for a linear volume (the default).
  for (const FrameVolume volume : {FrameVolume::Free, FrameVolume::Linear}) {
    SCOPED_TRACE(volume == FrameVolume::Free ? "free volume" : "linear volume");
    MorphOptions opt;
    opt.grid = 40;
    opt.warp = false;
    opt.volume = volume;
    const PreparedMorph m = prepare_morph(sphere, torus, opt);
    const int frames = 7;
    for (int f = 0; f < frames; ++f) {
      const double t = f / (frames - 1.0);
      const TriMesh mesh = frame_mesh(m, blend_field(m, t), t);
      const MeshStats s = mesh_stats(mesh);
      EXPECT_TRUE(s.closed_manifold) << f;
      EXPECT_GT(s.volume, 0) << f;
      EXPECT_EQ(test_support::self_intersections(mesh), 0) << f;
      if (f == 0 || f == frames - 1) {
        EXPECT_EQ(s.genus, f == 0 ? 0 : 1);
        EXPECT_EQ(s.components, 1);
        const metro::MetroResult r = metro::metro(mesh, f == 0 ? sphere : torus);
        EXPECT_LT(r.max, m.spacing()) << "frame " << f << " Hausdorff " << r.max;
      }
    }
  }
}

TEST(Pipeline, SimilarityAlignmentMovesFromSourceToTargetPlacement) {
  const TriMesh a = shapes::icosphere(3);
  TriMesh b = shapes::icosphere(3);
  for (Vec3& p : b.positions) p = 2.0 * p + Vec3(5, 0, 0);
  MorphOptions opt;
  opt.grid = 24;
  opt.warp = false;
  opt.align = Align::Similarity;
  const PreparedMorph m = prepare_morph(a, b, opt);
  EXPECT_NEAR(m.target_to_source.scale, 0.5, 1e-6);
  // Both fields are the same sphere in morph space; the last frame sits on the target.
  const TriMesh last = frame_mesh(m, blend_field(m, 1.0), 1.0);
  const Box3 box = bounding_box(last.positions);
  EXPECT_NEAR(0.5 * (box.min + box.max).x(), 5.0, 0.05);
  EXPECT_NEAR(box.max.y() - box.min.y(), 4.0, 0.1);
  EXPECT_LT(metro::metro(last, b).max, 2.0 * m.spacing());  // a morph-space voxel, scaled by 2
}

TEST(Pipeline, SimilarityAlignmentFindsTheRotationOfAnElongatedShape) {
  const TriMesh a = shapes::ellipsoid(2.0, 1.0, 0.5, 3);
  TriMesh b = a;  // a turned 90 degrees about z, scaled by 3 and moved
  for (Vec3& p : b.positions) p = 3.0 * Vec3(-p.y(), p.x(), p.z()) + Vec3(1, 2, 3);
  MorphOptions opt;
  opt.grid = 32;
  opt.warp = false;
  opt.align = Align::Similarity;
  const PreparedMorph m = prepare_morph(a, b, opt);
  // Target to source: undo the turn (up to the ellipsoid's own symmetries: x and y axes kept).
  const Eigen::Matrix3d r = m.target_to_source.rotation;
  EXPECT_NEAR(std::abs(r(0, 1)), 1.0, 1e-6);
  EXPECT_NEAR(std::abs(r(1, 0)), 1.0, 1e-6);
  EXPECT_NEAR(std::abs(r(2, 2)), 1.0, 1e-6);
  // The blend of identical aligned shapes is that shape at every t (volume within 3%).
  const double volume = 4.0 / 3.0 * M_PI * 2.0 * 1.0 * 0.5;
  const MeshStats mid = mesh_stats(frame_mesh(m, blend_field(m, 0.5), 0.0));
  EXPECT_NEAR(mid.volume, volume, 0.03 * volume);
  EXPECT_LT(metro::metro(frame_mesh(m, blend_field(m, 1.0), 1.0), b).max, 3.0 * m.spacing());
}
