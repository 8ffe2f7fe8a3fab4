// Tests of the square parameterization, its border degeneracies and the L2 stretch.
// Every patch is made in code; invariants are checked against values computed independently.

#include "qs/param/square_param.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <map>
#include <numbers>
#include <utility>

#include "qs/core/error.h"

namespace qs::param {
namespace {

using Edge = std::array<int, 2>;

/// A deterministic value in [-1, 1] from an integer (no library RNG: same numbers everywhere).
double hash_unit(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return 2.0 * (x / 4294967295.0) - 1.0;
}

/// The border loop chained from the half-edges that have no opposite (so the faces are on its
/// left), starting at `start` (or at the lowest border vertex when start < 0).
std::vector<int> border_loop(const std::vector<Tri>& faces, int start = -1) {
  std::map<std::pair<int, int>, int> half;
  for (const Tri& t : faces)
    for (int c = 0; c < 3; ++c) ++half[{t[c], t[(c + 1) % 3]}];
  std::map<int, int> next;
  for (const auto& [e, count] : half)
    if (!half.count({e.second, e.first})) {
      EXPECT_FALSE(next.count(e.first)) << "pinched border at vertex " << e.first;
      next[e.first] = e.second;
    }
  if (next.empty()) return {};
  if (start < 0) start = next.begin()->first;
  std::vector<int> loop;
  int v = start;
  do {
    loop.push_back(v);
    EXPECT_TRUE(next.count(v)) << "vertex " << v << " is not on the border";
    v = next[v];
  } while (v != start && loop.size() <= next.size());
  EXPECT_EQ(loop.size(), next.size()) << "more than one border loop";
  return loop;
}

/// Builds a PatchMesh from faces: the border loop rotated to start at corners[0], and
/// corner_index from the corner vertex ids. Unused vertices are kept.
PatchMesh make_patch(std::vector<Vec3> positions, std::vector<Tri> faces, const std::array<int, 4>& corners) {
  PatchMesh p;
  p.boundary = border_loop(faces, corners[0]);
  p.positions = std::move(positions);
  p.faces = std::move(faces);
  for (int k = 0; k < 4; ++k) {
    const auto it = std::find(p.boundary.begin(), p.boundary.end(), corners[k]);
    EXPECT_NE(it, p.boundary.end()) << "corner " << corners[k] << " is not on the border";
    p.corner_index[k] = static_cast<int>(it - p.boundary.begin());
  }
  return p;
}

/// An nx x ny vertex grid over [0, sx] x [0, sy] at z = 0, triangulated CCW seen from +z.
/// jitter > 0 moves interior vertices (both ways) and border vertices (along their side only) by
/// up to jitter times the spacing, deterministically.
PatchMesh grid_patch(int nx, int ny, double sx = 1, double sy = 1, double jitter = 0) {
  std::vector<Vec3> pos;
  std::vector<Tri> faces;
  const double hx = sx / (nx - 1), hy = sy / (ny - 1);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      double x = i * hx, y = j * hy;
      const auto id = static_cast<std::uint32_t>(j * nx + i);
      if (i > 0 && i < nx - 1) x += jitter * hx * hash_unit(2 * id);
      if (j > 0 && j < ny - 1) y += jitter * hy * hash_unit(2 * id + 1);
      pos.emplace_back(x, y, 0);
    }
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      const int a = j * nx + i, b = a + 1, c = a + nx + 1, d = a + nx;
      faces.push_back({a, b, c});
      faces.push_back({a, c, d});
    }
  return make_patch(std::move(pos), std::move(faces), {0, nx - 1, ny * nx - 1, (ny - 1) * nx});
}

/// A rigid motion that takes the z = 0 plane to a generic plane in 3D.
Vec3 rigid(const Vec3& p) {
  const Eigen::AngleAxisd r(0.7, Vec3(1, 2, 3).normalized());
  return r * p + Vec3(5, -2, 1);
}

/// Splits edge (a, b) at its 3D midpoint (or at `where` when given): the two faces holding it
/// become two each. The new vertex is interior when (a, b) is an interior edge.
void split_edge(PatchMesh& p, int a, int b, const Vec3* where = nullptr) {
  const int m = static_cast<int>(p.positions.size());
  p.positions.push_back(where ? *where : 0.5 * (p.positions[a] + p.positions[b]));
  const std::size_t nf = p.faces.size();
  int split = 0;
  for (std::size_t f = 0; f < nf; ++f)
    for (int c = 0; c < 3; ++c) {
      Tri t = p.faces[f];
      const int u = t[c], v = t[(c + 1) % 3], x = t[(c + 2) % 3];
      if ((u == a && v == b) || (u == b && v == a)) {
        p.faces[f] = {u, m, x};
        p.faces.push_back({m, v, x});
        ++split;
        break;
      }
    }
  ASSERT_EQ(split, 2) << "edge (" << a << "," << b << ") is not interior";
}

/// Inserts a vertex at `where` inside face f (1-to-3 split).
void split_face(PatchMesh& p, int f, const Vec3& where) {
  const int m = static_cast<int>(p.positions.size());
  p.positions.push_back(where);
  const Tri t = p.faces[f];
  p.faces[f] = {t[0], t[1], m};
  p.faces.push_back({t[1], t[2], m});
  p.faces.push_back({t[2], t[0], m});
}

/// Icosphere of radius 1 (own builder, so this test depends only on the param module).
void icosphere(int subdivisions, std::vector<Vec3>& pos, std::vector<Tri>& faces) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  pos = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
         {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  faces = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
           {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
           {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (Vec3& p : pos) p.normalize();
  for (int s = 0; s < subdivisions; ++s) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      pos.push_back((pos[a] + pos[b]).normalized());
      return mid[key] = static_cast<int>(pos.size()) - 1;
    };
    std::vector<Tri> next;
    for (const Tri& f : faces) {
      const int ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      next.push_back({f[0], ab, ca});
      next.push_back({f[1], bc, ab});
      next.push_back({f[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    faces = std::move(next);
  }
}

/// Half of an icosphere (tilted, cut by a plane through the centre: faces whose centroid is
/// above it), with 4 corners a quarter of the border apart, its border degeneracies split.
PatchMesh hemisphere_patch(int subdivisions, double scale = 1) {
  std::vector<Vec3> sphere;
  std::vector<Tri> sphere_faces;
  icosphere(subdivisions, sphere, sphere_faces);
  const Eigen::AngleAxisd tilt(0.3, Vec3(1, -1, 0.5).normalized());
  std::vector<int> local(sphere.size(), -1);
  std::vector<Vec3> pos;
  std::vector<Tri> faces;
  for (const Tri& f : sphere_faces) {
    if ((tilt * (sphere[f[0]] + sphere[f[1]] + sphere[f[2]])).z() <= 0) continue;
    Tri g;
    for (int c = 0; c < 3; ++c) {
      if (local[f[c]] < 0) {
        local[f[c]] = static_cast<int>(pos.size());
        pos.push_back(scale * sphere[f[c]]);
      }
      g[c] = local[f[c]];
    }
    faces.push_back(g);
  }
  const std::vector<int> b = border_loop(faces);
  const int m = static_cast<int>(b.size());
  PatchMesh p = make_patch(std::move(pos), std::move(faces), {b[0], b[m / 4], b[m / 2], b[3 * m / 4]});
  for (const Edge& e : border_degeneracies(p)) split_edge(p, e[0], e[1]);
  return p;
}

bool all_finite(const std::vector<Vec2>& uv) {
  return std::all_of(uv.begin(), uv.end(), [](const Vec2& x) { return x.allFinite(); });
}

/// The signed UV area of every face, summed: computed here, independently of SquareParam.
double uv_area(const PatchMesh& p, const std::vector<Vec2>& uv) {
  double sum = 0;
  for (const Tri& t : p.faces) {
    const Vec2 e1 = uv[t[1]] - uv[t[0]], e2 = uv[t[2]] - uv[t[0]];
    sum += 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());
  }
  return sum;
}

/// Largest relative residual of the mean-value equations at the interior vertices, with the
/// weights recomputed here from acos angles (an independent formula).
double mean_value_residual(const PatchMesh& p, const std::vector<Vec2>& uv) {
  const int nv = static_cast<int>(p.positions.size());
  std::vector<char> border(nv, 0);
  for (int v : p.boundary) border[v] = 1;
  std::vector<Vec2> res(nv, Vec2::Zero());
  std::vector<double> norm(nv, 0.0);
  for (const Tri& t : p.faces)
    for (int c = 0; c < 3; ++c) {
      const int i = t[c], j = t[(c + 1) % 3], k = t[(c + 2) % 3];
      const Vec3 u = p.positions[j] - p.positions[i], v = p.positions[k] - p.positions[i];
      const double angle = std::acos(std::clamp(u.dot(v) / (u.norm() * v.norm()), -1.0, 1.0));
      const double wj = std::tan(angle / 2) / u.norm(), wk = std::tan(angle / 2) / v.norm();
      res[i] += wj * (uv[i] - uv[j]) + wk * (uv[i] - uv[k]);
      norm[i] += wj + wk;
    }
  double worst = 0;
  for (int i = 0; i < nv; ++i)
    if (!border[i]) worst = std::max(worst, res[i].norm() / norm[i]);
  return worst;
}

// ---------------------------------------------------------------- parameterize_square

TEST(SquareParamTest, FlatSquareReproducesPlanarCoordinates) {
  const int n = 13;
  PatchMesh p = grid_patch(n, n, 1, 1, 0.3);
  const std::vector<Vec3> local = p.positions;
  for (Vec3& x : p.positions) x = rigid(2.5 * x);  // a 2.5-sided square placed generically in 3D
  const SquareParam sp = parameterize_square(p);
  ASSERT_EQ(sp.uv.size(), p.positions.size());
  for (std::size_t v = 0; v < local.size(); ++v) {
    EXPECT_NEAR(sp.uv[v].x(), local[v].x(), 1e-9) << "vertex " << v;
    EXPECT_NEAR(sp.uv[v].y(), local[v].y(), 1e-9) << "vertex " << v;
  }
  EXPECT_EQ(sp.flipped_faces, 0);
  EXPECT_EQ(sp.zero_area_faces, 0);
  EXPECT_TRUE(sp.bijective());
  EXPECT_NEAR(sp.uv_area_sum, 1.0, 1e-9);
  EXPECT_NEAR(uv_area(p, sp.uv), 1.0, 1e-9);

  const Stretch s = l2_stretch(p.positions, p.faces, sp.uv);
  ASSERT_EQ(s.face.size(), p.faces.size());
  for (std::size_t f = 0; f < s.face.size(); ++f) EXPECT_NEAR(s.face[f], 1.0, 1e-9) << "face " << f;
  EXPECT_NEAR(s.patch, 1.0, 1e-9);
  EXPECT_NEAR(s.area3d, 2.5 * 2.5, 1e-9);
}

TEST(SquareParamTest, CornersAndSidesFollowArcLength) {
  // A 2 x 1 rectangle: the border map is affine, so mean value reproduces uv = (x / 2, y).
  PatchMesh p = grid_patch(9, 5, 2, 1, 0.25);
  const SquareParam sp = parameterize_square(p);
  for (std::size_t v = 0; v < p.positions.size(); ++v) {
    EXPECT_NEAR(sp.uv[v].x(), p.positions[v].x() / 2, 1e-9);
    EXPECT_NEAR(sp.uv[v].y(), p.positions[v].y(), 1e-9);
  }
  const std::array<Vec2, 4> corner{Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};
  for (int k = 0; k < 4; ++k) EXPECT_EQ(sp.uv[p.boundary[p.corner_index[k]]], corner[k]);
}

TEST(SquareParamTest, RectangleIsStretched) {
  PatchMesh p = grid_patch(9, 5, 2, 1);
  const SquareParam sp = parameterize_square(p);
  ASSERT_TRUE(sp.bijective());
  const Stretch s = l2_stretch(p.positions, p.faces, sp.uv);
  // S_s = (2, 0, 0), S_t = (0, 1, 0): raw sqrt(5/2), normalized by sqrt(1/2): sqrt(5/4).
  EXPECT_GT(s.patch, 1.0);
  EXPECT_NEAR(s.patch, std::sqrt(1.25), 1e-9);
  for (double x : s.face) EXPECT_NEAR(x, std::sqrt(1.25), 1e-9);
}

TEST(SquareParamTest, HemisphereIsBijective) {
  const PatchMesh p = hemisphere_patch(3);
  ASSERT_GT(p.positions.size(), 200u);
  EXPECT_TRUE(border_degeneracies(p).empty());
  const SquareParam sp = parameterize_square(p);
  ASSERT_TRUE(all_finite(sp.uv));
  EXPECT_EQ(sp.flipped_faces, 0);
  EXPECT_EQ(sp.zero_area_faces, 0);
  EXPECT_NEAR(sp.uv_area_sum, 1.0, 1e-9);
  EXPECT_NEAR(uv_area(p, sp.uv), 1.0, 1e-9);

  std::vector<char> border(p.positions.size(), 0);
  for (int v : p.boundary) border[v] = 1;
  int interior = 0;
  for (std::size_t v = 0; v < p.positions.size(); ++v) {
    const Vec2& x = sp.uv[v];
    if (border[v]) {  // on the square's border
      const double d = std::min({x.x(), x.y(), 1 - x.x(), 1 - x.y()});
      EXPECT_NEAR(d, 0.0, 1e-15) << "border vertex " << v;
    } else {
      ++interior;
      EXPECT_GT(x.x(), 0) << "vertex " << v;
      EXPECT_LT(x.x(), 1) << "vertex " << v;
      EXPECT_GT(x.y(), 0) << "vertex " << v;
      EXPECT_LT(x.y(), 1) << "vertex " << v;
    }
  }
  EXPECT_GT(interior, 100);
  EXPECT_LT(mean_value_residual(p, sp.uv), 1e-10);

  const Stretch s = l2_stretch(p.positions, p.faces, sp.uv);
  EXPECT_TRUE(std::isfinite(s.patch));
  EXPECT_GT(s.patch, 1.0);  // a sphere is not developable
}

TEST(SquareParamTest, OrderingsAgree) {
  PatchMesh p = hemisphere_patch(3);
  SquareParamOptions colamd;
  colamd.ordering = LuOrdering::Colamd;
  const SquareParam a = parameterize_square(p), b = parameterize_square(p, colamd);
  for (std::size_t v = 0; v < a.uv.size(); ++v) EXPECT_LT((a.uv[v] - b.uv[v]).norm(), 1e-12);
  EXPECT_EQ(a.flipped_faces, b.flipped_faces);
  EXPECT_EQ(a.zero_area_faces, b.zero_area_faces);
}

TEST(SquareParamTest, ScaleInvariance) {
  const PatchMesh p = hemisphere_patch(2);
  const PatchMesh q = hemisphere_patch(2, 3.7);
  const SquareParam a = parameterize_square(p), b = parameterize_square(q);
  ASSERT_EQ(a.uv.size(), b.uv.size());
  for (std::size_t v = 0; v < a.uv.size(); ++v) EXPECT_LT((a.uv[v] - b.uv[v]).norm(), 1e-12);
  const Stretch sa = l2_stretch(p.positions, p.faces, a.uv);
  const Stretch sb = l2_stretch(q.positions, q.faces, b.uv);
  EXPECT_NEAR(sa.patch, sb.patch, 1e-12 * sa.patch);
  for (std::size_t f = 0; f < sa.face.size(); ++f) EXPECT_NEAR(sa.face[f], sb.face[f], 1e-12 * sa.face[f]);
  EXPECT_NEAR(sb.area3d, 3.7 * 3.7 * sa.area3d, 1e-9 * sb.area3d);

  // Scaling the UV domain changes nothing either.
  std::vector<Vec2> uv2 = a.uv;
  for (Vec2& x : uv2) x *= 5;
  EXPECT_NEAR(l2_stretch(p.positions, p.faces, uv2).patch, sa.patch, 1e-12 * sa.patch);
}

TEST(SquareParamTest, DegenerateGeometryGivesNoNaN) {
  const int n = 12;
  PatchMesh p = grid_patch(n, n, 1, 1, 0.2);
  for (Vec3& x : p.positions) x.z() = 0.2 * std::sin(3 * x.x()) * std::cos(2 * x.y());
  // Coincident but distinct vertices: split interior edge (a, a+1) at a itself.
  const int a = 3 * n + 4;
  const Vec3 at_a = p.positions[a];
  split_edge(p, a, a + 1, &at_a);
  // A needle: split edge (c, c+n) very close to c; the faces at the far vertices get an angle
  // near 1e-4 degrees.
  const int c = 7 * n + 6;
  const Vec3 near_c = p.positions[c] + 1.2e-6 * (p.positions[c + n] - p.positions[c]);
  split_edge(p, c, c + n, &near_c);
  // A cap: a vertex inside a face, almost on one of its edges (an angle of nearly 180 degrees).
  const int f = 2 * (8 * (n - 1) + 2);
  const Tri t = p.faces[f];
  const Vec3 mid = 0.5 * (p.positions[t[0]] + p.positions[t[1]]);
  split_face(p, f, mid + 1e-9 * (p.positions[t[2]] - mid));

  double min_angle = 180, max_angle = 0;
  int zero_edges = 0;
  for (const Tri& g : p.faces)
    for (int k = 0; k < 3; ++k) {
      const Vec3 u = p.positions[g[(k + 1) % 3]] - p.positions[g[k]];
      const Vec3 v = p.positions[g[(k + 2) % 3]] - p.positions[g[k]];
      if (u.norm() == 0 || v.norm() == 0) {
        ++zero_edges;
        continue;
      }
      const double angle = std::atan2(u.cross(v).norm(), u.dot(v)) * 180 / std::numbers::pi;
      if (angle > 0) min_angle = std::min(min_angle, angle);
      max_angle = std::max(max_angle, angle);
    }
  EXPECT_GT(zero_edges, 0);
  EXPECT_LT(min_angle, 1.5e-4);
  EXPECT_GT(max_angle, 179.9999);

  const SquareParam sp = parameterize_square(p);
  ASSERT_TRUE(all_finite(sp.uv));
  EXPECT_EQ(sp.flipped_faces, 0);
  EXPECT_EQ(sp.zero_area_faces, 0);
  EXPECT_TRUE(sp.bijective());
  EXPECT_NEAR(sp.uv_area_sum, 1.0, 1e-9);
  const int m = static_cast<int>(p.positions.size()) - 3;  // the coincident copy of a
  EXPECT_GT((sp.uv[m] - sp.uv[a]).norm(), 1e-6);           // pulled apart, not stacked

  const Stretch s = l2_stretch(p.positions, p.faces, sp.uv);
  EXPECT_TRUE(std::isfinite(s.patch));
  for (double x : s.face) EXPECT_TRUE(std::isfinite(x));
}

TEST(SquareParamTest, CoincidentBorderVerticesStayApart) {
  // Two distinct border vertices at the same place on side 0 (a zero-length border edge).
  PatchMesh p = grid_patch(6, 6);
  const int b1 = 2;  // on side 0
  p.positions[b1] = p.positions[b1 + 1];
  const SquareParam sp = parameterize_square(p);
  ASSERT_TRUE(all_finite(sp.uv));
  EXPECT_GT((sp.uv[b1] - sp.uv[b1 + 1]).norm(), 0.0);
  EXPECT_TRUE(sp.bijective());
}

TEST(SquareParamTest, NoInteriorVertices) {
  // Two triangles, 4 corners: nothing to solve.
  const PatchMesh p = make_patch({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 3}}, {0, 1, 2, 3});
  const SquareParam sp = parameterize_square(p);
  EXPECT_EQ(sp.uv[2], Vec2(1, 1));
  EXPECT_TRUE(sp.bijective());
  EXPECT_NEAR(sp.uv_area_sum, 1.0, 1e-15);
}

TEST(SquareParamTest, ReportsProgressAndHonoursCancel) {
  const PatchMesh p = grid_patch(6, 6);
  double last = -1;
  Context ctx;
  ctx.progress = [&](const std::string&, double x) { last = x; };
  parameterize_square(p, {}, ctx);
  EXPECT_EQ(last, 1.0);
  std::atomic<bool> cancel{true};
  Context stop;
  stop.cancel = &cancel;
  try {
    parameterize_square(p, {}, stop);
    FAIL() << "no exception";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::Internal);
  }
}

// ---------------------------------------------------------------- border_degeneracies

/// A 5 x 5 grid with, on side 0, a chord (1, 2) cutting off a pocket that holds one interior
/// vertex, and on side 2 an ear face (22, 23, e).
PatchMesh pocket_and_ear_patch() {
  const int n = 5;
  PatchMesh g = grid_patch(n, n);
  std::vector<Vec3> pos = g.positions;
  std::vector<Tri> faces = g.faces;
  const int w1 = 25, w2 = 26, c = 27, e = 28;
  pos.emplace_back(1.2 / 4, -0.5 / 4, 0);
  pos.emplace_back(1.8 / 4, -0.5 / 4, 0);
  pos.emplace_back(1.5 / 4, -0.2 / 4, 0);
  pos.emplace_back(2.5 / 4, 1 + 0.3 / 4, 0);
  faces.push_back({1, w1, c});
  faces.push_back({w1, w2, c});
  faces.push_back({w2, 2, c});
  faces.push_back({2, 1, c});
  faces.push_back({22, 23, e});
  return make_patch(std::move(pos), std::move(faces), {0, n - 1, n * n - 1, (n - 1) * n});
}

TEST(BorderDegeneraciesTest, FindsChordAndEar) {
  PatchMesh p = pocket_and_ear_patch();
  const auto found = border_degeneracies(p);
  EXPECT_EQ(found, (std::vector<Edge>{{1, 2}, {22, 23}}));
  // They are real: without splitting, the pocket and the ear collapse onto the border.
  const SquareParam before = parameterize_square(p);
  EXPECT_GE(before.zero_area_faces, 5);
  EXPECT_FALSE(before.bijective());

  for (const Edge& e : found) split_edge(p, e[0], e[1]);
  EXPECT_TRUE(border_degeneracies(p).empty());
  const SquareParam after = parameterize_square(p);
  EXPECT_EQ(after.zero_area_faces, 0);
  EXPECT_EQ(after.flipped_faces, 0);
  EXPECT_NEAR(after.uv_area_sum, 1.0, 1e-9);
}

TEST(BorderDegeneraciesTest, CornerCountsOnBothSides) {
  // Corners 0, 2, 3, 4 and a border vertex 1 on side 0; the ear (0, 1, 2) makes (0, 2) a chord
  // of side 0 between two corners. The other interior edge (0, 3) joins sides 3/0 and 1/2: fine.
  PatchMesh p = make_patch({{0, 0, 0}, {0.5, -0.2, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}},
                           {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}}, {0, 2, 3, 4});
  EXPECT_EQ(p.corner_index, (std::array<int, 4>{0, 2, 3, 4}));
  const auto found = border_degeneracies(p);
  ASSERT_EQ(found, (std::vector<Edge>{{0, 2}}));
  split_edge(p, 0, 2);
  EXPECT_TRUE(border_degeneracies(p).empty());
  const SquareParam sp = parameterize_square(p);
  EXPECT_TRUE(sp.bijective());
  EXPECT_NEAR(sp.uv_area_sum, 1.0, 1e-12);
}

TEST(BorderDegeneraciesTest, CleanPatchHasNone) {
  EXPECT_TRUE(border_degeneracies(grid_patch(7, 4)).empty());
  // Chords across a corner (between its two sides) are not degenerate.
  const PatchMesh p = make_patch({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0.5, 0}},
                                 {{0, 1, 4}, {1, 2, 4}, {2, 3, 4}}, {0, 1, 2, 3});
  EXPECT_TRUE(border_degeneracies(p).empty());
  EXPECT_TRUE(parameterize_square(p).bijective());
}

// ---------------------------------------------------------------- preconditions

/// Runs f, expects InvalidInput whose message contains every one of `parts`.
template <class F>
void expect_invalid(F f, std::initializer_list<const char*> parts) {
  try {
    f();
    ADD_FAILURE() << "no exception";
  } catch (const InvalidInput& e) {
    const std::string m = e.what();
    for (const char* part : parts) EXPECT_NE(m.find(part), std::string::npos) << "message: " << m;
  }
}

TEST(SquareParamPreconditionTest, CornersNotIncreasing) {
  PatchMesh p = grid_patch(5, 5);
  p.corner_index = {0, 8, 4, 12};
  expect_invalid([&] { parameterize_square(p); }, {"strictly increase", "0 8 4 12"});
  expect_invalid([&] { border_degeneracies(p); }, {"strictly increase"});
}

TEST(SquareParamPreconditionTest, FirstCornerNotAtLoopStart) {
  PatchMesh p = grid_patch(5, 5);
  p.corner_index = {1, 4, 8, 12};
  expect_invalid([&] { parameterize_square(p); }, {"corner_index[0] must be 0"});
}

TEST(SquareParamPreconditionTest, CornerIndexOutOfRange) {
  PatchMesh p = grid_patch(5, 5);
  p.corner_index = {0, 4, 8, 16};
  expect_invalid([&] { parameterize_square(p); }, {"corner_index[3] = 16 is out of range", "16 vertices"});
}

TEST(SquareParamPreconditionTest, BoundaryReversed) {
  PatchMesh p = grid_patch(5, 5);
  std::reverse(p.boundary.begin() + 1, p.boundary.end());  // clockwise, still from corner 0
  expect_invalid([&] { parameterize_square(p); }, {"reversed", "(0,5)", "counter-clockwise"});
}

TEST(SquareParamPreconditionTest, InteriorFaceReversed) {
  PatchMesh p = grid_patch(5, 5);
  Tri& t = p.faces[10];  // an interior face, turned over: its edges now run as its neighbours' do
  std::swap(t[1], t[2]);
  const std::string pair = "(" + std::to_string(t[0]) + "," + std::to_string(t[1]) + ")";
  expect_invalid([&] { parameterize_square(p); }, {"used twice in the same direction", pair.c_str()});
}

TEST(SquareParamPreconditionTest, UnusedVertex) {
  PatchMesh p = grid_patch(5, 5);
  p.positions.emplace_back(9, 9, 9);
  expect_invalid([&] { parameterize_square(p); }, {"used by no face", "25"});
}

TEST(SquareParamPreconditionTest, BoundaryPairNotAnEdge) {
  PatchMesh p = grid_patch(5, 5);
  std::swap(p.boundary[1], p.boundary[2]);
  expect_invalid([&] { parameterize_square(p); }, {"not an edge of any face", "(0,2)"});
}

TEST(SquareParamPreconditionTest, HoleIsNotADisk) {
  PatchMesh p = grid_patch(5, 5);
  p.faces.erase(p.faces.begin() + 10);  // an interior face: a second border loop
  expect_invalid([&] { parameterize_square(p); }, {"holes"});
}

TEST(SquareParamPreconditionTest, SecondComponent) {
  PatchMesh p = grid_patch(5, 5);
  // A closed tetrahedron beside the disk: V - E + F would still be 1 + 2, but check components.
  const int b = static_cast<int>(p.positions.size());
  for (int k = 0; k < 4; ++k) p.positions.emplace_back(3 + (k == 1), 3 + (k == 2), k == 3);
  for (const Tri& t : std::vector<Tri>{{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}})
    p.faces.push_back({b + t[0], b + t[1], b + t[2]});
  expect_invalid([&] { parameterize_square(p); }, {"2 connected components"});
}

TEST(SquareParamPreconditionTest, CollectsEveryProblem) {
  PatchMesh p = grid_patch(5, 5);
  p.positions.emplace_back(9, 9, 9);
  p.corner_index = {0, 4, 8, 40};
  p.faces.push_back({0, 1, 99});
  expect_invalid([&] { parameterize_square(p); }, {"outside [0, 26)", "out of range"});
}

TEST(SquareParamPreconditionTest, BadOptionsAndNonFinitePositions) {
  PatchMesh p = grid_patch(5, 5);
  SquareParamOptions o;
  o.min_edge_length = 0;
  expect_invalid([&] { parameterize_square(p, o); }, {"min_edge_length"});
  p.positions[7].x() = std::nan("");
  expect_invalid([&] { parameterize_square(p); }, {"non-finite position: 7"});
}

// ---------------------------------------------------------------- l2_stretch

TEST(StretchTest, FlippedFaceIsInfinite) {
  PatchMesh p = grid_patch(4, 4);
  SquareParam sp = parameterize_square(p);
  sp.uv[5] = Vec2(0.9, 0.9);  // fold the first interior vertex over its neighbours
  const Stretch s = l2_stretch(p.positions, p.faces, sp.uv);
  EXPECT_TRUE(std::isinf(s.patch));
  EXPECT_TRUE(std::any_of(s.face.begin(), s.face.end(), [](double x) { return std::isinf(x); }));
}

TEST(StretchTest, ConformalNonUniformIsAtLeastOne) {
  // q = exp(s + i t) over a grid in (s, t): conformal with a scale varying from 1 to e.
  PatchMesh p = grid_patch(17, 17);
  std::vector<Vec2> uv;
  for (Vec3& x : p.positions) {
    uv.emplace_back(x.x(), x.y());
    x = Vec3(std::exp(x.x()) * std::cos(x.y()), std::exp(x.x()) * std::sin(x.y()), 0);
  }
  const Stretch s = l2_stretch(p.positions, p.faces, uv);
  EXPECT_GT(s.patch, 1.0);
  EXPECT_LT(s.patch, 1.2);
}

TEST(StretchTest, ZeroAreaFacesWeighNothing) {
  // Two faces, one of them with zero 3D area: the patch value is that of the other one.
  const std::vector<Vec3> pos{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 1, 0}};
  const std::vector<Vec2> uv{{0, 0}, {1, 0}, {0, 1}, {0.5, 1}};
  const Stretch s = l2_stretch(pos, {{0, 1, 2}, {1, 3, 2}}, uv);
  EXPECT_TRUE(std::isfinite(s.patch));
  EXPECT_NEAR(s.area3d, 0.5, 1e-15);
  // Raw stretch of face 0 is 1; sigma = sqrt(0.75 / 0.5).
  EXPECT_NEAR(s.patch, std::sqrt(1.5), 1e-12);
}

TEST(StretchTest, RejectsMismatchedSizes) {
  const std::vector<Vec3> pos{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  expect_invalid([&] { l2_stretch(pos, {{0, 1, 2}}, {{0, 0}, {1, 0}}); }, {"2 uv coordinates for 3 vertices"});
  expect_invalid([&] { l2_stretch(pos, {{0, 1, 3}}, {{0, 0}, {1, 0}, {0, 1}}); }, {"face 0", "vertex id 3"});
}

// ---------------------------------------------------------------- timing (printed, not asserted)

// Larger bumpy grids: both orderings of the solve give bijective maps (their speed: qs-bench-dissect).
TEST(SquareParamTest, LargeBumpyGridsAreBijectiveWithEitherOrdering) {
  for (int n : {73, 143, 226}) {
    PatchMesh p = grid_patch(n, n, 1, 1, 0.3);
    for (Vec3& x : p.positions) x.z() = 0.1 * std::sin(7 * x.x()) * std::cos(5 * x.y());
    SquareParamOptions colamd;
    colamd.ordering = LuOrdering::Colamd;
    EXPECT_TRUE(parameterize_square(p).bijective()) << n;
    EXPECT_TRUE(parameterize_square(p, colamd).bijective()) << n;
  }
}

TEST(SquareParamTest, StretchMinimizationLowersStretchKeepsBorderAndBijectivity) {
  const PatchMesh p = hemisphere_patch(3);
  const SquareParam plain = parameterize_square(p);
  SquareParamOptions o;
  o.stretch_iterations = 8;
  const SquareParam opt = parameterize_square(p, o);
  ASSERT_TRUE(opt.bijective());
  EXPECT_NEAR(opt.uv_area_sum, 1.0, 1e-9);
  const double before = l2_stretch(p.positions, p.faces, plain.uv).patch;
  const double after = l2_stretch(p.positions, p.faces, opt.uv).patch;
  EXPECT_LT(after, before * 0.99) << "before " << before << ", after " << after;
  for (int v : p.boundary) EXPECT_EQ(opt.uv[v], plain.uv[v]) << "border vertex " << v << " moved";
  // A developable patch is already optimal: nothing to gain, the mean-value map is kept.
  const PatchMesh flat = grid_patch(9, 5, 2, 1);
  const SquareParam f0 = parameterize_square(flat);
  const SquareParam f1 = parameterize_square(flat, o);
  for (size_t v = 0; v < f0.uv.size(); ++v) EXPECT_LT((f0.uv[v] - f1.uv[v]).norm(), 1e-12);
}

TEST(SquareParamTest, StretchMinimizationFromAGivenFirstSolveGivesTheSameBits) {
  const PatchMesh p = hemisphere_patch(3);
  for (InteriorWeights w : {InteriorWeights::MeanValue, InteriorWeights::IntrinsicCotan}) {
    SquareParamOptions plain_options;
    plain_options.weights = w;
    const SquareParam plain = parameterize_square(p, plain_options);
    SquareParamOptions o = plain_options;
    o.stretch_iterations = 4;
    const SquareParam solved = parameterize_square(p, o);
    const PlainSolve first{plain.uv, {}};
    o.plain = &first;
    const SquareParam given = parameterize_square(p, o);
    EXPECT_EQ(given.uv, solved.uv);
    // Taken as it is: a different first map changes where the minimization goes.
    PlainSolve other{plain.uv, {}};
    for (Vec2& q : other.uv) q = 0.999 * q + Vec2(0.0005, 0.0005);
    for (int v : p.boundary) other.uv[v] = plain.uv[v];
    o.plain = &other;
    EXPECT_NE(parameterize_square(p, o).uv, solved.uv);
    // One of another size is ignored.
    const PlainSolve short_map{std::vector<Vec2>(plain.uv.begin(), plain.uv.end() - 1), {}};
    o.plain = &short_map;
    EXPECT_EQ(parameterize_square(p, o).uv, solved.uv);
  }
}

// The cotangent solves report their ordering; given back for the same patch it gives the same
// bits; one that is not a permutation of the interior vertices is ignored.
TEST(SquareParamTest, AGivenCholeskyOrderingGivesTheSameBits) {
  const PatchMesh p = hemisphere_patch(4);
  SquareParamOptions plain_options;
  plain_options.weights = InteriorWeights::IntrinsicCotan;
  const SquareParam plain = parameterize_square(p, plain_options);
  ASSERT_EQ(plain.weights, InteriorWeights::IntrinsicCotan);
  ASSERT_EQ(plain.cholesky_ordering.size(), p.positions.size() - p.boundary.size());
  EXPECT_TRUE(parameterize_square(p, {}).cholesky_ordering.empty());  // mean-value: LU
  SquareParamOptions o = plain_options;
  o.stretch_iterations = 4;
  PlainSolve given_plain{plain.uv, {}};
  o.plain = &given_plain;
  const SquareParam solved = parameterize_square(p, o);
  given_plain.cholesky_ordering = plain.cholesky_ordering;
  const SquareParam given = parameterize_square(p, o);
  EXPECT_EQ(given.uv, solved.uv);
  EXPECT_EQ(given.cholesky_ordering, plain.cholesky_ordering);
  given_plain.cholesky_ordering[0] = given_plain.cholesky_ordering[1];
  EXPECT_EQ(parameterize_square(p, o).uv, solved.uv);
  given_plain.cholesky_ordering.assign(plain.cholesky_ordering.begin(), plain.cholesky_ordering.end() - 1);
  EXPECT_EQ(parameterize_square(p, o).uv, solved.uv);
}

// A large cotangent system is ordered on a second thread while its weights are computed: the same
// map, bit for bit, as on one thread (a hemisphere patch of over 20000 interior vertices).
TEST(SquareParamTest, LargeCotangentSystemGivesTheSameBitsOnOneAndTwoThreads) {
  const PatchMesh p = hemisphere_patch(6);
  SquareParamOptions o;
  o.weights = InteriorWeights::IntrinsicCotan;
  o.stretch_iterations = 2;
  qs::Context one, two;
  one.threads = 1;
  two.threads = 2;
  const SquareParam a = parameterize_square(p, o, one);
  const SquareParam b = parameterize_square(p, o, two);
  ASSERT_GT(p.positions.size() - p.boundary.size(), 20000u);
  EXPECT_EQ(a.weights, InteriorWeights::IntrinsicCotan);
  EXPECT_TRUE(a.bijective());
  EXPECT_EQ(a.uv, b.uv);
}

TEST(SquareParamTest, StretchMinimizationRepairsAFingerSqueezedToZeroArea) {
  // A finger (a tube of length 40 radii closed by a cone): the mean-value map shrinks it about
  // e^(-length / radius), below double precision; stretch minimization spreads it out again.
  const int around = 16, rings = 80;
  std::vector<Vec3> pos;
  std::vector<Tri> faces;
  for (int k = 0; k <= rings; ++k)
    for (int a = 0; a < around; ++a) {
      const double t = 2 * M_PI * (a + 0.5 * (k % 2)) / around;
      pos.emplace_back(std::cos(t), std::sin(t), 0.5 * k);
    }
  auto id = [&](int k, int a) { return k * around + (a % around); };
  for (int k = 0; k < rings; ++k)
    for (int a = 0; a < around; ++a) {
      if (k % 2 == 0) {
        faces.push_back({id(k, a), id(k, a + 1), id(k + 1, a)});
        faces.push_back({id(k, a + 1), id(k + 1, a + 1), id(k + 1, a)});
      } else {
        faces.push_back({id(k, a), id(k + 1, a + 1), id(k + 1, a)});
        faces.push_back({id(k, a), id(k, a + 1), id(k + 1, a + 1)});
      }
    }
  const int tip = static_cast<int>(pos.size());
  pos.emplace_back(0, 0, 0.5 * rings + 1);
  for (int a = 0; a < around; ++a) faces.push_back({id(rings, a), id(rings, a + 1), tip});
  const std::vector<int> b = border_loop(faces);
  const int m = static_cast<int>(b.size());
  const PatchMesh p = make_patch(std::move(pos), std::move(faces), {b[0], b[m / 4], b[m / 2], b[3 * m / 4]});
  const SquareParam plain = parameterize_square(p);
  ASSERT_GT(plain.zero_area_faces + plain.flipped_faces, 0) << "the finger must defeat the plain map";
  SquareParamOptions o;
  o.stretch_iterations = 20;
  const SquareParam opt = parameterize_square(p, o);
  EXPECT_TRUE(opt.bijective()) << opt.zero_area_faces << " zero-area, " << opt.flipped_faces << " flipped";
  EXPECT_NEAR(opt.uv_area_sum, 1.0, 1e-9);
}

}  // namespace

// Cotangent weights on the intrinsic Delaunay triangulation: a flat patch, jittered (so some edges
// are not Delaunay and get flipped) and moved rigidly into 3D, maps onto itself (harmonic maps
// reproduce affine functions), the flips counted; the map is bijective.
TEST(IntrinsicCotan, AFlatJitteredSquareMapsOntoItself) {
  PatchMesh p = grid_patch(13, 13, 1, 1, 0.35);
  std::vector<Vec3> flat = p.positions;
  for (Vec3& x : p.positions) x = rigid(x);
  SquareParamOptions o;
  o.weights = InteriorWeights::IntrinsicCotan;
  const SquareParam sp = parameterize_square(p, o);
  EXPECT_GT(sp.intrinsic_flips, 0);
  EXPECT_TRUE(sp.bijective());
  EXPECT_NEAR(sp.uv_area_sum, 1.0, 1e-12);
  double worst = 0;
  for (size_t v = 0; v < flat.size(); ++v) worst = std::max(worst, (sp.uv[v] - flat[v].head<2>()).norm());
  EXPECT_LT(worst, 1e-9);
  // Mean-value weights flip nothing.
  EXPECT_EQ(parameterize_square(p).intrinsic_flips, 0);
}

// On a curved patch both weights give a bijective map; the intrinsic triangulation of an already
// Delaunay mesh (an icosphere's) needs few flips. Stretch minimization (solved as a symmetric
// system: the row of vertex i scaled by its own stretch factors) lowers the stretch.
TEST(IntrinsicCotan, AHemisphereMapsBijectivelyWithAndWithoutStretchMinimization) {
  const PatchMesh p = hemisphere_patch(4);
  double stretch[2] = {0, 0};
  for (int rounds : {0, 5}) {
    SquareParamOptions o;
    o.weights = InteriorWeights::IntrinsicCotan;
    o.stretch_iterations = rounds;
    const SquareParam sp = parameterize_square(p, o);
    EXPECT_TRUE(sp.bijective()) << sp.flipped_faces << " flipped, " << sp.zero_area_faces << " zero-area";
    EXPECT_NEAR(sp.uv_area_sum, 1.0, 1e-9);
    EXPECT_LT(sp.intrinsic_flips, static_cast<int>(p.faces.size()) / 10);
    EXPECT_EQ(sp.weights, InteriorWeights::IntrinsicCotan);
    stretch[rounds > 0] = l2_stretch(p.positions, p.faces, sp.uv).patch;
  }
  EXPECT_LT(stretch[1], stretch[0] * 0.99) << "stretch " << stretch[0] << " -> " << stretch[1];
}

}  // namespace qs::param

namespace qs::param {
namespace {

/// Two stacked "double chains" over [0,1] x [0,2] at z = 0: rows y = 0, 1, 2 of n + 1 vertices
/// each, every strip between two rows triangulated as two fans (from the lower row's first
/// vertex to the upper row, and from the upper row's last vertex to the lower row), as a cut
/// across a fan of slivers leaves it. Lawson's flips to the Delaunay triangulation are quadratic
/// in n here. Interior vertices: the middle row but its ends.
PatchMesh double_chain_patch(int n) {
  std::vector<Vec3> pos;
  for (int row = 0; row < 3; ++row)
    for (int i = 0; i <= n; ++i) pos.emplace_back(static_cast<double>(i) / n, row, 0.0);
  auto at = [n](int row, int i) { return row * (n + 1) + i; };
  std::vector<Tri> faces;
  for (int row = 0; row < 2; ++row)
    for (int i = 0; i < n; ++i) {
      faces.push_back({at(row, 0), at(row + 1, i + 1), at(row + 1, i)});
      faces.push_back({at(row + 1, n), at(row, i), at(row, i + 1)});
    }
  return make_patch(pos, faces, {at(0, 0), at(0, n), at(2, n), at(2, 0)});
}

}  // namespace

// The intrinsic Delaunay flips are bounded by a budget linear in the faces: past it the patch is
// solved with mean-value weights (still a bijection: positive weights, convex border), so that
// the cost stays linear where Lawson's flips would be quadratic. Small patches keep cotangent
// weights.
TEST(IntrinsicCotan, QuadraticFlipsFallBackToMeanValueWithinALinearBudget) {
  SquareParamOptions o;
  o.weights = InteriorWeights::IntrinsicCotan;
  const PatchMesh small = double_chain_patch(12);
  const SquareParam a = parameterize_square(small, o);
  EXPECT_EQ(a.weights, InteriorWeights::IntrinsicCotan);
  EXPECT_GT(a.intrinsic_flips, 0);
  EXPECT_TRUE(a.bijective());

  const PatchMesh big = double_chain_patch(300);
  const int nf = static_cast<int>(big.faces.size());
  o.stretch_iterations = 3;
  const SquareParam b = parameterize_square(big, o);
  EXPECT_EQ(b.weights, InteriorWeights::MeanValue);
  EXPECT_LE(b.intrinsic_flips, 4 * nf + 1000);
  EXPECT_GT(b.intrinsic_flips, 4 * nf);
  EXPECT_TRUE(b.bijective()) << b.flipped_faces << " flipped, " << b.zero_area_faces << " zero-area";
  EXPECT_NEAR(b.uv_area_sum, 1.0, 1e-9);
  // The same map as asking for mean-value weights.
  SquareParamOptions mv;
  mv.stretch_iterations = 3;
  const SquareParam c = parameterize_square(big, mv);
  ASSERT_EQ(c.uv.size(), b.uv.size());
  for (size_t v = 0; v < c.uv.size(); ++v) EXPECT_EQ(c.uv[v], b.uv[v]) << "vertex " << v;
}

// A held solve of a few free vertices (a local repair) gives, bit for bit, what a full solve with
// every other interior vertex pinned gives them, with either weights; the held vertices and the
// border are left as they were, and a held vertex outside the square is refused.
TEST(HeldSolverTest, GivesTheFreeVerticesWhatAPinnedSolveGivesThem) {
  const PatchMesh p = hemisphere_patch(4);
  const int nv = static_cast<int>(p.positions.size());
  std::vector<char> on_border(nv, 0);
  for (int v : p.boundary) on_border[v] = 1;
  for (const InteriorWeights weights : {InteriorWeights::MeanValue, InteriorWeights::IntrinsicCotan}) {
    SquareParamOptions o;
    o.weights = weights;
    const SquareParam own = parameterize_square(p, o);
    ASSERT_TRUE(own.bijective());
    // Held: the own map, shrunk toward the centre (a different map); free: every 7th interior vertex.
    std::vector<Vec2> at = own.uv;
    std::vector<char> free(nv, 0);
    int nfree = 0;
    for (int v = 0; v < nv; ++v) {
      if (on_border[v]) continue;
      at[v] = Vec2(0.5, 0.5) + 0.9 * (own.uv[v] - Vec2(0.5, 0.5));
      if (v % 7 == 0) free[v] = 1, ++nfree;
    }
    ASSERT_GT(nfree, 10);
    SquareParamOptions pinned = o;
    for (int v = 0; v < nv; ++v)
      if (!on_border[v] && !free[v]) pinned.pinned.emplace_back(v, at[v]);
    const SquareParam full = parameterize_square(p, pinned);
    const HeldSolver held(p, weights);
    std::vector<Vec2> local = at;
    held.solve(free, local);
    int moved = 0;
    for (int v = 0; v < nv; ++v) {
      if (free[v]) {
        EXPECT_EQ(local[v], full.uv[v]) << "free vertex " << v;
        moved += local[v] != at[v];
      } else {
        EXPECT_EQ(local[v], at[v]) << "held vertex " << v;
      }
    }
    EXPECT_GT(moved, nfree / 2);
    std::vector<Vec2> outside = at;
    for (int v = 0; v < nv; ++v)
      if (!on_border[v] && !free[v]) {
        outside[v] = Vec2(1.5, 0.5);
        break;
      }
    EXPECT_THROW(held.solve(free, outside), InvalidInput);
    EXPECT_THROW(held.solve(std::vector<char>(nv - 1, 0), local), InvalidInput);
  }
}


}  // namespace qs::param
