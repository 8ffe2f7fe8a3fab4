// The correspondence stages on small generated inputs: a capsule's skeleton, matching a generated
// pair, anchors, harmonic fields, transport with a known answer, the warp and its fold check.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "qs/core/error.h"
#include "qs/dfi/harmonic.h"
#include "qs/dfi/matching.h"
#include "qs/dfi/pipeline.h"
#include "qs/dfi/sdf.h"
#include "qs/dfi/skeleton.h"
#include "qs/dfi/transport.h"
#include "qs/dfi/warp.h"
#include "qs/shapes/shapes.h"
#include "test_meshes.h"

using namespace qs;
using namespace qs::dfi;

namespace {

// A capsule along x: a cylinder of radius r between x = -h and x = h with hemispherical caps.
TriMesh capsule(double h, double r) {
  return shapes::displaced_sphere(
      [h, r](const Vec3& d) {
        // Ray from the origin along d to the capsule surface: solve |p - clamp(p.x)| = r.
        double lo = 0, hi = h + r;
        for (int it = 0; it < 60; ++it) {
          const double t = 0.5 * (lo + hi);
          const Vec3 p = t * d;
          const double cx = std::clamp(p.x(), -h, h);
          ((p - Vec3(cx, 0, 0)).norm() < r ? lo : hi) = t;
        }
        return lo;
      },
      4);
}

}  // namespace

TEST(Skeleton, CapsuleSkeletonIsAPathAlongItsAxis) {
  const TriMesh m = capsule(1.0, 0.3);
  Skeleton s = curve_skeleton(m);
  prune_skeleton(s, 0.08 * bounding_box(m.positions).diagonal());
  ASSERT_GE(s.nodes.size(), 3u);
  for (const Vec3& p : s.nodes) {
    EXPECT_LT(std::hypot(p.y(), p.z()), 0.1) << p.transpose();  // on the axis
    EXPECT_LT(std::abs(p.x()), 1.3);
  }
  const std::vector<int> deg = node_degrees(s);
  EXPECT_EQ(std::count(deg.begin(), deg.end(), 1), 2);  // two terminals, no junction
  EXPECT_EQ(std::count_if(deg.begin(), deg.end(), [](int d) { return d >= 3; }), 0);
  const std::vector<Branch> b = skeleton_branches(s);
  ASSERT_EQ(b.size(), 1u);
  EXPECT_GT(b[0].length, 1.2);  // most of the axis
  EXPECT_NEAR(b[0].at(s, 0.5).x(), 0.0, 0.15);
}

TEST(Skeleton, SameMeshSameSkeletonWhateverWasAllocatedBefore) {
  const TriMesh m = capsule(1.0, 0.3);
  const Skeleton a = curve_skeleton(m);
  std::vector<std::unique_ptr<std::vector<double>>> clutter;  // change the heap between the calls
  for (int i = 0; i < 2000; ++i) clutter.push_back(std::make_unique<std::vector<double>>(1 + i % 37));
  for (int i = 0; i < 2000; i += 3) clutter[i].reset();
  const Skeleton b = curve_skeleton(m);
  ASSERT_EQ(a.nodes.size(), b.nodes.size());
  EXPECT_EQ(a.edges, b.edges);
  for (size_t i = 0; i < a.nodes.size(); ++i) EXPECT_EQ(a.nodes[i], b.nodes[i]) << i;
}

TEST(Skeleton, TorusSkeletonIsACycle) {
  const Skeleton s = curve_skeleton(shapes::torus(64, 16));
  const std::vector<int> deg = node_degrees(s);
  EXPECT_EQ(std::count(deg.begin(), deg.end(), 1), 0);  // no terminal on a ring
  EXPECT_GE(s.edges.size(), s.nodes.size());            // a cycle: at least as many edges as nodes
  for (const Vec3& p : s.nodes) EXPECT_NEAR(std::hypot(p.x(), p.y()), 1.0, 0.1);
}

TEST(Matching, GeneratedPairMatchesEndsAndTheBranch) {
  const TriMesh a = capsule(1.0, 0.3);
  TriMesh b = capsule(1.3, 0.25);  // longer and thinner, same structure
  Skeleton s0 = curve_skeleton(a), s1 = curve_skeleton(b);
  prune_skeleton(s0, 0.2);
  prune_skeleton(s1, 0.2);
  const auto b0 = skeleton_branches(s0), b1 = skeleton_branches(s1);
  const SkeletonMatching m = match_skeletons(s0, b0, s1, b1, {}, bounding_box(a.positions).diagonal());
  ASSERT_EQ(m.nodes.size(), 2u);
  for (const NodePair& p : m.nodes) EXPECT_GT(s0.nodes[p.source].x() * s1.nodes[p.target].x(), 0);  // same side
  ASSERT_EQ(m.branches.size(), 1u);
  const auto anchors = sample_anchors(s0, b0, s1, b1, m, 3);
  EXPECT_EQ(anchors.size(), 5u);  // 2 ends + 3 inside
  for (const AnchorPair& p : anchors) EXPECT_GT(p.source.x() * p.target.x(), -1e-3);

  // A forced pair wins over the nearest-first rule: the source's +x end with the target's -x end.
  int plus = -1, minus = -1;
  for (const NodePair& p : m.nodes) {
    if (s0.nodes[p.source].x() > 0) plus = p.source;
    if (s1.nodes[p.target].x() < 0) minus = p.target;
  }
  const SkeletonMatching f = match_skeletons(s0, b0, s1, b1, {{plus, minus, true, "tip"}}, 1.0);
  ASSERT_GE(f.nodes.size(), 1u);
  EXPECT_EQ(f.nodes[0].source, plus);
  EXPECT_EQ(f.nodes[0].target, minus);
  EXPECT_TRUE(f.nodes[0].forced);
}

TEST(Transport, OneDimensionalProblemHasTheSortedMatching) {
  // Points on a line with cost |x - y|: the optimum maps sorted to sorted (monotone).
  const std::vector<double> xs{0.3, 2.0, 1.1, 5.0}, ys{4.0, 0.0, 2.2, 1.0};
  Eigen::MatrixXd c(4, 4);
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) c(i, j) = std::abs(xs[i] - ys[j]);
  const TransportResult r = solve_transport(c);
  ASSERT_EQ(r.flows.size(), 4u);
  const int expect[4] = {1, 2, 3, 0};  // 0.3->0.0, 2.0->2.2, 1.1->1.0, 5.0->4.0
  for (const Flow& f : r.flows) {
    EXPECT_EQ(f.to, expect[f.from]);
    EXPECT_NEAR(f.mass, 0.25, 1e-12);
  }
  EXPECT_NEAR(r.cost, (0.3 + 0.2 + 0.1 + 1.0) / 4, 1e-9);
}

TEST(Transport, UnequalSizesSplitMassAndMeetTheMarginals) {
  Eigen::MatrixXd c(2, 3);
  c << 0, 1, 2,  //
      2, 1, 0;
  const TransportResult r = solve_transport(c);
  std::vector<double> row(2, 0), col(3, 0);
  for (const Flow& f : r.flows) {
    row[f.from] += f.mass;
    col[f.to] += f.mass;
  }
  for (double m : row) EXPECT_NEAR(m, 0.5, 1e-12);
  for (double m : col) EXPECT_NEAR(m, 1.0 / 3, 1e-12);
  EXPECT_NEAR(r.cost, 1.0 / 3, 1e-9);  // the middle item costs 1 from either side, the others 0
  EXPECT_THROW(solve_transport(Eigen::MatrixXd(0, 3)), InvalidInput);
}

TEST(Harmonic, FieldsAreOneAtTheirAnchorZeroAtOthersAndBetweenElsewhere) {
  const Grid sdf = test_support::analytic_grid(1.5, 20, [](const Vec3& p) {
    return std::max(std::abs(p.x()) - 1.2, std::max(std::abs(p.y()), std::abs(p.z())) - 0.3);  // a bar
  });
  Box3 box{sdf.origin, sdf.origin + sdf.spacing * Vec3(sdf.dims[0] - 1, sdf.dims[1] - 1, sdf.dims[2] - 1)};
  const VoxelSet v = interior_voxels(sdf, grid_over(box, 20, 1));
  ASSERT_GT(v.sample.size(), 20u);
  const int left = nearest_voxel(v, Vec3(-1.1, 0, 0)), right = nearest_voxel(v, Vec3(1.1, 0, 0));
  const Eigen::MatrixXd h = harmonic_fields(v, {left, right});
  EXPECT_DOUBLE_EQ(h(left, 0), 1.0);
  EXPECT_DOUBLE_EQ(h(right, 0), 0.0);
  for (int i = 0; i < h.rows(); ++i) {
    EXPECT_GE(h(i, 0), -1e-9);
    EXPECT_LE(h(i, 0), 1 + 1e-9);
    EXPECT_NEAR(h(i, 0) + h(i, 1), 1.0, 1e-6);  // the two fields partition unity on a connected bar
  }
  // Monotone along the bar.
  EXPECT_GT(h(nearest_voxel(v, Vec3(-0.5, 0, 0)), 0), h(nearest_voxel(v, Vec3(0.5, 0, 0)), 0));
  EXPECT_THROW(harmonic_fields(v, {left, left}), InvalidInput);
}

TEST(Warp, TranslationWarpMovesTheFieldAndDoesNotFold) {
  const Grid sdf = test_support::analytic_grid(2.0, 24, [](const Vec3& p) { return test_support::sphere_sd(p, Vec3::Zero(), 0.6); });
  Box3 box{sdf.origin, sdf.origin + sdf.spacing * Vec3(sdf.dims[0] - 1, sdf.dims[1] - 1, sdf.dims[2] - 1)};
  const VoxelSet v = interior_voxels(sdf, grid_over(box, 16, 1));
  std::vector<Vec3> dest;
  for (int i = 0; i < static_cast<int>(v.sample.size()); ++i) dest.push_back(v.position(i) + Vec3(0.5, 0, 0));
  Displacement d = extend_displacement(v, dest);
  EXPECT_NEAR(d.at(Vec3(1.5, 1.5, 0)).x(), 0.5, 1e-3);  // a constant field extends as a constant
  const FoldCheck f = remove_folds(d);
  EXPECT_NEAR(f.min_det, 1.0, 1e-3);
  EXPECT_EQ(f.smoothing_steps, 0);
  const Grid moved = warped_field(sdf, d, 1.0);
  EXPECT_NEAR(moved.sample(Vec3(0.5, 0, 0)), -0.6, 0.02);  // the sphere's centre moved by +0.5 x
  EXPECT_NEAR(moved.sample(Vec3(1.1, 0, 0)), 0.0, 0.02);
}

TEST(Warp, AFoldingFieldIsSmoothedUntilItNoLongerFolds) {
  const Grid sdf = test_support::analytic_grid(2.0, 16, [](const Vec3& p) { return test_support::sphere_sd(p, Vec3::Zero(), 1.0); });
  Box3 box{sdf.origin, sdf.origin + sdf.spacing * Vec3(sdf.dims[0] - 1, sdf.dims[1] - 1, sdf.dims[2] - 1)};
  const VoxelSet v = interior_voxels(sdf, grid_over(box, 12, 1));
  std::vector<Vec3> dest;  // mirror x: every interior voxel swaps sides, a fold for s near 0.5
  for (int i = 0; i < static_cast<int>(v.sample.size()); ++i) {
    const Vec3 p = v.position(i);
    dest.push_back(Vec3(-p.x(), p.y(), p.z()));
  }
  Displacement d = extend_displacement(v, dest);
  EXPECT_LE(check_folds(d).min_det, 0);
  const FoldCheck f = remove_folds(d);
  EXPECT_GT(f.min_det, 0);
  EXPECT_GT(f.smoothing_steps, 0);
}

TEST(Pipeline, WarpedMorphOfAGeneratedPairKeepsClosedFramesAndExactEnds) {
  const TriMesh a = capsule(1.0, 0.35);
  TriMesh b = shapes::ellipsoid(1.4, 0.5, 0.4, 3);
  MorphOptions opt;
  opt.grid = 32;
  opt.emd_voxels = 300;
  const PreparedMorph m = prepare_morph(a, b, opt);
  EXPECT_TRUE(m.warp);
  EXPECT_GE(m.anchors.size(), 2u);
  EXPECT_GT(m.source_folds.min_det, 0);
  EXPECT_GT(m.target_folds.min_det, 0);
  EXPECT_FALSE(m.bones.empty());  // one matched branch: the part warp
  EXPECT_GT(m.bone_min_det, 0);
  EXPECT_EQ(blend_field(m, 0.0).values, m.source_sdf.values);  // the ends are the inputs' fields
  for (double t : {0.0, 0.5, 1.0}) {
    const MeshStats s = mesh_stats(frame_mesh(m, blend_field(m, t), t));
    EXPECT_TRUE(s.closed_manifold) << t;
    EXPECT_EQ(s.components, 1) << t;
    EXPECT_EQ(s.genus, 0) << t;
  }
  // Same fields on one thread or two.
  EXPECT_EQ(blend_field(m, 0.5, 1).values, blend_field(m, 0.5, 2).values);
  MorphOptions global = opt;
  global.part_transport = false;
  EXPECT_EQ(prepare_morph(a, b, global).parts, 1);
}
