// Adaptive semi-regular remeshing (paper 4.2): balanced quadtrees, T-vertex templates, one
// connectivity for a set.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include "qs/core/error.h"
#include "qs/remesh/adaptive.h"
#include "qs/remesh/quality.h"
#include "qs/remesh/uniform.h"
#include "qs/shapes/shapes.h"
#include "remesh_checks.h"

using qs::remesh::QuadNode;
using qs::remesh_test::count_coincident;
using qs::remesh_test::equator_seeds;
using qs::remesh_test::expect_closed_manifold;
using qs::remesh_test::expect_valid_sphere;
using qs::remesh_test::pair_dissection;
using qs::remesh_test::seed_patches;
using qs::remesh_test::sphere_dissection;
using qs::remesh_test::star_dissection;
using ::testing::HasSubstr;

namespace {

std::set<std::array<int, 3>> face_set(const std::vector<qs::Tri>& faces) {
  std::set<std::array<int, 3>> s;
  for (auto f : faces) {
    std::rotate(f.begin(), std::min_element(f.begin(), f.end()), f.end());  // same cycle, canonical start
    s.insert(f);
  }
  return s;
}

// Leaves must tile every patch's unit square exactly, and adjacent leaves (inside a patch, or
// across a patch side) differ by at most one level. Checked on the finest grid: per patch an
// array of leaf levels per cell; across sides through the base topology's twin sides.
void expect_balanced_tiling(const qs::remesh::BaseTopology& t, const qs::remesh::QuadForest& f) {
  const int top = f.max_level, n = 1 << top;
  std::vector<std::vector<int>> level(t.num_patches(), std::vector<int>(n * n, -1));
  for (const auto& l : f.leaves) {
    const int s = 1 << (top - l.level);
    for (int j = l.j * s; j < (l.j + 1) * s; ++j)
      for (int i = l.i * s; i < (l.i + 1) * s; ++i) {
        EXPECT_EQ(level[l.patch][j * n + i], -1) << "leaves overlap";
        level[l.patch][j * n + i] = l.level;
      }
  }
  for (const auto& lv : level)
    for (int x : lv) ASSERT_GE(x, 0) << "a cell is covered by no leaf";
  int bad = 0;
  for (int p = 0; p < t.num_patches(); ++p)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int a = level[p][j * n + i];
        if (i + 1 < n && std::abs(a - level[p][j * n + i + 1]) > 1) ++bad;
        if (j + 1 < n && std::abs(a - level[p][(j + 1) * n + i]) > 1) ++bad;
      }
  // Across patch sides: cell s along side k (from corner k) faces cell n-1-s of the twin side.
  auto cell_on_side = [n](int k, int s) {
    switch (k) {
      case 0: return s;
      case 1: return s * n + (n - 1);
      case 2: return (n - 1) * n + (n - 1 - s);
      default: return (n - 1 - s) * n;
    }
  };
  for (int p = 0; p < t.num_patches(); ++p)
    for (int k = 0; k < 4; ++k) {
      const auto tw = t.twin(p, k);
      for (int s = 0; s < n; ++s)
        if (std::abs(level[p][cell_on_side(k, s)] - level[tw.patch][cell_on_side(tw.side, n - 1 - s)]) > 1) ++bad;
    }
  EXPECT_EQ(bad, 0) << "adjacent leaves more than one level apart";
}

void check_forest_mesh(const qs::remesh::BaseTopology& t, const std::vector<QuadNode>& split, const std::string& what) {
  SCOPED_TRACE(what);
  const auto f = qs::remesh::balance_forest(t, split);
  expect_balanced_tiling(t, f);
  // Every requested split is kept, with its ancestors.
  std::set<QuadNode> s(f.split.begin(), f.split.end());
  for (const auto& n : split) {
    EXPECT_TRUE(s.count(n));
    if (n.level > 0) { EXPECT_TRUE(s.count({n.patch, n.level - 1, n.i / 2, n.j / 2})); }
  }
  const auto c = qs::remesh::adaptive_connectivity(t, f);
  EXPECT_EQ(expect_closed_manifold(c.faces, c.num_vertices()), 2);
  // Each leaf corner is a vertex (no leaf is swallowed), found through the uniform numbering.
  EXPECT_EQ(c.level, f.max_level);
  const qs::remesh::UniformNumbering num(t, f.max_level);
  std::set<std::pair<int, qs::Vec2>, bool (*)(const std::pair<int, qs::Vec2>&, const std::pair<int, qs::Vec2>&)> sites(
      [](const std::pair<int, qs::Vec2>& a, const std::pair<int, qs::Vec2>& b) {
        return std::make_tuple(a.first, a.second.x(), a.second.y()) < std::make_tuple(b.first, b.second.x(), b.second.y());
      });
  for (int v = 0; v < c.num_vertices(); ++v) sites.insert({c.vertex_patch[v], c.vertex_uv[v]});
  EXPECT_EQ(sites.size(), static_cast<size_t>(c.num_vertices())) << "two vertices at one site";
}

// Random split sets: every node of level < depth is split with probability `rate`.
std::vector<QuadNode> random_splits(int patches, int depth, double rate, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<QuadNode> out;
  std::vector<QuadNode> todo;
  for (int p = 0; p < patches; ++p) todo.push_back({p, 0, 0, 0});
  while (!todo.empty()) {
    const QuadNode n = todo.back();
    todo.pop_back();
    if (n.level >= depth || u(rng) > rate) continue;
    out.push_back(n);
    for (int c = 0; c < 4; ++c) todo.push_back({n.patch, n.level + 1, 2 * n.i + (c & 1), 2 * n.j + (c >> 1)});
  }
  return out;
}

}  // namespace

TEST(AdaptiveConnectivity, RandomQuadtreesOnTheSeedPatchesStayManifold) {
  // Two patches sharing all four sides: every corner has valence 2.
  const auto t = qs::remesh::build_base_topology(seed_patches());
  check_forest_mesh(t, {}, "roots only");
  check_forest_mesh(t, {{0, 0, 0, 0}}, "one patch split once");
  check_forest_mesh(t, {{1, 0, 0, 0}, {1, 1, 0, 0}}, "one corner of the second patch twice");
  check_forest_mesh(t, {{0, 0, 0, 0}, {0, 1, 1, 1}, {0, 2, 3, 3}, {0, 3, 7, 7}}, "deep at a valence-2 corner");
  for (unsigned seed = 1; seed <= 40; ++seed)
    check_forest_mesh(t, random_splits(2, 5, 0.55, seed), "random seed " + std::to_string(seed));
}

TEST(AdaptiveConnectivity, RandomQuadtreesOnManyPatchesStayManifold) {
  const auto t = qs::remesh::build_base_topology(star_dissection().chart.patches);
  ASSERT_GT(t.num_patches(), 2);
  for (unsigned seed = 1; seed <= 15; ++seed)
    check_forest_mesh(t, random_splits(t.num_patches(), 4, 0.5, seed), "random seed " + std::to_string(seed));
}

TEST(AdaptiveConnectivity, BalanceDoesNotDependOnTheOrderOfTheSplits) {
  const auto t = qs::remesh::build_base_topology(star_dissection().chart.patches);
  auto split = random_splits(t.num_patches(), 5, 0.45, 7);
  const auto a = qs::remesh::balance_forest(t, split);
  std::reverse(split.begin(), split.end());
  const auto b = qs::remesh::balance_forest(t, split);
  EXPECT_EQ(a.split, b.split);
  EXPECT_EQ(a.leaves, b.leaves);
  EXPECT_EQ(qs::remesh::adaptive_connectivity(t, a).faces, qs::remesh::adaptive_connectivity(t, b).faces);
}

TEST(AdaptiveConnectivity, UniformTreesGiveTheUniformMesh) {
  const auto t = qs::remesh::build_base_topology(star_dissection().chart.patches);
  for (int level = 0; level <= 3; ++level) {
    std::vector<QuadNode> all;
    for (int p = 0; p < t.num_patches(); ++p)
      for (int l = 0; l < level; ++l)
        for (int j = 0; j < (1 << l); ++j)
          for (int i = 0; i < (1 << l); ++i) all.push_back({p, l, i, j});
    const auto c = qs::remesh::adaptive_connectivity(t, qs::remesh::balance_forest(t, all));
    const auto u = qs::remesh::uniform_connectivity(t, level);
    EXPECT_EQ(c.vertex_patch, u.vertex_patch) << "level " << level;
    EXPECT_EQ(c.vertex_uv, u.vertex_uv);
    EXPECT_EQ(face_set(c.faces), face_set(u.faces));
  }
}

TEST(AdaptiveConnectivity, RejectsNodesOutsideTheTrees) {
  const auto t = qs::remesh::build_base_topology(seed_patches());
  for (const QuadNode& n : {QuadNode{2, 0, 0, 0}, QuadNode{0, 1, 2, 0}, QuadNode{0, -1, 0, 0},
                            QuadNode{0, qs::remesh::kMaxAdaptiveLevel, 0, 0}}) {
    try {
      qs::remesh::balance_forest(t, {n});
      FAIL() << "node accepted";
    } catch (const qs::InvalidInput& e) {
      EXPECT_THAT(e.what(), HasSubstr("quadtree node"));
    }
  }
}

TEST(AdaptiveRemesh, TinyEpsilonReachesTheUniformFinestLevel) {
  const auto& chart = star_dissection().chart;
  qs::remesh::AdaptiveOptions o;
  o.epsilon = 1e-12;
  o.max_level = 3;
  const auto a = qs::remesh::remesh_adaptive(std::vector<qs::dissect::Chart>{chart}, o);
  const auto u = qs::remesh::remesh_uniform(chart, 3);
  EXPECT_EQ(a.remesh.connectivity.num_vertices(), u.connectivity.num_vertices());
  EXPECT_EQ(face_set(a.remesh.connectivity.faces), face_set(u.connectivity.faces));
  EXPECT_EQ(a.remesh.positions[0], u.positions);
  EXPECT_EQ(a.stats.balance_splits, 0);
  EXPECT_EQ(a.stats.unresolved_leaves, static_cast<int>(a.forest.leaves.size()));
  EXPECT_EQ(a.stats.leaves_per_level.back(), static_cast<int>(a.forest.leaves.size()));
}

TEST(AdaptiveRemesh, LargeEpsilonGivesTheCoarsestMesh) {
  const auto& chart = star_dissection().chart;
  qs::remesh::AdaptiveOptions o;
  o.epsilon = 10;
  const auto a = qs::remesh::remesh_adaptive(std::vector<qs::dissect::Chart>{chart}, o);
  const auto u = qs::remesh::remesh_uniform(chart, 0);
  EXPECT_EQ(a.forest.leaves.size(), chart.patches.size());
  EXPECT_EQ(a.remesh.connectivity.faces, u.connectivity.faces);
  EXPECT_EQ(a.remesh.positions[0], u.positions);
  // min_level still refines.
  o.min_level = 2;
  const auto b = qs::remesh::remesh_adaptive(std::vector<qs::dissect::Chart>{chart}, o);
  EXPECT_EQ(face_set(b.remesh.connectivity.faces), face_set(qs::remesh::remesh_uniform(chart, 2).connectivity.faces));
}

TEST(AdaptiveRemesh, RefinesWhereTheSurfaceIsCurvedAndHonoursEpsilon) {
  // A sphere with bumps: a smaller epsilon gives more vertices, always a valid closed mesh, and
  // the chart's vertices end up within a small multiple of epsilon of the remesh.
  const auto m = qs::shapes::bumpy_sphere(0.15, 4, 4);
  const auto d = qs::dissect::dissect(m, equator_seeds(m));
  const double diag = qs::bounding_box(m.positions).diagonal();
  int previous = 0;
  for (double eps : {0.05, 0.02, 0.01, 0.005}) {
    SCOPED_TRACE("epsilon " + std::to_string(eps));
    qs::remesh::AdaptiveOptions o;
    o.epsilon = eps;
    o.max_level = 7;
    const auto a = qs::remesh::remesh_adaptive(std::vector<qs::dissect::Chart>{d.chart}, o);
    const auto& c = a.remesh.connectivity;
    EXPECT_EQ(expect_closed_manifold(c.faces, c.num_vertices()), 2);
    expect_valid_sphere(a.remesh.mesh(0), "adaptive");
    EXPECT_EQ(count_coincident(a.remesh.positions[0], 1e-9 * diag), 0);
    expect_balanced_tiling(qs::remesh::build_base_topology(d.chart.patches), a.forest);
    EXPECT_EQ(a.stats.unresolved_leaves, 0);
    EXPECT_LE(a.stats.max_leaf_error, eps);
    EXPECT_GT(c.num_vertices(), previous);
    previous = c.num_vertices();
    EXPECT_LT(c.num_vertices(), qs::remesh::remesh_uniform(d.chart, a.forest.max_level).connectivity.num_vertices());
    // Distance from every chart vertex to the remesh (brute force over the faces).
    const auto& p = a.remesh.positions[0];
    double worst = 0;
    for (const auto& x : d.chart.mesh.positions) {
      double best = 1e300;
      for (const auto& f : c.faces) {
        // Distance to the triangle's plane region, by projection and clamping to its edges.
        const qs::Vec3 &a0 = p[f[0]], &a1 = p[f[1]], &a2 = p[f[2]];
        const qs::Vec3 n = (a1 - a0).cross(a2 - a0);
        if ((x - a0).norm() - std::max((a1 - a0).norm(), (a2 - a0).norm()) > best) continue;  // cannot be nearer
        double dist;
        const qs::Vec3 q = n.squaredNorm() > 0 ? qs::Vec3(x - n.dot(x - a0) / n.squaredNorm() * n) : x;
        const double w0 = (a1 - q).cross(a2 - q).dot(n), w1 = (a2 - q).cross(a0 - q).dot(n), w2 = (a0 - q).cross(a1 - q).dot(n);
        if (n.squaredNorm() > 0 && w0 >= 0 && w1 >= 0 && w2 >= 0) {
          dist = (x - q).norm();
        } else {
          auto seg = [&](const qs::Vec3& s0, const qs::Vec3& s1) {
            const double t = std::clamp((x - s0).dot(s1 - s0) / (s1 - s0).squaredNorm(), 0.0, 1.0);
            return (x - s0 - t * (s1 - s0)).norm();
          };
          dist = std::min({seg(a0, a1), seg(a1, a2), seg(a2, a0)});
        }
        best = std::min(best, dist);
      }
      worst = std::max(worst, best);
    }
    EXPECT_LT(worst / diag, 1.5 * eps);  // measured 0.91-0.97 eps: the templates only add points
  }
}

TEST(AdaptiveRemesh, SetUsesTheMaximumErrorOverItsMeshes) {
  const auto& s = pair_dissection();
  const std::vector<const qs::dissect::Chart*> charts = {&s.meshes[0].chart, &s.meshes[1].chart};
  qs::remesh::AdaptiveOptions o;
  o.epsilon = 0.01;
  o.max_level = 5;
  const auto set = qs::remesh::remesh_adaptive(charts, o);
  ASSERT_EQ(set.remesh.positions.size(), 2u);
  for (int i = 0; i < 2; ++i) expect_valid_sphere(set.remesh.mesh(i), "set mesh " + std::to_string(i));
  EXPECT_EQ(expect_closed_manifold(set.remesh.connectivity.faces, set.remesh.connectivity.num_vertices()), 2);
  // Each mesh alone needs a subset of the set's splits (balance is monotone).
  const std::set<QuadNode> all(set.forest.split.begin(), set.forest.split.end());
  std::vector<int> alone_vertices;
  for (int i = 0; i < 2; ++i) {
    const auto a = qs::remesh::remesh_adaptive({charts[i]}, o);
    for (const auto& n : a.forest.split) EXPECT_TRUE(all.count(n)) << "mesh " << i << " split missing from the set";
    alone_vertices.push_back(a.remesh.connectivity.num_vertices());
  }
  EXPECT_GE(set.remesh.connectivity.num_vertices(), std::max(alone_vertices[0], alone_vertices[1]));
  EXPECT_LT(alone_vertices[0], alone_vertices[1]) << "the smooth ellipsoid should need fewer vertices than the star";
}

TEST(AdaptiveRemesh, BadOptions) {
  const std::vector<qs::dissect::Chart> charts = {sphere_dissection().chart};
  auto expect_invalid = [&](qs::remesh::AdaptiveOptions o, const std::string& part) {
    try {
      qs::remesh::remesh_adaptive(charts, o);
      FAIL() << part << ": accepted";
    } catch (const qs::InvalidInput& e) {
      EXPECT_THAT(e.what(), HasSubstr(part));
    }
  };
  qs::remesh::AdaptiveOptions o;
  o.epsilon = 0;
  expect_invalid(o, "epsilon");
  o.epsilon = std::nan("");
  expect_invalid(o, "epsilon");
  o = {};
  o.max_level = qs::remesh::kMaxAdaptiveLevel + 1;
  expect_invalid(o, "max level");
  o = {};
  o.min_level = o.max_level + 1;
  expect_invalid(o, "min level");
  EXPECT_THROW(qs::remesh::remesh_adaptive(std::vector<qs::dissect::Chart>{}), qs::InvalidInput);
  const std::vector<const qs::dissect::Chart*> mixed = {&sphere_dissection().chart, &star_dissection().chart};
  EXPECT_THROW(qs::remesh::remesh_adaptive(mixed), qs::InvalidInput);
}

// ---- Even sampling (AdaptiveCriterion::Size, remesh_even) ------------------------------------

TEST(EvenRemesh, SetIsClosedManifoldWithOneConnectivityAndDeterministic) {
  const auto& s = pair_dissection();
  const std::vector<const qs::dissect::Chart*> charts = {&s.meshes[0].chart, &s.meshes[1].chart};
  const auto a = qs::remesh::remesh_even(charts, 3);
  const auto& c = a.remesh.connectivity;
  ASSERT_EQ(a.remesh.positions.size(), 2u);
  EXPECT_EQ(expect_closed_manifold(c.faces, c.num_vertices()), 2);
  for (int i = 0; i < 2; ++i) {
    expect_valid_sphere(a.remesh.mesh(i), "even mesh " + std::to_string(i));
    const double diag = qs::bounding_box(a.remesh.positions[i]).diagonal();
    EXPECT_EQ(count_coincident(a.remesh.positions[i], 1e-9 * diag), 0);
  }
  expect_balanced_tiling(qs::remesh::build_base_topology(s.meshes[0].chart.patches), a.forest);
  // Every leaf covers at most the bound of the surface in each mesh (none left over at the finest level).
  EXPECT_EQ(a.stats.unresolved_leaves, 0);
  double share_sum = 0;
  for (double x : qs::remesh::patch_area_shares(charts)) share_sum += x;
  EXPECT_GT(share_sum, 1.0) << "two different shapes: the largest shares add up to more than the surface";
  EXPECT_LE(a.stats.max_leaf_error,
            qs::remesh::even_options(3, static_cast<int>(charts[0]->patches.size()), share_sum).max_area);
  // About the uniform level's face count (the bound grows with the share sum).
  const double ratio = static_cast<double>(c.faces.size()) /
                       static_cast<double>(qs::remesh::remesh_uniform(*charts[0], 3).connectivity.faces.size());
  EXPECT_GT(ratio, 0.5);
  EXPECT_LT(ratio, 2.0);
  // Deterministic: the same input gives the same faces and the same positions, bit for bit.
  const auto b = qs::remesh::remesh_even(charts, 3);
  EXPECT_EQ(b.remesh.connectivity.faces, c.faces);
  EXPECT_EQ(b.remesh.positions, a.remesh.positions);
  // The set's splits include each mesh's own under the same bound (max over the set).
  const std::set<QuadNode> all(a.forest.split.begin(), a.forest.split.end());
  const auto o = qs::remesh::even_options(3, static_cast<int>(charts[0]->patches.size()), share_sum);
  for (int i = 0; i < 2; ++i)
    for (const auto& n : qs::remesh::remesh_adaptive({charts[i]}, o).forest.split) EXPECT_TRUE(all.count(n));
}

TEST(EvenRemesh, EqualPatchesGiveTheUniformLevel) {
  // The two seed patches of a sphere split at its equator cover half the surface each, evenly
  // mapped enough that every level-n node is under 2 / (P 4^n) and every level-(n-1) node over it.
  const auto& chart = sphere_dissection().chart;
  for (int level : {1, 2, 3}) {
    const auto a = qs::remesh::remesh_even({&chart}, level);
    qs::remesh::UniformOptions uo;  // the even remesh cuts its cells as qs-remesh's default does
    uo.diagonals = qs::remesh::DiagonalRule::BestAngle;
    const auto u = qs::remesh::remesh_uniform(chart, level, uo);
    EXPECT_EQ(face_set(a.remesh.connectivity.faces), face_set(u.connectivity.faces)) << "level " << level;
    EXPECT_EQ(a.remesh.positions[0].size(), u.positions.size());
  }
}

TEST(EvenRemesh, SamplesFollowTheAreaNotThePatchCount) {
  // The star blob's patches differ in size: the uniform grid gives each the same samples, the even
  // remesh about the same count spread by area, so its vertex density is more even.
  const auto& chart = star_dissection().chart;
  const auto u = qs::remesh::remesh_uniform(chart, 3);
  const auto e = qs::remesh::remesh_even({&chart}, 3);
  const auto du = qs::remesh::vertex_density(u.mesh());
  const auto de = qs::remesh::vertex_density(e.remesh.mesh(0));
  EXPECT_LT(de.spread, du.spread);
  const double ratio = static_cast<double>(e.remesh.connectivity.faces.size()) / u.connectivity.faces.size();
  EXPECT_GT(ratio, 0.5);
  EXPECT_LT(ratio, 2.0);
  EXPECT_THROW(qs::remesh::even_options(-1, 4), qs::InvalidInput);
  EXPECT_THROW(qs::remesh::even_options(2, 0), qs::InvalidInput);
  EXPECT_THROW(qs::remesh::even_options(2, 4, 0.5), qs::InvalidInput);
  qs::remesh::AdaptiveOptions o = qs::remesh::even_options(2, 4);
  o.max_area = 0;
  EXPECT_THROW(qs::remesh::remesh_adaptive(std::vector<qs::dissect::Chart>{chart}, o), qs::InvalidInput);
}
