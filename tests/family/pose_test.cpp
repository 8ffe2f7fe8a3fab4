// Posing a mesh by as-rigid-as-possible deformation: connectivity kept, handles moved by their
// rotation, the rest in place, no folds, deterministic; extremities and automatic landmarks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "qs/core/error.h"
#include "qs/family/family.h"
#include "qs/family/pose.h"
#include "qs/shapes/shapes.h"
#include "../common/test_support.h"

using qs::Vec3;
using qs::test::nearest_vertex;

namespace {

// A generated shape with four legs and a head (made in code, deterministic).
const qs::TriMesh& animal() {
  static const qs::TriMesh mesh = [] {
    qs::family::FamilyOptions o;
    o.shapes = 1;
    o.seed = 1;
    o.faces = 4000;
    o.limbs = 5;
    return qs::family::generate_family(o).shapes[0].mesh;
  }();
  return mesh;
}

}  // namespace

TEST(Pose, FindsTheLimbsOfAGeneratedAnimal) {
  const auto ext = qs::family::find_extremities(animal());
  int limbs = 0;
  for (const auto& e : ext) limbs += e.limb_radius > 0;
  EXPECT_GE(ext.size(), 5u);
  EXPECT_GE(limbs, 4);
  // Limbs first, then the other extremities, each by prominence.
  for (std::size_t k = 1; k < ext.size(); ++k) {
    EXPECT_GE(ext[k - 1].limb_radius > 0, ext[k].limb_radius > 0);
    if ((ext[k - 1].limb_radius > 0) == (ext[k].limb_radius > 0)) {
      EXPECT_GE(ext[k - 1].prominence, ext[k].prominence);
    }
  }
}

TEST(Pose, KeepsConnectivityMovesHandlesRigidlyAndLeavesTheRestInPlace) {
  const qs::TriMesh& mesh = animal();
  qs::family::PoseOptions opt;
  opt.seed = 3;
  opt.kind = qs::family::PoseKind::Bend;
  opt.min_angle_deg = opt.max_angle_deg = 40;
  const qs::family::Pose pose = qs::family::pose_mesh(mesh, opt);
  ASSERT_EQ(pose.mesh.faces, mesh.faces);
  ASSERT_EQ(pose.mesh.num_vertices(), mesh.num_vertices());
  ASSERT_GE(pose.limbs.size(), 3u);
  const double diag = qs::bounding_box(mesh.positions).diagonal();
  std::vector<char> moved(mesh.num_vertices(), 0);
  for (const auto& l : pose.limbs) {
    // Either the asked angle (either way round) or a smaller one after a fold, never below 15.
    EXPECT_LE(std::abs(l.angle_deg), 40 + 1e-9);
    EXPECT_GE(std::abs(l.angle_deg), 15);
    EXPECT_NEAR(l.axis.norm(), 1, 1e-12);
    const Eigen::Matrix3d r = Eigen::AngleAxisd(l.angle_deg * M_PI / 180, l.axis).toRotationMatrix();
    ASSERT_FALSE(l.handle.empty());
    for (int v : l.handle) {
      const Vec3 target = l.pivot + r * (mesh.positions[v] - l.pivot);
      EXPECT_LT((pose.mesh.positions[v] - target).norm(), 1e-6 * diag) << "handle vertex " << v;
    }
    // The tip really moved: a rotation of tens of degrees about the root.
    const double arm = (mesh.positions[l.tip] - l.pivot).norm();
    EXPECT_NEAR((pose.mesh.positions[l.tip] - mesh.positions[l.tip]).norm(),
                2 * arm * std::sin(std::abs(l.angle_deg) * M_PI / 360), 1e-6 * diag);
    EXPECT_GT(arm * std::sin(std::abs(l.angle_deg) * M_PI / 360), 0.02 * diag);
    for (int v : l.region) moved[v] = 1;
  }
  for (int v = 0; v < mesh.num_vertices(); ++v) {
    if (!moved[v]) {
      EXPECT_EQ(pose.mesh.positions[v], mesh.positions[v]) << "fixed vertex " << v;
    }
  }
  EXPECT_TRUE(qs::family::folded_faces(mesh, pose.mesh).empty());
  EXPECT_LT(pose.max_handle_error, 1e-6 * diag);
}

TEST(Pose, IsDeterministicAndDependsOnTheSeed) {
  qs::family::PoseOptions opt;
  opt.seed = 7;
  const auto a = qs::family::pose_mesh(animal(), opt);
  const auto b = qs::family::pose_mesh(animal(), opt);
  EXPECT_EQ(a.mesh.positions, b.mesh.positions);
  opt.seed = 8;
  const auto c = qs::family::pose_mesh(animal(), opt);
  EXPECT_NE(a.mesh.positions, c.mesh.positions);
  EXPECT_TRUE(qs::family::folded_faces(animal(), a.mesh).empty());
  EXPECT_TRUE(qs::family::folded_faces(animal(), c.mesh).empty());
}

TEST(Pose, FoldedFacesSeesAVertexPushedThroughTheSurface) {
  const qs::TriMesh sphere = qs::shapes::icosphere(3);
  qs::TriMesh dented = sphere;
  EXPECT_TRUE(qs::family::folded_faces(sphere, dented).empty());
  dented.positions[5] *= -0.2;  // through the centre to the other side: its fan turns over
  EXPECT_FALSE(qs::family::folded_faces(sphere, dented).empty());
}

TEST(Pose, ShortestLoopOrderGoesAroundNotAcross) {
  const qs::TriMesh sphere = qs::shapes::icosphere(4);
  const int px = nearest_vertex(sphere, Vec3(1, 0, 0)), nx = nearest_vertex(sphere, Vec3(-1, 0, 0));
  const int py = nearest_vertex(sphere, Vec3(0, 0.7, 0)), ny = nearest_vertex(sphere, Vec3(0, -1, 0));
  const auto order = qs::family::shortest_loop_order(sphere, {px, nx, py, ny});
  ASSERT_EQ(order.size(), 4u);
  EXPECT_EQ(order[0], px);
  EXPECT_EQ(order[2], nx);  // opposite points are not neighbours on the loop
}

TEST(Pose, ChoosesSeedsAndFeaturesAtDistinctExtremities) {
  const auto lm = qs::family::choose_landmarks(animal());
  ASSERT_EQ(lm.seeds.size(), 4u);
  EXPECT_GE(lm.features.size(), 2u);
  EXPECT_LE(lm.features.size(), 6u);
  std::set<int> all(lm.seeds.begin(), lm.seeds.end());
  for (const auto& [name, v] : lm.features) all.insert(v);
  EXPECT_EQ(all.size(), 4 + lm.features.size());
  const auto again = qs::family::choose_landmarks(animal());
  EXPECT_EQ(again.seeds, lm.seeds);
  EXPECT_EQ(again.features, lm.features);
}

TEST(Pose, RefusesOptionsOutOfRange) {
  qs::family::PoseOptions opt;
  opt.min_angle_deg = 70;
  opt.max_angle_deg = 50;
  EXPECT_THROW(qs::family::pose_mesh(animal(), opt), qs::InvalidInput);
  opt = {};
  opt.limbs = -1;
  EXPECT_THROW(qs::family::pose_mesh(animal(), opt), qs::InvalidInput);
  // A sphere has no limb.
  EXPECT_THROW(qs::family::pose_mesh(qs::shapes::icosphere(3), {}), qs::SolverError);
}
