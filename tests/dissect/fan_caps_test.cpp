// A mesh whose caps are fans of slivers around one vertex: the cuts across a fan leave patches
// whose intrinsic Delaunay flips would be quadratic; they fall back to mean-value weights within
// a linear flip budget and the dissection keeps every invariant.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "qs/core/mesh.h"
#include "qs/dissect/dissection.h"
#include "check_dissection.h"

namespace {

/// A double cone: a ring of k vertices at z = 0, apexes at z = +1 and -1 (valence k each), 2k
/// faces, outward.
qs::TriMesh double_cone(int k) {
  qs::TriMesh m;
  m.positions.emplace_back(0, 0, 1);
  m.positions.emplace_back(0, 0, -1);
  for (int i = 0; i < k; ++i) {
    const double t = 2 * std::numbers::pi * i / k;
    m.positions.emplace_back(std::cos(t), std::sin(t), 0);
  }
  for (int i = 0; i < k; ++i) {
    const int a = 2 + i, b = 2 + (i + 1) % k;
    m.faces.push_back({0, a, b});
    m.faces.push_back({1, b, a});
  }
  return m;
}

}  // namespace

TEST(FanCaps, ADoubleConeOfValence1500DissectsIntoBijectivePatchesWithinTau) {
  const qs::TriMesh m = double_cone(1500);
  qs::dissect::DissectOptions o;
  const auto d = qs::dissect::dissect(m, std::nullopt, o);
  EXPECT_GE(d.chart.patches.size(), 10u);
  EXPECT_LE(d.max_stretch, o.tau);
  for (const auto& p : d.chart.patches) EXPECT_EQ(p.flipped_faces, 0) << p.name;
  qs::testing::check_dissection(d, m.num_faces());
}
