// The rotation-aware part warp (bones.h), its Newton inversion, and the matching of terminal
// branches whose junction ends differ.
#include <gtest/gtest.h>

#include <cmath>

#include "qs/dfi/bones.h"
#include "qs/dfi/matching.h"
#include "qs/dfi/skeleton.h"
#include "qs/dfi/warp.h"
#include "test_meshes.h"

using namespace qs;
using namespace qs::dfi;

namespace {

// A bone from (0,0,0)-(1,0,0) to (0,0,0)-(0,1,0): the same length, turned by 90 degrees about z.
Bone quarter_turn() {
  Bone b;
  b.from_a = Vec3(0, 0, 0);
  b.from_b = Vec3(1, 0, 0);
  b.to_a = Vec3(0, 0, 0);
  b.to_b = Vec3(0, 1, 0);
  b.radius = 0.2;
  b.radial_scale = 1;
  return b;
}

}  // namespace

TEST(Bones, InterpolatedTransformIsIdentityThenFullAndRigidBetween) {
  const Bone b = quarter_turn();
  for (const Vec3& x : {Vec3(0.3, 0.1, -0.2), Vec3(1, 0, 0), Vec3(-0.5, 0.4, 0.7)})
    EXPECT_LT((bone_transform(b, 0.0, x) - x).norm(), 1e-12);
  EXPECT_LT((bone_transform(b, 1.0, b.from_a) - b.to_a).norm(), 1e-12);
  EXPECT_LT((bone_transform(b, 1.0, b.from_b) - b.to_b).norm(), 1e-12);
  // Halfway the bone keeps its length (a rotation by 45 degrees); the linear blend of the ends
  // would shorten it to cos 45 = 0.71.
  for (double s : {0.25, 0.5, 0.75}) {
    const Vec3 a = bone_transform(b, s, b.from_a), c = bone_transform(b, s, b.from_b);
    EXPECT_NEAR((c - a).norm(), 1.0, 1e-12) << s;
    EXPECT_NEAR(std::atan2((c - a).y(), (c - a).x()), s * M_PI / 2, 1e-9) << s;
  }
  // A stretched bone: twice as long and radially 1.5 times as thick.
  Bone t = b;
  t.to_b = Vec3(0, 2, 0);
  t.radial_scale = 1.5;
  EXPECT_LT((bone_transform(t, 1.0, Vec3(1, 0, 0)) - Vec3(0, 2, 0)).norm(), 1e-12);
  EXPECT_LT((bone_transform(t, 1.0, Vec3(0.5, 0, 0.2)) - Vec3(0, 1, 0.3)).norm(), 1e-12);
  // The inverse bone undoes it.
  const Bone back = inverse_bones({t})[0];
  const Vec3 x(0.7, 0.2, -0.1);
  EXPECT_LT((bone_transform(back, 1.0, bone_transform(t, 1.0, x)) - x).norm(), 1e-12);
}

TEST(Bones, OneBoneDisplacementIsItsTransformAndDoesNotFold) {
  const Bone b = quarter_turn();
  Box3 box{Vec3::Constant(-1.5), Vec3::Constant(1.5)};
  const Grid geometry = grid_over(box, 12, 1);
  for (double s : {0.0, 0.5, 1.0}) {
    const Displacement d = bone_displacement({b}, geometry, s);
    const Vec3 x = geometry.point(5, 7, 3);
    EXPECT_LT((x + d.at(x) - bone_transform(b, s, x)).norm(), 1e-5) << s;
    EXPECT_GT(min_jacobian(d), 0.99) << s;  // a rotation: det 1 everywhere
  }
  // Two bones that turn opposite ways: the blend stays one map; near each bone its own transform.
  Bone other = quarter_turn();
  other.from_a = Vec3(0, 0, 1);
  other.from_b = Vec3(1, 0, 1);
  other.to_a = Vec3(0, 0, 1);
  other.to_b = Vec3(0, -1, 1);
  const Displacement d = bone_displacement({b, other}, geometry, 1.0);
  const Vec3 near_b(0.5, 0, 0), near_other(0.5, 0, 1);
  EXPECT_LT((near_b + d.at(near_b) - Vec3(0, 0.5, 0)).norm(), 0.1);
  EXPECT_LT((near_other + d.at(near_other) - Vec3(0, -0.5, 1)).norm(), 0.1);
}

TEST(Bones, NewtonInversionWarpsAFieldByARotation) {
  // A sphere of radius 0.4 centred at (0.6, 0, 0), rotated by 90 degrees about z: the fixed point
  // x = y - u(x) does not converge for such a turn, Newton steps do.
  const Grid sdf = test_support::analytic_grid(1.5, 40, [](const Vec3& p) { return test_support::sphere_sd(p, Vec3(0.6, 0, 0), 0.4); });
  Bone b = quarter_turn();
  b.from_b = Vec3(1, 0, 0);
  Box3 box{sdf.origin, sdf.origin + sdf.spacing * Vec3(sdf.dims[0] - 1, sdf.dims[1] - 1, sdf.dims[2] - 1)};
  const Displacement d = bone_displacement({b}, grid_over(box, 20, 1), 1.0);
  const Grid moved = warped_field_newton(sdf, d, 1);
  EXPECT_NEAR(moved.sample(Vec3(0, 0.6, 0)), -0.4, 0.03);  // the centre went to (0, 0.6, 0)
  EXPECT_NEAR(moved.sample(Vec3(0, 1.0, 0)), 0.0, 0.03);
  EXPECT_GT(moved.sample(Vec3(0.6, 0, 0)), 0.3);  // and left its old place
  EXPECT_EQ(warped_field_newton(sdf, d, 1).values, warped_field_newton(sdf, d, 2).values);
}

TEST(Matching, TerminalBranchesMatchWhenTheirJunctionsDiffer) {
  // Source: a star, junction 0 at the origin with terminals 1 (+x), 2 (+y), 3 (-x).
  // Target: the same, but the +y arm leaves from a second junction 4 on the -x arm, which also
  // has a short spur 5: the +y terminal's branch ends at a junction that is not 0's match.
  Skeleton s0, s1;
  s0.nodes = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(-1, 0, 0)};
  s0.edges = {{0, 1}, {0, 2}, {0, 3}};
  s1.nodes = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(-0.1, 1, 0), Vec3(-1, 0, 0), Vec3(-0.3, 0, 0), Vec3(-0.3, -0.2, 0)};
  s1.edges = {{0, 1}, {0, 4}, {4, 3}, {4, 2}, {4, 5}};
  s0.node_vertices.resize(s0.nodes.size());
  s1.node_vertices.resize(s1.nodes.size());
  const auto b0 = skeleton_branches(s0), b1 = skeleton_branches(s1);
  const SkeletonMatching m = match_skeletons(s0, b0, s1, b1, {}, 3.0);
  ASSERT_EQ(m.branches.size(), 3u);  // every source arm, each by its terminal
  const std::vector<int> d0 = node_degrees(s0), d1 = node_degrees(s1);
  for (const BranchPair& p : m.branches) {
    const Branch& a = b0[p.source];
    const Branch& t = b1[p.target];
    const int tip0 = d0[a.a] == 1 ? a.a : a.b, tip1 = d1[t.a] == 1 ? t.a : t.b;
    EXPECT_LT((s0.nodes[tip0] - s1.nodes[tip1]).norm(), 0.2) << p.source << " -> " << p.target;
    EXPECT_EQ(p.reversed, (tip0 == a.a) != (tip1 == t.a));
  }
}

// A displacement that folds in one small region (a bump pushing the samples near the centre past
// each other along x) is repaired there: no cell folds after, and samples away from the fold keep
// their displacement exactly.
TEST(Bones, LocalFoldRepairSmoothsOnlyWhereTheWarpFolds) {
  Box3 box;
  box.min = Vec3::Constant(-1);
  box.max = Vec3::Constant(1);
  const Grid g = grid_over(box, 32, 1);
  Displacement d;
  for (auto& c : d.u) {
    c = g;
    c.values.assign(g.size(), 0.0f);
  }
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i) {
        const Vec3 p = g.point(i, j, k);
        const size_t id = g.index(i, j, k);
        // u_x = -2 x exp(-|p|^2 / 0.02): d(x + u_x)/dx = 1 - 2 = -1 at the centre.
        d.u[0].values[id] = static_cast<float>(-2.0 * p.x() * std::exp(-p.squaredNorm() / 0.02));
        d.u[1].values[id] = static_cast<float>(0.1 * p.y());  // a mild stretch everywhere else
      }
  ASSERT_LT(min_jacobian(d), 0.0);
  const Displacement before = d;
  const FoldRepair r = repair_folds_locally(d);
  EXPECT_GT(r.rounds, 0);
  EXPECT_GE(r.min_det, 0.1);
  EXPECT_GT(min_jacobian(d), 0.0);
  int untouched = 0, far = 0;
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i)
        if (g.point(i, j, k).norm() > 0.7) {
          ++far;
          const size_t id = g.index(i, j, k);
          untouched += d.u[0].values[id] == before.u[0].values[id] && d.u[1].values[id] == before.u[1].values[id];
        }
  EXPECT_EQ(untouched, far);
  // Nothing to repair: nothing changes.
  Displacement calm = before;
  for (auto& v : calm.u[0].values) v = 0.0f;
  const Displacement calm_before = calm;
  EXPECT_EQ(repair_folds_locally(calm).rounds, 0);
  EXPECT_EQ(calm.u[1].values, calm_before.u[1].values);
}
