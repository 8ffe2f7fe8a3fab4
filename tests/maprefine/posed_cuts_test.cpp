// A shape in another pose, dissected in one pose through a registration: where the first mesh's
// node map folds (a hoof squeezed to zero uv area), the other mesh's map taken over from it cannot
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

TEST(SharedMeshes, APosedHorseIsCutWhereTheFirstMeshIsCutWhereItsMapFolds) {
  const std::filesystem::path file = qs::testing::shared_meshes_dir() / "horse_5k.obj";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "no " << file;
  const auto validated = qs::mesh::validate(qs::io::read_mesh(file).mesh);
  ASSERT_TRUE(validated.report.accepted);
  const qs::TriMesh& horse = validated.mesh;
  const qs::TriMesh posed = qs::family::pose_mesh(horse, {}).mesh;  // qs-family pose's defaults, seed 1
  const qs::family::PoseLandmarks landmarks = qs::family::choose_landmarks(horse);

  qs::dissect::DissectOptions o;  // as qs-dissect runs it
  o.same_pose_untangle = qs::maprefine::untangler();
  const auto set = qs::dissect::dissect_set(
      {qs::test::with_landmarks(horse, landmarks, "horse"), qs::test::with_landmarks(posed, landmarks, "posed")}, o);
  ASSERT_EQ(set.poses.size(), 2u);
  EXPECT_TRUE(set.poses[1].registered());
  EXPECT_GT(set.same_pose_folded_taken, 0);
  for (const auto& d : set.meshes)
    for (const auto& patch : d.chart.patches) EXPECT_EQ(patch.flipped_faces + patch.zero_area_faces, 0);

  // Against the exact map (vertex i <-> vertex i), before the map refinement: a hoof that kept its
  // own map sent its patch's points to another leg's (21% of the diagonal at most, 1.7% mean).
  std::vector<cr::TruthMesh> truth(2);
  truth[0].name = "horse";
  truth[0].mesh = horse;
  truth[1].name = "posed";
  truth[1].mesh = posed;
  std::vector<cr::DissectedInput> in;
  for (const auto& d : set.meshes) in.push_back({&d.chart, cr::dissection_landmarks(d)});
  cr::MeasureOptions mo;
  mo.samples = 20000;
  const auto m = cr::measure_pair(cr::GroundTruth(std::move(truth)), in, 0, 1, mo);
  EXPECT_LT(m.dissection.max, 8.0);
  EXPECT_LT(m.dissection.mean, 0.6);
}

}  // namespace
