// The inner corners of a quinary split placed one by one (DissectOptions::same_pose).
#include <gtest/gtest.h>

#include <array>

#include "qs/dissect/dissect_detail.h"

namespace {

using qs::Vec2;
using qs::dissect::detail::inner_quad_ok;

std::array<Vec2, 4> standard(const Vec2& peak, double w) { return qs::dissect::detail::inner_corners(peak, w); }

}  // namespace

TEST(InnerQuad, EveryStandardSplitIsAccepted) {
  for (double w : {0.5, 0.6, 0.65})
    for (double x : {0.35, 0.5, 0.65})
      for (double y : {0.35, 0.5, 0.65}) EXPECT_TRUE(inner_quad_ok(standard(Vec2(x, y), w), 0.03)) << w << " " << x << " " << y;
}

TEST(InnerQuad, AGeneralConvexQuadIsAcceptedWithinTheMargin) {
  const std::array<Vec2, 4> q{Vec2(0.2, 0.3), Vec2(0.7, 0.15), Vec2(0.8, 0.8), Vec2(0.25, 0.6)};
  EXPECT_TRUE(inner_quad_ok(q, 0.03));
  EXPECT_FALSE(inner_quad_ok(q, 0.2));  // a corner 0.15 from the side
}

TEST(InnerQuad, FoldedCrossingOrDegenerateQuadsAreRejected) {
  // Clockwise (the corners in the wrong order).
  EXPECT_FALSE(inner_quad_ok({Vec2(0.3, 0.3), Vec2(0.3, 0.7), Vec2(0.7, 0.7), Vec2(0.7, 0.3)}, 0.03));
  // Not convex (corner 2 pushed inside).
  EXPECT_FALSE(inner_quad_ok({Vec2(0.3, 0.3), Vec2(0.7, 0.3), Vec2(0.4, 0.4), Vec2(0.3, 0.7)}, 0.03));
  // All four on one side of the square (posed corners that fell on the node's border).
  EXPECT_FALSE(inner_quad_ok({Vec2(0.35, 0), Vec2(0.6, 0), Vec2(0.62, 0), Vec2(0.5, 0)}, 0.0));
  // Convex and counter-clockwise, but turned half a turn: each outer cut crosses the quad.
  EXPECT_FALSE(inner_quad_ok({Vec2(0.7, 0.7), Vec2(0.3, 0.7), Vec2(0.3, 0.3), Vec2(0.7, 0.3)}, 0.03));
  // Outside the square.
  EXPECT_FALSE(inner_quad_ok({Vec2(-0.1, 0.3), Vec2(0.7, 0.3), Vec2(0.7, 0.7), Vec2(0.3, 0.7)}, 0.0));
}
