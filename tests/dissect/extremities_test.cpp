// matched_extremities: the tips of a shape's protrusions matched on the shape in another pose by
// their geodesic distances to the landmarks, unambiguous matches only.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "../common/shared_meshes.h"
#include "../common/test_support.h"
#include "qs/dissect/loop_guide.h"
#include "qs/family/pose.h"
#include "qs/io/read_mesh.h"
#include "qs/shapes/shapes.h"

using qs::test::nearest_vertex;

// The horse in another pose (four limbs bent or turned), landmarks on its body that leave the
// limbs free: the points found are matched where the pose took them (one connectivity: vertex i
// of A is vertex i of B), within about an edge (3% of the diagonal of this 5k-face mesh; the
// distances run along edges); the first one is the farthest from the landmarks.
TEST(MatchedExtremities, FindTheLimbsOfAHorseInAnotherPose) {
  const std::filesystem::path path = qs::testing::shared_meshes_dir() / "horse_5k.obj";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "no " << path << " (the shared test meshes)";
  const qs::TriMesh horse = qs::io::read_mesh(path).mesh;
  qs::family::PoseOptions opt;
  opt.seed = 7;
  const qs::family::Pose posed = qs::family::pose_mesh(horse, opt);
  ASSERT_GE(posed.limbs.size(), 3u);
  const std::vector<int> landmarks{1612, 1324, 291, 187, 299, 908};
  const auto ca = qs::dissect::geodesic_coordinates(horse, landmarks);
  const auto cb = qs::dissect::geodesic_coordinates(posed.mesh, landmarks);
  const auto pairs = qs::dissect::matched_extremities(horse, ca, posed.mesh, cb, 16, 0.05);
  ASSERT_GE(pairs.size(), 8u);
  ASSERT_LE(pairs.size(), 16u);
  const double diag = qs::bounding_box(posed.mesh.positions).diagonal();
  for (const auto& [p, q] : pairs)
    EXPECT_LT((posed.mesh.positions[q] - posed.mesh.positions[p]).norm(), 0.03 * diag) << p << " -> " << q;
  // The first point is A's farthest from the landmarks.
  auto nearest_landmark = [&](int v) {
    double d = INFINITY;
    for (int l = 0; l < ca.dims; ++l) d = std::min(d, ca.at(v)[l]);
    return d;
  };
  for (int v = 0; v < horse.num_vertices(); ++v) EXPECT_LE(nearest_landmark(v), nearest_landmark(pairs[0].first));
}

// A mirror-symmetric ellipsoid with its landmarks on the mirror plane: the two ends have the same
// geodesic coordinates, so neither is matched, and every point that is matched (A against itself)
// goes to itself, not to its mirror image.
TEST(MatchedExtremities, LeaveOutTheMirrorImagesThatTheLandmarksCannotTellApart) {
  const qs::TriMesh m = qs::shapes::ellipsoid(2.0, 1.0, 0.8, 4);
  const std::vector<int> landmarks{nearest_vertex(m, {0, 1, 0}), nearest_vertex(m, {0, 0, 0.8}),
                                   nearest_vertex(m, {0, -1, 0}), nearest_vertex(m, {0, 0, -0.8})};
  const auto c = qs::dissect::geodesic_coordinates(m, landmarks);
  const auto pairs = qs::dissect::matched_extremities(m, c, m, c, 16, 0.05);
  const int end_a = nearest_vertex(m, {2, 0, 0}), end_b = nearest_vertex(m, {-2, 0, 0});
  for (const auto& [p, q] : pairs) {
    EXPECT_NE(p, end_a);
    EXPECT_NE(p, end_b);
    EXPECT_LT((m.positions[q] - m.positions[p]).norm(), 0.1) << p << " -> " << q;
  }
}
