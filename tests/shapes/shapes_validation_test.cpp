// Every shape generator passes or fails qs::mesh::validate() the way its header says.

#include <gtest/gtest.h>

#include <string>

#include "qs/mesh/validate.h"
#include "qs/shapes/shapes.h"

namespace qs::shapes {
namespace {

using mesh::find_problem;
using mesh::format_report;
using mesh::Severity;
using mesh::validate;
using mesh::ValidationReport;

bool has_fatal(const ValidationReport& r) {
  for (const auto& p : r.problems)
    if (p.severity == Severity::Fatal) return true;
  return false;
}

void expect_accepted_sphere(const TriMesh& m, const char* name) {
  const ValidationReport r = validate(m).report;
  EXPECT_TRUE(r.accepted) << format_report(name, r);
  EXPECT_FALSE(has_fatal(r));
  EXPECT_EQ(r.genus, 0) << name;
  EXPECT_EQ(r.components, 1) << name;
  EXPECT_EQ(r.euler_characteristic, 2) << name;
  EXPECT_FALSE(r.orientation_flipped) << name;  // built outward
  EXPECT_GT(r.signed_volume, 0) << name;
  EXPECT_TRUE(r.boundary_loop_sizes.empty()) << name;
  EXPECT_EQ(find_problem(r, "unreferenced_vertices"), nullptr) << name;
  EXPECT_EQ(find_problem(r, "zero_area_faces"), nullptr) << name;
}

TEST(ShapesValidation, ClosedShapesAreAcceptedGenusZero) {
  for (int s = 0; s <= 4; ++s) expect_accepted_sphere(icosphere(s), "icosphere");
  expect_accepted_sphere(ellipsoid(3, 1, 0.2, 3), "ellipsoid");
  expect_accepted_sphere(bumpy_sphere(0.4, 7, 4), "bumpy_sphere");
  expect_accepted_sphere(star_blob(8, 2.5, 4), "star_blob");
  expect_accepted_sphere(star_blob(1, 4.0, 3), "star_blob 1 arm");
  for (int n : {1, 3, 10}) expect_accepted_sphere(cube_sphere(n), "cube_sphere");
}

TEST(ShapesValidation, SmoothShapesHaveNoTinyAngles) {
  for (const TriMesh& m : {icosphere(3), cube_sphere(8), bumpy_sphere(0.3, 4, 4)}) {
    const ValidationReport r = validate(m).report;
    EXPECT_EQ(find_problem(r, "tiny_angles"), nullptr) << format_report("m", r);
    EXPECT_GT(r.min_angle_degrees, 20);
  }
}

TEST(ShapesValidation, OpenDiskHasOneBoundaryLoop) {
  for (int rings : {1, 4}) {
    const ValidationReport r = validate(open_disk(rings)).report;
    EXPECT_FALSE(r.accepted);
    ASSERT_NE(find_problem(r, "boundary_edges"), nullptr);
    EXPECT_EQ(find_problem(r, "boundary_edges")->count, 6 * rings);
    EXPECT_EQ(r.boundary_loop_sizes, std::vector<int>{6 * rings});
    EXPECT_EQ(r.euler_characteristic, 1);
    EXPECT_EQ(r.genus, -1);
    EXPECT_EQ(r.problems.size(), 1u) << format_report("disk", r);
  }
}

TEST(ShapesValidation, TorusIsRejectedAsGenusOne) {
  const ValidationReport r = validate(torus(24, 12)).report;
  EXPECT_FALSE(r.accepted);
  EXPECT_EQ(r.genus, 1);
  ASSERT_NE(find_problem(r, "genus"), nullptr);
  EXPECT_EQ(r.problems.size(), 1u) << format_report("torus", r);
  EXPECT_NE(format_report("torus", r).find("rejected: genus"), std::string::npos);
}

TEST(ShapesValidation, TwoComponentsAreRejected) {
  const ValidationReport r = validate(two_components()).report;
  EXPECT_FALSE(r.accepted);
  EXPECT_EQ(r.components, 2);
  ASSERT_NE(find_problem(r, "multiple_components"), nullptr);
  EXPECT_EQ(find_problem(r, "multiple_components")->first_ids, (std::vector<long long>{0, 80}));
  EXPECT_EQ(find_problem(r, "genus"), nullptr);  // each part is a sphere
  EXPECT_EQ(r.problems.size(), 1u) << format_report("two", r);
}

TEST(ShapesValidation, NonManifoldFanIsRejected) {
  const ValidationReport r = validate(nonmanifold_fan()).report;
  EXPECT_FALSE(r.accepted);
  const mesh::Problem* p = find_problem(r, "non_manifold_edges");
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->count, 1);
  EXPECT_EQ(p->first_ids, (std::vector<long long>{0, 1}));
  ASSERT_NE(find_problem(r, "boundary_edges"), nullptr);
  EXPECT_EQ(find_problem(r, "boundary_edges")->first_ids, (std::vector<long long>{0, 4, 1, 4}));
}

}  // namespace
}  // namespace qs::shapes
