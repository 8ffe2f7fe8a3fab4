// The union quinary tree and feature alignment across a set of meshes (paper 3.4).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <set>

#include "../common/shared_meshes.h"
#include "check_dissection.h"
#include "qs/core/error.h"
#include "qs/dissect/dissection.h"
#include "qs/dissect/seed_loop.h"
#include "qs/io/read_mesh.h"
#include "qs/landmarks/landmarks.h"
#include "qs/mesh/validate.h"
#include "qs/shapes/shapes.h"
#include "../common/test_support.h"

using qs::dissect::DissectionSet;
using qs::dissect::MeshToDissect;
using qs::testing::check_dissection;
using ::testing::HasSubstr;

using qs::test::vertex_towards;

namespace {

// An analytic smooth deformation: same connectivity, positions bent, twisted and bulged.
qs::TriMesh deform(const qs::TriMesh& m) {
  qs::TriMesh out = m;
  for (auto& p : out.positions) {
    const double a = 0.6 * p.z();
    const double x = p.x() * std::cos(a) - p.y() * std::sin(a), y = p.x() * std::sin(a) + p.y() * std::cos(a);
    p = qs::Vec3(1.3 * x + 0.2 * std::sin(2 * p.z()), 0.8 * y, p.z() + 0.25 * x * x);
  }
  return out;
}

std::array<int, 4> equator_seeds(const qs::TriMesh& m) {
  return {vertex_towards(m, {1, 0, 0}), vertex_towards(m, {0, 1, 0}), vertex_towards(m, {-1, 0, 0}),
          vertex_towards(m, {0, -1, 0})};
}

std::vector<qs::dissect::Feature> features_at(const qs::TriMesh& m, const std::vector<qs::Vec3>& dirs) {
  std::vector<qs::dissect::Feature> f;
  for (size_t i = 0; i < dirs.size(); ++i) f.push_back({"f" + std::to_string(i), vertex_towards(m, dirs[i]), {}});
  return f;
}

void expect_common_structure(const DissectionSet& s, const std::vector<int>& input_faces) {
  ASSERT_EQ(s.meshes.size(), input_faces.size());
  for (size_t i = 0; i < s.meshes.size(); ++i) {
    SCOPED_TRACE("mesh " + std::to_string(i));
    check_dissection(s.meshes[i], input_faces[i]);
    EXPECT_EQ(s.meshes[i].base.quads, s.meshes[0].base.quads) << "base domains differ";
    ASSERT_EQ(s.meshes[i].chart.patches.size(), s.meshes[0].chart.patches.size());
    for (size_t p = 0; p < s.meshes[0].chart.patches.size(); ++p)
      EXPECT_EQ(s.meshes[i].chart.patches[p].name, s.meshes[0].chart.patches[p].name);
    // Features: the same patch and the same (u,v) in every mesh.
    ASSERT_EQ(s.meshes[i].features.size(), s.meshes[0].features.size());
    for (size_t k = 0; k < s.meshes[0].features.size(); ++k) {
      const auto& a = s.meshes[0].features[k];
      const auto& b = s.meshes[i].features[k];
      EXPECT_EQ(a.name, b.name);
      EXPECT_EQ(a.patch, b.patch) << a.name;
      EXPECT_LT((a.uv - b.uv).norm(), 1e-6) << a.name;
      // The placement agrees with the chart: the feature vertex carries that uv in that patch.
      const auto& c = s.meshes[i].chart;
      for (int f = 0; f < c.mesh.num_faces(); ++f)
        for (int j = 0; j < 3; ++j)
          if (c.mesh.faces[f][j] == b.vertex) {
            EXPECT_EQ(c.face_patch[f], b.patch) << b.name << " is on a patch border";
            EXPECT_LT((c.face_uv[f][j] - b.uv).norm(), 1e-9) << b.name;
          }
    }
  }
}

}  // namespace

TEST(DissectSet, DeformedPairGetsOneBaseDomainAndAlignedFeatures) {
  const auto a = qs::shapes::bumpy_sphere(0.08, 3, 4);
  const auto b = deform(a);
  const std::vector<qs::Vec3> dirs = {{0.3, 0.2, 1}, {-0.4, 0.5, 0.8}, {0.6, -0.5, 0.7}, {0.2, 0.3, -1}, {-0.5, -0.4, -0.8}};
  // Features at different vertices of the two meshes (the same directions on the deformed
  // shape), so that the alignment has real work to do.
  MeshToDissect ma{&a, equator_seeds(a), features_at(a, dirs), "a"};
  MeshToDissect mb{&b, ma.seeds, features_at(b, dirs), "b"};
  qs::dissect::DissectOptions o;
  o.tau = 1.1;  // forces splits
  o.max_patch_area = 0;  // by stretch alone
  const DissectionSet s = qs::dissect::dissect_set({ma, mb}, o);
  EXPECT_GT(s.meshes[0].chart.patches.size(), 2u);
  expect_common_structure(s, {a.num_faces(), b.num_faces()});
  for (const auto& n : s.tree) {
    ASSERT_EQ(n.mesh_stretch.size(), 2u);
    if (n.split) {
      // A node is split only when some mesh needed it.
      EXPECT_TRUE(n.mesh_stretch[0] > o.tau || n.mesh_stretch[1] > o.tau) << n.name;
    }
  }
  for (const auto& d : s.meshes)
    for (const auto& p : d.chart.patches)
      if (p.stretch > o.tau) { EXPECT_NE(p.stop, qs::dissect::StopReason::None) << p.name; }
}

TEST(DissectSet, StretchMinimizedLeavesKeepFeaturesAligned) {
  const auto a = qs::shapes::bumpy_sphere(0.08, 3, 4);
  const auto b = deform(a);
  const std::vector<qs::Vec3> dirs = {{0.3, 0.2, 1}, {-0.4, 0.5, 0.8}, {0.6, -0.5, 0.7}, {0.2, 0.3, -1}, {-0.5, -0.4, -0.8}};
  MeshToDissect ma{&a, equator_seeds(a), features_at(a, dirs), "a"};
  MeshToDissect mb{&b, ma.seeds, features_at(b, dirs), "b"};
  qs::dissect::DissectOptions o;
  o.tau = 1.1;
  o.stretch_iterations = 6;
  o.max_patch_area = 0.2;
  const DissectionSet s = qs::dissect::dissect_set({ma, mb}, o);
  expect_common_structure(s, {a.num_faces(), b.num_faces()});
}

TEST(DissectSet, UnionTreeHoldsEverySplitOfTheMeshThatNeedsThem) {
  // A smooth ellipsoid needs no split; a star blob needs several. Together, the set's tree must be
  // the star's own tree (its peaks decide every split), and the ellipsoid follows it.
  const auto smooth = qs::shapes::ellipsoid(1.2, 1, 0.9, 3);
  const auto star = qs::shapes::star_blob(4, 1.5, 4);
  qs::dissect::DissectOptions o;
  o.tau = 1.6;
  o.max_patch_area = 0;  // by stretch alone
  const auto seeds_smooth = equator_seeds(smooth), seeds_star = equator_seeds(star);
  const auto alone = qs::dissect::dissect(star, seeds_star, o);
  const auto alone_smooth = qs::dissect::dissect(smooth, seeds_smooth, o);
  ASSERT_EQ(alone_smooth.chart.patches.size(), 2u);
  ASSERT_GT(alone.chart.patches.size(), 2u);
  const DissectionSet s = qs::dissect::dissect_set(
      {{&smooth, seeds_smooth, {}, "smooth"}, {&star, seeds_star, {}, "star"}}, o);
  std::set<std::string> set_splits, star_splits;
  for (const auto& n : s.tree)
    if (n.split) set_splits.insert(n.name);
  for (const auto& n : alone.tree)
    if (n.split) star_splits.insert(n.name);
  for (const auto& n : star_splits) EXPECT_TRUE(set_splits.count(n)) << "split " << n << " missing from the union";
  expect_common_structure(s, {smooth.num_faces(), star.num_faces()});
}

TEST(DissectSet, AlignmentThroughFlipEventsStaysBijective) {
  // The second mesh is the first rotated about z inside its seed frame, so features move far in
  // the parameter domain and cross each other's warp triangles.
  const auto a = qs::shapes::ellipsoid(1.4, 1, 0.8, 4);
  std::vector<qs::Vec3> dirs;
  for (int i = 0; i < 6; ++i) dirs.push_back(qs::Vec3(std::cos(i * 1.1), std::sin(i * 1.1), 1.2));
  std::vector<qs::Vec3> dirs_b;
  for (int i = 0; i < 6; ++i) dirs_b.push_back(qs::Vec3(std::cos(i * 1.1 + 2.0), std::sin(i * 1.1 + 2.0), 0.6));
  MeshToDissect ma{&a, equator_seeds(a), features_at(a, dirs), "a"};
  MeshToDissect mb{&a, ma.seeds, features_at(a, dirs_b), "a-rotated-features"};
  // Both the default maps (geodesic seed curves, cotangent weights) and the old ones (edge paths,
  // mean-value weights). Warps without flip events fold mesh faces that straddle warp edges here
  // (node 0.4 and below: 1-5 folded faces per mesh, more after every local refinement) unless the
  // warp's edges are cut into the patch first, as the alignment does.
  qs::dissect::DissectOptions old_maps;
  old_maps.geodesic_seed_curves = false;
  old_maps.intrinsic_cotan = false;
  for (const auto& o : {qs::dissect::DissectOptions{}, old_maps}) {
    SCOPED_TRACE(o.intrinsic_cotan ? "default maps" : "old maps");
    const DissectionSet s = qs::dissect::dissect_set({ma, mb}, o);
    EXPECT_GT(s.warp_events, 0) << "the test should exercise flip events";
    expect_common_structure(s, {a.num_faces(), a.num_faces()});
  }
}

TEST(DissectSet, FoldedNewMapsFallBackToTheOldOnes) {
  // The flip-event set with max_depth 1: the default maps (geodesic curves, cotangent weights) end
  // with folded leaves (a warp with flip events at depth 1, no split left), the old ones (edge
  // paths, mean-value weights) do not; the safety net keeps the old maps' result and says why.
  const auto a = qs::shapes::ellipsoid(1.4, 1, 0.8, 4);
  std::vector<qs::Vec3> dirs, dirs_b;
  for (int i = 0; i < 6; ++i) dirs.push_back(qs::Vec3(std::cos(i * 1.1), std::sin(i * 1.1), 1.2));
  for (int i = 0; i < 6; ++i) dirs_b.push_back(qs::Vec3(std::cos(i * 1.1 + 2.0), std::sin(i * 1.1 + 2.0), 0.6));
  MeshToDissect ma{&a, equator_seeds(a), features_at(a, dirs), "a"};
  MeshToDissect mb{&a, ma.seeds, features_at(a, dirs_b), "b"};
  auto folded = [](const DissectionSet& s) {
    long n = 0;
    for (const auto& d : s.meshes)
      for (const auto& p : d.chart.patches) n += p.flipped_faces + p.zero_area_faces;
    return n;
  };
  qs::dissect::DissectOptions o;
  o.max_depth = 1;
  o.area_extra_depth = 0;  // no split past depth 1 for the large folded patches either
  o.fallback_maps = false;
  const DissectionSet raw = qs::dissect::dissect_set({ma, mb}, o);
  ASSERT_GT(folded(raw), 0) << "the test needs a set that the new maps leave folded";
  EXPECT_TRUE(raw.geodesic_seed_curves);
  EXPECT_TRUE(raw.intrinsic_cotan);
  EXPECT_TRUE(raw.maps_fallback.empty());
  o.fallback_maps = true;
  const DissectionSet s = qs::dissect::dissect_set({ma, mb}, o);
  EXPECT_EQ(folded(s), 0);
  EXPECT_FALSE(s.geodesic_seed_curves);
  EXPECT_FALSE(s.intrinsic_cotan);
  EXPECT_THAT(s.maps_fallback, HasSubstr(std::to_string(folded(raw)) + " folded uv faces with geodesic+cotan (patch "));
  expect_common_structure(s, {a.num_faces(), a.num_faces()});
  // The same as asking for the old maps.
  qs::dissect::DissectOptions old = o;
  old.geodesic_seed_curves = false;
  old.intrinsic_cotan = false;
  const DissectionSet direct = qs::dissect::dissect_set({ma, mb}, old);
  EXPECT_TRUE(direct.maps_fallback.empty());
  ASSERT_EQ(direct.meshes.size(), s.meshes.size());
  for (size_t i = 0; i < s.meshes.size(); ++i) {
    EXPECT_EQ(direct.meshes[i].chart.face_uv, s.meshes[i].chart.face_uv);
    EXPECT_EQ(direct.meshes[i].base.quads, s.meshes[i].base.quads);
  }
  EXPECT_EQ(qs::dissect::maps_name(true, true), "geodesic+cotan");
  EXPECT_EQ(qs::dissect::maps_name(false, false), "edge+mean-value");
}

TEST(DissectSet, FeaturesMustMatchAcrossTheSet) {
  const auto a = qs::shapes::ellipsoid(1.2, 1, 0.9, 3);
  MeshToDissect ma{&a, equator_seeds(a), features_at(a, {{0, 0, 1}, {0.3, 0.3, 1}}), "a.obj"};
  MeshToDissect mb{&a, ma.seeds, features_at(a, {{0, 0, 1}}), "b.obj"};
  try {
    qs::dissect::dissect_set({ma, mb});
    FAIL() << "expected InvalidInput";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("b.obj lacks 'f1'"));
  }
  // Two features on one vertex; a feature on a seed.
  MeshToDissect md{&a, ma.seeds, features_at(a, {{0, 0, 1}, {0, 0, 1}}), "d.obj"};
  EXPECT_THROW(qs::dissect::dissect_set({md}), qs::InvalidInput);
  MeshToDissect me{&a, ma.seeds, {{"on-seed", ma.seeds->at(0), {}}}, "e.obj"};
  EXPECT_THROW(qs::dissect::dissect_set({me}), qs::InvalidInput);
}

TEST(DissectSet, FeatureOnAFaceBecomesAVertex) {
  const auto a = qs::shapes::ellipsoid(1.2, 1, 0.9, 3);
  const int f = 17;
  qs::dissect::Feature on_face{"mid", -1, {f, {0.2, 0.3, 0.5}}};
  const auto d = qs::dissect::dissect_set({{&a, equator_seeds(a), {on_face}, "a"}});
  ASSERT_EQ(d.meshes[0].features.size(), 1u);
  const auto& fp = d.meshes[0].features[0];
  EXPECT_GE(fp.vertex, a.num_vertices()) << "a new vertex";
  const qs::Vec3 want = 0.2 * a.positions[a.faces[f][0]] + 0.3 * a.positions[a.faces[f][1]] +
                        0.5 * a.positions[a.faces[f][2]];
  EXPECT_LT((d.meshes[0].chart.mesh.positions[fp.vertex] - want).norm(), 1e-12);
  check_dissection(d.meshes[0], a.num_faces());
}

TEST(DissectSet, SeedLoopIsReroutedSoThatFeaturesKeepTheirSide) {
  // f1 is above the equator loop on a and below it on c: c's shortest loop is routed again (under
  // f1), so that every feature lies in the same seed patch of both meshes.
  const auto a = qs::shapes::ellipsoid(1.2, 1, 0.9, 3);
  MeshToDissect ma{&a, equator_seeds(a), features_at(a, {{0, 0, 1}, {0.3, 0.3, 1}}), "a.obj"};
  MeshToDissect mc{&a, ma.seeds, features_at(a, {{0, 0, 1}, {0.3, 0.3, -1}}), "c.obj"};
  const DissectionSet s = qs::dissect::dissect_set({ma, mc});
  for (size_t k = 0; k < 2; ++k)
    EXPECT_EQ(s.meshes[0].chart.patches[s.meshes[0].features[k].patch].name.substr(0, 1),
              s.meshes[1].chart.patches[s.meshes[1].features[k].patch].name.substr(0, 1))
        << s.meshes[0].features[k].name;
  expect_common_structure(s, {a.num_faces(), a.num_faces()});
}

TEST(DissectSet, RerouteForSidesMovesOnePathAroundAVertex) {
  const auto a = qs::shapes::ellipsoid(1.2, 1, 0.9, 3);
  const auto seeds = equator_seeds(a);
  const qs::dissect::SeedLoop loop = qs::dissect::trace_seed_loop(a, seeds);
  const int below = vertex_towards(a, {0.3, 0.3, -1}), above = vertex_towards(a, {0, 0, 1});
  const std::vector<int> before = qs::dissect::sides_of_vertices(a, loop, {below, above});
  ASSERT_NE(before[0], before[1]);
  // Ask for `below` on the side of `above`.
  const qs::dissect::SeedLoop r =
      qs::dissect::reroute_for_sides(a, loop, {}, {{below, before[1]}, {above, before[1]}});
  const std::vector<int> after = qs::dissect::sides_of_vertices(a, r, {below, above});
  EXPECT_EQ(after[0], before[1]);
  EXPECT_EQ(after[1], before[1]);
  EXPECT_EQ(r.seeds, loop.seeds);
}

TEST(DissectSet, RerouteForSidesMovesAPathAroundAVertexRightBesideIt) {
  // A vertex pulled to 2% of an edge from a vertex of the loop: the waypoint across it still has
  // room (at least two mean edge lengths away).
  auto a = qs::shapes::ellipsoid(1.2, 1, 0.9, 3);
  const qs::dissect::SeedLoop loop = qs::dissect::trace_seed_loop(a, equator_seeds(a));
  const std::vector<int>& path = loop.paths[0];
  ASSERT_GE(path.size(), 3u);
  const int x = path[path.size() / 2];
  std::set<int> on_loop;
  for (const auto& p : loop.paths) on_loop.insert(p.begin(), p.end());
  int f = -1;
  for (const qs::Tri& t : a.faces)
    for (int k = 0; k < 3 && f < 0; ++k)
      if (t[k] == x)
        for (int j = 1; j < 3; ++j)
          if (!on_loop.count(t[(k + j) % 3])) f = t[(k + j) % 3];
  ASSERT_GE(f, 0);
  a.positions[f] = a.positions[x] + 0.02 * (a.positions[f] - a.positions[x]);
  const int far = vertex_towards(a, {0, 0, 1});
  const std::vector<int> before = qs::dissect::sides_of_vertices(a, loop, {f, far});
  const qs::dissect::SeedLoop r =
      qs::dissect::reroute_for_sides(a, loop, {}, {{f, 1 - before[0]}, {far, before[1]}});
  const std::vector<int> after = qs::dissect::sides_of_vertices(a, r, {f, far});
  EXPECT_EQ(after[0], 1 - before[0]);
  EXPECT_EQ(after[1], before[1]);
  EXPECT_EQ(r.seeds, loop.seeds);
}

TEST(DissectSet, SeedsGivenAsSurfacePointsAreExactPatchCorners) {
  const auto a = qs::shapes::ellipsoid(1.2, 1, 0.9, 3);
  const auto b = deform(a);
  // Points inside faces near the equator, and one on an edge.
  const auto vs = equator_seeds(a);
  std::array<qs::landmarks::SurfacePoint, 4> pts;
  for (int i = 0; i < 4; ++i) {
    int f = 0;
    for (; f < a.num_faces(); ++f)
      if (a.faces[f][0] == vs[i]) break;
    pts[i] = {f, {0.5, 0.3, 0.2}};
  }
  pts[3].bary = {0.6, 0.4, 0.0};
  MeshToDissect ma{&a, std::nullopt, {}, "a"};
  ma.seed_points = pts;
  MeshToDissect mb{&b, std::nullopt, {}, "b"};
  mb.seed_points = pts;
  qs::dissect::DissectOptions o;
  o.tau = 1.2;
  const DissectionSet s = qs::dissect::dissect_set({ma, mb}, o);
  for (size_t m = 0; m < 2; ++m) {
    const auto& d = s.meshes[m];
    const qs::TriMesh& in = m == 0 ? a : b;
    for (int i = 0; i < 4; ++i) {
      const auto& sp = d.seed_placements[i];
      EXPECT_TRUE(sp.inserted);
      EXPECT_EQ(sp.vertex, d.seeds[i]);
      EXPECT_GE(sp.vertex, in.num_vertices());
      const qs::Vec3 want = qs::landmarks::position_of(in, pts[i]);
      EXPECT_LT((d.chart.mesh.positions[sp.vertex] - want).norm(), 1e-12);
      // The seed is a corner of every patch around it: its wedge uv is a corner of the square.
      int wedges = 0;
      for (int f = 0; f < d.chart.mesh.num_faces(); ++f)
        for (int j = 0; j < 3; ++j)
          if (d.chart.mesh.faces[f][j] == sp.vertex) {
            const qs::Vec2 uv = d.chart.face_uv[f][j];
            const double dx = std::min(std::abs(uv.x()), std::abs(uv.x() - 1));
            const double dy = std::min(std::abs(uv.y()), std::abs(uv.y() - 1));
            EXPECT_LT(std::max(dx, dy), 1e-9) << "seed " << i << " uv " << uv.transpose();
            ++wedges;
          }
      EXPECT_GT(wedges, 0);
    }
  }
  expect_common_structure(s, {a.num_faces(), b.num_faces()});
}

// Landmarks that do not correspond (random vertices, as a user may pick by mistake) fold patch
// maps. Such a map can put interior vertices outside the unit square (here at (-5.9, -5.3)); the
// feature alignment used to hand them to the warp, which refused them as invalid input: exit 2
// with a message about the warp. Now the result is a dissection (with folded leaves, qs-dissect's
// exit 4 that tells to check the landmarks) or a SolverError, never InvalidInput.
TEST(DissectSet, LandmarksThatDoNotCorrespondAreNotInvalidInput) {
  const std::filesystem::path file = qs::testing::shared_meshes_dir() / "camel_4k_fixed.obj";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << "no " << file;
  const auto validated = qs::mesh::validate(qs::io::read_mesh(file).mesh);
  ASSERT_TRUE(validated.report.accepted);
  const qs::TriMesh& m = validated.mesh;
  auto features = [](int a, int b, int c) {
    return std::vector<qs::dissect::Feature>{{"a", a, {}}, {"b", b, {}}, {"c", c, {}}};
  };
  MeshToDissect ma{&m, std::array<int, 4>{1654, 985, 822, 309}, features(1416, 450, 943), "camel a"};
  MeshToDissect mb{&m, std::array<int, 4>{724, 1115, 1266, 1515}, features(181, 523, 1561), "camel b"};
  qs::dissect::DissectOptions o;
  o.max_depth = 2;  // the failure came at depth 1; deeper only costs time
  o.area_extra_depth = 0;
  o.fallback_maps = false;
  o.stretch_iterations = 0;
  try {
    const DissectionSet s = qs::dissect::dissect_set({ma, mb}, o);
    ASSERT_EQ(s.meshes.size(), 2u);
    EXPECT_EQ(s.meshes[0].chart.patches.size(), s.meshes[1].chart.patches.size());
  } catch (const qs::SolverError&) {
    // the other documented outcome for meshes that cannot be dissected together
  } catch (const qs::InvalidInput& e) {
    ADD_FAILURE() << "valid meshes and landmarks refused as invalid input: " << e.what();
  }
}

// The measurement hooks (DissectOptions::replace_seed_loops, replace_node_maps) as
// qs-bench-stage-attribution uses them: with A's loop and A's node maps put into B (one
// connectivity, other positions), B's chart is A's: the same cut mesh and the same (u, v).
TEST(DissectSet, ExactStagesFromTheFirstMeshGiveItsChart) {
  const auto a = qs::shapes::bumpy_sphere(0.08, 3, 4);
  const auto b = deform(a);
  MeshToDissect ma{&a, equator_seeds(a), {}, "a"};
  MeshToDissect mb{&b, ma.seeds, {}, "b"};
  qs::dissect::DissectOptions o;
  // Splits by area, every leaf within tau: no leaf rounds or repairs, which run on each surface.
  o.tau = 10;
  o.max_patch_area = 0.1;
  o.stretch_iterations = 0;
  o.geodesic_seed_curves = false;
  int loops = 0, maps = 0;
  o.replace_seed_loops = [&](std::vector<qs::dissect::GeodesicLoop>& l) {
    ASSERT_EQ(l.size(), 2u);
    l[1].loop = l[0].loop;
    ++loops;
  };
  o.replace_node_maps = [&](std::vector<qs::dissect::DissectOptions::NodeMapRef>& m, bool) {
    ASSERT_EQ(*m[1].vertices, *m[0].vertices);
    *m[1].uv = *m[0].uv;
    ++maps;
  };
  const DissectionSet s = qs::dissect::dissect_set({ma, mb}, o);
  EXPECT_EQ(loops, 1);
  EXPECT_GT(s.meshes[0].chart.patches.size(), 2u);
  EXPECT_GT(maps, 2);
  const auto& ca = s.meshes[0].chart;
  const auto& cb = s.meshes[1].chart;
  ASSERT_EQ(cb.mesh.faces, ca.mesh.faces);
  EXPECT_EQ(cb.face_patch, ca.face_patch);
  for (size_t f = 0; f < ca.face_uv.size(); ++f)
    for (int k = 0; k < 3; ++k) ASSERT_EQ(cb.face_uv[f][k], ca.face_uv[f][k]) << "face " << f;
  // Without the hooks the deformed mesh has maps of its own.
  o.replace_seed_loops = nullptr;
  o.replace_node_maps = nullptr;
  const DissectionSet own = qs::dissect::dissect_set({ma, mb}, o);
  EXPECT_NE(own.meshes[1].chart.face_uv, own.meshes[0].chart.face_uv);
}
