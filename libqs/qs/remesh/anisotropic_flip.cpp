// The anisotropic remesh's edge flips on the surface (docs/algorithms.md).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_set>
#include <utility>

#include "qs/core/error.h"
#include "qs/core/geometry2d.h"
#include "qs/mesh/connectivity.h"
#include "qs/remesh/anisotropic_detail.h"

namespace qs::remesh::aniso {

// A flip's new edge may lie this share of its length off the surface (at its midpoint) where the
// old edge lay closer (see flip_for_angles).
constexpr double kFlipChordSlack = 0.005;
// ... and its two triangles may cover this much more area than the old two (a flip across a fold
// of a squeezed map does much more: polygirl_20k's level-5 vertex spread 33.8 -> 50 without it).
constexpr double kFlipAreaGrowth = 1.05;

namespace {

// How far the chord from xa to xb (the 3D points of (u,v) ua, ub of patch p) passes from the
// surface, along n: the distance of its 3D midpoint from the chart's point at its (u,v) midpoint.
double chord_gap(const ChartSampler& s, int p, const Vec2& ua, const Vec2& ub, const Vec3& xa, const Vec3& xb,
                 const Vec3& n, int& hint) {
  return std::abs(n.dot(0.5 * (xa + xb) - s.point(p, 0.5 * (ua + ub), hint)));
}

}  // namespace

// Edge flips on the surface (docs/algorithms.md): an edge whose two triangles lie in one patch is
// flipped when that raises the smallest angle of the two over the set, their worst angle is under
// below_degrees, the new edge has a patch-interior end and is no edge yet, and the two new
// triangles are counter-clockwise in the patch's (u,v). Half-edge he = 3 f + k runs from corner k
// of face f to corner k + 1; faces are replaced in place, edges visited from a stack (last in,
// first out), so the result is a function of the input alone. Returns the number of flips.
// `touched` (#V) flags the four corners of every flipped pair.
int flip_for_angles(const std::vector<ChartSampler>& samplers, SemiRegularConnectivity& c,
                    const std::vector<std::vector<Vec3>>& positions, double below_degrees,
                    std::vector<char>& touched) {
  const BaseTopology& t = samplers[0].topology();
  auto interior = [&](int x) { return patch_interior(c, x); };
  auto& faces = c.faces;
  const int nf = c.num_faces();
  auto from = [&](int he) { return faces[he / 3][he % 3]; };
  auto to = [&](int he) { return faces[he / 3][(he % 3 + 1) % 3]; };
  auto next = [](int he) { return he - he % 3 + (he % 3 + 1) % 3; };
  auto prev = [](int he) { return he - he % 3 + (he % 3 + 2) % 3; };
  // Twins (the same half-edge numbering as qs::mesh::Connectivity), kept up to date by the flips.
  std::vector<int> twin = mesh::build_connectivity(TriMesh{positions[0], faces}).opposite;
  // Whether an edge joins v and w: around v through the twins (the mesh is closed and manifold).
  auto joined = [&](int start, int w) {  // start: a half-edge leaving v
    int he = start;
    for (int guard = 0; guard < nf; ++guard) {
      if (to(he) == w) return true;
      he = twin[prev(he)];
      if (he < 0 || he == start) return false;
    }
    return false;
  };
  auto patch_of = [&](int f) {
    for (int v : faces[f])
      if (interior(v)) return c.vertex_patch[v];
    return -1;
  };
  auto quality = [&](const Tri& f, const Tri& g) {
    double q = 1;
    for (const auto& x : positions)
      q = std::min({q, sin_min_angle(x[f[0]], x[f[1]], x[f[2]]), sin_min_angle(x[g[0]], x[g[1]], x[g[2]])});
    return q;
  };
  const double threshold = std::sin(below_degrees * M_PI / 180);
  std::vector<int> hints(samplers.size(), -1);
  std::vector<int> work;
  work.reserve(3 * static_cast<size_t>(nf));
  for (int he = 3 * nf - 1; he >= 0; --he) work.push_back(he);
  int flips = 0;
  const long budget = 20L * nf;  // visits; flips raise the sorted angles, so this is a guard only
  for (long visit = 0; !work.empty() && visit < budget; ++visit) {
    const int h = work.back();
    work.pop_back();
    const int g_he = twin[h];
    if (g_he < 0) continue;
    const int f = h / 3, g = g_he / 3;
    if (f == g) continue;
    const int a = from(h), b = to(h), cc = to(next(h)), d = to(next(g_he));
    if (cc == d || (!interior(cc) && !interior(d))) continue;
    const int p = patch_of(f);
    if (p < 0 || patch_of(g) != p) continue;
    const double before = quality(faces[f], faces[g]);
    if (!(before < threshold)) continue;
    const Tri f_new = {cc, a, d}, g_new = {d, b, cc};
    if (!(quality(f_new, g_new) > before * (1 + 1e-9))) continue;
    if (joined(prev(h), d)) continue;  // prev(h) leaves cc
    // Counter-clockwise in the patch's (u,v), with a margin against rounding.
    const Vec2 near = c.vertex_uv[interior(cc) ? cc : d];
    const Vec2 ua = uv_in_patch(t, c, a, p, near), ub = uv_in_patch(t, c, b, p, near),
               uc = uv_in_patch(t, c, cc, p, near), ud = uv_in_patch(t, c, d, p, near);
    const double total = std::abs(cross2(ub - ua, uc - ua)) + std::abs(cross2(ua - ub, ud - ub));
    if (!(cross2(ua - uc, ud - uc) > 1e-6 * total && cross2(ub - ud, uc - ud) > 1e-6 * total)) continue;
    // The new edge stays as close to the surface as the old one (in every mesh): the distance of
    // its 3D midpoint from the chart's point at its (u,v) midpoint, along the normal of the two
    // old triangles (the map's tangential distortion does not count), at most the old edge's or
    // kFlipChordSlack of its length, and the pair's area grows by kFlipAreaGrowth at most, so
    // that a flip across a bend or a fold does not cut the surface.
    bool near_surface = true;
    const bool set = samplers.size() > 1;
    for (size_t m = 0; m < samplers.size() && near_surface; ++m) {
      const auto& x = positions[m];
      Vec3 n = (x[b] - x[a]).cross(x[cc] - x[a]) + (x[a] - x[b]).cross(x[d] - x[b]);
      const double nn = n.norm();
      if (!(nn > 0)) continue;
      n /= nn;
      const double old_gap = chord_gap(samplers[m], p, ua, ub, x[a], x[b], n, hints[m]);
      const double new_gap = chord_gap(samplers[m], p, uc, ud, x[cc], x[d], n, hints[m]);
      double allowed = std::max(old_gap, kFlipChordSlack * (x[cc] - x[d]).norm());
      // The pair's four sides, only when needed (in a set, a mesh sampled more coarsely than the
      // remesh has chords off its surface everywhere: its old diagonal happening to lie on one
      // chart face must not block a flip that another mesh needs).
      const std::array<std::pair<int, Vec2>, 4> quad = {{{a, ua}, {d, ud}, {b, ub}, {cc, uc}}};
      for (int k = 0; k < 4 && set && new_gap > allowed; ++k) {
        const auto& [v0, w0] = quad[k];
        const auto& [v1, w1] = quad[(k + 1) % 4];
        allowed = std::max(allowed, chord_gap(samplers[m], p, w0, w1, x[v0], x[v1], n, hints[m]));
      }
      const double old_area = (x[b] - x[a]).cross(x[cc] - x[a]).norm() + (x[a] - x[b]).cross(x[d] - x[b]).norm();
      const double new_area = (x[a] - x[cc]).cross(x[d] - x[cc]).norm() + (x[b] - x[d]).cross(x[cc] - x[d]).norm();
      near_surface = new_gap <= allowed && new_area <= kFlipAreaGrowth * old_area;
    }
    if (!near_surface) continue;
    // The outer half-edges' twins, then the two faces and their six half-edges.
    const int t_bc = twin[next(h)], t_ca = twin[prev(h)], t_ad = twin[next(g_he)], t_db = twin[prev(g_he)];
    faces[f] = f_new;  // 3f: c->a, 3f+1: a->d, 3f+2: d->c
    faces[g] = g_new;  // 3g: d->b, 3g+1: b->c, 3g+2: c->d
    auto link = [&](int x, int y) {
      twin[x] = y;
      if (y >= 0) twin[y] = x;
    };
    link(3 * f, t_ca), link(3 * f + 1, t_ad), link(3 * g, t_db), link(3 * g + 1, t_bc), link(3 * f + 2, 3 * g + 2);
    ++flips;
    touched[a] = touched[b] = touched[cc] = touched[d] = 1;
    for (int k = 0; k < 2; ++k) work.push_back(3 * f + k), work.push_back(3 * g + k);
  }
  return flips;
}

}  // namespace qs::remesh::aniso
