// The seeds' cyclic order: the set's shortest loop, the same permutation for every mesh.
#include <gtest/gtest.h>

#include <cmath>

#include "qs/dissect/dissection.h"
#include "qs/dissect/loop_guide.h"
#include "qs/dissect/seed_order.h"
#include "qs/mesh/validate.h"
#include "qs/shapes/shapes.h"
#include "../common/test_support.h"

using qs::dissect::MeshToDissect;

using qs::test::vertex_towards;

namespace {

// Four seeds around the waist of an elongated ellipsoid, given in the order +x, -x, +y, -y: the
// loop through them in that order crosses the waist twice; the belt order is +x, +y, -x, -y.
struct Waist {
  qs::TriMesh mesh;
  std::array<int, 4> crossing;
};

Waist waist(double bend) {
  Waist w;
  w.mesh = qs::shapes::ellipsoid(1.0, 0.8, 2.5, 4);
  for (auto& p : w.mesh.positions) p.x() += bend * p.z() * p.z();
  w.crossing = {vertex_towards(w.mesh, {1, 0, 0}), vertex_towards(w.mesh, {-1, 0, 0}),
                vertex_towards(w.mesh, {0, 1, 0}), vertex_towards(w.mesh, {0, -1, 0})};
  return w;
}

TEST(SeedOrder, GeodesicCoordinatesAreSymmetricAndTriangular) {
  const Waist w = waist(0);
  const std::vector<int> seeds(w.crossing.begin(), w.crossing.end());
  const auto c = qs::dissect::geodesic_coordinates(w.mesh, seeds);
  ASSERT_EQ(c.dims, 4);
  for (int a = 0; a < 4; ++a) {
    EXPECT_EQ(c.at(seeds[a])[a], 0);
    for (int b = 0; b < 4; ++b) {
      EXPECT_NEAR(c.at(seeds[a])[b], c.at(seeds[b])[a], 1e-12);
      for (int v = 0; v < w.mesh.num_vertices(); v += 97) EXPECT_LE(c.at(v)[b], c.at(v)[a] + c.at(seeds[a])[b] + 1e-12);
    }
  }
  // Opposite waist points are farther apart than neighbours (half the waist against a quarter).
  EXPECT_GT(c.at(seeds[0])[1], 1.4 * c.at(seeds[0])[2]);
}

TEST(SeedOrder, WindingOrderIsReplacedByTheBeltForTheWholeSet) {
  const Waist a = waist(0), b = waist(0.1);
  std::vector<MeshToDissect> set(2);
  set[0].mesh = &a.mesh;
  set[0].seeds = a.crossing;
  set[1].mesh = &b.mesh;
  set[1].seeds = b.crossing;
  const auto choice = qs::dissect::shortest_seed_order(set);
  ASSERT_TRUE(choice.changed());
  // (0,2,1,3): +x, +y, -x, -y.
  EXPECT_EQ(choice.order, (std::array<int, 4>{0, 2, 1, 3}));
  EXPECT_LT(choice.lengths[2] * 1.2, choice.lengths[0]);

  const auto out = qs::dissect::dissect_set(set);
  EXPECT_EQ(out.seed_order, choice.order);
  // Seed k of the result is the given seed order[k] in both meshes.
  for (size_t i = 0; i < 2; ++i) {
    const auto& given = *set[i].seeds;
    const auto& used = out.meshes[i].seeds;
    for (int k = 0; k < 4; ++k)
      EXPECT_EQ((out.meshes[i].chart.mesh.positions[used[k]] - set[i].mesh->positions[given[choice.order[k]]]).norm(),
                0.0);
  }
}

TEST(SeedOrder, BeltOrderAndAutomaticSeedsAreKept) {
  const Waist a = waist(0);
  std::vector<MeshToDissect> set(1);
  set[0].mesh = &a.mesh;
  set[0].seeds = std::array<int, 4>{a.crossing[0], a.crossing[2], a.crossing[1], a.crossing[3]};
  EXPECT_FALSE(qs::dissect::shortest_seed_order(set).changed());
  set[0].seeds.reset();
  const auto choice = qs::dissect::shortest_seed_order(set);
  EXPECT_FALSE(choice.changed());
  EXPECT_EQ(choice.lengths[0], 0);
}

TEST(SeedOrder, SeedsOutOfRangeAreLeftToTheSeedLoopToReport) {
  const Waist a = waist(0);
  std::vector<MeshToDissect> set(1);
  set[0].mesh = &a.mesh;
  set[0].seeds = std::array<int, 4>{0, 1, 2, a.mesh.num_vertices()};
  EXPECT_FALSE(qs::dissect::shortest_seed_order(set).changed());
}

}  // namespace
