#include "qs/shapes/shapes.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/mesh/validate.h"

namespace qs::shapes {
namespace {

constexpr double kPi = std::numbers::pi;

/// Signed volume about the origin, computed here independently of the library.
double volume_of(const TriMesh& m) {
  double v = 0;
  for (const Tri& t : m.faces)
    v += m.positions[t[0]].dot(m.positions[t[1]].cross(m.positions[t[2]])) / 6.0;
  return v;
}

/// Every face seen from the origin is counter-clockwise: the mesh is star-shaped about the
/// origin and outward-oriented (no face is folded over).
void expect_star_shaped_outward(const TriMesh& m) {
  int bad = 0;
  for (const Tri& t : m.faces)
    if (m.positions[t[0]].dot(m.positions[t[1]].cross(m.positions[t[2]])) <= 0) ++bad;
  EXPECT_EQ(bad, 0);
}

double max_radius(const TriMesh& m) {
  double r = 0;
  for (const Vec3& p : m.positions) r = std::max(r, p.norm());
  return r;
}

double min_radius(const TriMesh& m) {
  double r = 1e300;
  for (const Vec3& p : m.positions) r = std::min(r, p.norm());
  return r;
}

void expect_invalid(auto&& call, const std::string& part) {
  try {
    call();
    ADD_FAILURE() << "expected InvalidInput containing '" << part << "'";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

TEST(Shapes, IcosphereCountsAndRadius) {
  for (int s = 0; s <= 4; ++s) {
    const TriMesh m = icosphere(s);
    const int p = 1 << (2 * s);
    EXPECT_EQ(m.num_faces(), 20 * p);
    EXPECT_EQ(m.num_vertices(), 10 * p + 2);
    EXPECT_NEAR(min_radius(m), 1.0, 1e-12);
    EXPECT_NEAR(max_radius(m), 1.0, 1e-12);
    expect_star_shaped_outward(m);
  }
  // The volume converges to the ball's from below.
  const double v4 = volume_of(icosphere(4)), v5 = volume_of(icosphere(5));
  EXPECT_LT(v4, v5);
  EXPECT_LT(v5, 4.0 / 3.0 * kPi);
  EXPECT_NEAR(v5, 4.0 / 3.0 * kPi, 0.005 * 4.0 / 3.0 * kPi);
}

TEST(Shapes, EllipsoidSatisfiesItsEquation) {
  const double a = 2, b = 1, c = 0.5;
  const TriMesh m = ellipsoid(a, b, c, 3);
  EXPECT_EQ(m.num_faces(), icosphere(3).num_faces());
  for (const Vec3& p : m.positions) {
    const double q = p.x() * p.x() / (a * a) + p.y() * p.y() / (b * b) + p.z() * p.z() / (c * c);
    EXPECT_NEAR(q, 1.0, 1e-12);
  }
  expect_star_shaped_outward(m);
  EXPECT_NEAR(volume_of(m) / volume_of(icosphere(3)), a * b * c, 1e-9);
}

TEST(Shapes, BumpySphereStaysInItsRadiusBand) {
  const double amplitude = 0.3;
  const TriMesh m = bumpy_sphere(amplitude, 6, 4);
  EXPECT_EQ(m.num_faces(), icosphere(4).num_faces());
  EXPECT_GE(min_radius(m), 1 - amplitude - 1e-12);
  EXPECT_LE(max_radius(m), 1 + amplitude + 1e-12);
  EXPECT_GT(max_radius(m) - min_radius(m), amplitude);  // it really is bumpy
  expect_star_shaped_outward(m);
  // Frequency 0 is the unit sphere.
  EXPECT_NEAR(max_radius(bumpy_sphere(0.5, 0, 2)), 1.0, 1e-12);
}

TEST(Shapes, StarBlobHasLongArms) {
  const int arms = 6;
  const double length = 2.0;
  const TriMesh m = star_blob(arms, length, 5);
  expect_star_shaped_outward(m);
  EXPECT_NEAR(min_radius(m), 1.0, 1e-6);
  // Each arm reaches ~1 + length along its direction.
  for (const Vec3& a : fibonacci_directions(arms)) {
    double reach = 0;
    for (const Vec3& p : m.positions) reach = std::max(reach, p.dot(a));
    EXPECT_GT(reach, 1 + 0.9 * length);
    EXPECT_LT(reach, 1 + 1.01 * length);
  }
  // Thin: 30 degrees away from every arm the surface is back near the body.
  int far = 0;
  for (const Vec3& p : m.positions) {
    bool near_arm = false;
    for (const Vec3& a : fibonacci_directions(arms))
      near_arm = near_arm || p.normalized().dot(a) > std::cos(30 * kPi / 180);
    if (near_arm) continue;
    ++far;
    EXPECT_LT(p.norm(), 1.1);
  }
  EXPECT_GT(far, m.num_vertices() / 3);
  EXPECT_EQ(max_radius(star_blob(0, 3.0, 2)), max_radius(icosphere(2)));
}

TEST(Shapes, FibonacciDirectionsAreUnitAndSpread) {
  const std::vector<Vec3> d = fibonacci_directions(50);
  ASSERT_EQ(d.size(), 50u);
  double min_angle = kPi;
  for (std::size_t i = 0; i < d.size(); ++i) {
    EXPECT_NEAR(d[i].norm(), 1.0, 1e-12);
    for (std::size_t j = 0; j < i; ++j) min_angle = std::min(min_angle, std::acos(d[i].dot(d[j])));
  }
  EXPECT_GT(min_angle, 0.5 * std::sqrt(4 * kPi / 50));  // no two bunched together
  EXPECT_TRUE(fibonacci_directions(0).empty());
}

TEST(Shapes, CubeSphereCounts) {
  for (int n : {1, 2, 5, 17}) {
    const TriMesh m = cube_sphere(n);
    EXPECT_EQ(m.num_faces(), 12 * n * n);
    EXPECT_EQ(m.num_vertices(), 6 * n * n + 2);
    EXPECT_NEAR(min_radius(m), 1.0, 1e-12);
    EXPECT_NEAR(max_radius(m), 1.0, 1e-12);
    expect_star_shaped_outward(m);
  }
}

TEST(Shapes, OpenDiskIsAFlatHexagon) {
  for (int rings : {1, 2, 7}) {
    const TriMesh m = open_disk(rings);
    EXPECT_EQ(m.num_faces(), 6 * rings * rings);
    EXPECT_EQ(m.num_vertices(), 3 * rings * (rings + 1) + 1);
    EXPECT_NEAR(max_radius(m), 1.0, 1e-12);
    double area = 0;
    for (const Tri& t : m.faces) {
      const Vec3 n =
          (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]);
      EXPECT_GT(n.z(), 0);  // counter-clockwise seen from +z
      area += 0.5 * n.z();
      for (int v : t) EXPECT_EQ(m.positions[v].z(), 0.0);
    }
    EXPECT_NEAR(area, 1.5 * std::sqrt(3.0), 1e-9);  // regular hexagon of circumradius 1
  }
}

TEST(Shapes, TorusIsOutward) {
  const TriMesh m = torus(64, 32);
  EXPECT_EQ(m.num_faces(), 2 * 64 * 32);
  EXPECT_EQ(m.num_vertices(), 64 * 32);
  const double exact = 2 * kPi * kPi * 1.0 * 0.4 * 0.4;
  EXPECT_NEAR(volume_of(m), exact, 0.02 * exact);
}

TEST(Shapes, TwoComponentsAndFan) {
  const TriMesh two = two_components();
  EXPECT_EQ(two.num_faces(), 160);
  EXPECT_EQ(two.num_vertices(), 84);
  EXPECT_NEAR(volume_of(two), 2 * volume_of(icosphere(1)), 1e-9);
  const TriMesh fan = nonmanifold_fan();
  EXPECT_EQ(fan.num_faces(), 5);
  EXPECT_EQ(fan.num_vertices(), 5);
  TriMesh tet = fan;
  tet.faces.pop_back();
  EXPECT_GT(volume_of(tet), 0);
}

TEST(Shapes, AreDeterministic) {
  EXPECT_EQ(icosphere(3).faces, icosphere(3).faces);
  EXPECT_EQ(icosphere(3).positions, icosphere(3).positions);
  EXPECT_EQ(star_blob(7, 1.5, 3).positions, star_blob(7, 1.5, 3).positions);
  EXPECT_EQ(cube_sphere(4).faces, cube_sphere(4).faces);
  EXPECT_EQ(bumpy_sphere(0.2, 5, 3).positions, bumpy_sphere(0.2, 5, 3).positions);
}

TEST(Shapes, InvalidArgumentsThrow) {
  expect_invalid([] { icosphere(-1); }, "icosphere: subdivisions = -1 is outside [0, 9]");
  expect_invalid([] { icosphere(10); }, "icosphere");
  expect_invalid([] { ellipsoid(1, 0, 1, 1); }, "ellipsoid");
  expect_invalid([] { ellipsoid(1, NAN, 1, 1); }, "ellipsoid");
  expect_invalid([] { bumpy_sphere(1.0, 3, 1); }, "bumpy_sphere: amplitude");
  expect_invalid([] { bumpy_sphere(0.1, -3, 1); }, "frequency");
  expect_invalid([] { star_blob(-1, 1, 1); }, "star_blob: arms");
  expect_invalid([] { star_blob(3, -1, 1); }, "arm_length");
  expect_invalid([] { cube_sphere(0); }, "cube_sphere: n = 0");
  expect_invalid([] { open_disk(0); }, "open_disk");
  expect_invalid([] { torus(2, 5); }, "torus: major");
  expect_invalid([] { torus(5, 2); }, "torus: minor");
  expect_invalid([] { displaced_sphere([](const Vec3&) { return -1.0; }, 1); }, "displaced_sphere");
  expect_invalid([] { displaced_sphere(nullptr, 1); }, "displaced_sphere");
}

}  // namespace
}  // namespace qs::shapes
