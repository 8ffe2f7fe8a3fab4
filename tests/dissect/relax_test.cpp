// Relaxation of the seed loop (paper 3.3, figure 6). Every property is checked independently of
// the implementation: own edge set and flood fill, own point-to-triangle distance.

#include "qs/dissect/relax.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "qs/core/error.h"
#include "qs/dissect/seed_loop.h"
#include "qs/shapes/shapes.h"

namespace {

using qs::TriMesh;
using qs::Vec3;
using qs::dissect::RelaxedLoop;
using qs::dissect::RelaxOptions;
using qs::dissect::SeedLoop;
using Seeds = std::array<int, 4>;
using ::testing::HasSubstr;

using Edge = std::pair<int, int>;
Edge edge(int a, int b) { return {std::min(a, b), std::max(a, b)}; }

double length(const TriMesh& m, const std::vector<int>& p) {
  double sum = 0;
  for (std::size_t k = 1; k < p.size(); ++k) sum += (m.positions[p[k]] - m.positions[p[k - 1]]).norm();
  return sum;
}

int nearest_vertex(const TriMesh& m, const Vec3& direction) {
  int best = 0;
  for (int v = 1; v < m.num_vertices(); ++v)
    if (m.positions[v].normalized().dot(direction.normalized()) >
        m.positions[best].normalized().dot(direction.normalized()))
      best = v;
  return best;
}

/// Everything trace_seed_loop guarantees, checked with an own flood fill.
void expect_valid_loop(const TriMesh& m, const Seeds& seeds, const SeedLoop& loop) {
  EXPECT_EQ(loop.seeds, seeds);
  std::map<Edge, std::vector<int>> faces_of;
  for (int f = 0; f < m.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) faces_of[edge(m.faces[f][k], m.faces[f][(k + 1) % 3])].push_back(f);
  for (const auto& [e, fs] : faces_of) ASSERT_EQ(fs.size(), 2u) << "edge " << e.first << "-" << e.second;
  const std::set<int> seed_set(seeds.begin(), seeds.end());
  std::map<int, int> uses;
  std::set<Edge> loop_edges;
  for (int i = 0; i < 4; ++i) {
    const auto& p = loop.paths[i];
    ASSERT_GE(p.size(), 2u) << "path " << i;
    EXPECT_EQ(p.front(), seeds[i]);
    EXPECT_EQ(p.back(), seeds[(i + 1) % 4]);
    for (std::size_t k = 0; k < p.size(); ++k) {
      ++uses[p[k]];
      if (k + 1 < p.size()) {
        const Edge e = edge(p[k], p[k + 1]);
        EXPECT_EQ(faces_of.count(e), 1u) << "path " << i << " jumps " << p[k] << "->" << p[k + 1];
        EXPECT_TRUE(loop_edges.insert(e).second) << "edge used twice";
      }
    }
  }
  for (const auto& [v, n] : uses) EXPECT_EQ(n, seed_set.count(v) ? 2 : 1) << "vertex " << v;
  std::vector<int> part(m.num_faces(), -1);
  int parts = 0;
  for (int f0 = 0; f0 < m.num_faces(); ++f0) {
    if (part[f0] >= 0) continue;
    std::vector<int> stack{f0};
    part[f0] = parts;
    while (!stack.empty()) {
      const int f = stack.back();
      stack.pop_back();
      for (int k = 0; k < 3; ++k) {
        const Edge e = edge(m.faces[f][k], m.faces[f][(k + 1) % 3]);
        if (loop_edges.count(e)) continue;
        for (int g : faces_of.at(e))
          if (part[g] < 0) {
            part[g] = parts;
            stack.push_back(g);
          }
      }
    }
    ++parts;
  }
  EXPECT_EQ(parts, 2);
  for (const Edge& e : loop_edges) {
    const auto it = faces_of.find(e);
    if (it != faces_of.end()) {
      EXPECT_NE(part[it->second[0]], part[it->second[1]]);
    }
  }
  EXPECT_NO_THROW(qs::dissect::seed_patch_of_faces(m, loop));
}

/// Distance from p to triangle abc (Ericson, Real-Time Collision Detection 5.1.5).
double point_triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return (p - a).norm();
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return (p - b).norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return (p - c).norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
  const double denom = 1 / (va + vb + vc);
  return (p - (a + ab * (vb * denom) + ac * (vc * denom))).norm();
}

/// Largest distance from a vertex added by the relaxation to the input surface.
double max_distance_of_new_vertices(const TriMesh& input, const TriMesh& result) {
  double worst = 0;
  for (int v = input.num_vertices(); v < result.num_vertices(); ++v) {
    double d = std::numeric_limits<double>::infinity();
    for (const auto& t : input.faces)
      d = std::min(d, point_triangle_distance(result.positions[v], input.positions[t[0]], input.positions[t[1]],
                                              input.positions[t[2]]));
    worst = std::max(worst, d);
  }
  return worst;
}

/// All the invariants of a relaxation result.
void expect_valid_result(const TriMesh& m, const SeedLoop& loop, const RelaxedLoop& r) {
  expect_valid_loop(r.mesh, loop.seeds, r.loop);
  ASSERT_GE(r.mesh.num_vertices(), m.num_vertices());
  EXPECT_EQ(r.inserted_vertices, r.mesh.num_vertices() - m.num_vertices());
  for (int v = 0; v < m.num_vertices(); ++v) ASSERT_EQ(r.mesh.positions[v], m.positions[v]) << "vertex " << v;
  // Euler characteristic 2: still a closed genus-0 mesh.
  std::set<Edge> edges;
  for (const auto& t : r.mesh.faces)
    for (int k = 0; k < 3; ++k) edges.insert(edge(t[k], t[(k + 1) % 3]));
  EXPECT_EQ(r.mesh.num_vertices() - static_cast<int>(edges.size()) + r.mesh.num_faces(), 2);
  const double diagonal = qs::bounding_box(m.positions).diagonal();
  EXPECT_LT(max_distance_of_new_vertices(m, r.mesh), 1e-12 * diagonal);
  // The surface is only refined: the same area.
  double a0 = 0, a1 = 0;
  for (int f = 0; f < m.num_faces(); ++f) a0 += qs::face_area(m, f);
  for (int f = 0; f < r.mesh.num_faces(); ++f) a1 += qs::face_area(r.mesh, f);
  EXPECT_NEAR(a1, a0, 1e-9 * a0);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(r.length_before[i], length(m, loop.paths[i]), 1e-12);
    EXPECT_NEAR(r.length_after[i], length(r.mesh, r.loop.paths[i]), 1e-12);
  }
  EXPECT_EQ(r.steps.size() % 4, 0u);
}

struct Case {
  std::string name;
  TriMesh mesh;
  Seeds seeds;
};

std::vector<Case> cases() {
  std::vector<Case> out;
  for (auto [name, mesh] : std::vector<std::pair<std::string, TriMesh>>{
           {"bumpy_sphere", qs::shapes::bumpy_sphere(0.2, 5, 3)},
           {"star_blob", qs::shapes::star_blob(6, 1.5, 4)},
           {"ellipsoid", qs::shapes::ellipsoid(3, 2, 1, 3)}}) {
    out.push_back({name + " chosen seeds", mesh, qs::dissect::choose_seeds(mesh)});
    // A tilted belt: paths across the mesh's edge directions, which makes edge paths zig-zag.
    Seeds tilted{};
    const std::array<Vec3, 4> dirs = {Vec3(1, 0.1, 0.5), Vec3(-0.2, 1, 0.3), Vec3(-1, 0.1, -0.5),
                                      Vec3(0.2, -1, -0.3)};
    for (int i = 0; i < 4; ++i) tilted[i] = nearest_vertex(mesh, dirs[i]);
    out.push_back({name + " tilted seeds", mesh, tilted});
  }
  return out;
}

TEST(RelaxSeedLoop, ResultIsAValidSeedLoopOnTheSameSurface) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    const SeedLoop loop = qs::dissect::trace_seed_loop(c.mesh, c.seeds);
    for (int rounds : {1, 2}) {
      SCOPED_TRACE("rounds " + std::to_string(rounds));
      RelaxOptions options;
      options.rounds = rounds;
      const RelaxedLoop r = qs::dissect::relax_seed_loop(c.mesh, loop, options);
      expect_valid_result(c.mesh, loop, r);
      ASSERT_EQ(r.steps.size(), 4u * rounds);
      int relaxed = 0;
      for (const auto& s : r.steps) {
        relaxed += s.relaxed;
        EXPECT_EQ(s.relaxed, s.why.empty()) << s.why;
      }
      EXPECT_EQ(relaxed, 4 * rounds) << "every step should succeed on these smooth shapes";
      EXPECT_GT(r.inserted_vertices, 0);
    }
  }
}

// Seeds at the axis ends of an ellipsoid: the loop's geodesic is the equator z = 0 (a mirror
// plane of the mesh as well as of the ellipsoid), which shortest edge paths can only follow in a
// zig-zag. The relaxed curves lie on the equator far more closely and are shorter.
TEST(RelaxSeedLoop, EllipsoidEquatorCurvesBecomeShorterAndFlatter) {
  const TriMesh m = qs::shapes::ellipsoid(3, 2, 1, 4);
  const Seeds seeds{nearest_vertex(m, Vec3(1, 0, 0)), nearest_vertex(m, Vec3(0, 1, 0)),
                    nearest_vertex(m, Vec3(-1, 0, 0)), nearest_vertex(m, Vec3(0, -1, 0))};
  for (int s : seeds) ASSERT_NEAR(m.positions[s].z(), 0, 1e-12);
  const SeedLoop loop = qs::dissect::trace_seed_loop(m, seeds);
  const RelaxedLoop r = qs::dissect::relax_seed_loop(m, loop);
  expect_valid_result(m, loop, r);
  // The smooth quarter ellipse arc (the mesh's own section is a little shorter, being inscribed).
  double quarter = 0;
  const int n = 100000;
  for (int k = 0; k < n; ++k) {
    const double a = M_PI / 2 * k / n, b = M_PI / 2 * (k + 1) / n;
    quarter += std::hypot(3 * (std::cos(b) - std::cos(a)), 2 * (std::sin(b) - std::sin(a)));
  }
  for (int i = 0; i < 4; ++i) {
    SCOPED_TRACE("curve " + std::to_string(i));
    double z_before = 0, z_after = 0;
    for (int v : loop.paths[i]) z_before = std::max(z_before, std::abs(m.positions[v].z()));
    for (int v : r.loop.paths[i]) z_after = std::max(z_after, std::abs(r.mesh.positions[v].z()));
    EXPECT_LT(r.length_after[i], r.length_before[i]);
    EXPECT_LT(std::abs(r.length_after[i] - quarter), 0.5 * std::abs(r.length_before[i] - quarter));
    EXPECT_LT(z_after, 0.5 * z_before);
  }
}

// The first step cuts the input mesh itself: its new vertices lie on input edges, between the ends.
TEST(RelaxSeedLoop, FirstStepPutsNewVerticesOnInputEdges) {
  const TriMesh m = qs::shapes::bumpy_sphere(0.2, 5, 3);
  const SeedLoop loop = qs::dissect::trace_seed_loop(m, qs::dissect::choose_seeds(m));
  const RelaxedLoop r = qs::dissect::relax_seed_loop(m, loop);
  ASSERT_TRUE(r.steps[0].relaxed) << r.steps[0].why;
  ASSERT_GT(r.steps[0].inserted_vertices, 0);
  std::set<Edge> edges;
  for (const auto& t : m.faces)
    for (int k = 0; k < 3; ++k) edges.insert(edge(t[k], t[(k + 1) % 3]));
  const double diagonal = qs::bounding_box(m.positions).diagonal();
  for (int v = m.num_vertices(); v < m.num_vertices() + r.steps[0].inserted_vertices; ++v) {
    const Vec3& p = r.mesh.positions[v];
    bool on_edge = false;
    for (const Edge& e : edges) {
      const Vec3 a = m.positions[e.first], ab = m.positions[e.second] - a;
      const double t = (p - a).dot(ab) / ab.squaredNorm();
      if (t > 0 && t < 1 && (a + t * ab - p).norm() < 1e-13 * diagonal) {
        on_edge = true;
        break;
      }
    }
    EXPECT_TRUE(on_edge) << "vertex " << v << " is on no input edge";
  }
}

TEST(RelaxSeedLoop, CurvesDoNotPassThroughVerticesToAvoid) {
  const TriMesh m = qs::shapes::bumpy_sphere(0.2, 5, 3);
  const SeedLoop loop = qs::dissect::trace_seed_loop(m, qs::dissect::choose_seeds(m));
  const RelaxedLoop free = qs::dissect::relax_seed_loop(m, loop);
  // The input vertices the unconstrained curves pass through (besides the seeds).
  RelaxOptions options;
  options.keep_sides = false;  // a curve may pass on either side of them (see the next test)
  for (const auto& p : free.loop.paths)
    for (std::size_t k = 1; k + 1 < p.size(); ++k)
      if (p[k] < m.num_vertices()) options.avoid.push_back(p[k]);
  ASSERT_FALSE(options.avoid.empty()) << "the test needs curves that snap onto input vertices";
  const RelaxedLoop r = qs::dissect::relax_seed_loop(m, loop, options);
  expect_valid_result(m, loop, r);
  for (const auto& s : r.steps) EXPECT_TRUE(s.relaxed) << s.why;
  const std::set<int> avoid(options.avoid.begin(), options.avoid.end());
  for (const auto& p : r.loop.paths)
    for (std::size_t k = 1; k + 1 < p.size(); ++k) EXPECT_EQ(avoid.count(p[k]), 0u) << "vertex " << p[k];
}

TEST(RelaxSeedLoop, KeepsVerticesToAvoidOnTheirSideOfTheLoop) {
  // Input vertices that the unconstrained relaxation moves to the other side of the loop: given
  // as vertices to avoid, they must stay where the input loop has them, the steps that would
  // move them being refused with a reason.
  const TriMesh m = qs::shapes::bumpy_sphere(0.2, 5, 3);
  const SeedLoop loop = qs::dissect::trace_seed_loop(m, qs::dissect::choose_seeds(m));
  const RelaxedLoop free = qs::dissect::relax_seed_loop(m, loop);
  std::vector<int> all(m.num_vertices());
  for (int v = 0; v < m.num_vertices(); ++v) all[v] = v;
  const std::vector<int> before = qs::dissect::sides_of_vertices(m, loop, all);
  const std::vector<int> after = qs::dissect::sides_of_vertices(free.mesh, free.loop, all);
  RelaxOptions options;
  for (int v = 0; v < m.num_vertices(); ++v)
    if (before[v] >= 0 && after[v] >= 0 && before[v] != after[v]) options.avoid.push_back(v);
  ASSERT_FALSE(options.avoid.empty()) << "the test needs a relaxation that moves a curve across vertices";
  const RelaxedLoop r = qs::dissect::relax_seed_loop(m, loop, options);
  expect_valid_result(m, loop, r);
  const std::vector<int> kept = qs::dissect::sides_of_vertices(r.mesh, r.loop, options.avoid);
  for (std::size_t k = 0; k < options.avoid.size(); ++k)
    EXPECT_EQ(kept[k], before[options.avoid[k]]) << "vertex " << options.avoid[k];
  int refused = 0;
  for (const auto& s : r.steps)
    if (!s.relaxed) {
      ++refused;
      EXPECT_THAT(s.why, HasSubstr("other side")) << s.why;
    }
  EXPECT_GT(refused, 0);
}

TEST(RelaxSeedLoop, IsDeterministic) {
  const TriMesh m = qs::shapes::bumpy_sphere(0.2, 5, 3);
  const SeedLoop loop = qs::dissect::trace_seed_loop(m, qs::dissect::choose_seeds(m));
  const RelaxedLoop a = qs::dissect::relax_seed_loop(m, loop);
  const RelaxedLoop b = qs::dissect::relax_seed_loop(m, loop);
  EXPECT_EQ(a.mesh.positions, b.mesh.positions);
  EXPECT_EQ(a.mesh.faces, b.mesh.faces);
  EXPECT_EQ(a.loop.paths, b.loop.paths);
}

TEST(RelaxSeedLoop, ZeroRoundsReturnsTheInput) {
  const TriMesh m = qs::shapes::icosphere(2);
  const SeedLoop loop = qs::dissect::trace_seed_loop(m, qs::dissect::choose_seeds(m));
  RelaxOptions options;
  options.rounds = 0;
  const RelaxedLoop r = qs::dissect::relax_seed_loop(m, loop, options);
  EXPECT_EQ(r.mesh.positions, m.positions);
  EXPECT_EQ(r.mesh.faces, m.faces);
  EXPECT_EQ(r.loop.paths, loop.paths);
  EXPECT_EQ(r.inserted_vertices, 0);
  EXPECT_TRUE(r.steps.empty());
  EXPECT_EQ(r.length_before, r.length_after);
}

TEST(RelaxSeedLoop, ReportsProgressAndHonoursCancel) {
  const TriMesh m = qs::shapes::icosphere(3);
  const SeedLoop loop = qs::dissect::trace_seed_loop(m, qs::dissect::choose_seeds(m));
  std::vector<double> fractions;
  qs::Context context;
  context.progress = [&](const std::string& stage, double f) {
    EXPECT_EQ(stage, "relax seed loop");
    fractions.push_back(f);
  };
  qs::dissect::relax_seed_loop(m, loop, {}, context);
  ASSERT_FALSE(fractions.empty());
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_EQ(fractions.back(), 1.0);
  std::atomic<bool> cancel{true};
  qs::Context cancelled;
  cancelled.cancel = &cancel;
  EXPECT_THROW(qs::dissect::relax_seed_loop(m, loop, {}, cancelled), qs::Error);
}

TEST(RelaxSeedLoopErrors, RejectsABrokenLoopAndBadOptions) {
  const TriMesh m = qs::shapes::icosphere(2);
  const SeedLoop loop = qs::dissect::trace_seed_loop(m, qs::dissect::choose_seeds(m));
  SeedLoop broken = loop;
  broken.paths[1].erase(broken.paths[1].begin() + 1);  // no longer an edge path
  try {
    qs::dissect::relax_seed_loop(m, broken);
    ADD_FAILURE() << "no exception";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("seed loop"));
  }
  RelaxOptions options;
  options.rounds = -1;
  try {
    qs::dissect::relax_seed_loop(m, loop, options);
    ADD_FAILURE() << "no exception";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("rounds"));
  }
  options.rounds = 1;
  options.avoid = {m.num_vertices()};
  try {
    qs::dissect::relax_seed_loop(m, loop, options);
    ADD_FAILURE() << "no exception";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("avoid"));
  }
  options.avoid.clear();
  options.snap = 0.5;
  try {
    qs::dissect::relax_seed_loop(m, loop, options);
    ADD_FAILURE() << "no exception";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("snap"));
  }
}

}  // namespace
