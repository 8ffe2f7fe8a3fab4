// The default dissection options (chosen by qs-bench-defaults; docs/tools/qs-dissect.md) and the
// patch counts documented for them.
#include <gtest/gtest.h>

#include <filesystem>

#include "qs/dissect/dissection.h"
#include "qs/io/read_mesh.h"
#include "qs/mesh/validate.h"
#include "qs/shapes/shapes.h"

namespace {

qs::TriMesh example(const char* name) {
  const auto r = qs::io::read_mesh(std::filesystem::path(QS_SOURCE_DIR) / "examples" / name);
  const auto v = qs::mesh::validate(r.mesh);
  EXPECT_TRUE(v.report.accepted) << name;
  return v.mesh;
}

}  // namespace

TEST(DissectDefaults, AreTheDocumentedOnes) {
  const qs::dissect::DissectOptions o;
  EXPECT_EQ(o.tau, 3.0);
  EXPECT_EQ(o.max_patch_area, 0.15);
  EXPECT_EQ(o.stretch_iterations, 10);
  EXPECT_EQ(o.same_pose_detect, qs::dissect::kSamePoseDetect);  // the pipeline's: same pose found
  EXPECT_EQ(o.max_depth, 6);
  EXPECT_EQ(o.min_faces_to_split, 150);
  EXPECT_EQ(o.min_split_area, 0.01);    // README, qs-dissect, "Bodies and long limbs"
  EXPECT_EQ(o.force_split_area, 0.03);
  EXPECT_EQ(o.area_extra_depth, 4);     // README, "Even sampling of bodies"
  EXPECT_EQ(o.protrusion_stretch, 1000);  // README, "Default options", squeezed protrusions
  EXPECT_TRUE(o.geodesic_seed_curves);  // the tessellation-independent maps
  EXPECT_TRUE(o.intrinsic_cotan);
}

TEST(DissectDefaults, SmoothShapeGetsAreaCappedPatches) {
  // The stretch rule alone leaves an ellipsoid in its 2 seed patches (each half the surface); the
  // default area cap splits both, and, under the default cotangent maps, their centre children
  // (0.4, 1.4) once more: 18 patches, none over 15% of the area (the old edge paths and mean-value
  // maps: 10 patches; the largest stretch is 1.19 or 1.20 either way).
  const auto m = qs::shapes::ellipsoid(1.5, 1, 0.8, 3);
  const auto d = qs::dissect::dissect(m, std::nullopt);
  EXPECT_EQ(d.chart.patches.size(), 18u);
  EXPECT_LE(d.max_stretch, 1.25);
  std::vector<double> area(d.chart.patches.size(), 0.0);
  double total = 0;
  for (int f = 0; f < d.chart.mesh.num_faces(); ++f) {
    const double a = qs::face_area(d.chart.mesh, f);
    area[d.chart.face_patch[f]] += a;
    total += a;
  }
  for (size_t p = 0; p < area.size(); ++p) EXPECT_LE(area[p], 0.15 * total) << d.chart.patches[p].name;
  qs::dissect::DissectOptions stretch_only;
  stretch_only.max_patch_area = 0;
  EXPECT_EQ(qs::dissect::dissect(m, std::nullopt, stretch_only).chart.patches.size(), 2u);
}

TEST(DissectDefaults, ExampleMeshesGetTheDocumentedPatchCounts) {
  // README, "Default options": spot_2k 22 patches, fish_blub_2k 58 (automatic seeds, alone; 54
  // before area_extra_depth, 46 with the old edge paths and mean-value maps).
  const auto spot = qs::dissect::dissect(example("spot_2k.obj"), std::nullopt);
  EXPECT_EQ(spot.chart.patches.size(), 22u);
  EXPECT_LE(spot.max_stretch, 3.0);
  const auto fish = qs::dissect::dissect(example("fish_blub_2k.obj"), std::nullopt);
  EXPECT_EQ(fish.chart.patches.size(), 58u);
  EXPECT_LE(fish.max_stretch, 3.0);
}
