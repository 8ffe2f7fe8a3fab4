// Metro distance: known distances between simple surfaces, determinism, preconditions, and the
// closest-point structure against a brute-force search written independently here.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/metro/metro.h"
#include "qs/shapes/shapes.h"

using qs::TriMesh;
using qs::Vec3;
using qs::metro::metro;
using qs::metro::MetroOptions;
using qs::metro::MetroResult;
using ::testing::HasSubstr;

namespace {

TriMesh transformed(TriMesh m, double scale, const Vec3& shift) {
  for (Vec3& p : m.positions) p = scale * p + shift;
  return m;
}

MetroOptions with_samples(long n) {
  MetroOptions o;
  o.face_samples = n;
  return o;
}

/// The smallest distance from the origin to any face's plane: a lower bound on the radius of
/// every point of a mesh that is star-shaped about the origin.
double min_plane_radius(const TriMesh& m) {
  double r = std::numeric_limits<double>::infinity();
  for (const auto& f : m.faces) {
    const Vec3 &a = m.positions[f[0]], &b = m.positions[f[1]], &c = m.positions[f[2]];
    const Vec3 n = (b - a).cross(c - a).normalized();
    r = std::min(r, std::abs(n.dot(a)));
  }
  return r;
}

// Independent reference: distance to a segment, and to a triangle as "projection inside, else
// the nearest of the three edges".
double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

double triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  double best = std::min({segment_distance(p, a, b), segment_distance(p, b, c), segment_distance(p, c, a)});
  if (n.squaredNorm() > 0) {
    const Vec3 q = p - n.dot(p - a) / n.squaredNorm() * n;  // projection onto the plane
    const bool inside = (b - a).cross(q - a).dot(n) >= 0 && (c - b).cross(q - b).dot(n) >= 0 &&
                        (a - c).cross(q - c).dot(n) >= 0;
    if (inside) best = std::min(best, (p - q).norm());
  }
  return best;
}

double brute_force_distance(const TriMesh& m, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& f : m.faces)
    best = std::min(best, triangle_distance(p, m.positions[f[0]], m.positions[f[1]], m.positions[f[2]]));
  return best;
}

}  // namespace

TEST(Metro, ConcentricSpheresAreATenthApart) {
  // A unit icosphere and the same scaled by 1.1. Every point of A has a radius in [rmin, 1] and
  // every point of B one in [1.1 rmin, 1.1] (rmin bounds the tessellation's sag), so each
  // distance lies in [1.1 rmin - 1, 1.1 - rmin]; with 5 subdivisions that is 0.1 within 0.3%.
  const TriMesh a = qs::shapes::icosphere(5);
  const TriMesh b = transformed(a, 1.1, Vec3::Zero());
  const double rmin = min_plane_radius(a);
  ASSERT_GT(rmin, 0.999);
  const double lo = 1.1 * rmin - 1, hi = 1.1 - rmin;
  const MetroResult r = metro(a, b, with_samples(50000));
  for (const auto* s : {&r.a_to_b, &r.b_to_a}) {
    EXPECT_NEAR(s->mean, 0.1, 0.001);
    EXPECT_GE(s->mean, lo);
    EXPECT_LE(s->max, hi);
    EXPECT_GE(s->rms, s->mean);
    EXPECT_LE(s->rms, s->max);
    EXPECT_EQ(s->samples, 50000);
    EXPECT_EQ(s->vertex_samples, a.num_vertices());
  }
  EXPECT_NEAR(r.mean, 0.1, 0.001);
  EXPECT_EQ(r.max, std::max(r.a_to_b.max, r.b_to_a.max));
  EXPECT_DOUBLE_EQ(r.mean, 0.5 * (r.a_to_b.mean + r.b_to_a.mean));
  EXPECT_DOUBLE_EQ(r.diagonal, qs::bounding_box(a.positions).diagonal());
  EXPECT_NEAR(r.area_b / r.area_a, 1.21, 1e-9);
  // The reported location of the maximum is a point of the sampled mesh at that distance.
  EXPECT_NEAR(qs::metro::SurfaceDistance(b).distance(r.a_to_b.max_at), r.a_to_b.max, 1e-12);
  EXPECT_NEAR(r.a_to_b.max_at.norm(), 1.0, 1.0 - rmin + 1e-12);
}

TEST(Metro, IdenticalMeshesAreZeroApart) {
  const TriMesh a = qs::shapes::bumpy_sphere(0.2, 5, 4);
  const MetroResult r = metro(a, a, with_samples(20000));
  EXPECT_LT(r.max, 1e-13 * r.diagonal);
  EXPECT_LT(r.rms, 1e-14 * r.diagonal);
  EXPECT_GT(r.diagonal, 2.0);
}

TEST(Metro, TranslatedPlaneGivesTheTranslationDistance) {
  // A flat disk and the same disk 0.05 above it: every point is exactly 0.05 from the other.
  const TriMesh a = qs::shapes::open_disk(6);
  const TriMesh b = transformed(a, 1.0, Vec3(0, 0, 0.05));
  const MetroResult r = metro(a, b, with_samples(10000));
  for (const double v : {r.a_to_b.mean, r.a_to_b.rms, r.a_to_b.max, r.b_to_a.mean, r.b_to_a.rms,
                         r.b_to_a.max, r.mean, r.rms, r.max})
    EXPECT_NEAR(v, 0.05, 1e-12);
  EXPECT_NEAR(r.diagonal, qs::bounding_box(a.positions).diagonal(), 1e-15);
}

TEST(Metro, OneSidedDistancesDifferWhenOneSurfaceHasMore) {
  // B = the unit sphere plus a second one at (3, 0, 0); A is the first alone. A lies on B, but
  // B's second sphere is far from A: the two directions differ, and the two-sided max is B's.
  const TriMesh b = qs::shapes::two_components();
  TriMesh a;
  a.positions.assign(b.positions.begin(), b.positions.begin() + 42);
  a.faces.assign(b.faces.begin(), b.faces.begin() + 80);
  const MetroResult r = metro(a, b, with_samples(20000));
  EXPECT_LT(r.a_to_b.max, 1e-12);
  EXPECT_GT(r.b_to_a.max, 2.0);
  EXPECT_LT(r.b_to_a.max, 3.0 + 1e-9);
  EXPECT_GT(r.b_to_a.mean, 0.5);  // half of B's area is 1 to 3 away
  EXPECT_EQ(r.max, r.b_to_a.max);
  EXPECT_GT(r.b_to_a.max_at.x(), 1.5);  // on the far sphere
}

TEST(Metro, DeterministicForASeedAndAnyThreadCount) {
  const TriMesh a = qs::shapes::bumpy_sphere(0.1, 4, 4);
  const TriMesh b = qs::shapes::ellipsoid(1.05, 1.0, 0.95, 4);
  MetroOptions o = with_samples(30000);
  o.threads = 1;
  const MetroResult one = metro(a, b, o);
  for (int threads : {1, 2, 3, 8}) {
    o.threads = threads;
    const MetroResult r = metro(a, b, o);
    EXPECT_EQ(r.a_to_b.mean, one.a_to_b.mean) << threads;
    EXPECT_EQ(r.a_to_b.rms, one.a_to_b.rms) << threads;
    EXPECT_EQ(r.a_to_b.max, one.a_to_b.max) << threads;
    EXPECT_EQ(r.a_to_b.max_at, one.a_to_b.max_at) << threads;
    EXPECT_EQ(r.b_to_a.mean, one.b_to_a.mean) << threads;
    EXPECT_EQ(r.b_to_a.max, one.b_to_a.max) << threads;
    EXPECT_EQ(r.max, one.max);
    EXPECT_EQ(r.rms, one.rms);
  }
  // Another seed samples other points: other numbers, but the same estimate.
  o.seed = 12345;
  const MetroResult other = metro(a, b, o);
  EXPECT_NE(other.a_to_b.mean, one.a_to_b.mean);
  EXPECT_NEAR(other.a_to_b.mean, one.a_to_b.mean, 0.02 * one.a_to_b.mean);
  EXPECT_NEAR(other.b_to_a.rms, one.b_to_a.rms, 0.02 * one.b_to_a.rms);
}

TEST(Metro, SampleCountsAndIgnoredVertices) {
  TriMesh a = qs::shapes::icosphere(2);  // 320 faces, 162 vertices
  const TriMesh b = qs::shapes::icosphere(3);  // 1280 faces
  a.positions.push_back(Vec3(100, 100, 100));  // used by no face: neither sampled nor in the box
  MetroOptions o;
  o.min_samples = 1000;
  o.samples_per_face = 3;
  MetroResult r = metro(a, b, o);
  EXPECT_EQ(r.a_to_b.samples, 3 * 1280);
  EXPECT_EQ(r.b_to_a.samples, 3 * 1280);
  EXPECT_EQ(r.a_to_b.vertex_samples, 162);
  EXPECT_EQ(r.b_to_a.vertex_samples, 642);
  EXPECT_LT(r.diagonal, 4.0);
  o.min_samples = 5000;
  EXPECT_EQ(metro(a, b, o).a_to_b.samples, 5000);
  o.sample_vertices = false;
  r = metro(a, b, o);
  EXPECT_EQ(r.a_to_b.vertex_samples, 0);
  EXPECT_EQ(r.b_to_a.vertex_samples, 0);
  // B's vertices alone can be left out (a remesh's lie on the original); the surface samples and
  // so the mean and RMS do not change.
  o.sample_vertices = true;
  const MetroResult all = metro(a, b, o);
  o.sample_vertices_b = false;
  r = metro(a, b, o);
  EXPECT_EQ(r.a_to_b.vertex_samples, 162);
  EXPECT_EQ(r.b_to_a.vertex_samples, 0);
  EXPECT_EQ(r.mean, all.mean);
  EXPECT_EQ(r.rms, all.rms);
  EXPECT_LE(r.max, all.max);
}

TEST(Metro, SurfaceDistanceMatchesBruteForce) {
  const TriMesh m = qs::shapes::bumpy_sphere(0.3, 7, 3);
  const qs::metro::SurfaceDistance sd(m);
  std::uint64_t s = 7;
  auto next = [&] {  // a small LCG is enough for query points
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(s >> 11) * 0x1.0p-53;
  };
  for (int i = 0; i < 400; ++i) {
    const double scale = i < 200 ? 1.5 : 4.0;  // near the surface, and far from it
    const Vec3 p(scale * (2 * next() - 1), scale * (2 * next() - 1), scale * (2 * next() - 1));
    const auto c = sd.closest(p);
    EXPECT_NEAR(c.distance, brute_force_distance(m, p), 1e-12) << i;
    EXPECT_NEAR((p - c.point).norm(), c.distance, 1e-12);
    const auto& f = m.faces[static_cast<size_t>(c.face)];
    EXPECT_NEAR(triangle_distance(c.point, m.positions[f[0]], m.positions[f[1]], m.positions[f[2]]), 0, 1e-12);
  }
}

TEST(Metro, ARefitTreeAnswersAsAFreshOne) {
  TriMesh m = qs::shapes::bumpy_sphere(0.3, 7, 3);
  qs::metro::SurfaceDistance sd(m);
  // A large, uneven move: every vertex twisted about z and stretched along x.
  for (Vec3& p : m.positions) {
    const double a = 1.2 * p.z();
    p = Vec3(2.5 * (std::cos(a) * p.x() - std::sin(a) * p.y()), std::sin(a) * p.x() + std::cos(a) * p.y(), p.z());
  }
  sd.refit(m);
  const qs::metro::SurfaceDistance fresh(m);
  std::vector<int> hints(200, -1);
  for (int round = 0; round < 2; ++round) {  // the second round starts from the first's hints
    for (int i = 0; i < 200; ++i) {
      const double t = 0.61 * i;
      const Vec3 p(3 * std::cos(t) * std::sin(0.3 * i), 1.3 * std::sin(t), 1.3 * std::cos(0.7 * i));
      EXPECT_NEAR(sd.closest(p).distance, brute_force_distance(m, p), 1e-12) << i;
      const Vec3 facing(std::cos(t), std::sin(t), 0.5);
      const auto a = sd.closest_facing(p, facing, 0.2, hints[static_cast<size_t>(i)]);
      EXPECT_NEAR(a.distance, fresh.closest_facing(p, facing, 0.2).distance, 1e-12) << i;
    }
  }
  const TriMesh other = qs::shapes::bumpy_sphere(0.3, 7, 2);
  EXPECT_THROW(sd.refit(other), qs::InvalidInput);
}

TEST(Metro, ATreeBuiltOnSeveralThreadsIsTheSameTree) {
  // 81,920 faces: over the size from which the build splits its subtrees over threads.
  const TriMesh m = qs::shapes::bumpy_sphere(0.2, 5, 6);
  ASSERT_GE(m.num_faces(), 40000);
  const qs::metro::SurfaceDistance one(m, "mesh", 1), four(m, "mesh", 4);
  for (int i = 0; i < 500; ++i) {
    const double t = 0.37 * i;
    const Vec3 p(1.4 * std::cos(t) * std::sin(0.21 * i), 1.4 * std::sin(t), 1.4 * std::cos(0.53 * i));
    const auto a = one.closest(p), b = four.closest(p);
    EXPECT_EQ(a.face, b.face) << i;
    EXPECT_EQ(a.distance, b.distance) << i;
    EXPECT_EQ(a.point, b.point) << i;
    const Vec3 facing(std::sin(t), 0.3, std::cos(t));
    EXPECT_EQ(one.closest_facing(p, facing, 0.1).face, four.closest_facing(p, facing, 0.1).face) << i;
  }
  EXPECT_NEAR(one.distance(Vec3(0.1, 0.2, 0.3)), brute_force_distance(m, Vec3(0.1, 0.2, 0.3)), 1e-12);
}

TEST(Metro, ClosestFacingKeepsToTheQuerysSideOfAThinPart) {
  // A thin slab seen from inside its lower sheet: the upper sheet (facing down) is nearer, but
  // only the lower sheet faces up as the query's normal does.
  TriMesh m;
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 0.1), Vec3(1, 0, 0.1), Vec3(0, 1, 0.1)};
  m.faces = {{0, 1, 2}, {3, 5, 4}};  // facing up at z = 0, down at z = 0.1
  const qs::metro::SurfaceDistance sd(m);
  const Vec3 q(0.2, 0.2, 0.06);
  EXPECT_EQ(sd.closest(q).face, 1);
  const auto up = sd.closest_facing(q, Vec3(0, 0, 3), 0.0);  // any length: the direction counts
  EXPECT_EQ(up.face, 0);
  EXPECT_NEAR(up.distance, 0.06, 1e-15);
  EXPECT_NEAR((up.point - Vec3(0.2, 0.2, 0)).norm(), 0, 1e-15);
  EXPECT_EQ(sd.closest_facing(q, Vec3(0, 0, -1), 0.0).face, 1);
  // A cosine no face meets, and a zero direction: none.
  const auto none = sd.closest_facing(q, Vec3(1, 0, 0), 0.5);
  EXPECT_EQ(none.face, -1);
  EXPECT_TRUE(std::isinf(none.distance));
  EXPECT_EQ(sd.closest_facing(q, Vec3::Zero(), -1.0).face, -1);
  // On a closed surface with the outward normal at the query's nearest point, it agrees with
  // closest() wherever that point's face faces the same way.
  const TriMesh b = qs::shapes::bumpy_sphere(0.3, 7, 3);
  const qs::metro::SurfaceDistance sb(b);
  for (int i = 0; i < 50; ++i) {
    const double t = 0.37 * i;
    const Vec3 p(1.1 * std::cos(t) * std::sin(0.05 + 0.06 * i), 1.1 * std::sin(t) * std::sin(0.05 + 0.06 * i),
                 1.1 * std::cos(0.05 + 0.06 * i));
    const auto c = sb.closest(p);
    const auto& f = b.faces[static_cast<size_t>(c.face)];
    const Vec3 n = (b.positions[f[1]] - b.positions[f[0]]).cross(b.positions[f[2]] - b.positions[f[0]]);
    const auto cf = sb.closest_facing(p, n, 0.999);
    EXPECT_NEAR(cf.distance, c.distance, 1e-12) << i;
  }
}

TEST(Metro, DegenerateFacesAreMeasuredAsTheirEdges) {
  TriMesh m;
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(3, 0, 0), Vec3(0, 5, 0), Vec3(1, 5, 0), Vec3(0, 6, 0)};
  m.faces = {{0, 1, 2}, {3, 4, 5}};  // a collinear "triangle" and a real one far away
  const qs::metro::SurfaceDistance sd(m);
  EXPECT_NEAR(sd.distance(Vec3(2, 1, 0)), 1.0, 1e-15);   // above the far end of the segment 0-2
  EXPECT_NEAR(sd.distance(Vec3(4, 0, 0)), 1.0, 1e-15);   // beyond its end
  EXPECT_NEAR(sd.distance(Vec3(-1, 0, 2)), std::sqrt(5.0), 1e-15);
  // The degenerate face gets no surface samples, and is still a target.
  const MetroResult r = metro(m, m, with_samples(1000));
  EXPECT_LT(r.max, 1e-12);
}

TEST(Metro, RejectsWhatItCannotMeasure) {
  const TriMesh ok = qs::shapes::icosphere(1);
  auto message = [&](const TriMesh& a, const TriMesh& b) -> std::string {
    try {
      metro(a, b, with_samples(100));
    } catch (const qs::InvalidInput& e) {
      return e.what();
    }
    return "no exception";
  };
  EXPECT_THAT(message(TriMesh{}, ok), HasSubstr("A: the mesh has no faces"));
  TriMesh bad_index = ok;
  bad_index.faces[7][1] = 999;
  bad_index.faces[9][2] = -1;
  const std::string m1 = message(ok, bad_index);
  EXPECT_THAT(m1, HasSubstr("B: "));
  EXPECT_THAT(m1, HasSubstr("2 faces with a vertex index outside [0, 42) (faces 7, 9)"));
  TriMesh nan = ok;
  nan.positions[5].y() = std::numeric_limits<double>::quiet_NaN();
  nan.positions[6].z() = std::numeric_limits<double>::infinity();
  EXPECT_THAT(message(nan, ok), HasSubstr("2 vertices used by faces have a NaN or infinite coordinate (vertices 5, 6)"));
  // Both problems at once are both reported.
  TriMesh both = bad_index;
  both.positions[5].x() = std::numeric_limits<double>::quiet_NaN();
  const std::string m2 = message(both, ok);
  EXPECT_THAT(m2, HasSubstr("faces 7, 9"));
  EXPECT_THAT(m2, HasSubstr("vertices 5"));
  TriMesh flat;
  flat.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0)};
  flat.faces = {{0, 1, 2}};
  EXPECT_THAT(message(ok, flat), HasSubstr("B: every face has zero area (1 faces)"));
  EXPECT_THROW(qs::metro::SurfaceDistance{TriMesh{}}, qs::InvalidInput);

  MetroOptions o;
  o.face_samples = -1;
  EXPECT_THROW(metro(ok, ok, o), qs::InvalidInput);
  o = {};
  o.samples_per_face = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(metro(ok, ok, o), qs::InvalidInput);
  o = {};
  o.min_samples = 0;
  EXPECT_THROW(metro(ok, ok, o), qs::InvalidInput);
  o = {};
  o.threads = -2;
  EXPECT_THROW(metro(ok, ok, o), qs::InvalidInput);
}

TEST(Metro, ReportsProgressAndStopsWhenCancelled) {
  const TriMesh a = qs::shapes::icosphere(3);
  std::vector<std::string> stages;
  double last = -1;
  qs::Context ctx;
  ctx.progress = [&](const std::string& stage, double f) {
    if (stages.empty() || stages.back() != stage) stages.push_back(stage);
    last = f;
  };
  metro(a, a, with_samples(20000), ctx);
  EXPECT_THAT(stages, ::testing::ElementsAre("metro A -> B", "metro B -> A"));
  EXPECT_EQ(last, 1.0);

  std::atomic<bool> cancel{true};
  ctx.cancel = &cancel;
  try {
    metro(a, a, with_samples(20000), ctx);
    FAIL() << "not cancelled";
  } catch (const qs::Error& e) {
    EXPECT_EQ(e.code(), qs::ErrorCode::Internal);
    EXPECT_THAT(e.what(), HasSubstr("cancelled"));
  }
}

TEST(Metro, ExactOnBadlySpreadTrianglesToo) {
  // Triangles at exponentially growing distances make a lopsided hierarchy; the answers must
  // still be those of the brute-force search.
  TriMesh m;
  for (int i = 0; i < 1500; ++i) {
    const double x = std::pow(2.0, i / 16.0), s = 0.1 * x;
    const int v = m.num_vertices();
    m.positions.push_back(Vec3(x, 0, 0));
    m.positions.push_back(Vec3(x + s, 0, s * (i % 3)));
    m.positions.push_back(Vec3(x, s, 0));
    m.faces.push_back({v, v + 1, v + 2});
  }
  const qs::metro::SurfaceDistance sd(m);
  for (int i = 0; i < 1500; i += 37) {
    const Vec3 p(std::pow(2.0, i / 16.0 + 0.03), 0.3 * std::pow(2.0, i / 16.0), -1.0);
    EXPECT_NEAR(sd.distance(p), brute_force_distance(m, p), 1e-12 * p.norm()) << i;
  }
}

TEST(Metro, AThrowingProgressCallbackStopsTheWorkCleanly) {
  const TriMesh a = qs::shapes::icosphere(3);
  qs::Context ctx;
  int calls = 0;
  ctx.progress = [&](const std::string&, double f) {
    if (f > 0 && ++calls == 2) throw std::runtime_error("stop here");
  };
  MetroOptions o = with_samples(100000);
  o.threads = 2;
  EXPECT_THROW(metro(a, a, o, ctx), std::runtime_error);
}

TEST(Metro, VertexDistanceWeighsBothWaysByArea) {
  // A unit icosphere and the same scaled by 1.1: every vertex 0.1 from the other surface (within
  // its sag), both ways; the same on one thread.
  const TriMesh a = qs::shapes::icosphere(4);
  const TriMesh b = transformed(a, 1.1, Vec3::Zero());
  const qs::metro::SurfaceDistance ta(a), tb(b);
  const auto d = qs::metro::vertex_distance(a, ta, b, tb, 0.99);
  EXPECT_NEAR(d.mean, 0.1, 0.002);
  EXPECT_NEAR(d.quantile, 0.1, 0.002);
  EXPECT_GE(d.quantile, d.mean - 0.002);
  qs::Context one;
  one.threads = 1;
  const auto d1 = qs::metro::vertex_distance(a, ta, b, tb, 0.99, one);
  EXPECT_EQ(d1.mean, d.mean);
  EXPECT_EQ(d1.quantile, d.quantile);
  // A surface against itself: zero.
  const auto self = qs::metro::vertex_distance(a, ta, a, ta, 0.5);
  EXPECT_EQ(self.mean, 0);
  EXPECT_EQ(self.quantile, 0);
}
