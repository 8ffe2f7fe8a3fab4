// Remesh quality measures: smallest-angle statistics and sampling density spreads, on meshes whose
// answers are known by construction.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "qs/core/error.h"
#include "qs/remesh/base_topology.h"
#include "qs/remesh/quality.h"
#include "qs/remesh/uniform.h"
#include "remesh_checks.h"

using ::testing::HasSubstr;

namespace {

constexpr double kPi = 3.14159265358979323846;

/// An isosceles triangle whose apex angle is `apex` degrees, legs of length 1, placed at x0.
void add_isosceles(qs::TriMesh& m, double apex, double x0) {
  const double h = apex * kPi / 180.0 / 2.0;
  const int b = m.num_vertices();
  m.positions.emplace_back(x0, 0, 0);
  m.positions.emplace_back(x0 + std::sin(h), std::cos(h), 0);
  m.positions.emplace_back(x0 - std::sin(h), std::cos(h), 0);
  m.faces.push_back({b, b + 1, b + 2});
}

/// A regular n x n grid of unit squares in the plane z = 0, each split into two right isosceles
/// triangles, scaled by `size` and shifted by x0.
void add_grid(qs::TriMesh& m, int n, double size, double x0) {
  const int b = m.num_vertices();
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.positions.emplace_back(x0 + size * i / n, size * j / n, 0);
  auto id = [&](int i, int j) { return b + j * (n + 1) + i; };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      m.faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
}

}  // namespace

TEST(AngleStats, RegularGridSplitGives45Everywhere) {
  qs::TriMesh m;
  add_grid(m, 8, 2.0, 0);
  const auto s = qs::remesh::smallest_angle_stats(m);
  EXPECT_EQ(s.faces, 128);
  EXPECT_EQ(s.under_5, 0);
  EXPECT_EQ(s.under_10, 0);
  EXPECT_EQ(s.under_20, 0);
  EXPECT_NEAR(s.median, 45, 1e-9);
  EXPECT_NEAR(s.min, 45, 1e-9);
}

TEST(AngleStats, KnownSmallestAnglesGiveTheShares) {
  // Isosceles triangles with apex angles below 60: the apex is the smallest angle.
  qs::TriMesh m;
  const double apex[] = {3, 7, 15, 30, 45, 50};
  for (int k = 0; k < 6; ++k) add_isosceles(m, apex[k], 3.0 * k);
  add_isosceles(m, 60, 20);   // equilateral: 60
  add_isosceles(m, 120, 25);  // base angles 30
  // A degenerate triangle (a repeated position): smallest angle 0.
  const int b = m.num_vertices();
  m.positions.emplace_back(40, 0, 0);
  m.positions.emplace_back(40, 0, 0);
  m.positions.emplace_back(41, 1, 0);
  m.faces.push_back({b, b + 1, b + 2});
  // Smallest angles: 3 7 15 30 45 50 60 30 0 -> sorted 0 3 7 15 30 30 45 50 60.
  const auto s = qs::remesh::smallest_angle_stats(m);
  EXPECT_EQ(s.faces, 9);
  EXPECT_DOUBLE_EQ(s.under_5, 2.0 / 9);
  EXPECT_DOUBLE_EQ(s.under_10, 3.0 / 9);
  EXPECT_DOUBLE_EQ(s.under_20, 4.0 / 9);
  EXPECT_NEAR(s.median, 30, 1e-9);
  EXPECT_EQ(s.min, 0);
  // An even count takes the mean of the two middle values: without the degenerate face and the
  // 120-degree one, with another 50: 3 7 15 30 45 50 50 60.
  m.faces.pop_back();
  m.faces.pop_back();
  add_isosceles(m, 50, 50);
  EXPECT_NEAR(qs::remesh::smallest_angle_stats(m).median, 0.5 * (30 + 45), 1e-9);
}

TEST(AngleStats, TinyAnglesAreAccurate) {
  // acos(dot) would lose a 1e-4 degree angle entirely; the measure must not.
  qs::TriMesh m;
  add_isosceles(m, 1e-4, 0);
  EXPECT_NEAR(qs::remesh::smallest_angle_stats(m).min, 1e-4, 1e-10);
}

TEST(AngleStats, EmptyMeshAndBadIndices) {
  EXPECT_EQ(qs::remesh::smallest_angle_stats(qs::TriMesh{}).faces, 0);
  qs::TriMesh m;
  add_grid(m, 1, 1, 0);
  m.faces.push_back({0, 1, 9});
  try {
    qs::remesh::smallest_angle_stats(m);
    FAIL() << "expected InvalidInput";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("face 2 has vertex index 9"));
  }
}

TEST(AngleStats, UniformRemeshOfASphereIsWellShaped) {
  // Two seed patches of a sphere: the grids are smooth, no sliver, and every statistic is ordered.
  const auto d = qs::remesh_test::sphere_dissection();
  const auto r = qs::remesh::remesh_uniform(d.chart, 4);
  const auto s = qs::remesh::smallest_angle_stats(r.mesh());
  EXPECT_EQ(s.faces, r.connectivity.num_faces());
  EXPECT_LE(s.under_5, s.under_10);
  EXPECT_LE(s.under_10, s.under_20);
  EXPECT_GT(s.min, 0);
  EXPECT_LE(s.min, s.median);
  EXPECT_LE(s.median, 60);
  EXPECT_GT(s.median, 20);
}

TEST(DensitySpread, EvenGridHasSpreadOne) {
  qs::TriMesh m;
  add_grid(m, 10, 1.0, 0);
  const auto d = qs::remesh::vertex_density(m);
  // Every face has area 1/200: 100 vertices per unit area.
  EXPECT_NEAR(d.p5, 100, 1e-9);
  EXPECT_NEAR(d.p50, 100, 1e-9);
  EXPECT_NEAR(d.p95, 100, 1e-9);
  EXPECT_NEAR(d.spread, 1, 1e-12);
}

TEST(DensitySpread, TwoDensitiesOverEqualAreas) {
  // Two unit squares, one with 4x4 cells and one with 8x8: densities 16 and 64 vertices per unit
  // area over equal areas, so the 5th percentile is the coarse one and the 95th the fine one.
  qs::TriMesh m;
  add_grid(m, 4, 1.0, 0);
  add_grid(m, 8, 1.0, 5);
  const auto d = qs::remesh::vertex_density(m);
  EXPECT_NEAR(d.p5, 16, 1e-9);
  EXPECT_NEAR(d.p95, 64, 1e-9);
  EXPECT_NEAR(d.spread, 4, 1e-9);
  // Weighted by area, not by face count: a fine region over 2% of the surface is outside the
  // 5-95 band even though it holds most of the faces.
  qs::TriMesh n;
  add_grid(n, 2, 7.0, 0);                   // area 49, 8 faces
  add_grid(n, 20, 1.0, 10);                 // area 1, 800 faces
  const auto e = qs::remesh::vertex_density(n);
  EXPECT_NEAR(e.p5, 8.0 / 98.0, 1e-12);     // 1 / (2 * 49/8)
  EXPECT_NEAR(e.p95, 8.0 / 98.0, 1e-12);
  EXPECT_NEAR(e.spread, 1, 1e-12);
}

TEST(DensitySpread, ChartDensityFollowsTheUvAreas) {
  // Two faces of 3D area 0.5 each; the first covers half of the unit square, the second an
  // eighth: with 4 cells per side, 16 * (uv area) / (3D area) = 16 and 4 cells per unit area.
  qs::dissect::Chart c;
  c.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 0, 0}, {6, 0, 0}, {5, 1, 0}};
  c.mesh.faces = {{0, 1, 2}, {3, 4, 5}};
  c.face_patch = {0, 0};
  c.face_uv = {{qs::Vec2(0, 0), qs::Vec2(1, 0), qs::Vec2(0, 1)},
               {qs::Vec2(0, 0), qs::Vec2(0.5, 0), qs::Vec2(0, 0.5)}};
  const auto d = qs::remesh::chart_density(c, 4);
  EXPECT_NEAR(d.p5, 4, 1e-12);
  EXPECT_NEAR(d.p95, 16, 1e-12);
  EXPECT_NEAR(d.spread, 4, 1e-12);
  EXPECT_THROW(qs::remesh::chart_density(c, 0), qs::InvalidInput);
  // A face squeezed to zero uv area has no samples at all: the spread is infinite.
  c.face_uv[1] = {qs::Vec2(0, 0), qs::Vec2(0.5, 0), qs::Vec2(1, 0)};
  c.mesh.positions.push_back({9, 0, 0});
  c.mesh.positions.push_back({10, 0, 0});
  c.mesh.positions.push_back({9, 1, 0});
  c.mesh.faces.push_back({6, 7, 8});
  c.face_uv.push_back(c.face_uv[1]);
  c.face_patch.push_back(0);
  EXPECT_TRUE(std::isinf(qs::remesh::chart_density(c, 4).spread));
}

TEST(DensitySpread, ChartDensityWithACountPerPatch) {
  // Two patches of 3D area 0.5 and 2 (a triangle of each, covering half of each unit square): with
  // the same 4 cells per side the densities are 16 and 4 (spread 4); with 4 and 8 cells per side
  // (sides in proportion to the square root of the areas) both are 16: spread 1.
  qs::dissect::Chart c;
  c.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 0, 0}, {7, 0, 0}, {5, 2, 0}};
  c.mesh.faces = {{0, 1, 2}, {3, 4, 5}};
  c.face_patch = {0, 1};
  c.face_uv = {{qs::Vec2(0, 0), qs::Vec2(1, 0), qs::Vec2(0, 1)}, {qs::Vec2(0, 0), qs::Vec2(1, 0), qs::Vec2(0, 1)}};
  const auto same = qs::remesh::chart_density(c, 4);
  EXPECT_NEAR(same.p5, 4, 1e-12);
  EXPECT_NEAR(same.p95, 16, 1e-12);
  EXPECT_NEAR(same.spread, 4, 1e-12);
  const auto sized = qs::remesh::chart_density(c, std::vector<double>{4, 8});
  EXPECT_NEAR(sized.p5, 16, 1e-12);
  EXPECT_NEAR(sized.p95, 16, 1e-12);
  EXPECT_NEAR(sized.spread, 1, 1e-12);
  EXPECT_THROW(qs::remesh::chart_density(c, std::vector<double>{4}), qs::InvalidInput);  // patch 1 has no count
  EXPECT_THROW(qs::remesh::chart_density(c, std::vector<double>{4, 0}), qs::InvalidInput);
  // Shares of the surface: 0.5 / 2.5 and 2 / 2.5; for a set, the larger of each patch's shares.
  c.patches.resize(2);
  const auto one = qs::remesh::patch_area_shares({&c});
  EXPECT_NEAR(one[0], 0.2, 1e-12);
  EXPECT_NEAR(one[1], 0.8, 1e-12);
  qs::dissect::Chart d = c;
  for (int v = 0; v < 3; ++v) d.mesh.positions[v] *= 2;  // patch 0 now 2 of 4
  const auto both = qs::remesh::patch_area_shares({&c, &d});
  EXPECT_NEAR(both[0], 0.5, 1e-12);
  EXPECT_NEAR(both[1], 0.8, 1e-12);
  qs::dissect::Chart e = c;
  e.patches.resize(3);
  EXPECT_THROW(qs::remesh::patch_area_shares({&c, &e}), qs::InvalidInput);
}

TEST(DensitySpread, PatchTexelSharesFollowTheMedianFace) {
  // Two patches, each two triangles over the unit square (uv area 0.5 each). Patch 1 is evenly
  // mapped (3D areas 1 and 1): its share is its area share, 2 / 6. Patch 0 has 3D areas 1 and 3:
  // uv / 3D = 0.5 and 1/6; the area-weighted median is 1/6 (the larger face), so it covers
  // 1 / (1/6) = 6 units at that density: 6 / 6 = 1 (its area share would be 4 / 6).
  qs::dissect::Chart c;
  auto tri = [&](double a, double b, const qs::Vec3& o) {  // a right triangle of legs a, b: area ab/2
    const int v = c.mesh.num_vertices();
    c.mesh.positions.push_back(o);
    c.mesh.positions.push_back(o + qs::Vec3(a, 0, 0));
    c.mesh.positions.push_back(o + qs::Vec3(0, b, 0));
    c.mesh.faces.push_back({v, v + 1, v + 2});
  };
  tri(1, 2, {0, 0, 0});
  tri(2, 3, {10, 0, 0});
  tri(1, 2, {20, 0, 0});
  tri(1, 2, {30, 0, 0});
  c.face_patch = {0, 0, 1, 1};
  const std::array<qs::Vec2, 3> lower = {qs::Vec2(0, 0), qs::Vec2(1, 0), qs::Vec2(0, 1)};
  const std::array<qs::Vec2, 3> upper = {qs::Vec2(1, 0), qs::Vec2(1, 1), qs::Vec2(0, 1)};
  c.face_uv = {lower, upper, lower, upper};
  c.patches.resize(2);
  const auto t = qs::remesh::patch_texel_shares({&c});
  ASSERT_EQ(t.size(), 2u);
  EXPECT_NEAR(t[0], 1.0, 1e-12);
  EXPECT_NEAR(t[1], 2.0 / 6.0, 1e-12);
  const auto a = qs::remesh::patch_area_shares({&c});
  EXPECT_NEAR(a[0], 4.0 / 6.0, 1e-12);
  EXPECT_NEAR(a[1], 2.0 / 6.0, 1e-12);
  EXPECT_THROW(qs::remesh::patch_texel_shares({}), qs::InvalidInput);
}

TEST(DensitySpread, RemeshOfASphereIsFairlyEven) {
  // Vertex density of a level-4 remesh of a sphere's two seed patches, and the chart density at
  // the same grid resolution: both measure one mapping, so their spreads agree roughly.
  const auto d = qs::remesh_test::sphere_dissection();
  const auto r = qs::remesh::remesh_uniform(d.chart, 4);
  const auto v = qs::remesh::vertex_density(r.mesh());
  const auto c = qs::remesh::chart_density(d.chart, 16);
  EXPECT_GE(v.spread, 1);
  EXPECT_LT(v.spread, 8);
  EXPECT_GE(c.spread, 1);
  EXPECT_LT(c.spread, 8);
  // Vertex density ~ cells per unit area (a cell is two faces, one vertex).
  EXPECT_NEAR(v.p50 / c.p50, 1.0, 0.3);
}

TEST(BestAngleDiagonals, ClosedManifoldNeverWorseAndOneFaceListForASet) {
  using qs::remesh::DiagonalRule;
  qs::remesh::UniformOptions best;
  best.diagonals = DiagonalRule::BestAngle;
  // Two seed patches (base vertices of valence 2) and a star blob's many patches (valence 3-5).
  for (const auto* d : {&qs::remesh_test::sphere_dissection(), &qs::remesh_test::star_dissection()}) {
    for (int level = 0; level <= 4; ++level) {
      SCOPED_TRACE("level " + std::to_string(level) + ", " + std::to_string(d->chart.patches.size()) + " patches");
      const auto pattern = qs::remesh::remesh_uniform(d->chart, level);
      const auto chosen = qs::remesh::remesh_uniform(d->chart, level, best);
      EXPECT_EQ(chosen.positions, pattern.positions);
      EXPECT_EQ(chosen.connectivity.vertex_uv, pattern.connectivity.vertex_uv);
      ASSERT_EQ(chosen.connectivity.faces.size(), pattern.connectivity.faces.size());
      EXPECT_EQ(qs::remesh_test::expect_closed_manifold(chosen.connectivity.faces, chosen.connectivity.num_vertices()),
                2);
      // Per cell (faces 2k, 2k+1): the worst smallest angle never drops.
      const auto ap = qs::remesh::smallest_angle_stats(pattern.mesh());
      const auto ac = qs::remesh::smallest_angle_stats(chosen.mesh());
      EXPECT_GE(ac.median, ap.median - 1e-9);
      EXPECT_LE(ac.under_20, ap.under_20 + 1e-12);
      const auto& pf = pattern.connectivity.faces;
      const auto& cf = chosen.connectivity.faces;
      auto worst = [](const qs::TriMesh& m, size_t k) {
        qs::TriMesh cell{m.positions, {m.faces[k], m.faces[k + 1]}};
        return qs::remesh::smallest_angle_stats(cell).min;
      };
      const qs::TriMesh mp = pattern.mesh(), mc = chosen.mesh();
      for (size_t k = 0; k + 1 < pf.size(); k += 2) {
        if (pf[k] != cf[k]) {
          EXPECT_GT(worst(mc, k), worst(mp, k) - 1e-9) << "cell " << k / 2;
        }
      }
    }
  }
  // A set: one decision per cell for all meshes, so they share the face list.
  const auto sphere = qs::shapes::icosphere(3);
  const auto ellipsoid = qs::shapes::ellipsoid(1.8, 1, 0.6, 3);
  const auto seeds = qs::remesh_test::equator_seeds(sphere);
  qs::dissect::DissectOptions o;
  o.max_patch_area = 0.2;
  const auto set = qs::dissect::dissect_set({{&sphere, seeds, {}, "s"}, {&ellipsoid, seeds, {}, "e"}}, o);
  const auto r = qs::remesh::remesh_uniform({set.meshes[0].chart, set.meshes[1].chart}, 3, best);
  EXPECT_EQ(qs::remesh_test::expect_closed_manifold(r.connectivity.faces, r.connectivity.num_vertices()), 2);
  for (int m = 0; m < 2; ++m) qs::remesh_test::expect_valid_sphere(r.mesh(m), "set mesh " + std::to_string(m));
}
