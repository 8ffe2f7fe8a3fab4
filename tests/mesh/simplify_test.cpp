// Coarser tessellations by edge collapses: still a valid sphere, near the input, no slivers, the
// face count asked for, deterministic.
#include "qs/mesh/simplify.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "qs/mesh/validate.h"
#include "qs/metro/metro.h"
#include "qs/shapes/shapes.h"

namespace qs::mesh {
namespace {

double quality(const TriMesh& m, const Tri& t) {
  const Vec3 a = m.positions[t[0]], b = m.positions[t[1]], c = m.positions[t[2]];
  const double e = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  return 2 * std::sqrt(3.0) * (b - a).cross(c - a).norm() / e;
}

TEST(Simplify, KeepsAThinArmedSphereValidCloseAndWithoutSlivers) {
  const TriMesh input = shapes::star_blob(6, 1.5, 5);  // 20480 faces, six thin arms
  const TriMesh out = simplify(input, 2000);
  EXPECT_GE(out.num_faces(), 2000);
  EXPECT_LE(out.num_faces(), 2100);
  const ValidationResult v = validate(out);
  EXPECT_TRUE(v.report.accepted);
  EXPECT_FALSE(v.report.orientation_flipped);
  EXPECT_EQ(v.report.genus, 0);
  EXPECT_EQ(find_problem(v.report, "zero_area_faces"), nullptr);
  // Near the input: every coarse vertex (measured: max 1.4%, mean 0.04% of the diagonal).
  const metro::SurfaceDistance on_input(input, "input");
  const double diag = bounding_box(input.positions).diagonal();
  double worst = 0, sum = 0;
  for (const Vec3& p : out.positions) {
    const double d = on_input.distance(p) / diag;
    worst = std::max(worst, d);
    sum += d;
  }
  EXPECT_LT(worst, 0.02);
  EXPECT_LT(sum / out.num_vertices(), 0.001);
  // No sliver that the input did not have (measured: the worst face 0.20).
  double worst_quality = 1;
  for (const Tri& t : out.faces) worst_quality = std::min(worst_quality, quality(out, t));
  EXPECT_GT(worst_quality, 0.15);
  // The same output twice.
  const TriMesh again = simplify(input, 2000);
  EXPECT_EQ(again.positions, out.positions);
  EXPECT_EQ(again.faces, out.faces);
}

TEST(Simplify, StopsAtATetrahedronAndKeepsASmallerTarget) {
  const TriMesh input = shapes::icosphere(2);  // 320 faces
  const TriMesh out = simplify(input, 1);
  EXPECT_GE(out.num_faces(), 4);
  EXPECT_TRUE(validate(out).report.accepted);
  const TriMesh same = simplify(input, 1000);  // already below the target
  EXPECT_EQ(same.faces, input.faces);
  EXPECT_EQ(same.positions, input.positions);
}

}  // namespace
}  // namespace qs::mesh
