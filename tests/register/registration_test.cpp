// Registration of a surface onto itself in another pose: the map it gives (each registered vertex's
// nearest point) against the exact one, determinism, and the poses through it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "qs/core/error.h"
#include "qs/metro/metro.h"
#include "qs/register/registration.h"
#include "../common/posed_animal.h"

using qs::TriMesh;
using qs::Vec3;
using qs::registration::LandmarkPair;

namespace {

// The registration's inputs on a posed generated animal (vertex i <-> vertex i is exact).
struct PosedPair {
  TriMesh a, b;
  std::vector<LandmarkPair> landmarks;
};

const PosedPair& pair() {
  static const PosedPair p = [] {
    const qs::test::PosedAnimal animal = qs::test::posed_animal(1);
    PosedPair out{animal.a, animal.b, {}};
    for (int v : animal.landmarks.seeds) out.landmarks.push_back({out.a.positions[v], out.b.positions[v]});
    for (const auto& [name, v] : animal.landmarks.features)
      out.landmarks.push_back({out.a.positions[v], out.b.positions[v]});
    return out;
  }();
  return p;
}

double diagonal(const TriMesh& m) { return qs::bounding_box(m.positions).diagonal(); }

// Mean distance of each vertex's image (its nearest point of b from `at`) to its exact image,
// over the diagonal.
double mean_error(const PosedPair& p, const std::vector<Vec3>& at) {
  const qs::metro::SurfaceDistance on_b(p.b, "B");
  double sum = 0;
  for (int v = 0; v < p.a.num_vertices(); ++v) sum += (on_b.closest(at[v]).point - p.b.positions[v]).norm();
  return sum / p.a.num_vertices() / diagonal(p.b);
}

// Each face split in four at its edges' midpoints: the same surface, the vertices kept first.
TriMesh split_in_four(const TriMesh& m) {
  TriMesh out = m;
  out.faces.clear();
  std::map<std::pair<int, int>, int> mid;
  auto midpoint = [&](int a, int b) {
    const auto key = std::minmax(a, b);
    const auto [it, added] = mid.try_emplace(key, out.num_vertices());
    if (added) out.positions.push_back(0.5 * (m.positions[a] + m.positions[b]));
    return it->second;
  };
  for (const auto& t : m.faces) {
    const int ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
    out.faces.push_back({t[0], ab, ca});
    out.faces.push_back({ab, t[1], bc});
    out.faces.push_back({ca, bc, t[2]});
    out.faces.push_back({ab, bc, ca});
  }
  return out;
}

}  // namespace

TEST(Registration, BringsAPosedSurfaceCloseToItsExactMap) {
  const PosedPair& p = pair();
  const auto r = qs::registration::register_surface(p.a, p.b, p.landmarks);
  ASSERT_EQ(r.positions.size(), p.a.positions.size());
  // The baseline: A moved by the landmarks' similarity, then nearest points.
  std::vector<Vec3> from, to;
  for (const auto& l : p.landmarks) from.push_back(l.on_a), to.push_back(l.on_b);
  const Eigen::Matrix4d s = qs::fit_similarity(from, to);
  std::vector<Vec3> moved;
  for (const Vec3& x : p.a.positions) moved.push_back((s * x.homogeneous()).head<3>());
  const double baseline = mean_error(p, moved), registered = mean_error(p, r.positions);
  // Measured: 4.8% of the diagonal for the baseline, 1.3% registered (its thin legs, 4000 faces).
  EXPECT_LT(registered, 0.02);
  EXPECT_LT(registered, baseline / 3);
  // It lies on B (within the bound that makes a set one pose) and is nearly isometric.
  EXPECT_LT(r.p99_distance, 0.01);
  EXPECT_LT(r.distortion, 1.1);
  EXPECT_GE(r.distortion, 1.0);
}

TEST(Registration, IsDeterministicOnAnyThreadCount) {
  const PosedPair& p = pair();
  qs::registration::RegisterOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const auto a = qs::registration::register_surface(p.a, p.b, p.landmarks, one);
  const auto b = qs::registration::register_surface(p.a, p.b, p.landmarks, two);
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.mean_distance, b.mean_distance);
  EXPECT_EQ(a.distortion, b.distortion);
}

TEST(Registration, RefusesTooFewLandmarksAndNoStages) {
  const PosedPair& p = pair();
  const std::vector<LandmarkPair> two(p.landmarks.begin(), p.landmarks.begin() + 2);
  EXPECT_THROW(qs::registration::register_surface(p.a, p.b, two), qs::InvalidInput);
  qs::registration::RegisterOptions none;
  none.stages.clear();
  EXPECT_THROW(qs::registration::register_surface(p.a, p.b, p.landmarks, none), qs::InvalidInput);
}

TEST(Registration, PoseMapsPointsAndNormalsBothWays) {
  const PosedPair& p = pair();
  const qs::registration::Pose pose(p.a, qs::registration::register_surface(p.a, p.b, p.landmarks));
  ASSERT_TRUE(pose.registered());
  const double diag = diagonal(p.b);
  const auto na = qs::vertex_normals(p.a.positions, p.a.faces);
  const auto nb = qs::vertex_normals(p.b.positions, p.b.faces);
  double forward = 0, back = 0, turned = 0;
  for (int v = 0; v < p.a.num_vertices(); ++v) {
    forward += (pose.forward(p.a.positions[v]) - p.b.positions[v]).norm();
    back += (pose.inverse(pose.forward(p.a.positions[v])) - p.a.positions[v]).norm();
    turned += pose.forward(p.a.positions[v], na[v]).normal.normalized().dot(nb[v]);
  }
  const int n = p.a.num_vertices();
  EXPECT_LT(forward / n / diag, 0.02);   // each vertex near its exact image
  EXPECT_LT(back / n / diag, 1e-9);       // the inverse undoes the forward map on A's surface
  EXPECT_GT(turned / n, 0.95);            // normals turn with the limbs
  // A similarity maps by its matrix, and from_inverse by the inverse of the one given.
  Eigen::Matrix4d s = Eigen::Matrix4d::Identity();
  s.topLeftCorner<3, 3>() = 2 * Eigen::AngleAxisd(0.5, Vec3::UnitZ()).toRotationMatrix();
  s.topRightCorner<3, 1>() = Vec3(1, 2, 3);
  const qs::registration::Pose sim(s), inv = qs::registration::Pose::from_inverse(s.inverse());
  const Vec3 x(0.3, -0.2, 0.7);
  EXPECT_LT((sim.forward(x) - (s * x.homogeneous()).head<3>()).norm(), 1e-12);
  EXPECT_LT((sim.inverse(sim.forward(x)) - x).norm(), 1e-12);
  EXPECT_LT((inv.forward(x) - sim.forward(x)).norm(), 1e-12);
  EXPECT_FALSE(sim.registered());
  EXPECT_LT((qs::registration::Pose().forward(x) - x).norm(), 0.0 + 1e-15);
}

TEST(Registration, LargeMeshesRunTheEarlyStagesCoarseAndStayAsClose) {
  const PosedPair& p = pair();
  qs::registration::RegisterOptions fine, coarse;
  fine.coarse_faces = 0;
  coarse.coarse_faces = p.a.num_faces() / 4;  // as a 4x larger A would with the default
  const auto f = qs::registration::register_surface(p.a, p.b, p.landmarks, fine);
  const auto c = qs::registration::register_surface(p.a, p.b, p.landmarks, coarse);
  EXPECT_NE(c.positions, f.positions);  // the coarse stages ran
  const double ef = mean_error(p, f.positions), ec = mean_error(p, c.positions);
  // Measured: 1.20% of the diagonal coarse (A and B), 0.94% with every stage on A and toward B.
  EXPECT_LT(ec, 1.4 * ef);
  EXPECT_LT(c.p99_distance, 0.01);
  EXPECT_LT(c.distortion, 1.1);
  coarse.threads = 1;
  EXPECT_EQ(qs::registration::register_surface(p.a, p.b, p.landmarks, coarse).positions, c.positions);
}

TEST(Registration, ALargeBIsPulledTowardACoarseCopyFirstAndStaysAsClose) {
  const PosedPair& p = pair();
  const PosedPair big{p.a, split_in_four(p.b), p.landmarks};  // B: 4x the faces, the same surface
  qs::registration::RegisterOptions fine, coarse;
  fine.coarse_faces = 0;
  coarse.coarse_faces = p.a.num_faces();  // A is not coarsened, B is
  const auto f = qs::registration::register_surface(big.a, big.b, big.landmarks, fine);
  const auto c = qs::registration::register_surface(big.a, big.b, big.landmarks, coarse);
  EXPECT_NE(c.positions, f.positions);  // the early stages pulled toward the coarse B
  const double ef = mean_error(big, f.positions), ec = mean_error(big, c.positions);
  // Measured: 1.272% of the diagonal, 1.273% toward B in every stage.
  EXPECT_LT(ec, 1.1 * ef);
  EXPECT_LT(c.p99_distance, 0.01);
  coarse.threads = 1;
  EXPECT_EQ(qs::registration::register_surface(big.a, big.b, big.landmarks, coarse).positions, c.positions);
}
