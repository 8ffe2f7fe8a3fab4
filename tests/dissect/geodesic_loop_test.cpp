// Geodesic seed curves: straighten_seed_loop on surfaces whose geodesics are known, its
// loop invariants, and what it buys the dissection: one surface tessellated twice maps closer to
// the identity.

#include "qs/dissect/geodesic_loop.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>
#include <vector>

#include "qs/core/error.h"
#include "qs/correspondence/correspondence.h"
#include "qs/dissect/dissection.h"
#include "qs/dissect/seed_loop.h"
#include "qs/family/family.h"
#include "qs/shapes/shapes.h"
#include "../common/test_support.h"

using qs::test::vertex_towards;

namespace {

using qs::TriMesh;
using qs::Vec3;
using qs::dissect::GeodesicLoop;
using qs::dissect::GeodesicLoopOptions;
using qs::dissect::SeedLoop;
using ::testing::HasSubstr;

/// Four seeds on a tilted great circle of the unit sphere.
std::array<int, 4> tilted_seeds(const TriMesh& m) {
  const Vec3 n = Vec3(0.3, 0.2, 1).normalized();
  const Vec3 a = n.cross(Vec3(1, 0, 0)).normalized(), b = n.cross(a);
  std::array<int, 4> s{};
  for (int k = 0; k < 4; ++k) s[k] = vertex_towards(m, std::cos(k * M_PI / 2 + 0.1) * a + std::sin(k * M_PI / 2 + 0.1) * b);
  return s;
}

/// Largest distance of curve i's vertices from the plane of the great circle through its ends.
double off_great_circle(const TriMesh& m, const SeedLoop& loop, int i) {
  const auto& p = loop.paths[i];
  const Vec3 n = m.positions[p.front()].cross(m.positions[p.back()]).normalized();
  double worst = 0;
  for (int v : p) worst = std::max(worst, std::abs(n.dot(m.positions[v])));
  return worst;
}

double length(const TriMesh& m, const std::vector<int>& p) {
  double l = 0;
  for (size_t k = 1; k < p.size(); ++k) l += (m.positions[p[k]] - m.positions[p[k - 1]]).norm();
  return l;
}

/// Every loop invariant, with an own edge set: edge paths between the seeds, vertices used once
/// (seeds twice), two parts.
void expect_valid_loop(const TriMesh& m, const SeedLoop& loop) {
  std::set<std::pair<int, int>> edges;
  for (const auto& t : m.faces)
    for (int k = 0; k < 3; ++k) edges.insert({std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3])});
  std::map<int, int> uses;
  for (int i = 0; i < 4; ++i) {
    const auto& p = loop.paths[i];
    ASSERT_GE(p.size(), 2u);
    EXPECT_EQ(p.front(), loop.seeds[i]);
    EXPECT_EQ(p.back(), loop.seeds[(i + 1) % 4]);
    for (size_t k = 0; k < p.size(); ++k) {
      ++uses[p[k]];
      if (k + 1 < p.size()) {
        EXPECT_TRUE(edges.count({std::min(p[k], p[k + 1]), std::max(p[k], p[k + 1])}));
      }
    }
  }
  const std::set<int> seeds(loop.seeds.begin(), loop.seeds.end());
  for (const auto& [v, n] : uses) EXPECT_EQ(n, seeds.count(v) ? 2 : 1) << "vertex " << v;
  EXPECT_NO_THROW(qs::dissect::seed_patch_of_faces(m, loop));
}

/// New vertices lie on input edges: at (1-t) a + t b of two input vertices a, b of one face.
void expect_new_vertices_on_input_edges(const TriMesh& in, const TriMesh& out) {
  for (int v = 0; v < in.num_vertices(); ++v) ASSERT_EQ(in.positions[v], out.positions[v]);
  for (int v = in.num_vertices(); v < out.num_vertices(); ++v) {
    double best = INFINITY;
    for (const auto& t : in.faces)
      for (int k = 0; k < 3; ++k) {
        const Vec3 &a = in.positions[t[k]], &b = in.positions[t[(k + 1) % 3]];
        const double s = std::clamp((out.positions[v] - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
        best = std::min(best, (a + s * (b - a) - out.positions[v]).norm());
      }
    EXPECT_LT(best, 1e-12) << "vertex " << v;
  }
}

class GreatCircles : public ::testing::TestWithParam<int> {};

TEST_P(GreatCircles, StraightenedCurvesFollowTheGreatCirclesAndAreShorter) {
  const TriMesh m = GetParam() == 0 ? qs::shapes::icosphere(4) : qs::shapes::cube_sphere(24);
  const auto seeds = tilted_seeds(m);
  const SeedLoop edge_loop = qs::dissect::trace_seed_loop(m, seeds);
  const GeodesicLoop g = qs::dissect::straighten_seed_loop(m, edge_loop);
  expect_valid_loop(g.mesh, g.loop);
  expect_new_vertices_on_input_edges(m, g.mesh);
  EXPECT_GT(g.inserted_vertices, 0);
  double mean_edge = 0;
  for (const auto& t : m.faces) mean_edge += (m.positions[t[0]] - m.positions[t[1]]).norm();
  mean_edge /= m.num_faces();
  for (int i = 0; i < 4; ++i) {
    SCOPED_TRACE("curve " + std::to_string(i));
    EXPECT_TRUE(g.straightened[i]) << g.why[i];
    EXPECT_TRUE(g.why[i].empty());
    const double before = off_great_circle(m, edge_loop, i), after = off_great_circle(g.mesh, g.loop, i);
    // The polyhedral geodesic stays within a small part of an edge of the great circle (the
    // inscribed polyhedron's chord error); the edge path zig-zags by about half an edge.
    EXPECT_LT(after, 0.15 * mean_edge) << "edge path: " << before;
    EXPECT_LT(after, 0.5 * before);
    const double arc = std::acos(m.positions[seeds[i]].normalized().dot(m.positions[seeds[(i + 1) % 4]].normalized()));
    EXPECT_NEAR(g.length_after[i], length(g.mesh, g.loop.paths[i]), 1e-12);
    EXPECT_LE(g.length_after[i], g.length_before[i]);
    EXPECT_NEAR(g.length_after[i], arc, 0.01 * arc);  // inscribed: slightly shorter than the arc
  }
}

INSTANTIATE_TEST_SUITE_P(TwoTessellations, GreatCircles, ::testing::Values(0, 1));

TEST(GeodesicLoop, OnACutMeshItIsTheSameAsOnTheMesh) {
  const TriMesh m = qs::shapes::cube_sphere(12);
  const SeedLoop edge_loop = qs::dissect::trace_seed_loop(m, tilted_seeds(m));
  GeodesicLoopOptions o;
  o.avoid = {5, 77};
  const GeodesicLoop a = qs::dissect::straighten_seed_loop(m, edge_loop, o);
  ASSERT_TRUE(a.any_straightened());
  // A cut mesh whose out-half-edges and labels are not a fresh build's (a face split and undone).
  qs::dissect::CutMesh cm(m);
  cm.checkpoint();
  cm.split_face(0, Vec3(0.2, 0.3, 0.5));
  cm.rollback();
  cm.set_patch(3, 1);
  const GeodesicLoop b = qs::dissect::straighten_seed_loop(cm, edge_loop, o);
  EXPECT_EQ(b.mesh.positions, a.mesh.positions);
  EXPECT_EQ(b.mesh.faces, a.mesh.faces);
  EXPECT_EQ(b.loop.paths, a.loop.paths);
  EXPECT_EQ(b.straightened, a.straightened);
  EXPECT_EQ(b.why, a.why);
  EXPECT_EQ(b.length_after, a.length_after);
  EXPECT_EQ(b.face_patches, a.face_patches);
  EXPECT_EQ(b.inserted_vertices, a.inserted_vertices);
  // A loop that is not one: the same refusal as on the mesh.
  SeedLoop broken = edge_loop;
  broken.paths[1].pop_back();
  EXPECT_THROW(qs::dissect::straighten_seed_loop(cm, broken, o), qs::InvalidInput);
  EXPECT_THROW(qs::dissect::straighten_seed_loop(m, broken, o), qs::InvalidInput);
}

TEST(GeodesicLoop, ItsCutMeshIsTheRefinedMeshBuiltAfresh) {
  const TriMesh m = qs::shapes::icosphere(4);
  const GeodesicLoop g = qs::dissect::straighten_seed_loop(m, qs::dissect::trace_seed_loop(m, tilted_seeds(m)));
  ASSERT_TRUE(g.any_straightened());
  ASSERT_TRUE(g.cut.has_value());
  const qs::dissect::CutMesh fresh(g.mesh);
  const qs::dissect::CutMesh& cut = *g.cut;
  EXPECT_EQ(cut.positions(), fresh.positions());
  ASSERT_EQ(cut.faces(), fresh.faces());
  for (int h = 0; h < 3 * fresh.num_faces(); ++h) ASSERT_EQ(cut.opposite(h), fresh.opposite(h)) << "half-edge " << h;
  // The straightening's splits leave other out-half-edges than a fresh build; reset() restores them.
  for (int v = 0; v < fresh.num_vertices(); ++v) ASSERT_EQ(cut.out_halfedge(v), fresh.out_halfedge(v)) << "vertex " << v;
  EXPECT_EQ(cut.face_patches(), fresh.face_patches());
}

TEST(GeodesicLoop, AvoidedVerticesKeepTheirSideAndAreNeverOnTheLoop) {
  const TriMesh m = qs::shapes::bumpy_sphere(0.2, 5, 4);
  const auto seeds = tilted_seeds(m);
  const SeedLoop edge_loop = qs::dissect::trace_seed_loop(m, seeds);
  // Avoid every 7th vertex that is not on the loop: many lie next to the curves.
  std::set<int> on_loop;
  for (const auto& p : edge_loop.paths) on_loop.insert(p.begin(), p.end());
  GeodesicLoopOptions o;
  for (int v = 0; v < m.num_vertices(); v += 7)
    if (!on_loop.count(v)) o.avoid.push_back(v);
  const auto before = qs::dissect::sides_of_vertices(m, edge_loop, o.avoid);
  const GeodesicLoop g = qs::dissect::straighten_seed_loop(m, edge_loop, o);
  expect_valid_loop(g.mesh, g.loop);
  EXPECT_EQ(qs::dissect::sides_of_vertices(g.mesh, g.loop, o.avoid), before);
  for (int i = 0; i < 4; ++i) {
    if (!g.straightened[i]) {
      EXPECT_FALSE(g.why[i].empty());
    }
  }
  // The faces' seed patches come with the refined mesh, as seed_patch_of_faces() gives them.
  ASSERT_TRUE(g.any_straightened());
  EXPECT_EQ(g.face_patches, qs::dissect::seed_patch_of_faces(g.mesh, g.loop));
  EXPECT_EQ(qs::dissect::sides_of_vertices(g.mesh, g.face_patches, o.avoid), before);
  ASSERT_GT(g.inserted_vertices, 0);  // so the input has fewer faces than the labels
  EXPECT_THROW(qs::dissect::sides_of_vertices(m, g.face_patches, o.avoid), qs::InvalidInput);
}

TEST(GeodesicLoop, BadOptionsAreRejected) {
  const TriMesh m = qs::shapes::icosphere(2);
  const SeedLoop loop = qs::dissect::trace_seed_loop(m, tilted_seeds(m));
  GeodesicLoopOptions o;
  o.snap = 0.5;
  EXPECT_THAT([&] { qs::dissect::straighten_seed_loop(m, loop, o); },
              ::testing::ThrowsMessage<qs::InvalidInput>(HasSubstr("snap")));
  o = {};
  o.avoid = {m.num_vertices()};
  EXPECT_THAT([&] { qs::dissect::straighten_seed_loop(m, loop, o); },
              ::testing::ThrowsMessage<qs::InvalidInput>(HasSubstr("out of range")));
}

/// Mean error (% of the diagonal) of one smooth surface tessellated twice (qs-family
/// --variation 0), dissected together: the ideal is the identity.
double self_error(const qs::dissect::DissectOptions& options) {
  qs::family::FamilyOptions fo;
  fo.shapes = 2;
  fo.seed = 3;
  fo.faces = 3000;
  fo.limbs = 4;
  fo.variation = 0;
  const auto fam = qs::family::generate_family(fo);
  const auto set = qs::dissect::dissect_set(
      {qs::correspondence::dissect_input(fam.shapes[0]), qs::correspondence::dissect_input(fam.shapes[1])}, options);
  for (const auto& d : set.meshes)
    for (const auto& p : d.chart.patches) EXPECT_EQ(p.flipped_faces + p.zero_area_faces, 0) << p.name;
  std::vector<qs::correspondence::TruthMesh> truth(2);
  std::vector<qs::correspondence::DissectedInput> in;
  for (int k = 0; k < 2; ++k) {
    truth[k].name = fam.shapes[k].name;
    truth[k].mesh = fam.shapes[k].mesh;
    qs::family::SurfaceMap sm;
    sm.sphere = fam.shapes[k].parameters;
    truth[k].map = sm;
    in.push_back({&set.meshes[k].chart, qs::correspondence::dissection_landmarks(set.meshes[k])});
  }
  qs::correspondence::MeasureOptions mo;
  mo.samples = 20000;
  return qs::correspondence::measure_pair(qs::correspondence::GroundTruth(truth), in, 0, 1, mo).dissection.mean;
}

TEST(GeodesicLoop, OneSurfaceTessellatedTwiceMapsCloserToTheIdentity) {
  // The default maps (geodesic seed curves, intrinsic cotangent weights) against the edge paths
  // with the same weights, and against the old maps (edge paths, mean-value weights); the maps
  // alone, without the same-pose steps (the pair is one surface, so one pose).
  qs::dissect::DissectOptions maps_only;
  maps_only.same_pose_detect = 0;
  qs::dissect::DissectOptions edges = maps_only, old_maps = maps_only;
  edges.geodesic_seed_curves = false;
  old_maps.geodesic_seed_curves = false;
  old_maps.intrinsic_cotan = false;
  const double now = self_error(maps_only);
  const double edge_paths = self_error(edges);
  const double old = self_error(old_maps);
  EXPECT_LT(now, 0.85 * edge_paths) << "edge paths " << edge_paths << "%, geodesic curves " << now << "%";
  EXPECT_LT(now, 0.7 * old) << "old maps " << old << "%, default maps " << now << "%";
}

}  // namespace
