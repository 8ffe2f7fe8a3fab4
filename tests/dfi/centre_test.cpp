// Skeleton centring (centre.h): nodes off the axis of a capsule, some of them outside it, move to
// the axis within the plane normal to their branch; an inside junction stays.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "qs/dfi/centre.h"
#include "test_meshes.h"

using namespace qs;
using namespace qs::dfi;

namespace {
// Capsule about the x axis from -1 to 1, radius 0.3.
double capsule(const Vec3& p) {
  const double x = std::clamp(p.x(), -1.0, 1.0);
  return (p - Vec3(x, 0, 0)).norm() - 0.3;
}
}  // namespace

TEST(Centre, NodesOffTheAxisMoveOntoItAlongTheirNormalPlane) {
  const Grid g = test_support::analytic_grid(1.6, 40, capsule);
  Skeleton s;
  // Straight along x, 0.42 off the axis: every node's normal plane is x = const.
  for (int k = 0; k <= 8; ++k) s.nodes.push_back(Vec3(-0.8 + 0.2 * k, 0.4, 0.12));
  for (int k = 0; k < 8; ++k) s.edges.push_back({k, k + 1});
  const Skeleton before = s;
  const CentreReport r = centre_skeleton(s, g);
  EXPECT_EQ(r.outside_before, 9);  // 0.42 from the axis, the radius is 0.3
  EXPECT_EQ(r.outside_after, 0);
  EXPECT_EQ(r.moved, 9);
  for (size_t v = 0; v < s.nodes.size(); ++v) {
    EXPECT_EQ(s.nodes[v].x(), before.nodes[v].x()) << v;  // within the normal plane
    EXPECT_LT(std::hypot(s.nodes[v].y(), s.nodes[v].z()), 0.5 * g.spacing) << v;
    EXPECT_LT(g.sample(s.nodes[v]), -0.3 + g.spacing) << v;
  }
  EXPECT_EQ(s.edges, before.edges);
}

TEST(Centre, AnInsideJunctionStaysAndAnOutsideOneComesIn) {
  const Grid g = test_support::analytic_grid(1.6, 40, capsule);
  Skeleton s;
  s.nodes = {Vec3(0, 0.1, 0), Vec3(-0.5, 0, 0), Vec3(0.5, 0, 0), Vec3(0, 0, 0.25)};
  s.edges = {{0, 1}, {0, 2}, {0, 3}};  // node 0 a junction inside, off the axis
  Skeleton t = s;
  centre_skeleton(s, g);
  EXPECT_EQ(s.nodes[0], t.nodes[0]);
  t.nodes[0] = Vec3(0, 0.45, 0);  // the same junction outside: it descends until inside
  const CentreReport r = centre_skeleton(t, g);
  EXPECT_LT(g.sample(t.nodes[0]), 0.0);
  EXPECT_EQ(r.outside_after, 0);
}
