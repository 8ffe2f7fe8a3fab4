// Tests of the foldover-free warp of the unit square (triangulation over time).
// Bijectivity is checked independently of the warp mesh, two ways: for moderate (coherent)
// motions, a warped regular grid must keep every triangle positive; for any motion, warped
// disjoint lines (refined until the polylines follow the curves) must stay disjoint and simple.
// Every motion also checks: positive warp mesh, points in the square, border points unchanged,
// features landing bit-exactly on their targets.

#include "qs/warp/warp.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "qs/core/error.h"

namespace qs::warp {
namespace {

/// A deterministic value in [0, 1] from an integer (no library RNG: same numbers everywhere).
double hash01(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x / 4294967295.0;
}

double orient(const Vec2& a, const Vec2& b, const Vec2& c) {
  return (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
}

/// n x n points (i / (n-1), j / (n-1)), row by row: the border and the corners included.
std::vector<Vec2> grid_points(int n) {
  std::vector<Vec2> p;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) p.emplace_back(static_cast<double>(i) / (n - 1), static_cast<double>(j) / (n - 1));
  return p;
}

/// Grid triangles (two per cell) of the first n*n warped points with signed area <= 0.
int folded_grid_triangles(const std::vector<Vec2>& q, int n) {
  int folded = 0;
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const Vec2& p00 = q[j * n + i];
      const Vec2& p10 = q[j * n + i + 1];
      const Vec2& p01 = q[(j + 1) * n + i];
      const Vec2& p11 = q[(j + 1) * n + i + 1];
      if (!(orient(p00, p10, p11) > 0)) ++folded;
      if (!(orient(p00, p11, p01) > 0)) ++folded;
    }
  }
  return folded;
}

/// True when the closed segments p0-p1 and q0-q1 cross or touch (the boxes must overlap, so that
/// collinear pieces of one straight image do not count; no exact predicates needed at these scales).
bool segments_meet(const Vec2& p0, const Vec2& p1, const Vec2& q0, const Vec2& q1) {
  if ((p0.cwiseMax(p1) - q0.cwiseMin(q1)).minCoeff() < 0 || (q0.cwiseMax(q1) - p0.cwiseMin(p1)).minCoeff() < 0)
    return false;
  const double o1 = orient(p0, p1, q0), o2 = orient(p0, p1, q1);
  const double o3 = orient(q0, q1, p0), o4 = orient(q0, q1, p1);
  return o1 * o2 <= 0 && o3 * o4 <= 0;
}

/// Checks shared by every motion: the warp mesh is positive, every point stays in the square,
/// border points stay put, and the features (appended after the first `n` points) land exactly.
void check_common(const WarpResult& r, const std::vector<Vec2>& pts, int n, const std::vector<Vec2>& f,
                  const std::vector<Vec2>& g) {
  ASSERT_EQ(r.points.size(), pts.size());
  EXPECT_GT(r.min_warp_area, 0);
  EXPECT_EQ(r.warp_triangles, 2 * (4 + static_cast<int>(f.size())) - 6);
  int off_border = 0, outside = 0;
  for (int i = 0; i < n; ++i) {
    const Vec2& p = pts[i];
    const Vec2& q = r.points[i];
    if (q.x() < 0 || q.x() > 1 || q.y() < 0 || q.y() > 1) ++outside;
    if ((p.x() == 0 || p.x() == 1 || p.y() == 0 || p.y() == 1) && q != p) ++off_border;
  }
  EXPECT_EQ(outside, 0);
  EXPECT_EQ(off_border, 0);
  for (std::size_t k = 0; k < f.size(); ++k) {
    EXPECT_EQ(r.points[n + k].x(), g[k].x()) << "feature " << k;
    EXPECT_EQ(r.points[n + k].y(), g[k].y()) << "feature " << k;
  }
}

/// Pairs of non-adjacent segments of the polylines that meet (grid hashing over the square).
int crossing_polylines(const std::vector<std::vector<Vec2>>& lines) {
  const int g = 256;
  std::vector<std::vector<std::pair<int, int>>> cells(g * g);  // (line, segment)
  auto cell = [g](double x) { return std::clamp(static_cast<int>(x * g), 0, g - 1); };
  for (int i = 0; i < static_cast<int>(lines.size()); ++i)
    for (int j = 0; j + 1 < static_cast<int>(lines[i].size()); ++j) {
      const Vec2 lo = lines[i][j].cwiseMin(lines[i][j + 1]), hi = lines[i][j].cwiseMax(lines[i][j + 1]);
      for (int y = cell(lo.y()); y <= cell(hi.y()); ++y)
        for (int x = cell(lo.x()); x <= cell(hi.x()); ++x) cells[y * g + x].emplace_back(i, j);
    }
  std::vector<std::array<int, 4>> meets;
  for (const auto& c : cells)
    for (std::size_t a = 0; a < c.size(); ++a)
      for (std::size_t b = a + 1; b < c.size(); ++b) {
        const auto [i, j] = std::min(c[a], c[b]);
        const auto [k, l] = std::max(c[a], c[b]);
        if (i == k && l - j <= 1) continue;  // neighbours on one polyline
        if (segments_meet(lines[i][j], lines[i][j + 1], lines[k][l], lines[k][l + 1])) meets.push_back({i, j, k, l});
      }
  std::sort(meets.begin(), meets.end());
  return static_cast<int>(std::unique(meets.begin(), meets.end()) - meets.begin());
}

/// Warps `count` horizontal lines y = (i + 0.5) / count (then the features) and expects their
/// images not to meet. An injective map takes disjoint lines to disjoint simple curves whatever its
/// kinks and stretch (unlike chord triangles of a grid, which fold where a piecewise-linear map
/// shears strongly within one cell). Each line is refined until every image segment is short and
/// its midpoint's image lies on it (within 1e-6), so the polylines follow the curves.
/// Checks the common invariants on every warp as well.
WarpResult warp_lines(const std::vector<Vec2>& f, const std::vector<Vec2>& g, int count = 40, int samples = 1000,
                      const WarpOptions& o = {}) {
  std::vector<std::vector<double>> xs(count);
  for (auto& x : xs)
    for (int j = 0; j < samples; ++j) x.push_back(static_cast<double>(j) / (samples - 1));
  auto warp_all = [&](const std::vector<std::vector<double>>& at, std::vector<std::vector<Vec2>>& out) {
    std::vector<Vec2> pts;
    for (int i = 0; i < count; ++i)
      for (const double x : at[i]) pts.emplace_back(x, (i + 0.5) / count);
    const int n = static_cast<int>(pts.size());
    pts.insert(pts.end(), f.begin(), f.end());
    WarpResult r = warp_square(f, g, pts, o);
    check_common(r, pts, n, f, g);
    out.assign(count, {});
    for (int i = 0, k = 0; i < count; ++i)
      for (std::size_t j = 0; j < at[i].size(); ++j) out[i].push_back(r.points[k++]);
    return r;
  };
  std::vector<std::vector<Vec2>> images, mids;
  WarpResult r = warp_all(xs, images);
  for (int pass = 0; pass < 24; ++pass) {
    std::vector<std::vector<double>> mx(count);
    for (int i = 0; i < count; ++i)
      for (std::size_t j = 0; j + 1 < xs[i].size(); ++j) mx[i].push_back(0.5 * (xs[i][j] + xs[i][j + 1]));
    warp_all(mx, mids);
    int refined = 0;
    for (int i = 0; i < count; ++i) {
      std::vector<double> x = {xs[i][0]};
      std::vector<Vec2> im = {images[i][0]};
      for (std::size_t j = 0; j + 1 < xs[i].size(); ++j) {
        const Vec2& a = images[i][j];
        const Vec2& b = images[i][j + 1];
        const Vec2& m = mids[i][j];
        const double off = std::abs(orient(a, b, m)) / std::max((b - a).norm(), 1e-300);
        if (((b - a).norm() > 1e-3 || off > 1e-6) && xs[i][j + 1] - xs[i][j] > 1e-12) {
          x.push_back(mx[i][j]);
          im.push_back(m);
          ++refined;
        }
        x.push_back(xs[i][j + 1]);
        im.push_back(b);
      }
      xs[i] = std::move(x);
      images[i] = std::move(im);
    }
    if (refined == 0) break;
  }
  EXPECT_EQ(crossing_polylines(images), 0);
  return r;
}

/// Warps a grid of n x n points (then the features) and expects no grid triangle to fold.
WarpResult warp_grid(const std::vector<Vec2>& f, const std::vector<Vec2>& g, int n, const WarpOptions& o = {}) {
  std::vector<Vec2> pts = grid_points(n);
  pts.insert(pts.end(), f.begin(), f.end());
  WarpResult r = warp_square(f, g, pts, o);
  check_common(r, pts, n * n, f, g);
  EXPECT_EQ(folded_grid_triangles(r.points, n), 0);
  return r;
}

/// Targets f + amplitude * (a smooth field that vanishes on the border).
std::vector<Vec2> smooth_targets(const std::vector<Vec2>& f, double amplitude) {
  std::vector<Vec2> g;
  for (const Vec2& p : f)
    g.push_back(p + amplitude * Vec2(std::sin(3.1 * p.y() + 0.3) * std::sin(M_PI * p.x()),
                                     std::cos(2.3 * p.x()) * std::sin(M_PI * p.y())));
  return g;
}

std::vector<Vec2> random_features(int count, std::uint32_t seed, double lo = 0.05, double hi = 0.95) {
  std::vector<Vec2> f;
  for (std::uint32_t i = 0; static_cast<int>(f.size()) < count; ++i) {
    const Vec2 p(lo + (hi - lo) * hash01(seed + 2 * i), lo + (hi - lo) * hash01(seed + 2 * i + 1));
    bool far = true;
    for (const Vec2& q : f) far = far && (p - q).norm() > 0.01;
    if (far) f.push_back(p);
  }
  return f;
}

TEST(WarpSquare, IdentityWhenTargetsAreFeatures) {
  const std::vector<Vec2> f = random_features(12, 100);
  std::vector<Vec2> pts = grid_points(41);
  for (int i = 0; i < 500; ++i) pts.emplace_back(hash01(7000 + 2 * i), hash01(7001 + 2 * i));
  const WarpResult r = warp_square(f, f, pts);
  EXPECT_EQ(r.events, 0);
  EXPECT_EQ(r.detours, 0);
  ASSERT_EQ(r.points.size(), pts.size());
  double worst = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) worst = std::max(worst, (r.points[i] - pts[i]).norm());
  EXPECT_LE(worst, 1e-15);
}

TEST(WarpSquare, SingleFeatureWithoutEventsIsAffinePerTriangle) {
  // Corners + one central feature: the warp mesh is the fan of 4 triangles around it, whose
  // star is the whole square, so the motion needs no flip and each fan triangle maps affinely.
  const Vec2 f(0.5, 0.5), g(0.57, 0.46);
  const std::vector<Vec2> c = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};
  std::vector<Vec2> pts;
  for (int i = 0; i < 2000; ++i) pts.emplace_back(hash01(300 + 2 * i), hash01(301 + 2 * i));
  const WarpResult r = warp_square({f}, {g}, pts);
  EXPECT_EQ(r.events, 0);
  EXPECT_EQ(r.warp_triangles, 4);
  // The warp mesh comes back: the fan of the feature (vertex 4) over the 4 sides, CCW at the start
  // and at the end.
  ASSERT_EQ(r.triangles.size(), 4u);
  std::vector<std::array<int, 2>> sides;
  for (const auto& t : r.triangles) {
    const std::vector<Vec2> start = {c[0], c[1], c[2], c[3], f}, end = {c[0], c[1], c[2], c[3], g};
    EXPECT_GT(orient(start[t[0]], start[t[1]], start[t[2]]), 0);
    EXPECT_GT(orient(end[t[0]], end[t[1]], end[t[2]]), 0);
    const int k = static_cast<int>(std::find(t.begin(), t.end(), 4) - t.begin());
    ASSERT_LT(k, 3);
    sides.push_back({t[(k + 1) % 3], t[(k + 2) % 3]});
  }
  std::sort(sides.begin(), sides.end());
  EXPECT_EQ(sides, (std::vector<std::array<int, 2>>{{0, 1}, {1, 2}, {2, 3}, {3, 0}}));
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Vec2& p = pts[i];
    for (int s = 0; s < 4; ++s) {
      const Vec2& a = c[s];
      const Vec2& b = c[(s + 1) % 4];
      const double area = orient(a, b, f);
      const double wa = orient(p, b, f) / area, wb = orient(a, p, f) / area, wf = orient(a, b, p) / area;
      if (std::min({wa, wb, wf}) < -1e-12) continue;
      const Vec2 expected = wa * a + wb * b + wf * g;
      EXPECT_NEAR(r.points[i].x(), expected.x(), 1e-15) << "point " << i;
      EXPECT_NEAR(r.points[i].y(), expected.y(), 1e-15) << "point " << i;
      break;
    }
  }
}

TEST(WarpSquare, FeatureCrossingFarPastOthersFlipsAndStaysBijective) {
  const std::vector<Vec2> f = {Vec2(0.12, 0.52), Vec2(0.5, 0.3),  Vec2(0.5, 0.7),  Vec2(0.35, 0.42),
                               Vec2(0.65, 0.6),  Vec2(0.3, 0.2),  Vec2(0.7, 0.8),  Vec2(0.62, 0.45)};
  std::vector<Vec2> g = f;
  g[0] = Vec2(0.88, 0.47);
  const WarpResult r = warp_lines(f, g);
  EXPECT_GT(r.events, 3);
  EXPECT_EQ(r.detours, 0);
}

TEST(WarpSquare, TwoFeaturesSwapPlaces) {
  // Straight paths would collide head-on: one feature steps aside first.
  const std::vector<Vec2> f = {Vec2(0.3, 0.5), Vec2(0.7, 0.5), Vec2(0.5, 0.8), Vec2(0.5, 0.2)};
  const std::vector<Vec2> g = {Vec2(0.7, 0.5), Vec2(0.3, 0.5), Vec2(0.5, 0.8), Vec2(0.5, 0.2)};
  const WarpResult r = warp_lines(f, g);
  EXPECT_GE(r.detours, 1);
  EXPECT_GT(r.events, 0);
}

TEST(WarpSquare, ThreeFeaturesRotateThroughEachOthersPlaces) {
  const std::vector<Vec2> f = {Vec2(0.3, 0.3), Vec2(0.7, 0.3), Vec2(0.5, 0.7), Vec2(0.5, 0.45), Vec2(0.2, 0.8)};
  const std::vector<Vec2> g = {Vec2(0.7, 0.3), Vec2(0.5, 0.7), Vec2(0.3, 0.3), Vec2(0.5, 0.45), Vec2(0.2, 0.8)};
  // With one round the targets block each other in a cycle: one steps aside first.
  WarpOptions o;
  o.rounds = 1;
  const WarpResult r = warp_lines(f, g, 40, 1000, o);
  EXPECT_GE(r.detours, 1);
  EXPECT_GT(r.events, 0);
}

TEST(WarpSquare, PathThroughAnotherFeatureDetours) {
  // Feature 1 sits exactly on feature 0's straight path and does not move.
  const std::vector<Vec2> f = {Vec2(0.2, 0.5), Vec2(0.5, 0.5), Vec2(0.5, 0.25)};
  const std::vector<Vec2> g = {Vec2(0.8, 0.5), Vec2(0.5, 0.5), Vec2(0.5, 0.25)};
  const WarpResult r = warp_lines(f, g);
  EXPECT_GE(r.detours, 1);
}

TEST(WarpSquare, TargetOnAnotherFeaturesStartWaitsForIt) {
  // Feature 0's target is feature 1's start: feature 1 (next in line) moves first, no detour.
  const std::vector<Vec2> f = {Vec2(0.4, 0.5), Vec2(0.5, 0.5)};
  const std::vector<Vec2> g = {Vec2(0.5, 0.5), Vec2(0.6, 0.55)};
  const WarpResult r = warp_grid(f, g, 81);
  EXPECT_EQ(r.detours, 0);
}

TEST(WarpSquare, CrossingACollinearRowHasSimultaneousEvents) {
  // Collinear features at the start (CGAL's Delaunay copes), and a feature crossing their line.
  std::vector<Vec2> f;
  for (int i = 0; i < 5; ++i) f.emplace_back(0.2 + 0.15 * i, 0.5);
  f.emplace_back(0.47, 0.85);
  std::vector<Vec2> g = f;
  g.back() = Vec2(0.47, 0.15);
  const WarpResult r = warp_lines(f, g);
  EXPECT_GT(r.events, 0);
}

TEST(WarpSquare, TranslatedRegularGridOfFeatures) {
  // Many cocircular and collinear features: events at equal times, targets on old lines.
  std::vector<Vec2> f, g;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) {
      f.emplace_back(0.2 + 0.2 * i, 0.2 + 0.2 * j);
      g.emplace_back(0.2 + 0.2 * i + 0.1, 0.2 + 0.2 * j + 0.1);
    }
  const WarpResult r = warp_lines(f, g);
  EXPECT_GT(r.events, 0);
}

TEST(WarpSquare, SmoothMotionKeepsGridTrianglesUnfolded) {
  // A coherent motion (neighbours move alike), as when features move to their mean over similar
  // meshes: the warped grid must have no folded triangle even though many flips happen.
  const std::vector<Vec2> f = random_features(50, 11);
  const WarpResult r = warp_grid(f, smooth_targets(f, 0.2), 201);
  EXPECT_GT(r.events, 50);
}

TEST(WarpSquare, OneRoundIsStillBijective) {
  // The paper's order (each feature all the way at once): grid triangles may fold where the map
  // shears within a cell, but the map itself stays injective.
  WarpOptions o;
  o.rounds = 1;
  const std::vector<Vec2> f = random_features(50, 21);
  const WarpResult r = warp_lines(f, smooth_targets(f, 0.2), 40, 1000, o);
  EXPECT_GT(r.events, 50);
}

TEST(WarpSquare, CheckersDetectFolds) {
  // The two bijectivity checks used above must see a map that folds the square along x = 0.5.
  const int n = 41;
  std::vector<Vec2> q = grid_points(n);
  for (Vec2& p : q) p.x() = 0.5 + std::abs(p.x() - 0.5) * (p.x() < 0.5 ? 0.5 : 1.0);
  EXPECT_GT(folded_grid_triangles(q, n), 0);
  std::vector<std::vector<Vec2>> lines(10);
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 200; ++j) {
      const double x = j / 199.0, y = (i + 0.5) / 10;
      lines[i].emplace_back(0.5 + 0.5 * std::abs(x - 0.5), y + 0.2 * (x - 0.5) * (x - 0.5));
    }
  EXPECT_GT(crossing_polylines(lines), 0);
}

TEST(WarpSquare, DegenerateLatticeMotionsTerminate) {
  // Features on a lattice (many cocircular quads, collinear rows, a mover passing tangent to
  // circles and through their crossings), one of them moved to every other lattice point or
  // between two; then the whole lattice rotated (targets are other features' starts: cycles).
  int cases = 0;
  for (const int n : {4, 5}) {
    for (int s = 0; s < (n - 1) * (n - 1); ++s) {
      for (int t = 0; t < (n - 1) * (n - 1); ++t) {
        if (s == t) continue;
        const Vec2 from((s % (n - 1) + 1.0) / n, (s / (n - 1) + 1.0) / n);
        const Vec2 to((t % (n - 1) + 1.0 + 0.5 * (t % 2)) / n, (t / (n - 1) + 1.0) / n);
        std::vector<Vec2> f = {from}, g = {to};
        for (int i = 1; i < n; ++i)
          for (int j = 1; j < n; ++j) {
            const Vec2 p(static_cast<double>(i) / n, static_cast<double>(j) / n);
            if (p != from && (p - to).norm() > 1e-9) {
              f.push_back(p);
              g.push_back(p);
            }
          }
        WarpOptions o;
        o.rounds = t % 3 == 0 ? 1 : 16;
        std::vector<Vec2> pts = grid_points(11);
        pts.insert(pts.end(), f.begin(), f.end());
        const WarpResult r = warp_square(f, g, pts, o);
        check_common(r, pts, 121, f, g);
        ++cases;
      }
    }
    for (int rot = 1; rot < 4; ++rot) {
      for (const int rounds : {1, 16}) {
        std::vector<Vec2> f, g;
        for (int i = 1; i < n; ++i)
          for (int j = 1; j < n; ++j) {
            f.emplace_back(static_cast<double>(i) / n, static_cast<double>(j) / n);
            Vec2 c = f.back() - Vec2(0.5, 0.5);
            for (int r = 0; r < rot; ++r) c = Vec2(-c.y(), c.x());
            g.push_back(c + Vec2(0.5, 0.5));
          }
        WarpOptions o;
        o.rounds = rounds;
        std::vector<Vec2> pts = grid_points(11);
        pts.insert(pts.end(), f.begin(), f.end());
        const WarpResult r = warp_square(f, g, pts, o);
        check_common(r, pts, 121, f, g);
        ++cases;
      }
    }
  }
  EXPECT_EQ(cases, 324);
}

TEST(WarpSquare, NearlyCocircularClusterDoesNotFlipBackAndForth) {
  // Real input (regression): three features ~1e-3 apart move ~0.035 toward the lower right. At one
  // moment the quad of the three features and the corner (0, 1) is cocircular: the kinetic step
  // flipped its diagonal, then the Lawson pass saw the new diagonal as non-Delaunay within
  // rounding and flipped it back, forever (more than max_events flips at one time).
  const std::vector<Vec2> f = {Vec2(0.7223420261674397, 0.74981545428860086),
                               Vec2(0.72230802473914923, 0.75283953129023273),
                               Vec2(0.722419691410494, 0.7515741835248797)};
  const std::vector<Vec2> g = {Vec2(0.73665837891131025, 0.71567337612736615),
                               Vec2(0.73681263756554971, 0.71859455726639987),
                               Vec2(0.73680032520687688, 0.71732953548462397)};
  std::vector<Vec2> pts = {
      Vec2(0.24304563349000347, 0.044486290720485301), Vec2(0, 0.27040686775905287),
      Vec2(0, 0.15599098372515607),                    Vec2(0.31065852493880763, 0.35930276782915294),
      Vec2(0.24704326132309348, 0.44801854771892463),  Vec2(0.26991378063239296, 0),
      Vec2(0.28951605471696468, 0.64449581387247012),  Vec2(0.12876821620106627, 1),
      Vec2(0.18365761533376287, 0.94882554026877075),  Vec2(0.13702743234019898, 1),
      Vec2(0.12444068953045373, 1),                    Vec2(0.055771335635680375, 1),
      Vec2(0.181885618007363, 0.93915569076116634),    Vec2(0, 0.47719225505271878),
      Vec2(0.16472141666804332, 0.5568050096484406),   Vec2(0, 0.48990808715280287),
      Vec2(0, 0.44422276374490444),                    Vec2(0.45341265428312444, 0.14913866461675004),
      Vec2(0.32261722999174469, 0),                    Vec2(0, 0.79660696164530476)};
  const int n = static_cast<int>(pts.size());
  pts.insert(pts.end(), f.begin(), f.end());
  WarpResult r;
  ASSERT_NO_THROW(r = warp_square(f, g, pts));
  check_common(r, pts, n, f, g);
  EXPECT_LT(r.events, 1000);
  for (const int rounds : {1, 16, 64}) {
    WarpOptions o;
    o.rounds = rounds;
    ASSERT_NO_THROW(r = warp_square(f, g, pts, o)) << "rounds " << rounds;
    check_common(r, pts, n, f, g);
  }
  warp_lines(f, g);  // bijective: disjoint lines stay disjoint
}

TEST(WarpSquare, TargetEqualToStartDoesNotMove) {
  const std::vector<Vec2> f = {Vec2(0.3, 0.6), Vec2(0.6, 0.4)};
  const std::vector<Vec2> g = {Vec2(0.3, 0.6), Vec2(0.65, 0.45)};
  std::vector<Vec2> pts = {f[0]};
  const WarpResult r = warp_square(f, g, pts);
  EXPECT_EQ(r.points[0], f[0]);
}

TEST(WarpSquare, BorderPointsAndCornersStayExactlyOnTheirSide) {
  const std::vector<Vec2> f = random_features(10, 900);
  const std::vector<Vec2> g = random_features(10, 1900);
  std::vector<Vec2> pts = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};
  for (int i = 0; i < 200; ++i) {
    const double s = hash01(50 + i);
    pts.insert(pts.end(), {Vec2(s, 0), Vec2(1, s), Vec2(s, 1), Vec2(0, s)});
  }
  pts.emplace_back(-1e-13, 0.5);  // within the tolerance outside: clamped onto the border
  pts.emplace_back(0.5, 1 + 1e-13);
  const WarpResult r = warp_square(f, g, pts);
  EXPECT_GT(r.events, 0);
  for (std::size_t i = 0; i + 2 < pts.size(); ++i) EXPECT_EQ(r.points[i], pts[i]) << "point " << i;
  EXPECT_EQ(r.points[pts.size() - 2], Vec2(0, 0.5));
  EXPECT_EQ(r.points[pts.size() - 1], Vec2(0.5, 1));
}

TEST(WarpSquare, LargeRandomCaseIsBijective) {
  const std::vector<Vec2> f = random_features(50, 11);
  std::vector<Vec2> g;
  for (int k = 0; k < 50; ++k) {
    const Vec2 shift(0.3 * (hash01(500 + 2 * k) - 0.5), 0.3 * (hash01(501 + 2 * k) - 0.5));
    g.push_back((f[k] + shift).cwiseMax(Vec2(0.02, 0.02)).cwiseMin(Vec2(0.98, 0.98)));
  }
  const WarpResult r = warp_lines(f, g, 50, 2000);  // 100000 points at first
  EXPECT_GT(r.events, 20);
}

TEST(WarpSquare, Deterministic) {
  const std::vector<Vec2> f = random_features(30, 77);
  const std::vector<Vec2> g = random_features(30, 4077);
  std::vector<Vec2> pts;
  for (int i = 0; i < 20000; ++i) pts.emplace_back(hash01(9000 + 2 * i), hash01(9001 + 2 * i));
  const WarpResult a = warp_square(f, g, pts);
  const WarpResult b = warp_square(f, g, pts);
  EXPECT_GT(a.events, 0);
  EXPECT_EQ(a.events, b.events);
  ASSERT_EQ(a.points.size(), b.points.size());
  EXPECT_EQ(std::memcmp(a.points.data(), b.points.data(), a.points.size() * sizeof(Vec2)), 0);
}

/// The message of the qs::Error that `f` throws, checking its type.
template <class E, class F>
std::string message_of(F f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
    return {};
  }
  ADD_FAILURE() << "no exception";
  return {};
}

TEST(WarpSquare, RejectsFeaturesTooClose) {
  const std::vector<Vec2> f = {Vec2(0.3, 0.3), Vec2(0.6, 0.6), Vec2(0.3, 0.30005)};
  const std::string m = message_of<InvalidInput>([&] { warp_square(f, f, {}); });
  EXPECT_NE(m.find("features closer than min_feature_distance"), std::string::npos) << m;
  EXPECT_NE(m.find("0 at (0.3, 0.3) and 2 at (0.3, 0.30005)"), std::string::npos) << m;
  // The same for targets.
  std::vector<Vec2> g = {Vec2(0.4, 0.4), Vec2(0.5, 0.5), Vec2(0.50002, 0.5)};
  const std::vector<Vec2> ok = {Vec2(0.3, 0.3), Vec2(0.6, 0.6), Vec2(0.7, 0.3)};
  const std::string mt = message_of<InvalidInput>([&] { warp_square(ok, g, {}); });
  EXPECT_NE(mt.find("targets closer than min_feature_distance"), std::string::npos) << mt;
  EXPECT_NE(mt.find("1 at (0.5, 0.5) and 2"), std::string::npos) << mt;
}

TEST(WarpSquare, RejectsFeaturesOutsideOrOnTheBorder) {
  const std::vector<Vec2> f = {Vec2(0.5, 0.5), Vec2(1.2, 0.5), Vec2(0.00001, 0.5), Vec2(0.4, 0.7)};
  const std::vector<Vec2> g = {Vec2(0.5, 0.5), Vec2(0.6, 0.5), Vec2(0.3, 0.5), Vec2(0.4, 1.0)};
  const std::string m = message_of<InvalidInput>([&] { warp_square(f, g, {}); });
  EXPECT_NE(m.find("features closer than min_feature_distance (0.000100) to the square's border or outside it: "
                   "1 at (1.2, 0.5), 2 at (1e-05, 0.5)"),
            std::string::npos)
      << m;
  EXPECT_NE(m.find("targets closer than min_feature_distance (0.000100) to the square's border or outside it: "
                   "3 at (0.4, 1)"),
            std::string::npos)
      << m;
}

TEST(WarpSquare, RejectsLengthMismatch) {
  const std::string m =
      message_of<InvalidInput>([] { warp_square({Vec2(0.5, 0.5), Vec2(0.2, 0.2)}, {Vec2(0.5, 0.5)}, {}); });
  EXPECT_NE(m.find("2 features but 1 targets"), std::string::npos) << m;
}

TEST(WarpSquare, RejectsPointsOutsideTheSquare) {
  const std::vector<Vec2> pts = {Vec2(0.5, 0.5), Vec2(1.001, 0.5), Vec2(0.5, -1e-9), Vec2(NAN, 0.5)};
  const std::string m = message_of<InvalidInput>([&] { warp_square({}, {}, pts); });
  EXPECT_NE(m.find("points outside the unit square"), std::string::npos) << m;
  EXPECT_NE(m.find("1 at (1.001, 0.5), 2 at (0.5, -1e-09), 3 at (nan, 0.5)"), std::string::npos) << m;
}

TEST(WarpSquare, RejectsBadOptions) {
  WarpOptions o;
  o.min_feature_distance = 0;
  EXPECT_NE(message_of<InvalidInput>([&] { warp_square({}, {}, {}, o); }).find("min_feature_distance"),
            std::string::npos);
  o = WarpOptions{};
  o.max_events = -1;
  EXPECT_NE(message_of<InvalidInput>([&] { warp_square({}, {}, {}, o); }).find("max_events"), std::string::npos);
}

TEST(WarpSquare, TooManyEventsIsASolverError) {
  const std::vector<Vec2> f = random_features(20, 5);
  const std::vector<Vec2> g = random_features(20, 6005);
  WarpOptions o;
  o.max_events = 3;
  const std::string m = message_of<SolverError>([&] { warp_square(f, g, {}, o); });
  EXPECT_NE(m.find("too different to align"), std::string::npos) << m;
}

TEST(WarpSquare, Cancel) {
  std::atomic<bool> cancel{true};
  Context ctx;
  ctx.cancel = &cancel;
  const std::string m =
      message_of<Error>([&] { warp_square({Vec2(0.5, 0.5)}, {Vec2(0.6, 0.6)}, {Vec2(0.2, 0.2)}, {}, ctx); });
  EXPECT_EQ(m, "cancelled");
}

TEST(WarpSquare, NoFeatures) {
  const std::vector<Vec2> pts = grid_points(11);
  const WarpResult r = warp_square({}, {}, pts);
  EXPECT_EQ(r.warp_triangles, 2);
  for (std::size_t i = 0; i < pts.size(); ++i) EXPECT_NEAR((r.points[i] - pts[i]).norm(), 0, 1e-15);
}

}  // namespace
}  // namespace qs::warp
