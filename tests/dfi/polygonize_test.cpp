// Marching tetrahedra on analytic fields: closed, manifold, outward, no self-intersections,
// the right topology, vertices on the surface.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "qs/core/error.h"
#include "qs/dfi/polygonize.h"
#include "qs/mesh/validate.h"
#include "qs/shapes/shapes.h"
#include "test_meshes.h"

using namespace qs;
using namespace qs::dfi;
using qs::dfi::test_support::analytic_grid;

TEST(Polygonize, SphereIsAClosedOutwardManifoldOnTheSurface) {
  const Grid g = analytic_grid(1.5, 24, [](const Vec3& p) { return test_support::sphere_sd(p, Vec3(0.05, -0.03, 0.02), 1.0); });
  const TriMesh m = polygonize(g);
  const MeshStats s = mesh_stats(m);
  EXPECT_TRUE(s.closed_manifold);
  EXPECT_EQ(s.components, 1);
  EXPECT_EQ(s.genus, 0);
  // Validation is independent of our stats: closed, manifold (vertex fans too), oriented, genus 0.
  const auto v = mesh::validate(m);
  EXPECT_TRUE(v.report.accepted) << mesh::format_report("sphere", v.report);
  EXPECT_FALSE(v.report.orientation_flipped);
  const double volume = 4.0 / 3.0 * M_PI;
  EXPECT_NEAR(s.volume, volume, 0.02 * volume);
  // Linear interpolation of a smooth distance: vertices within a small fraction of a cell.
  for (const Vec3& p : m.positions) EXPECT_NEAR((p - Vec3(0.05, -0.03, 0.02)).norm(), 1.0, 0.05 * g.spacing);
  EXPECT_EQ(test_support::self_intersections(m), 0);
}

TEST(Polygonize, TorusHasGenusOneAndTwoSpheresTwoComponents) {
  const Grid torus = analytic_grid(1.6, 28, [](const Vec3& p) { return test_support::torus_sd(p, 1.0, 0.4); });
  const TriMesh t = polygonize(torus);
  const MeshStats st = mesh_stats(t);
  EXPECT_TRUE(st.closed_manifold);
  EXPECT_EQ(st.components, 1);
  EXPECT_EQ(st.genus, 1);
  EXPECT_GT(st.volume, 0);
  EXPECT_EQ(test_support::self_intersections(t), 0);

  const Grid two = analytic_grid(2.0, 24, [](const Vec3& p) {
    return std::min(test_support::sphere_sd(p, Vec3(-1, 0, 0), 0.7), test_support::sphere_sd(p, Vec3(1, 0, 0), 0.7));
  });
  const MeshStats s2 = mesh_stats(polygonize(two));
  EXPECT_TRUE(s2.closed_manifold);
  EXPECT_EQ(s2.components, 2);
  EXPECT_EQ(s2.genus, 0);
}

TEST(Polygonize, SaddleCellsStayManifold) {
  // Two spheres that nearly touch: cells with ambiguous (saddle) sign patterns between them.
  for (double gap : {0.0, 0.013, 0.031, 0.05}) {
    const Grid g = analytic_grid(2.0, 20, [gap](const Vec3& p) {
      return std::min(test_support::sphere_sd(p, Vec3(-0.8 - gap, 0.01, 0), 0.8),
                      test_support::sphere_sd(p, Vec3(0.8 + gap, -0.02, 0.03), 0.8));
    });
    const TriMesh m = polygonize(g);
    const MeshStats s = mesh_stats(m);
    EXPECT_TRUE(s.closed_manifold) << gap;
    const auto v = mesh::validate(m, {.allow_any_genus = true});
    EXPECT_EQ(mesh::find_problem(v.report, "non_manifold_vertices"), nullptr) << gap;
    EXPECT_EQ(mesh::find_problem(v.report, "non_manifold_edges"), nullptr) << gap;
    EXPECT_EQ(test_support::self_intersections(m), 0) << gap;
  }
}

TEST(Polygonize, RejectsAShapeThatTouchesTheGridBoundary) {
  const Grid g = analytic_grid(1.0, 10, [](const Vec3& p) { return test_support::sphere_sd(p, Vec3::Zero(), 1.5); });
  EXPECT_THAT([&] { polygonize(g); },
              ::testing::ThrowsMessage<InvalidInput>(::testing::HasSubstr("boundary sample")));
}

TEST(MeshStats, CountsGenusComponentsAndVolume) {
  const MeshStats torus = mesh_stats(shapes::torus(24, 12));
  EXPECT_TRUE(torus.closed_manifold);
  EXPECT_EQ(torus.genus, 1);
  EXPECT_EQ(torus.components, 1);
  const MeshStats two = mesh_stats(shapes::two_components());
  EXPECT_EQ(two.components, 2);
  EXPECT_EQ(two.genus, 0);
  TriMesh open = shapes::icosphere(1);
  open.faces.pop_back();
  EXPECT_FALSE(mesh_stats(open).closed_manifold);
}

// The independent check itself: it must see a crossing, in 3D and within one plane, and must not
// see one between coplanar faces that only lie side by side (a field's planar patch).
TEST(SelfIntersectionCheck, CountsCrossingsAndNotNeighboursInOnePlane) {
  TriMesh crossing;
  crossing.positions = {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(0.5, 0.5, -1), Vec3(0.5, 0.5, 1), Vec3(3, 3, 0)};
  crossing.faces = {{0, 1, 2}, {3, 4, 5}};
  EXPECT_EQ(test_support::self_intersections(crossing), 1);
  TriMesh overlapping;  // two triangles in z = 0, the second's corner inside the first
  overlapping.positions = {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 2, 0), Vec3(0.5, 0.5, 0), Vec3(3, 1, 0), Vec3(3, 3, 0)};
  overlapping.faces = {{0, 1, 2}, {3, 4, 5}};
  EXPECT_EQ(test_support::self_intersections(overlapping), 1);
  TriMesh side_by_side;  // in one tilted plane, apart (the frame that the 3D signs alone flagged)
  const Vec3 s(0.043, 0.0154, 0), z(0, 0, 1);
  side_by_side.positions = {Vec3::Zero(), s + 0.008 * z, -0.035 * z, s - 0.035 * z, 1.6 * s + 0.018 * z, 1.6 * s - 0.035 * z};
  for (Vec3& p : side_by_side.positions) p += Vec3(-0.49, 1.2876132009968655, 0.0001);
  side_by_side.faces = {{0, 1, 2}, {3, 4, 5}};
  EXPECT_EQ(test_support::self_intersections(side_by_side), 0);
}
