// Signed distance fields of meshes made in code, against analytic distances.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "qs/core/error.h"
#include "qs/dfi/sdf.h"
#include "qs/shapes/shapes.h"
#include "test_meshes.h"

using namespace qs;
using namespace qs::dfi;

namespace {

Grid domain_around(double extent, int cells) {
  Box3 box;
  box.min = Vec3::Constant(-extent);
  box.max = Vec3::Constant(extent);
  return grid_over(box, cells, 2);
}

}  // namespace

TEST(SignedDistance, SphereMatchesTheAnalyticDistance) {
  const TriMesh sphere = shapes::icosphere(4);  // unit sphere, 5120 faces: facets within ~0.002
  const Grid g = signed_distance(sphere, domain_around(1.3, 24));
  double worst = 0;
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) {
        const double d = g.values[g.index(i, j, k)];
        const double exact = g.point(i, j, k).norm() - 1.0;
        worst = std::max(worst, std::abs(d - exact));
        if (std::abs(exact) > 0.01) {
          EXPECT_EQ(d < 0, exact < 0) << i << " " << j << " " << k;
        }
      }
  EXPECT_LT(worst, 0.01);
}

TEST(SignedDistance, TorusSignAndPropagatedDistancesMatchExactEverywhere) {
  const TriMesh torus = shapes::torus(96, 48);
  const Grid domain = domain_around(1.8, 30);
  const Grid fast = signed_distance(torus, domain);  // exact band + closest-point sweeps
  SdfOptions exact_opt;
  exact_opt.band = 0;
  const Grid exact = signed_distance(torus, domain, exact_opt);
  int wrong_sign = 0;
  double worst = 0;
  for (size_t id = 0; id < exact.values.size(); ++id) {
    worst = std::max(worst, static_cast<double>(std::abs(fast.values[id] - exact.values[id])));
    int k = static_cast<int>(id / (exact.dims[0] * exact.dims[1]));
    int j = static_cast<int>(id / exact.dims[0] % exact.dims[1]);
    int i = static_cast<int>(id % exact.dims[0]);
    const double analytic = test_support::torus_sd(exact.point(i, j, k), 1.0, 0.4);
    if (std::abs(analytic) > 0.02) wrong_sign += (exact.values[id] < 0) != (analytic < 0);
  }
  EXPECT_EQ(wrong_sign, 0);
  // The sweeps propagate closest points, not distances: off by a small fraction of a cell.
  EXPECT_LT(worst, 0.25 * exact.spacing);
}

TEST(SignedDistance, SameBytesOnOneOrTwoThreads) {
  const TriMesh torus = shapes::torus(40, 20);
  const Grid domain = domain_around(1.6, 20);
  SdfOptions one, two;
  one.threads = 1;
  two.threads = 2;
  EXPECT_EQ(signed_distance(torus, domain, one).values, signed_distance(torus, domain, two).values);
}

TEST(SignedDistance, RejectsAnEmptyMeshAndBadOptions) {
  EXPECT_THROW(signed_distance(TriMesh{}, domain_around(1, 8)), InvalidInput);
  SdfOptions bad;
  bad.band = -1;
  EXPECT_THAT([&] { signed_distance(shapes::icosphere(1), domain_around(1.5, 8), bad); },
              ::testing::ThrowsMessage<InvalidInput>(::testing::HasSubstr("band")));
}

TEST(Grid, TrilinearSampleReproducesALinearField) {
  Grid g = domain_around(1.0, 8);
  g.values.resize(g.size());
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) {
        const Vec3 p = g.point(i, j, k);
        g.values[g.index(i, j, k)] = static_cast<float>(0.5 * p.x() - 0.25 * p.y() + 2 * p.z());
      }
  const Vec3 q(0.123, -0.456, 0.789);
  EXPECT_NEAR(g.sample(q), 0.5 * q.x() - 0.25 * q.y() + 2 * q.z(), 1e-5);
}
