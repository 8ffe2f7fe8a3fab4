// Anisotropic even remesh (anisotropic.h): cells split in u or v alone where they are long on the
// surface, conforming (no T-junction), one connectivity for a set, deterministic.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>

#include "qs/bake/split_mesh.h"
#include "qs/core/error.h"
#include "qs/remesh/adaptive.h"
#include "qs/remesh/anisotropic.h"
#include "qs/remesh/chart_sampler.h"
#include "qs/remesh/quality.h"
#include "qs/remesh/uniform.h"
#include "qs/shapes/shapes.h"
#include "remesh_checks.h"

using qs::remesh_test::expect_closed_manifold;
using qs::remesh_test::expect_valid_sphere;
using qs::remesh_test::vertex_towards;
using ::testing::HasSubstr;

namespace {

// Two long ellipsoids (5:1 and 3.5:1) dissected together into their two seed patches, with seeds
// near the ends of the long axis: each patch is a long strip, mapped onto the unit square.
const qs::dissect::DissectionSet& strip_set() {
  static const auto s = [] {
    static const auto a = qs::shapes::ellipsoid(5, 1, 1, 4);
    static const auto b = qs::shapes::ellipsoid(3.5, 1.2, 0.9, 4);
    auto seeds = [](const qs::TriMesh& m, double x, double y) {
      return std::array<int, 4>{vertex_towards(m, {x, y, 0}), vertex_towards(m, {-x, y, 0}),
                                vertex_towards(m, {-x, -y, 0}), vertex_towards(m, {x, -y, 0})};
    };
    qs::dissect::DissectOptions o;
    o.max_patch_area = 0;
    o.tau = 1e9;  // no quinary split: the two strips stay whole
    return qs::dissect::dissect_set({{&a, seeds(a, 4, 1), {}, "long"}, {&b, seeds(b, 3, 1), {}, "longer"}}, o);
  }();
  return s;
}

std::vector<const qs::dissect::Chart*> charts_of(const qs::dissect::DissectionSet& s) {
  std::vector<const qs::dissect::Chart*> c;
  for (const auto& m : s.meshes) c.push_back(&m.chart);
  return c;
}

// A leaf's aspect measured here from its corners only (the mean of its two u sides over the mean
// of its two v sides, on the surface, or its inverse, whichever is >= 1), the largest over the meshes.
double corner_aspect(const std::vector<qs::remesh::ChartSampler>& samplers, const qs::remesh::AnisoNode& n) {
  const double su = 1.0 / (1 << n.lu), sv = 1.0 / (1 << n.lv);
  double worst = 1;
  for (const auto& s : samplers) {
    const qs::Vec3 c0 = s.point(n.patch, {n.i * su, n.j * sv}), c1 = s.point(n.patch, {(n.i + 1) * su, n.j * sv});
    const qs::Vec3 c2 = s.point(n.patch, {(n.i + 1) * su, (n.j + 1) * sv}), c3 = s.point(n.patch, {n.i * su, (n.j + 1) * sv});
    const double r = ((c1 - c0).norm() + (c2 - c3).norm()) / ((c3 - c0).norm() + (c2 - c1).norm());
    worst = std::max({worst, r, 1 / r});
  }
  return worst;
}

TEST(Anisotropic, StripCellsStayNearSquareAndTheMeshIsClosed) {
  const auto& set = strip_set();
  ASSERT_EQ(set.meshes.front().chart.patches.size(), 2u);
  const auto charts = charts_of(set);
  const auto a = qs::remesh::remesh_even_anisotropic(charts, 4);
  const auto& c = a.remesh.connectivity;
  ASSERT_EQ(a.remesh.positions.size(), 2u);
  EXPECT_EQ(expect_closed_manifold(c.faces, c.num_vertices()), 2);
  for (int m = 0; m < 2; ++m) expect_valid_sphere(a.remesh.mesh(m), "anisotropic remesh of mesh " + std::to_string(m));

  // Some cells were split in one direction only (the strips are long), and every leaf, measured
  // independently from its 4 corners, is within the aspect bound (a little slack: the library
  // measures along 3 lines through the cell, this test along its 2 sides).
  int one_way = 0;
  std::vector<qs::remesh::ChartSampler> samplers;
  for (const auto* ch : charts) samplers.emplace_back(*ch);
  double worst = 1;
  for (const auto& n : a.leaves) {
    one_way += n.lu != n.lv;
    worst = std::max(worst, corner_aspect(samplers, n));
  }
  EXPECT_GT(one_way, static_cast<int>(a.leaves.size()) / 2);
  EXPECT_LE(worst, 1.25 * qs::remesh::kDefaultMaxAspect);
  EXPECT_LE(a.stats.max_leaf_aspect, qs::remesh::kDefaultMaxAspect);
  EXPECT_EQ(a.stats.unresolved_leaves, 0);

  // Better shaped than the square-cell even remesh and the uniform grid of the same level.
  const auto sq = qs::remesh::remesh_even(charts, 4);
  const auto un = qs::remesh::remesh_uniform(charts, 4);
  for (int m = 0; m < 2; ++m) {
    const auto aa = qs::remesh::smallest_angle_stats(a.remesh.mesh(m));
    const auto sa = qs::remesh::smallest_angle_stats(sq.remesh.mesh(m));
    const auto ua = qs::remesh::smallest_angle_stats(un.mesh(m));
    EXPECT_GT(aa.median, sa.median + 5) << "mesh " << m;
    EXPECT_GT(aa.median, ua.median + 5) << "mesh " << m;
    EXPECT_LT(aa.under_20, 0.5 * sa.under_20) << "mesh " << m;
    EXPECT_LT(aa.under_20, 0.5 * ua.under_20) << "mesh " << m;
    EXPECT_GE(aa.median, 35) << "mesh " << m;
  }
}

TEST(Anisotropic, OneConnectivityForTheSetAndDeterministic) {
  const auto& set = strip_set();
  const auto charts = charts_of(set);
  const auto a = qs::remesh::remesh_even_anisotropic(charts, 3);
  const auto b = qs::remesh::remesh_even_anisotropic(charts, 3);
  EXPECT_EQ(a.remesh.connectivity.faces, b.remesh.connectivity.faces);
  EXPECT_EQ(a.remesh.connectivity.vertex_uv, b.remesh.connectivity.vertex_uv);
  EXPECT_EQ(a.remesh.positions, b.remesh.positions);
  // Each mesh alone decides other cells; the set's tree serves both meshes with one face list,
  // and every vertex of each is a point of that mesh's chart at the vertex's (patch, u, v).
  for (int m = 0; m < 2; ++m) {
    const qs::remesh::ChartSampler s(*charts[m]);
    const auto& c = a.remesh.connectivity;
    for (int v = 0; v < c.num_vertices(); v += 7)
      EXPECT_LT((s.point(c.vertex_patch[v], c.vertex_uv[v]) - a.remesh.positions[m][v]).norm(), 1e-12);
  }
  const auto alone = qs::remesh::remesh_even_anisotropic({charts[0]}, 3);
  EXPECT_EQ(expect_closed_manifold(alone.remesh.connectivity.faces, alone.remesh.connectivity.num_vertices()), 2);
}

// Conforming and closed whatever the refinement: the two seed patches (valence-2 corners, every
// side shared by the same two patches), a quinary-split star, a pair of different shapes, at
// several area and aspect bounds, with levels from the roots only to deep trees.
// Faces whose three corners lie inside one patch (one uv frame) that are not counter-clockwise in
// (u,v) there: what qs-bake refuses ("lies in no patch with a counter-clockwise (u,v) triangle").
int clockwise_uv_faces(const qs::remesh::SemiRegularConnectivity& c) {
  int bad = 0;
  for (const auto& f : c.faces) {
    bool one_frame = true;
    for (int v : f) {
      const qs::Vec2& uv = c.vertex_uv[v];
      one_frame = one_frame && v >= c.num_base_vertices && c.vertex_patch[v] == c.vertex_patch[f[0]] && uv.x() > 0 &&
                  uv.x() < 1 && uv.y() > 0 && uv.y() < 1;
    }
    if (!one_frame) continue;
    const qs::Vec2 &a = c.vertex_uv[f[0]], &b = c.vertex_uv[f[1]], &d = c.vertex_uv[f[2]];
    bad += !((b - a).x() * (d - a).y() - (b - a).y() * (d - a).x() > 0);
  }
  return bad;
}

TEST(Anisotropic, ClosedManifoldOnManyTrees) {
  struct Case {
    std::string name;
    std::vector<const qs::dissect::Chart*> charts;
  };
  std::vector<Case> cases = {{"sphere", {&qs::remesh_test::sphere_dissection().chart}},
                             {"star", {&qs::remesh_test::star_dissection().chart}},
                             {"pair", charts_of(qs::remesh_test::pair_dissection())},
                             {"strips", charts_of(strip_set())}};
  for (const auto& k : cases)
    for (double area : {2.0, 0.3, 0.05, 0.004})
      for (double aspect : {1.5, 2.0, 4.0})
        for (int max_level : {0, 1, 3, 6}) {
          qs::remesh::AnisotropicOptions o;
          o.max_area = area;
          o.max_aspect = aspect;
          o.max_level = max_level;
          const auto a = qs::remesh::remesh_anisotropic(k.charts, o);
          const auto& c = a.remesh.connectivity;
          SCOPED_TRACE(k.name + " area " + std::to_string(area) + " aspect " + std::to_string(aspect) + " max level " +
                       std::to_string(max_level));
          EXPECT_EQ(expect_closed_manifold(c.faces, c.num_vertices()), 2);
          EXPECT_EQ(clockwise_uv_faces(c), 0);
          EXPECT_LE(a.stats.finest_level, max_level);
          // Every leaf of the balanced trees has a neighbour at most one level coarser along each
          // side, so a leaf gets at most one hanging vertex per side: at most 8 fan triangles.
          EXPECT_LE(c.num_faces(), 8 * static_cast<int>(a.leaves.size()));
          for (size_t m = 0; m < k.charts.size(); ++m) expect_valid_sphere(a.remesh.mesh(static_cast<int>(m)), k.name);
        }
}

// A copy of a dissection's chart whose maps are sheared inside every patch: each wedge's u moves by
// k sin(pi u) sin(2 pi waves v) / 2 (v kept; monotone in u for k < 2 / pi, the identity on the
// square's border; the shear du'/dv reaches k pi waves), so the remesh's cells are parallelograms on
// the surface, not rectangles. (A few thin chart triangles may still turn over in uv, so points are
// not compared with an unhinted lookup.)
qs::dissect::Chart sheared(const qs::dissect::Chart& in, double k, int waves = 1) {
  qs::dissect::Chart c = in;
  for (auto& w : c.face_uv)
    for (auto& uv : w) {
      const double u = uv.x(), v = uv.y();
      if (u > 0 && u < 1 && v > 0 && v < 1) uv.x() = u + 0.5 * k * std::sin(M_PI * u) * std::sin(2 * M_PI * waves * v);
    }
  return c;
}

// The smoothing moves only patch-interior vertices, within their patch, along the surface; it never
// lowers the smallest angle much, and on sheared maps it removes most slivers.
TEST(Anisotropic, SmoothingRemovesSliversOfShearedMaps) {
  // The sphere with the edge-path, mean-value maps (the star fixture's maps too): their own
  // anisotropy adds to the shear, so the unsmoothed remesh has slivers to remove. (The default
  // cotangent maps of an icosphere are near-conformal: sheared by the most this shear allows
  // while staying injective, k < 2/pi, they leave under 1% of the faces under 20 degrees.)
  static const qs::dissect::Dissection sphere = [] {
    const auto m = qs::shapes::icosphere(4);
    qs::dissect::DissectOptions o;
    o.max_patch_area = 0;
    o.geodesic_seed_curves = false;
    o.intrinsic_cotan = false;
    return qs::dissect::dissect(m, qs::remesh_test::equator_seeds(m), o);
  }();
  for (const auto* base : {&sphere.chart, &qs::remesh_test::star_dissection().chart}) {
    const qs::dissect::Chart chart = sheared(*base, 0.6);
    const std::vector<const qs::dissect::Chart*> charts = {&chart};
    qs::remesh::AnisotropicOptions o = qs::remesh::anisotropic_options(4, static_cast<int>(chart.patches.size()));
    o.smooth_iterations = 0;
    o.flip_rounds = 0;  // the smoothing alone (the flips: FlipsRemoveNeedlesOfShearedMaps)
    o.slide_sides = false;  // the interior alone (the sides: SideVerticesSlideAlongTheirSideOnly)
    const auto raw = qs::remesh::remesh_anisotropic(charts, o);
    o.smooth_iterations = qs::remesh::kDefaultSmoothIterations;
    const auto smooth = qs::remesh::remesh_anisotropic(charts, o);
    const auto& c0 = raw.remesh.connectivity;
    const auto& c1 = smooth.remesh.connectivity;
    ASSERT_EQ(c0.num_vertices(), c1.num_vertices());
    ASSERT_EQ(c0.num_faces(), c1.num_faces());
    EXPECT_EQ(expect_closed_manifold(c1.faces, c1.num_vertices()), 2);
    EXPECT_EQ(clockwise_uv_faces(c1), 0);  // the re-cuts after smoothing keep every face counter-clockwise
    expect_valid_sphere(smooth.remesh.mesh(0), "smoothed anisotropic remesh");
    EXPECT_GT(smooth.stats.smoothed_moves, 0);
    // Corners and patch sides stay where they were; interior vertices stay inside their patch.
    int moved = 0;
    for (int v = 0; v < c1.num_vertices(); ++v) {
      ASSERT_EQ(c0.vertex_patch[v], c1.vertex_patch[v]);
      const qs::Vec2 a = c0.vertex_uv[v], b = c1.vertex_uv[v];
      const bool inside = a.x() > 0 && a.x() < 1 && a.y() > 0 && a.y() < 1;
      if (!inside) {
        EXPECT_EQ(a, b) << "vertex " << v;
        EXPECT_EQ(raw.remesh.positions[0][v], smooth.remesh.positions[0][v]) << "vertex " << v;
      } else {
        EXPECT_TRUE(b.x() > 0 && b.x() < 1 && b.y() > 0 && b.y() < 1) << "vertex " << v;
        moved += a != b;
      }
    }
    EXPECT_GT(moved, 0);
    const auto before = qs::remesh::smallest_angle_stats(raw.remesh.mesh(0));
    const auto after = qs::remesh::smallest_angle_stats(smooth.remesh.mesh(0));
    ASSERT_GT(before.under_20, 0.02) << "the sheared maps should give slivers without smoothing";
    EXPECT_GE(after.min, 0.5 * before.min);  // the worst may drop a little where its ring gains (see the header)
    EXPECT_LT(after.under_20, 0.5 * before.under_20);
    EXPECT_LE(after.under_10, before.under_10);
    EXPECT_GT(after.median, before.median);
  }
}

// Anisotropic remeshes of `charts` at level 4: without flips, with one round (flips only: the same
// vertices) and with the default rounds.
struct FlipRuns {
  qs::remesh::AnisotropicRemesh none, one, full;
  qs::remesh::AnisotropicOptions options;  ///< full's
};
FlipRuns flip_runs(const std::vector<const qs::dissect::Chart*>& charts, int level) {
  qs::remesh::AnisotropicOptions o = qs::remesh::anisotropic_options(level, static_cast<int>(charts[0]->patches.size()));
  FlipRuns r;
  o.flip_rounds = 0;
  r.none = qs::remesh::remesh_anisotropic(charts, o);
  o.flip_rounds = 1;
  r.one = qs::remesh::remesh_anisotropic(charts, o);
  o.flip_rounds = qs::remesh::kDefaultFlipRounds;
  r.full = qs::remesh::remesh_anisotropic(charts, o);
  r.options = o;
  return r;
}

// The worst over the meshes of a set: the largest share under 10 and 20 degrees, the lowest median.
qs::remesh::AngleStats worst_angles(const qs::remesh::AnisotropicRemesh& a) {
  qs::remesh::AngleStats w;
  w.median = 90;
  for (size_t m = 0; m < a.remesh.positions.size(); ++m) {
    const auto s = qs::remesh::smallest_angle_stats(a.remesh.mesh(static_cast<int>(m)));
    w.under_10 = std::max(w.under_10, s.under_10);
    w.under_20 = std::max(w.under_20, s.under_20);
    w.median = std::min(w.median, s.median);
  }
  return w;
}

// What the flips must keep: a closed 2-manifold, every face counter-clockwise in the (u,v) of a
// patch that holds its three corners (qs-bake's split_by_patch finds each face's patch). (The
// vertices' points are checked on unsheared charts, SmoothedSetSharesConnectivity; see sheared().)
void expect_flipped_remesh_valid(const std::vector<const qs::dissect::Chart*>& charts,
                                 const qs::remesh::AnisotropicRemesh& a, const std::string& what) {
  SCOPED_TRACE(what);
  const auto& c = a.remesh.connectivity;
  EXPECT_EQ(expect_closed_manifold(c.faces, c.num_vertices()), 2);
  EXPECT_EQ(clockwise_uv_faces(c), 0);
  EXPECT_EQ(a.face_leaf.size(), c.faces.size());
  for (size_t m = 0; m < charts.size(); ++m) {
    const qs::remesh::ChartSampler s(*charts[m]);
    EXPECT_NO_THROW(qs::bake::split_by_patch(c, a.remesh.positions[m], s.topology())) << "mesh " << m;
    expect_valid_sphere(a.remesh.mesh(static_cast<int>(m)), what);
  }
}

// Where the map shears, every cell is a thin parallelogram on the surface, and no cut of a cell nor
// the affine-invariant smoothing gives triangles above the shear angle: the flips across cells do.
// They move no vertex, keep the face count, and raise the angles a lot.
TEST(Anisotropic, FlipsRemoveNeedlesOfShearedMaps) {
  struct Case {
    const qs::dissect::Chart* base;
    int waves;
  };
  for (const Case& k : {Case{&qs::remesh_test::sphere_dissection().chart, 4}, Case{&qs::remesh_test::star_dissection().chart, 2}}) {
    const qs::dissect::Chart chart = sheared(*k.base, 0.6, k.waves);
    const std::vector<const qs::dissect::Chart*> charts = {&chart};
    const FlipRuns r = flip_runs(charts, 4);
    const auto none = worst_angles(r.none), one = worst_angles(r.one), full = worst_angles(r.full);
    SCOPED_TRACE("waves " + std::to_string(k.waves));
    ASSERT_GT(none.under_20, 0.05) << "the sheared maps should leave needles without flips";
    EXPECT_EQ(r.none.stats.flips, 0);
    EXPECT_GT(r.one.stats.flips, 0);
    expect_flipped_remesh_valid(charts, r.one, "one round");
    expect_flipped_remesh_valid(charts, r.full, "default rounds");
    // One round flips edges only: the same vertices at the same points, as many faces.
    EXPECT_EQ(r.one.remesh.connectivity.vertex_uv, r.none.remesh.connectivity.vertex_uv);
    EXPECT_EQ(r.one.remesh.positions, r.none.remesh.positions);
    EXPECT_EQ(r.one.remesh.connectivity.num_faces(), r.none.remesh.connectivity.num_faces());
    EXPECT_NE(r.one.remesh.connectivity.faces, r.none.remesh.connectivity.faces);
    EXPECT_LT(one.under_20, 0.6 * none.under_20);
    EXPECT_LE(one.under_10, none.under_10);
    EXPECT_GT(one.median, none.median + 2);
    // The default rounds (flips, smoothing, flips, ...) do better still.
    EXPECT_LT(full.under_20, 0.4 * none.under_20);
    EXPECT_LE(full.under_10, one.under_10);
    EXPECT_GT(full.median, none.median + 5);
  }
}

// A set flips by its worst mesh: one connectivity for all, deterministic, valid in every mesh, and
// the worst mesh's angles improve.
TEST(Anisotropic, FlipsKeepOneConnectivityForASet) {
  const auto& pair = qs::remesh_test::pair_dissection();
  const qs::dissect::Chart a = sheared(pair.meshes[0].chart, 0.6, 3), b = sheared(pair.meshes[1].chart, 0.5, 2);
  const std::vector<const qs::dissect::Chart*> charts = {&a, &b};
  const FlipRuns r = flip_runs(charts, 3);
  const auto again = qs::remesh::remesh_anisotropic(charts, r.options);
  EXPECT_EQ(again.remesh.connectivity.faces, r.full.remesh.connectivity.faces);
  EXPECT_EQ(again.remesh.connectivity.vertex_uv, r.full.remesh.connectivity.vertex_uv);
  EXPECT_EQ(again.remesh.positions, r.full.remesh.positions);
  EXPECT_GT(r.full.stats.flips, 0);
  ASSERT_EQ(r.full.remesh.positions.size(), 2u);
  expect_flipped_remesh_valid(charts, r.one, "one round");
  expect_flipped_remesh_valid(charts, r.full, "default rounds");
  const auto none = worst_angles(r.none), full = worst_angles(r.full);
  EXPECT_LT(full.under_20, none.under_20);
  EXPECT_LE(full.under_10, none.under_10);
  EXPECT_GT(full.median, none.median);
}

// The fraction along side s (0 bottom, 1 right, 2 top, 3 left) from corner s of a point on it.
double side_fraction(int s, const qs::Vec2& uv) {
  return s == 0 ? uv.x() : s == 1 ? uv.y() : s == 2 ? 1 - uv.x() : 1 - uv.y();
}
int side_of(const qs::Vec2& uv) {
  if ((uv.y() == 0) + (uv.x() == 1) + (uv.y() == 1) + (uv.x() == 0) != 1) return -1;
  return uv.y() == 0 ? 0 : uv.x() == 1 ? 1 : uv.y() == 1 ? 2 : 3;
}

// With the sliding, a patch-side vertex moves along its side only: the same patch, the same side
// (its fixed coordinate bit-identical), its point in every mesh the chart's point there seen from
// both patches of the side (the side's polyline), corners fixed; the set keeps one connectivity,
// closed and 2-manifold, every face counter-clockwise in a patch's (u,v) (qs-bake's
// split_by_patch), deterministically; interior vertices stay inside their patch.
TEST(Anisotropic, SideVerticesSlideAlongTheirSideOnly) {
  const auto& pair = qs::remesh_test::pair_dissection();
  const qs::dissect::Chart a = sheared(pair.meshes[0].chart, 0.6, 3), b = sheared(pair.meshes[1].chart, 0.5, 2);
  const std::vector<const qs::dissect::Chart*> charts = {&a, &b};
  qs::remesh::AnisotropicOptions o = qs::remesh::anisotropic_options(3, static_cast<int>(a.patches.size()));
  ASSERT_TRUE(o.slide_sides) << "sliding is the default";
  const auto on = qs::remesh::remesh_anisotropic(charts, o);
  const auto again = qs::remesh::remesh_anisotropic(charts, o);
  o.slide_sides = false;
  const auto off = qs::remesh::remesh_anisotropic(charts, o);
  EXPECT_EQ(off.stats.slid_moves, 0);
  EXPECT_GT(on.stats.slid_moves, 0);
  EXPECT_EQ(again.remesh.connectivity.faces, on.remesh.connectivity.faces);
  EXPECT_EQ(again.remesh.connectivity.vertex_uv, on.remesh.connectivity.vertex_uv);
  EXPECT_EQ(again.remesh.positions, on.remesh.positions);
  expect_flipped_remesh_valid(charts, on, "sliding");
  const auto& c0 = off.remesh.connectivity;
  const auto& c1 = on.remesh.connectivity;
  ASSERT_EQ(c0.num_vertices(), c1.num_vertices());
  ASSERT_EQ(c0.vertex_patch, c1.vertex_patch);
  std::vector<qs::remesh::ChartSampler> samplers;
  for (const auto* c : charts) samplers.emplace_back(*c);
  const auto& t = samplers[0].topology();
  int slid = 0;
  for (int v = 0; v < c1.num_vertices(); ++v) {
    const qs::Vec2 u0 = c0.vertex_uv[v], u1 = c1.vertex_uv[v];
    const int p = c1.vertex_patch[v], s = side_of(u0);
    if (v < c1.num_base_vertices) {
      EXPECT_EQ(u0, u1) << "corner " << v;
      for (size_t m = 0; m < charts.size(); ++m) EXPECT_EQ(off.remesh.positions[m][v], on.remesh.positions[m][v]);
      continue;
    }
    if (s < 0) {
      EXPECT_TRUE(u1.x() > 0 && u1.x() < 1 && u1.y() > 0 && u1.y() < 1) << "interior vertex " << v << " left its patch";
      continue;
    }
    ASSERT_EQ(side_of(u1), s) << "side vertex " << v << " left side " << s << " of patch " << p;
    slid += u0 != u1;
    const double f = side_fraction(s, u1);
    EXPECT_TRUE(f > 0 && f < 1) << "vertex " << v;
    const qs::remesh::PatchSide tw = t.twin(p, s);
    const double r = 1 - f;
    const qs::Vec2 twin_uv = tw.side == 0 ? qs::Vec2(r, 0) : tw.side == 1 ? qs::Vec2(1, r) : tw.side == 2 ? qs::Vec2(1 - r, 1) : qs::Vec2(0, 1 - r);
    for (size_t m = 0; m < charts.size(); ++m) {
      EXPECT_LT((samplers[m].point(p, u1) - on.remesh.positions[m][v]).norm(), 1e-12) << "vertex " << v << " mesh " << m;
      EXPECT_LT((samplers[m].point(tw.patch, twin_uv) - on.remesh.positions[m][v]).norm(), 1e-9)
          << "vertex " << v << " seen from the twin patch " << tw.patch << ", mesh " << m;
    }
  }
  EXPECT_GT(slid, 0);
}

// A set keeps one connectivity and one (u, v) per vertex with the smoothing, deterministically, and
// every moved vertex is its chart's point at its (u, v) in every mesh.
TEST(Anisotropic, SmoothedSetSharesConnectivity) {
  const auto& pair = qs::remesh_test::pair_dissection();
  const std::vector<const qs::dissect::Chart*> charts = {&pair.meshes[0].chart, &pair.meshes[1].chart};
  const auto r1 = qs::remesh::remesh_even_anisotropic(charts, 3);
  const auto r2 = qs::remesh::remesh_even_anisotropic(charts, 3);
  EXPECT_GT(r1.stats.smoothed_moves, 0);
  EXPECT_EQ(r1.remesh.connectivity.faces, r2.remesh.connectivity.faces);
  EXPECT_EQ(r1.remesh.connectivity.vertex_uv, r2.remesh.connectivity.vertex_uv);
  EXPECT_EQ(r1.remesh.positions, r2.remesh.positions);
  EXPECT_EQ(expect_closed_manifold(r1.remesh.connectivity.faces, r1.remesh.connectivity.num_vertices()), 2);
  for (int m = 0; m < 2; ++m) {
    const qs::remesh::ChartSampler s(*charts[m]);
    const auto& c = r1.remesh.connectivity;
    for (int v = 0; v < c.num_vertices(); ++v)
      EXPECT_LT((s.point(c.vertex_patch[v], c.vertex_uv[v]) - r1.remesh.positions[m][v]).norm(), 1e-12)
          << "vertex " << v << " of mesh " << m;
  }
}

TEST(Anisotropic, BadOptionsAreRejected) {
  const auto charts = charts_of(strip_set());
  qs::remesh::AnisotropicOptions o;
  try {
    qs::remesh::remesh_anisotropic(charts, o);
    ADD_FAILURE() << "max_area 0 accepted";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("area bound"));
  }
  o.max_area = 0.1;
  o.max_aspect = 1.2;
  try {
    qs::remesh::remesh_anisotropic(charts, o);
    ADD_FAILURE() << "max_aspect 1.2 accepted";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr(">= 1.5"));
  }
  o.max_aspect = 2;
  o.max_level = qs::remesh::kMaxAnisotropicLevel + 1;
  EXPECT_THROW(qs::remesh::remesh_anisotropic(charts, o), qs::InvalidInput);
  EXPECT_THROW(qs::remesh::remesh_anisotropic({}, qs::remesh::anisotropic_options(2, 2)), qs::InvalidInput);
  o.max_level = 3;
  o.smooth_iterations = -1;
  try {
    qs::remesh::remesh_anisotropic(charts, o);
    ADD_FAILURE() << "smooth_iterations -1 accepted";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("smoothing sweeps -1"));
  }
  o.smooth_iterations = 2;
  o.smooth_below = 75;
  try {
    qs::remesh::remesh_anisotropic(charts, o);
    ADD_FAILURE() << "smooth_below 75 accepted";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("0..60 degrees"));
  }
  o.smooth_below = qs::remesh::kDefaultSmoothBelow;
  for (int rounds : {-1, 11}) {
    o.flip_rounds = rounds;
    try {
      qs::remesh::remesh_anisotropic(charts, o);
      ADD_FAILURE() << "flip_rounds " << rounds << " accepted";
    } catch (const qs::InvalidInput& e) {
      EXPECT_THAT(e.what(), HasSubstr("flip rounds " + std::to_string(rounds) + " are out of range; expected 0..10"));
    }
  }
  EXPECT_THROW(qs::remesh::anisotropic_options(-1, 2), qs::InvalidInput);
  EXPECT_THROW(qs::remesh::anisotropic_options(3, 0), qs::InvalidInput);
}

}  // namespace
