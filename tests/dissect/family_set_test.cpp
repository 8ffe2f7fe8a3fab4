// Set dissections of generated families (qs::family): smooth limbed shapes, each its own
// tessellation, seeds and limb-tip features given as surface points. Every family must end with
// every leaf bijective, every feature at one (patch, u, v), every seed exactly a patch corner.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "qs/dissect/dissection.h"
#include "qs/correspondence/correspondence.h"
#include "qs/family/family.h"

namespace {

struct Generated {
  qs::family::Family family;
  std::vector<qs::dissect::MeshToDissect> set;
};

// The first n shapes of a 16-shape family (shape i does not depend on N).
const Generated& family_of(std::uint64_t seed) {
  static std::map<std::uint64_t, Generated> cache;
  auto it = cache.find(seed);
  if (it != cache.end()) return it->second;
  Generated& g = cache[seed];
  qs::family::FamilyOptions o;
  o.shapes = 16;
  o.seed = seed;
  g.family = qs::family::generate_family(o);
  for (const auto& s : g.family.shapes) g.set.push_back(qs::correspondence::dissect_input(s));
  return g;
}

void expect_exact_common_structure(const qs::dissect::DissectionSet& s) {
  const auto& first = s.meshes.front();
  for (const auto& d : s.meshes) {
    EXPECT_EQ(d.base.quads, first.base.quads);
    EXPECT_TRUE(d.base.closed_conforming);
    EXPECT_EQ(d.base.euler_characteristic, 2);
    for (const auto& p : d.chart.patches) EXPECT_EQ(p.flipped_faces + p.zero_area_faces, 0) << p.name;
    ASSERT_EQ(d.features.size(), first.features.size());
    for (size_t k = 0; k < d.features.size(); ++k) {
      EXPECT_EQ(d.features[k].patch, first.features[k].patch) << d.features[k].name;
      EXPECT_LT((d.features[k].uv - first.features[k].uv).lpNorm<Eigen::Infinity>(), 1e-9) << d.features[k].name;
    }
    // Seeds: inserted vertices whose every wedge is a corner of the square.
    for (int i = 0; i < 4; ++i) {
      const int v = d.seed_placements[i].vertex;
      ASSERT_EQ(v, d.seeds[i]);
      int wedges = 0;
      for (int f = 0; f < d.chart.mesh.num_faces(); ++f)
        for (int j = 0; j < 3; ++j)
          if (d.chart.mesh.faces[f][j] == v) {
            const qs::Vec2 uv = d.chart.face_uv[f][j];
            EXPECT_LT(std::max(std::min(std::abs(uv.x()), std::abs(uv.x() - 1)),
                               std::min(std::abs(uv.y()), std::abs(uv.y() - 1))),
                      1e-9);
            ++wedges;
          }
      EXPECT_GT(wedges, 0);
    }
  }
}

class FamilySet : public ::testing::TestWithParam<std::tuple<int, int>> {};

TEST_P(FamilySet, EveryLeafBijectiveFeaturesAndSeedsExact) {
  const auto [seed, n] = GetParam();
  const Generated& g = family_of(static_cast<std::uint64_t>(seed));
  const std::vector<qs::dissect::MeshToDissect> set(g.set.begin(), g.set.begin() + n);
  const qs::dissect::DissectionSet s = qs::dissect::dissect_set(set);
  ASSERT_EQ(s.meshes.size(), static_cast<size_t>(n));
  EXPECT_GT(s.meshes[0].chart.patches.size(), 2u);
  expect_exact_common_structure(s);
}

INSTANTIATE_TEST_SUITE_P(Families, FamilySet,
                         ::testing::Combine(::testing::Values(1, 2, 3), ::testing::Values(2, 4, 8, 16)),
                         [](const auto& info) {
                           return "seed" + std::to_string(std::get<0>(info.param)) + "_n" +
                                  std::to_string(std::get<1>(info.param));
                         });

TEST(FamilySetSplit, ASplitWhoseCutsCrossIsTriedAgainAndEveryLeafEndsBijective) {
  // With the old maps (edge seed paths, mean-value weights), seed 1's first four shapes have a
  // node whose split's cuts cross where they pass through vertices near them; the split is tried
  // again with cuts kept on their segments (before, the node's patch was refined and split again).
  const Generated& g = family_of(1);
  qs::dissect::DissectOptions old_maps;
  old_maps.geodesic_seed_curves = false;
  old_maps.intrinsic_cotan = false;
  old_maps.intrinsic_loops = false;  // the loops that lead to that node: each shape's own
  const std::vector<qs::dissect::MeshToDissect> set(g.set.begin(), g.set.begin() + 4);
  const qs::dissect::DissectionSet s = qs::dissect::dissect_set(set, old_maps);
  EXPECT_GT(s.retried_splits, 0) << "the test should exercise a split tried again";
  for (const auto& d : s.meshes)
    for (const auto& p : d.chart.patches) EXPECT_NE(p.stop, qs::dissect::StopReason::SplitFailed) << p.name;
  expect_exact_common_structure(s);
  // The cuts only resample the surface: every chart vertex lies on its input mesh's surface, so
  // the total area is unchanged.
  for (size_t i = 0; i < set.size(); ++i) {
    double a_in = 0, a_chart = 0;
    for (int f = 0; f < g.set[i].mesh->num_faces(); ++f) a_in += qs::face_area(*g.set[i].mesh, f);
    for (int f = 0; f < s.meshes[i].chart.mesh.num_faces(); ++f) a_chart += qs::face_area(s.meshes[i].chart.mesh, f);
    EXPECT_NEAR(a_chart, a_in, 1e-9 * a_in);
  }
}

}  // namespace
