// ValidateOptions::allow_any_genus (qs-dfi): genus reported as a Note, everything else unchanged.
#include <gtest/gtest.h>

#include "qs/mesh/validate.h"
#include "qs/shapes/shapes.h"

using namespace qs;

TEST(ValidateAnyGenus, TorusIsAcceptedWithItsGenusReportedOnlyWhenAsked) {
  const TriMesh torus = shapes::torus(16, 8);
  const auto strict = mesh::validate(torus);
  EXPECT_FALSE(strict.report.accepted);
  ASSERT_NE(mesh::find_problem(strict.report, "genus"), nullptr);
  EXPECT_EQ(mesh::find_problem(strict.report, "genus")->severity, mesh::Severity::Fatal);

  mesh::ValidateOptions any;
  any.allow_any_genus = true;
  const auto loose = mesh::validate(torus, any);
  EXPECT_TRUE(loose.report.accepted);
  EXPECT_EQ(loose.report.genus, 1);
  const mesh::Problem* g = mesh::find_problem(loose.report, "genus");
  ASSERT_NE(g, nullptr);
  EXPECT_EQ(g->severity, mesh::Severity::Note);
  EXPECT_NE(g->message.find("genus 1"), std::string::npos);
}

TEST(ValidateAnyGenus, OtherProblemsStillReject) {
  mesh::ValidateOptions any;
  any.allow_any_genus = true;
  EXPECT_FALSE(mesh::validate(shapes::open_disk(3), any).report.accepted);
  EXPECT_FALSE(mesh::validate(shapes::two_components(), any).report.accepted);
  EXPECT_FALSE(mesh::validate(shapes::nonmanifold_fan(), any).report.accepted);
}
