// Topology control (topology.h): the simple-point test on the polygonizer's 14-neighbour lattice
// and make_ball on small analytic fields: a thin handle is cut (one closed genus-0 surface, no
// self-intersections), a ball is left exactly as it is, a second piece and a cavity go.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "qs/core/error.h"
#include "qs/dfi/pipeline.h"
#include "qs/dfi/topology.h"
#include "qs/mesh/validate.h"
#include "qs/metro/metro.h"
#include "qs/shapes/shapes.h"
#include "test_meshes.h"

using namespace qs;
using namespace qs::dfi;
using test_support::analytic_grid;

namespace {

int bit(int dx, int dy, int dz) {
  for (int n = 0; n < 14; ++n)
    if (kNeighbours14[n][0] == dx && kNeighbours14[n][1] == dy && kNeighbours14[n][2] == dz) return n;
  return -1;
}

// One closed, oriented, manifold genus-0 piece without self-intersections (qs::mesh::validate
// checks the vertex fans too).
void expect_sphere(const TriMesh& m, const char* what) {
  const MeshStats s = mesh_stats(m);
  EXPECT_TRUE(s.closed_manifold) << what;
  EXPECT_EQ(s.components, 1) << what;
  EXPECT_EQ(s.genus, 0) << what;
  EXPECT_GT(s.volume, 0) << what;
  const auto v = mesh::validate(m);
  EXPECT_TRUE(v.report.accepted) << what << ": " << mesh::format_report(what, v.report);
  EXPECT_EQ(test_support::self_intersections(m), 0) << what;
}

// A ball with a thin ring through it: the ring's arc outside the ball is a handle (genus 1).
double ball_with_handle(const Vec3& p) {
  const Vec3 q = p - Vec3(0.8, 0, 0);
  return std::min(test_support::sphere_sd(p, Vec3::Zero(), 0.6), test_support::torus_sd(q, 0.7, 0.09));
}

}  // namespace

TEST(SimplePoint, TheLinkTestOnThe14Lattice) {
  const unsigned all = (1u << 14) - 1;
  EXPECT_FALSE(is_simple_14(0));    // an isolated sample would be a new component
  EXPECT_FALSE(is_simple_14(all));  // a sample enclosed by the set would fill a cavity of one sample
  for (int n = 0; n < 14; ++n) EXPECT_TRUE(is_simple_14(1u << n)) << n;  // one neighbour: a bump
  // Two opposite neighbours (not joined in the link): adding the sample would join two pieces or
  // close a loop.
  EXPECT_FALSE(is_simple_14(1u << bit(1, 0, 0) | 1u << bit(-1, 0, 0)));
  // (1,0,0) and (1,1,0) are neighbours of each other: one piece, simple.
  EXPECT_TRUE(is_simple_14(1u << bit(1, 0, 0) | 1u << bit(1, 1, 0)));
  // (1,0,0) and (0,1,0) are not joined on this lattice (their difference (-1,1,0) is no edge of
  // the Kuhn tetrahedra), unlike in the 26-neighbourhood: two pieces, not simple.
  EXPECT_FALSE(is_simple_14(1u << bit(1, 0, 0) | 1u << bit(0, 1, 0)));
  // Symmetry of the test: S and its complement change roles.
  for (unsigned m = 0; m <= all; m += 37) EXPECT_EQ(is_simple_14(m), is_simple_14(all & ~m)) << m;
}

TEST(MakeBall, ABallIsLeftExactlyAsItIs) {
  Grid g = analytic_grid(1.5, 30, [](const Vec3& p) { return test_support::sphere_sd(p, Vec3(0.05, -0.02, 0.03), 1.0); });
  const Grid before = g;
  const BallReport r = make_ball(g);
  EXPECT_GT(r.inside, 1000u);
  EXPECT_EQ(r.removed, 0u);
  EXPECT_EQ(r.components_removed, 0u);
  EXPECT_EQ(g.values, before.values);
}

TEST(MakeBall, AThinHandleIsCutToOneGenusZeroSurface) {
  Grid g = analytic_grid(1.7, 48, ball_with_handle);
  const MeshStats raw = mesh_stats(polygonize(g));
  ASSERT_EQ(raw.genus, 1);  // the field as given has the handle
  ASSERT_EQ(raw.components, 1);
  const BallReport r = make_ball(g);
  EXPECT_GT(r.removed, 0u);
  EXPECT_LT(r.removed, r.inside / 20);  // a cut through the handle, not the handle
  EXPECT_EQ(r.components_removed, 0u);
  const TriMesh m = polygonize(g);
  expect_sphere(m, "ball with a cut handle");
  // What is left out lies on the handle (outside the ball), where the field is highest: the
  // volume is almost all kept.
  EXPECT_GT(mesh_stats(m).volume, 0.9 * raw.volume);
  // Deterministic: the same field gives the same result.
  Grid again = analytic_grid(1.7, 48, ball_with_handle);
  make_ball(again);
  EXPECT_EQ(again.values, g.values);
}

TEST(MakeBall, ASecondPieceGoesAndTheDeeperOneStays) {
  Grid g = analytic_grid(1.5, 32, [](const Vec3& p) {
    return std::min(test_support::sphere_sd(p, Vec3(-0.6, 0, 0), 0.5), test_support::sphere_sd(p, Vec3(0.7, 0, 0), 0.3));
  });
  ASSERT_EQ(mesh_stats(polygonize(g)).components, 2);
  const BallReport r = make_ball(g);
  EXPECT_EQ(r.components_removed, 1u);
  const TriMesh m = polygonize(g);
  expect_sphere(m, "two balls");
  for (const Vec3& p : m.positions) EXPECT_LT(p.x(), 0.1);  // the bigger (deeper) ball is the one kept
}

TEST(MakeBall, AHollowShellIsOpenedToOneSphere) {
  Grid g = analytic_grid(1.2, 32, [](const Vec3& p) {
    return std::max(test_support::sphere_sd(p, Vec3::Zero(), 0.9), -test_support::sphere_sd(p, Vec3::Zero(), 0.45));
  });
  ASSERT_EQ(mesh_stats(polygonize(g)).components, 2);  // outer and inner wall
  const BallReport r = make_ball(g);
  EXPECT_GT(r.removed, 0u);
  expect_sphere(polygonize(g), "hollow shell");
}

TEST(MakeBall, RejectsAnOutsideValueBelowTheSnapTolerance) {
  Grid g = analytic_grid(1.5, 12, [](const Vec3& p) { return test_support::sphere_sd(p, Vec3::Zero(), 1.0); });
  BallOptions o;
  o.outside_value = 0;
  try {
    make_ball(g, o);
    FAIL() << "expected InvalidInput";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("snap tolerance"), std::string::npos) << e.what();
  }
}

// In a morph: the control runs on the frames when both inputs are genus 0, on the genus-0 end
// alone otherwise, and not at all when switched off.
TEST(MakeBall, MorphFramesAreControlledOnlyWhereTheInputsAreGenusZero) {
  TriMesh sphere = shapes::icosphere(3), torus = shapes::torus(48, 16);
  MorphOptions opt;
  opt.grid = 24;
  opt.warp = false;
  const PreparedMorph st = prepare_morph(sphere, torus, opt);
  EXPECT_EQ(st.source_genus, 0);
  EXPECT_EQ(st.target_genus, 1);
  EXPECT_TRUE(controls_topology(st, 0.0));
  EXPECT_FALSE(controls_topology(st, 0.5));
  EXPECT_FALSE(controls_topology(st, 1.0));
  TriMesh other = shapes::icosphere(3);
  for (Vec3& p : other.positions) p = Vec3(1.3 * p.x(), 0.8 * p.y(), p.z());
  const PreparedMorph ss = prepare_morph(sphere, other, opt);
  for (double t : {0.0, 0.5, 1.0}) {
    EXPECT_TRUE(controls_topology(ss, t)) << t;
    BlendInfo info;
    const Grid f = blend_field(ss, t, 1, &info);
    EXPECT_TRUE(info.topology_controlled) << t;
    EXPECT_EQ(info.ball.removed, 0u) << t;  // nothing to cut between two balls
    expect_sphere(frame_mesh(ss, f, t), "sphere to ellipsoid");
  }
  opt.topology_control = false;
  const PreparedMorph off = prepare_morph(sphere, other, opt);
  EXPECT_FALSE(controls_topology(off, 0.5));
}

// An end frame from the input's own field on a finer grid: a plate thinner than a voxel touches
// itself across samples and shows handles the input does not have; with the control (the input is
// genus 0) the frame is one genus-0 piece again, and still within a voxel of the input.
TEST(MakeBall, AnEndFrameCarriesItsGenusZeroInputsGenus) {
  TriMesh plate = shapes::ellipsoid(1.0, 0.8, 0.05, 4);
  for (Vec3& p : plate.positions) p = Eigen::AngleAxisd(0.5, Vec3(1, 1, 0).normalized()) * p;  // off the grid's planes
  const TriMesh ball = shapes::icosphere(3);
  MorphOptions opt;
  opt.grid = 20;
  opt.warp = false;
  opt.topology_control = false;
  const PreparedMorph off = prepare_morph(plate, ball, opt);
  const MeshStats raw = mesh_stats(endpoint_frame(off, plate, false, 2));
  EXPECT_TRUE(raw.genus > 0 || raw.components > 1) << "the test needs a plate the sampling breaks";
  opt.topology_control = true;
  const PreparedMorph on = prepare_morph(plate, ball, opt);
  BallReport report;
  const TriMesh end = endpoint_frame(on, plate, false, 2, {}, {}, &report);
  EXPECT_GT(report.removed, 0u);
  expect_sphere(end, "plate end frame");
  EXPECT_LT(metro::metro(end, plate).max, on.spacing());
}
