// The weights of a node's map in a set (set_dissector.cpp): which meshes choose them together, and
// when those ask for mean-value weights.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "qs/dissect/dissect_detail.h"

using qs::dissect::detail::joint_weights;
using qs::dissect::detail::wants_mean_value;

namespace {

qs::param::SquareParam map(int flipped, int zero) {
  qs::param::SquareParam sp;
  sp.flipped_faces = flipped;
  sp.zero_area_faces = zero;
  return sp;
}

}  // namespace

// Meshes of one surface decide together: mean-value weights where they unfold a triangle or make
// a squeezed map bijective; a squeeze that both weights leave keeps the cotangent map.
TEST(NodeWeights, MeanValueOnlyWhereItUnfoldsOrMakesBijective) {
  EXPECT_FALSE(wants_mean_value(map(0, 0), map(0, 0), false));    // bijective already
  EXPECT_TRUE(wants_mean_value(map(1, 0), map(0, 0), false));     // a folded triangle, unfolded
  EXPECT_TRUE(wants_mean_value(map(2, 30), map(0, 10), false));   // folded triangles, fewer folds
  EXPECT_FALSE(wants_mean_value(map(1, 0), map(1, 0), false));    // no fewer folds
  EXPECT_FALSE(wants_mean_value(map(1, 0), map(0, 3), false));    // more folds
  EXPECT_TRUE(wants_mean_value(map(0, 1672), map(0, 0), false));  // a squeeze made bijective
  EXPECT_FALSE(wants_mean_value(map(0, 28), map(0, 4), false));   // a squeeze both weights leave
  // One tessellation (a pose of the same face list): mean-value wherever it folds fewer faces.
  EXPECT_TRUE(wants_mean_value(map(0, 28), map(0, 4), true));
  EXPECT_FALSE(wants_mean_value(map(0, 28), map(0, 28), true));
  EXPECT_FALSE(wants_mean_value(map(0, 0), map(0, 0), true));
}

// Together: mesh 0 and the meshes whose landmarks' geodesic distances are within
// kIntrinsicLoopIsometry of its own (one surface in other poses or tessellations); other shapes,
// and a mesh with no partner, choose alone.
TEST(NodeWeights, JointOnlyForOneSurface) {
  using V = std::vector<char>;
  const double iso = qs::dissect::detail::kIntrinsicLoopIsometry;
  EXPECT_EQ(joint_weights({}), V{});                               // not measured (one pose, one mesh)
  EXPECT_EQ(joint_weights({0.0}), V{0});                           // alone
  EXPECT_EQ(joint_weights({0.0, 0.028}), (V{1, 1}));               // a pose pair
  EXPECT_EQ(joint_weights({0.0, iso}), (V{1, 1}));                 // at the bound
  EXPECT_EQ(joint_weights({0.0, 0.189, 0.465}), (V{0, 0, 0}));     // spot, cat, koala
  EXPECT_EQ(joint_weights({0.0, 0.01, 0.3, 0.02}), (V{1, 1, 0, 1}));
  EXPECT_EQ(joint_weights({0.0, INFINITY, NAN}), (V{0, 0, 0}));    // unmeasurable: alone
  EXPECT_EQ(joint_weights({0.0, 1.1 * iso}), (V{0, 0}));
}
