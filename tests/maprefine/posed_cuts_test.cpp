// A shape in another pose, dissected in one pose through a registration: where the first mesh's
// node map folds (a foot squeezed to zero uv area), the other mesh's map taken over from it cannot
// be bijective, and the split still cuts it where the first mesh is cut.
#include <gtest/gtest.h>

#include <filesystem>

#include "../common/posed_animal.h"
#include "../common/shared_meshes.h"
#include "qs/correspondence/correspondence.h"
#include "qs/dissect/dissection.h"
#include "qs/family/pose.h"
#include "qs/io/read_mesh.h"
#include "qs/maprefine/map_refine.h"
#include "qs/mesh/validate.h"

namespace {

namespace cr = qs::correspondence;

TEST(SharedMeshes, APosedCamelIsCutWhereTheFirstMeshIsCutWhereItsMapFolds) {
  const std::filesystem::path file = qs::testing::shared_meshes_dir() / "camel_4k_fixed.obj";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "no " << file;
  const auto validated = qs::mesh::validate(qs::io::read_mesh(file).mesh);
  ASSERT_TRUE(validated.report.accepted);
  const qs::TriMesh& camel = validated.mesh;
  qs::family::PoseOptions po;  // qs-family pose --seed 7
  po.seed = 7;
  const qs::TriMesh posed = qs::family::pose_mesh(camel, po).mesh;
  const qs::family::PoseLandmarks landmarks = qs::family::choose_landmarks(camel);

  qs::dissect::DissectOptions o;  // as qs-dissect runs it
  o.same_pose_untangle = qs::maprefine::untangler();
  const auto set = qs::dissect::dissect_set(
      {qs::test::with_landmarks(camel, landmarks, "camel"), qs::test::with_landmarks(posed, landmarks, "posed")}, o);
  ASSERT_EQ(set.poses.size(), 2u);
  EXPECT_TRUE(set.poses[1].registered());
  EXPECT_GT(set.same_pose_folded_taken, 0);
  for (const auto& d : set.meshes)
    for (const auto& patch : d.chart.patches) EXPECT_EQ(patch.flipped_faces + patch.zero_area_faces, 0);

  // Against the exact map (vertex i <-> vertex i), before the map refinement. Measured: 2.9% of the
  // diagonal at most, 0.31% mean; a foot that kept its own map sent its patch's points elsewhere
  // (16.6% at most, 0.60% mean).
  std::vector<cr::TruthMesh> truth(2);
  truth[0].name = "camel";
  truth[0].mesh = camel;
  truth[1].name = "posed";
  truth[1].mesh = posed;
  std::vector<cr::DissectedInput> in;
  for (const auto& d : set.meshes) in.push_back({&d.chart, cr::dissection_landmarks(d)});
  cr::MeasureOptions mo;
  mo.samples = 20000;
  const auto m = cr::measure_pair(cr::GroundTruth(std::move(truth)), in, 0, 1, mo);
  EXPECT_LT(m.dissection.max, 6.0);
  EXPECT_LT(m.dissection.mean, 0.45);
}

}  // namespace
