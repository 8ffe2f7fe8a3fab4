#pragma once
// Independent checks of remesher output (computed here, not by the library), and the
// dissections the remesh tests share.

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "qs/core/mesh.h"
#include "qs/dissect/dissection.h"
#include "qs/mesh/validate.h"
#include "qs/shapes/shapes.h"
#include "../common/test_support.h"

namespace qs::remesh_test {

using qs::test::vertex_towards;

/// Every directed edge once and its reverse once (so every edge has exactly two faces, oppositely
/// oriented: closed, manifold, no T-junction), one fan per vertex, no unused vertex. Returns V-E+F.
inline int expect_closed_manifold(const std::vector<Tri>& faces, int num_vertices) {
  std::map<std::pair<int, int>, int> directed;
  std::vector<int> used(num_vertices, 0);
  for (const auto& f : faces) {
    EXPECT_TRUE(f[0] != f[1] && f[1] != f[2] && f[2] != f[0]) << "face repeats a vertex";
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(f[k], 0);
      EXPECT_LT(f[k], num_vertices);
      if (f[k] < 0 || f[k] >= num_vertices) return 0;
      ++directed[{f[k], f[(k + 1) % 3]}];
      used[f[k]] = 1;
    }
  }
  int bad = 0;
  for (const auto& [e, n] : directed) {
    if (n != 1 || !directed.count({e.second, e.first})) {
      if (++bad <= 5) ADD_FAILURE() << "edge " << e.first << "-" << e.second << ": " << n << " faces one way, "
                                   << (directed.count({e.second, e.first}) ? directed.at({e.second, e.first}) : 0)
                                   << " the other (expected 1 and 1)";
    }
  }
  EXPECT_EQ(bad, 0) << "edges without exactly two faces";
  EXPECT_EQ(std::accumulate(used.begin(), used.end(), 0), num_vertices) << "unused vertices";
  // One fan per vertex: around v, face (v, a, b) links a -> b; the links must form one cycle.
  std::vector<std::vector<std::pair<int, int>>> links(num_vertices);
  for (const auto& f : faces)
    for (int k = 0; k < 3; ++k) links[f[k]].emplace_back(f[(k + 1) % 3], f[(k + 2) % 3]);
  int pinched = 0;
  for (int v = 0; v < num_vertices; ++v) {
    auto& l = links[v];
    if (l.empty()) continue;
    std::map<int, int> next(l.begin(), l.end());
    size_t steps = 0;
    int a = l[0].first;
    do {
      const auto it = next.find(a);
      if (it == next.end()) break;
      a = it->second;
      ++steps;
    } while (a != l[0].first && steps <= l.size());
    if (steps != l.size()) ++pinched;
  }
  EXPECT_EQ(pinched, 0) << "vertices whose faces form more than one fan";
  return num_vertices - static_cast<int>(directed.size()) / 2 + static_cast<int>(faces.size());
}

/// Number of vertex pairs closer than tol (positions sorted by x, then a window scan).
inline int count_coincident(const std::vector<Vec3>& p, double tol) {
  std::vector<int> order(p.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return p[a].x() < p[b].x(); });
  int n = 0;
  for (size_t i = 0; i < order.size(); ++i)
    for (size_t j = i + 1; j < order.size() && p[order[j]].x() - p[order[i]].x() < tol; ++j)
      if ((p[order[i]] - p[order[j]]).norm() < tol) ++n;
  return n;
}

/// The full validator agrees: closed, manifold, one component, genus 0, outward (not flipped).
inline void expect_valid_sphere(const TriMesh& m, const std::string& what) {
  const auto r = qs::mesh::validate(m).report;
  EXPECT_TRUE(r.accepted) << qs::mesh::format_report(what, r);
  EXPECT_FALSE(r.orientation_flipped) << what << " is inside out";
  EXPECT_EQ(r.euler_characteristic, 2) << what;
  EXPECT_GT(r.signed_volume, 0) << what;
}

// ---- Shared inputs (each computed once per test binary) ----

inline std::array<int, 4> equator_seeds(const qs::TriMesh& m) {
  return {vertex_towards(m, {1, 0, 0}), vertex_towards(m, {0, 1, 0}), vertex_towards(m, {-1, 0, 0}),
          vertex_towards(m, {0, -1, 0})};
}

// Dissections shared by the tests (computed once).
inline const qs::dissect::Dissection& sphere_dissection() {
  static const auto d = [] {
    const auto m = qs::shapes::icosphere(4);
    qs::dissect::DissectOptions o;
    o.max_patch_area = 0;  // the two seed patches (no area cap)
    return qs::dissect::dissect(m, equator_seeds(m), o);
  }();
  return d;
}

inline const qs::dissect::Dissection& star_dissection() {
  static const auto d = [] {
    qs::dissect::DissectOptions o;
    o.tau = 1.4;
    // The maps these tests were written for: with the
    // default cotangent maps some level-3 cells of AdaptiveRemesh.TinyEpsilon... lie inside one flat
    // input triangle (error 0, not "unresolved" at epsilon 1e-12).
    o.geodesic_seed_curves = false;
    o.intrinsic_cotan = false;
    return qs::dissect::dissect(qs::shapes::star_blob(4, 1.5, 4), std::nullopt, o);
  }();
  return d;
}

// An ellipsoid and a star blob dissected together: one structure, very different charts.
inline const qs::dissect::DissectionSet& pair_dissection() {
  static const auto s = [] {
    static const auto smooth = qs::shapes::ellipsoid(1.2, 1, 0.9, 3);
    static const auto star = qs::shapes::star_blob(4, 1.5, 4);
    qs::dissect::DissectOptions o;
    o.tau = 1.6;
    return qs::dissect::dissect_set(
        {{&smooth, equator_seeds(smooth), {}, "smooth"}, {&star, equator_seeds(star), {}, "star"}}, o);
  }();
  return s;
}

// The two seed patches of a 4-corner loop: they share all four sides (valence-2 corners).
inline std::vector<qs::dissect::PatchInfo> seed_patches() {
  std::vector<qs::dissect::PatchInfo> p(2);
  p[0].name = "0";
  p[0].corners = {10, 11, 12, 13};
  p[1].name = "1";
  p[1].corners = {10, 13, 12, 11};
  return p;
}

}  // namespace qs::remesh_test
