// The exact merge of two charts (qs-merge, SMCC 3.5-3.7): invariants on hand-made charts with every
// degenerate case (coinciding vertices, a vertex on an edge, collinear edges, crossings through
// a vertex), on dissected spheres of two resolutions, and the merge of a chart with itself.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <set>

#include "qs/core/error.h"
#include "qs/dissect/dissection.h"
#include "qs/merge/merge.h"
#include "qs/shapes/shapes.h"
#include "../common/test_support.h"

using qs::Vec2;
using qs::Vec3;
using qs::dissect::Chart;
using qs::merge::Merged;
using ::testing::HasSubstr;

using qs::test::vertex_towards;

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;

int orient(const Vec2& p, const Vec2& q, const Vec2& r) {
  return static_cast<int>(CGAL::orientation(K::Point_2(p.x(), p.y()), K::Point_2(q.x(), q.y()), K::Point_2(r.x(), r.y())));
}

// A closed "pillow": the unit square twice, front (patch 0, z >= 0) and back (patch 1, z <= 0),
// glued along the border. An n x n grid per side whose cells are cut by the diagonal (0,0)-(1,1)
// (`rising`) or (1,0)-(0,1) on the front, the other one on the back (else both sides would cut
// the same corner off: one triangle twice). Patch 1's uv is the front's mirrored in u.
Chart pillow(int n, bool rising_front) {
  const bool rising_back = !rising_front;
  Chart c;
  std::map<std::pair<int, int>, int> border;  // grid (i, j) on the border -> vertex
  auto h = [](double u, double v) { return 0.8 * u * (1 - u) * v * (1 - v) + 0.1 * std::sin(3 * u) * u * (1 - u); };
  for (int side = 0; side < 2; ++side) {
    std::vector<int> id((n + 1) * (n + 1));
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const bool on_border = i == 0 || j == 0 || i == n || j == n;
        auto it = border.find({i, j});
        if (on_border && it != border.end()) {
          id[j * (n + 1) + i] = it->second;
          continue;
        }
        const double u = static_cast<double>(i) / n, v = static_cast<double>(j) / n;
        id[j * (n + 1) + i] = c.mesh.num_vertices();
        c.mesh.positions.push_back(Vec3(u, v, side == 0 ? h(u, v) : -h(u, v)));
        if (on_border) border[{i, j}] = id[j * (n + 1) + i];
      }
    const bool rising = side == 0 ? rising_front : rising_back;
    auto uv = [&](int i, int j) {
      const Vec2 p(static_cast<double>(i) / n, static_cast<double>(j) / n);
      return side == 0 ? p : Vec2(1 - p.x(), p.y());
    };
    auto add = [&](std::array<std::pair<int, int>, 3> t) {
      if (side == 1) std::swap(t[1], t[2]);  // seen from outside the back is mirrored
      qs::Tri f;
      std::array<Vec2, 3> w;
      for (int k = 0; k < 3; ++k) f[k] = id[t[k].second * (n + 1) + t[k].first], w[k] = uv(t[k].first, t[k].second);
      c.mesh.faces.push_back(f);
      c.face_uv.push_back(w);
      c.face_patch.push_back(side);
    };
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        if (rising) {
          add({{{i, j}, {i + 1, j}, {i + 1, j + 1}}});
          add({{{i, j}, {i + 1, j + 1}, {i, j + 1}}});
        } else {
          add({{{i, j}, {i + 1, j}, {i, j + 1}}});
          add({{{i + 1, j}, {i + 1, j + 1}, {i, j + 1}}});
        }
      }
  }
  c.patches.resize(2);
  c.patches[0].name = "0";
  c.patches[1].name = "1";
  return c;
}

double area3(const std::vector<Vec3>& P, const qs::Tri& t) {
  return 0.5 * (P[t[1]] - P[t[0]]).cross(P[t[2]] - P[t[0]]).norm();
}

// Every "done when" invariant that does not need files.
void expect_exact_merge(const Chart& a, const Chart& b, const Merged& m) {
  const int nv = static_cast<int>(m.positions_a.size());
  ASSERT_EQ(m.positions_b.size(), static_cast<size_t>(nv));
  ASSERT_EQ(m.vertex_a.size(), static_cast<size_t>(nv));
  // Closed, manifold, genus 0: every edge twice, once each way; V - E + F = 2.
  std::map<std::pair<int, int>, int> edges;
  for (const auto& t : m.faces)
    for (int k = 0; k < 3; ++k) ++edges[{t[k], t[(k + 1) % 3]}];
  for (const auto& [e, count] : edges) {
    EXPECT_EQ(count, 1) << "edge " << e.first << "-" << e.second;
    EXPECT_EQ(edges.count({e.second, e.first}), 1u) << "edge " << e.first << "-" << e.second << " has no twin";
  }
  EXPECT_EQ(nv - static_cast<long long>(edges.size()) / 2 + static_cast<long long>(m.faces.size()), 2);
  // Every input vertex once, bitwise.
  for (auto [chart, vmap, pos] : {std::tuple{&a, &m.vertex_a, &m.positions_a}, std::tuple{&b, &m.vertex_b, &m.positions_b}}) {
    std::vector<int> seen(chart->mesh.num_vertices(), 0);
    for (int v = 0; v < nv; ++v) {
      const int c = (*vmap)[v];
      if (c < 0) continue;
      ++seen[c];
      for (int d = 0; d < 3; ++d) EXPECT_EQ((*pos)[v][d], chart->mesh.positions[c][d]) << "vertex " << v;  // bitwise
    }
    for (int c = 0; c < chart->mesh.num_vertices(); ++c) EXPECT_EQ(seen[c], 1) << "chart vertex " << c;
  }
  // Faces: positive in uv; children of each parent sum to the parent's uv and 3D area; normals agree.
  std::vector<double> uv_area(a.patches.size(), 0.0);
  std::vector<double> child_a(a.mesh.num_faces(), 0.0), child_b(b.mesh.num_faces(), 0.0);
  int nonpositive_uv = 0, thin = 0;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    const auto& t = m.faces[f];
    // vertex_uv is in the vertex's lowest patch: faces of other patches need their own uv, so
    // check orientation on faces whose three vertices sit in the face's patch.
    if (m.vertex_patch[t[0]] == m.face_patch[f] && m.vertex_patch[t[1]] == m.face_patch[f] &&
        m.vertex_patch[t[2]] == m.face_patch[f]) {
      const auto &p = m.vertex_uv[t[0]], &q = m.vertex_uv[t[1]], &r = m.vertex_uv[t[2]];
      // The library checks every face exactly on the exact points; the rounded uv written to
      // remesh.json keep that orientation except for faces a rounding thin.
      const double uv_area = std::abs((q - p).x() * (r - p).y() - (q - p).y() * (r - p).x());
      if (uv_area > 1e-24) nonpositive_uv += orient(p, q, r) <= 0;
    }
    child_a[m.face_parent_a[f]] += area3(m.positions_a, t);
    child_b[m.face_parent_b[f]] += area3(m.positions_b, t);
    const Vec3 na = (m.positions_a[t[1]] - m.positions_a[t[0]]).cross(m.positions_a[t[2]] - m.positions_a[t[0]]);
    const auto& pa = a.mesh.faces[m.face_parent_a[f]];
    const Vec3 np = (a.mesh.positions[pa[1]] - a.mesh.positions[pa[0]]).cross(a.mesh.positions[pa[2]] - a.mesh.positions[pa[0]]);
    if (na.norm() > 1e-12 * np.norm()) {
      EXPECT_GT(na.dot(np), 0) << "face " << f;
    } else {
      ++thin;
    }  }
  EXPECT_EQ(nonpositive_uv, 0);
  double total_a = 0, total_m = 0;
  for (int f = 0; f < a.mesh.num_faces(); ++f) {
    const double pa = area3(a.mesh.positions, a.mesh.faces[f]);
    EXPECT_NEAR(child_a[f], pa, 1e-12 * std::max(pa, 1e-3)) << "A face " << f;
    total_a += pa;
    total_m += child_a[f];
  }
  EXPECT_NEAR(total_m, total_a, 1e-12 * total_a);
  for (int f = 0; f < b.mesh.num_faces(); ++f) {
    const double pb = area3(b.mesh.positions, b.mesh.faces[f]);
    EXPECT_NEAR(child_b[f], pb, 1e-12 * std::max(pb, 1e-3)) << "B face " << f;
  }
  EXPECT_LE(m.faces.size(), 8u * (a.mesh.faces.size() + b.mesh.faces.size()));
  EXPECT_EQ(m.stats.thin_faces_a, thin);
  EXPECT_EQ(m.stats.normal_disagreements_a, 0);
  EXPECT_EQ(m.stats.normal_disagreements_b, 0);
}

// The merge of a chart with itself is the chart, face for face.
void expect_self_merge(const Chart& c) {
  const Merged m = qs::merge::merge_charts(c, c);
  ASSERT_EQ(m.faces.size(), c.mesh.faces.size());
  ASSERT_EQ(m.positions_a.size(), c.mesh.positions.size());
  for (size_t v = 0; v < m.vertex_a.size(); ++v) EXPECT_EQ(m.vertex_a[v], m.vertex_b[v]);
  std::multiset<std::array<int, 3>> got, want;
  for (const auto& t : m.faces) {
    std::array<int, 3> r{m.vertex_a[t[0]], m.vertex_a[t[1]], m.vertex_a[t[2]]};
    std::rotate(r.begin(), std::min_element(r.begin(), r.end()), r.end());
    got.insert(r);
  }
  for (const auto& t : c.mesh.faces) {
    std::array<int, 3> r{t[0], t[1], t[2]};
    std::rotate(r.begin(), std::min_element(r.begin(), r.end()), r.end());
    want.insert(r);
  }
  EXPECT_EQ(got, want);
  EXPECT_EQ(m.stats.crossings, 0);
  EXPECT_EQ(m.stats.coincident_vertices, c.mesh.num_vertices());
}

qs::dissect::DissectionSet dissect_pair(const qs::TriMesh& a, const qs::TriMesh& b) {
  qs::dissect::DissectOptions o;
  o.tau = 1.6;
  o.min_faces_to_split = 60;
  std::vector<qs::dissect::MeshToDissect> in(2);
  in[0].mesh = &a;
  in[1].mesh = &b;
  in[0].name = "a";
  in[1].name = "b";
  return qs::dissect::dissect_set(in, o);
}

}  // namespace

TEST(Merge, RefinementGivesTheFinerChart) {
  // B's grid refines A's (same diagonal direction): every A vertex is a B vertex, every A edge a
  // chain of collinear B edges, every B vertex inside an A triangle or on an A edge.
  const Chart a = pillow(2, true), b = pillow(4, true);
  const Merged m = qs::merge::merge_charts(a, b);
  expect_exact_merge(a, b, m);
  EXPECT_EQ(m.faces.size(), b.mesh.faces.size());
  EXPECT_EQ(m.positions_a.size(), b.mesh.positions.size());
  EXPECT_EQ(m.stats.crossings, 0);
  EXPECT_EQ(m.stats.coincident_vertices, a.mesh.num_vertices());
  EXPECT_GT(m.stats.b_on_a_edge, 0);
}

TEST(Merge, OppositeDiagonalsCrossAtCellCentres) {
  // The same grid with the other diagonals: all vertices coincide, the diagonals cross.
  const Chart a = pillow(3, true), b = pillow(3, false);
  const Merged m = qs::merge::merge_charts(a, b);
  expect_exact_merge(a, b, m);
  EXPECT_EQ(m.stats.crossings, 2 * 9);  // one per cell, both patches
  EXPECT_EQ(m.faces.size(), 2u * 9 * 4);
}

TEST(Merge, VertexOnEdgeAndCrossingsThroughVertices) {
  // A 2x2 grid against a 3x3 grid with other diagonals; and a 2x2 against 6x6 (vertices on edges,
  // collinear pieces and crossings at vertices of the finer grid).
  for (auto [na, nb, ra, rb] : {std::tuple{2, 3, true, false}, std::tuple{2, 6, true, false}, std::tuple{3, 6, false, true},
                                std::tuple{4, 5, true, true}}) {
    SCOPED_TRACE(std::to_string(na) + " x " + std::to_string(nb));
    const Chart a = pillow(na, ra), b = pillow(nb, rb);
    expect_exact_merge(a, b, qs::merge::merge_charts(a, b));
    expect_exact_merge(b, a, qs::merge::merge_charts(b, a));
  }
}

TEST(Merge, SelfMergeGivesBackTheChart) {
  expect_self_merge(pillow(3, true));
  const qs::TriMesh s = qs::shapes::icosphere(2);
  const auto set = dissect_pair(s, s);
  expect_self_merge(set.meshes[0].chart);
}

TEST(Merge, CubeSphereAgainstTwiceTheResolution) {
  // Coinciding corners, sides with points at different parameters, crossings everywhere.
  const qs::TriMesh a = qs::shapes::cube_sphere(4), b = qs::shapes::cube_sphere(8);
  const auto set = dissect_pair(a, b);
  const Chart& ca = set.meshes[0].chart;
  const Chart& cb = set.meshes[1].chart;
  const Merged m = qs::merge::merge_charts(ca, cb);
  expect_exact_merge(ca, cb, m);
  EXPECT_GT(m.stats.crossings, 0);
  EXPECT_GE(m.stats.coincident_vertices, 4);  // at least the seed corners
  // The merged mesh at t = 0 covers A's surface: its areas sum to A's.
  double area_a = 0, area_m = 0;
  for (int f = 0; f < a.num_faces(); ++f) area_a += qs::face_area(a, f);
  for (const auto& t : m.faces) area_m += area3(m.positions_a, t);
  EXPECT_NEAR(area_m, area_a, 1e-12 * area_a);
}

TEST(Merge, OutputDoesNotDependOnThreadsOrRuns) {
  const Chart a = pillow(5, true), b = pillow(7, false);
  qs::merge::MergeOptions one, two;
  one.threads = 1;
  two.threads = 2;
  const Merged m1 = qs::merge::merge_charts(a, b, one), m2 = qs::merge::merge_charts(a, b, two);
  EXPECT_EQ(m1.faces, m2.faces);
  EXPECT_EQ(m1.positions_a, m2.positions_a);
  EXPECT_EQ(m1.positions_b, m2.positions_b);
  EXPECT_EQ(m1.vertex_uv, m2.vertex_uv);
  EXPECT_EQ(m1.face_parent_a, m2.face_parent_a);
}

TEST(Merge, BetterTriangulationHasNoSmallerAngles) {
  const Chart a = pillow(4, true), b = pillow(7, false);
  qs::merge::MergeOptions fan;
  fan.improve_slivers = false;
  const Merged best = qs::merge::merge_charts(a, b), f = qs::merge::merge_charts(a, b, fan);
  expect_exact_merge(a, b, f);
  EXPECT_EQ(best.faces.size(), f.faces.size());  // the same polygons, cut differently
  EXPECT_GE(best.stats.min_angle_uv, f.stats.min_angle_uv);
  EXPECT_LE(best.stats.slivers_uv, f.stats.slivers_uv);
}

TEST(Merge, FlippedUvTriangleIsRefusedNamingThePatch) {
  Chart a = pillow(3, true);
  const Chart b = pillow(3, false);
  // Swap two wedge uvs of a face in patch 1: its uv triangle turns clockwise.
  int f = 0;
  while (a.face_patch[f] != 1) ++f;
  std::swap(a.face_uv[f][0], a.face_uv[f][1]);
  std::swap(a.mesh.faces[f][0], a.mesh.faces[f][1]);
  try {
    qs::merge::merge_charts(a, b);
    FAIL() << "flipped uv accepted";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("mesh A: patch 1 ('1')"));
    EXPECT_THAT(e.what(), HasSubstr("flipped"));
  }
  // A zero-area uv triangle likewise.
  Chart d = pillow(3, true);
  d.face_uv[0][2] = d.face_uv[0][1];
  EXPECT_THROW(qs::merge::check_chart_uv(d, "d"), qs::InvalidInput);
}

TEST(Merge, ChartsOfDifferentDissectionsAreRefused) {
  Chart a = pillow(2, true), b = pillow(2, true);
  b.patches[1].name = "0.3";
  EXPECT_THROW(qs::merge::merge_charts(a, b), qs::InvalidInput);
  // A border vertex off the square's side.
  Chart c = pillow(2, true);
  for (auto& w : c.face_uv)
    for (auto& p : w)
      if (p == Vec2(0.5, 0)) p = Vec2(0.5, 1e-9);
  try {
    qs::merge::check_chart_uv(c, "c");
    FAIL() << "off-border uv accepted";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("not on a side of the unit square"));
  }
}

// Moves the uv of chart vertex `v` in patch `patch` (every wedge of it there).
void move_uv(Chart& c, int v, int patch, const Vec2& uv) {
  for (int f = 0; f < c.mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k)
      if (c.face_patch[f] == patch && c.mesh.faces[f][k] == v) c.face_uv[f][k] = uv;
}

// The chart vertex of `c` at uv `at` in patch `patch`.
int vertex_at(const Chart& c, int patch, const Vec2& at) {
  for (int f = 0; f < c.mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k)
      if (c.face_patch[f] == patch && c.face_uv[f][k] == at) return c.mesh.faces[f][k];
  return -1;
}

TEST(Merge, SidePointsThatTheTwoPatchesPlaceDifferentlyAreReconciled) {
  const Chart a = pillow(2, true);
  const double up = std::nextafter(0.5, 1.0);
  // B's side point at u = 0.5 on v = 0 coincides with A's in patch 0 but misses it by one unit in
  // the last place in patch 1: it is made to coincide there too.
  Chart b = pillow(2, false);
  const int side = vertex_at(b, 0, Vec2(0.5, 0));
  const int side_a = vertex_at(a, 0, Vec2(0.5, 0));
  ASSERT_GE(side, 0);
  move_uv(b, side, 1, Vec2(up, 0));
  const Merged m = qs::merge::merge_charts(a, b);
  expect_exact_merge(a, b, m);
  EXPECT_EQ(m.stats.side_points_moved, 1);
  bool together = false;
  for (size_t v = 0; v < m.vertex_a.size(); ++v) together = together || (m.vertex_a[v] == side_a && m.vertex_b[v] == side);
  EXPECT_TRUE(together);
  // B's side point just after A's in patch 0 and, mirrored, just before it in patch 1 — the
  // other order: it is put after A's in patch 1 too.
  Chart c = pillow(2, false);
  move_uv(c, side, 0, Vec2(up, 0));
  move_uv(c, side, 1, Vec2(up, 0));
  const Merged mc = qs::merge::merge_charts(a, c);
  expect_exact_merge(a, c, mc);
  EXPECT_EQ(mc.stats.side_points_moved, 1);
  EXPECT_EQ(mc.stats.coincident_vertices, a.mesh.num_vertices() - 1);
}

namespace {

}  // namespace

TEST(Merge, CubeSphereWithSeedsAndFeaturesAgainstTwiceTheResolution) {
  // Seeds and features at the same places on both: corners and features coincide in the merge.
  const qs::TriMesh a = qs::shapes::cube_sphere(4), b = qs::shapes::cube_sphere(8);
  const std::vector<Vec3> seed_dirs = {{1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
  const std::vector<Vec3> feature_dirs = {{0, 0, 1}, {0.5, 0.5, -0.7}, {-0.6, 0.2, -0.75}};
  std::vector<qs::dissect::MeshToDissect> in(2);
  const qs::TriMesh* meshes[2] = {&a, &b};
  for (int i = 0; i < 2; ++i) {
    in[i].mesh = meshes[i];
    in[i].name = i ? "b" : "a";
    std::array<int, 4> seeds;
    for (int k = 0; k < 4; ++k) seeds[k] = vertex_towards(*meshes[i], seed_dirs[k]);
    in[i].seeds = seeds;
    for (size_t k = 0; k < feature_dirs.size(); ++k)
      in[i].features.push_back({"f" + std::to_string(k), vertex_towards(*meshes[i], feature_dirs[k]), {}});
  }
  qs::dissect::DissectOptions o;
  o.tau = 1.6;
  o.min_faces_to_split = 60;
  const auto set = qs::dissect::dissect_set(in, o);
  const Chart& ca = set.meshes[0].chart;
  const Chart& cb = set.meshes[1].chart;
  const Merged m = qs::merge::merge_charts(ca, cb);
  expect_exact_merge(ca, cb, m);
  // Every base vertex (patch corner) and every feature is one merged vertex of A and B together.
  const auto& fa = set.meshes[0].features;
  const auto& fb = set.meshes[1].features;
  ASSERT_EQ(fa.size(), feature_dirs.size());
  std::set<std::pair<int, int>> coincident;
  for (size_t v = 0; v < m.vertex_a.size(); ++v)
    if (m.vertex_a[v] >= 0 && m.vertex_b[v] >= 0) coincident.insert({m.vertex_a[v], m.vertex_b[v]});
  for (size_t k = 0; k < fa.size(); ++k)
    EXPECT_TRUE(coincident.count({fa[k].vertex, fb[k].vertex})) << "feature " << fa[k].name;
  for (size_t c = 0; c < set.meshes[0].base.vertices.size(); ++c)
    EXPECT_TRUE(coincident.count({set.meshes[0].base.vertices[c], set.meshes[1].base.vertices[c]})) << "corner " << c;
  EXPECT_EQ(m.stats.coincident_vertices, static_cast<int>(coincident.size()));
}
