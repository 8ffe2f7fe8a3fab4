#include "qs/dfi/sdf.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <tuple>

#include "qs/core/error.h"
#include "qs/core/parallel.h"
#include "qs/metro/metro.h"

namespace qs::dfi {

namespace {

struct Crossing {
  int row;
  double x;
  int dir;  ///< +1 entering (outward normal towards -x), -1 leaving
  bool operator<(const Crossing& o) const { return std::tie(row, x, dir) < std::tie(o.row, o.x, o.dir); }
};

}  // namespace

std::vector<char> inside_mask(const TriMesh& mesh, const Grid& g) {
  const int nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
  // Row (j, k) runs along x through (y, z) = origin + h * (j + ey, k + ez).
  const double ey = 1e-7 * std::sqrt(2.0), ez = 1e-7 * std::sqrt(3.0);
  std::vector<Crossing> crossings;
  const double h = g.spacing;
  for (const Tri& t : mesh.faces) {
    const Vec3& A = mesh.positions[t[0]];
    const Vec3& B = mesh.positions[t[1]];
    const Vec3& C = mesh.positions[t[2]];
    // 2D (y, z) in cell units relative to the grid origin, minus the row offset.
    auto yz = [&](const Vec3& p) {
      return Vec2((p.y() - g.origin.y()) / h - ey, (p.z() - g.origin.z()) / h - ez);
    };
    const Vec2 a = yz(A), b = yz(B), c = yz(C);
    const double area = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    if (area == 0) continue;  // edge-on: rows through it cross its neighbours
    const int j0 = std::max(0, static_cast<int>(std::ceil(std::min({a.x(), b.x(), c.x()}))));
    const int j1 = std::min(ny - 1, static_cast<int>(std::floor(std::max({a.x(), b.x(), c.x()}))));
    const int k0 = std::max(0, static_cast<int>(std::ceil(std::min({a.y(), b.y(), c.y()}))));
    const int k1 = std::min(nz - 1, static_cast<int>(std::floor(std::max({a.y(), b.y(), c.y()}))));
    if (j0 > j1 || k0 > k1) continue;
    const int dir = area > 0 ? -1 : +1;  // (y,z) counter-clockwise: normal +x: leaving
    // Edge function evaluated from the lower vertex id, so two triangles sharing an edge get
    // exactly opposite values.
    auto edge = [&](int u, int v, const Vec2& pu, const Vec2& pv, const Vec2& p) {
      if (u < v) return (pv - pu).x() * (p - pu).y() - (pv - pu).y() * (p - pu).x();
      return -((pu - pv).x() * (p - pv).y() - (pu - pv).y() * (p - pv).x());
    };
    const double s = area > 0 ? 1.0 : -1.0;
    for (int k = k0; k <= k1; ++k)
      for (int j = j0; j <= j1; ++j) {
        const Vec2 p(j, k);
        const double wa = s * edge(t[1], t[2], b, c, p);  // opposite a
        const double wb = s * edge(t[2], t[0], c, a, p);
        const double wc = s * edge(t[0], t[1], a, b, p);
        if (wa < 0 || wb < 0 || wc < 0) continue;
        const double sum = wa + wb + wc;
        if (!(sum > 0)) continue;
        const double x = (wa * A.x() + wb * B.x() + wc * C.x()) / sum;
        crossings.push_back({k * ny + j, (x - g.origin.x()) / h, dir});
      }
  }
  std::sort(crossings.begin(), crossings.end());
  std::vector<char> inside(g.size(), 0);
  size_t c = 0;
  for (int row = 0; row < ny * nz; ++row) {
    const int j = row % ny, k = row / ny;
    int winding = 0;
    for (int i = 0; i < nx; ++i) {
      while (c < crossings.size() && crossings[c].row == row && crossings[c].x < i) winding += crossings[c++].dir;
      inside[g.index(i, j, k)] = winding > 0;
    }
    while (c < crossings.size() && crossings[c].row == row) ++c;
  }
  return inside;
}

Grid signed_distance(const TriMesh& mesh, const Grid& domain, const SdfOptions& options, const Context& ctx) {
  if (mesh.faces.empty()) throw InvalidInput("signed distance: the mesh has no faces");
  if (options.band < 0) throw InvalidInput("signed distance: band is " + std::to_string(options.band) + "; expected >= 0");
  if (options.threads < 0) throw InvalidInput("signed distance: threads is " + std::to_string(options.threads) + "; expected >= 0");
  Grid g = domain;
  const size_t n = g.size();
  const int nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
  const double h = g.spacing;
  const metro::SurfaceDistance surface(mesh, "mesh");

  // Which samples get an exact distance.
  std::vector<char> exact(n, options.band == 0 ? 1 : 0);
  if (options.band > 0) {
    for (const Tri& t : mesh.faces) {
      Vec3 lo = mesh.positions[t[0]], hi = lo;
      for (int v : t) {
        lo = lo.cwiseMin(mesh.positions[v]);
        hi = hi.cwiseMax(mesh.positions[v]);
      }
      int a[3], b[3];
      for (int ax = 0; ax < 3; ++ax) {
        a[ax] = std::max(0, static_cast<int>(std::floor((lo[ax] - g.origin[ax]) / h)) - options.band);
        b[ax] = std::min(g.dims[ax] - 1, static_cast<int>(std::ceil((hi[ax] - g.origin[ax]) / h)) + options.band);
      }
      for (int k = a[2]; k <= b[2]; ++k)
        for (int j = a[1]; j <= b[1]; ++j)
          for (int i = a[0]; i <= b[0]; ++i) exact[g.index(i, j, k)] = 1;
    }
  }
  ctx.report("signed distance", 0.05);
  // Exact closest points, in parallel over z-slabs (each sample written once).
  std::vector<Eigen::Vector3f> closest(n, Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
  std::vector<float> dist(n, std::numeric_limits<float>::infinity());
  parallel_for(nz, options.threads, ctx, [&](int k) {
    ctx.check_cancel();
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const size_t id = g.index(i, j, k);
        if (!exact[id]) continue;
        const auto r = surface.closest(g.point(i, j, k));
        closest[id] = r.point.cast<float>();
        dist[id] = static_cast<float>(r.distance);
      }
  });
  ctx.report("signed distance", 0.6);
  // Closest-point propagation: eight raster sweeps, each looking at the upstream neighbours.
  if (options.band > 0) {
    for (int sweep = 0; sweep < 8; ++sweep) {
      const int sx = sweep & 1 ? -1 : 1, sy = sweep & 2 ? -1 : 1, sz = sweep & 4 ? -1 : 1;
      for (int kk = 0; kk < nz; ++kk) {
        const int k = sz > 0 ? kk : nz - 1 - kk;
        for (int jj = 0; jj < ny; ++jj) {
          const int j = sy > 0 ? jj : ny - 1 - jj;
          for (int ii = 0; ii < nx; ++ii) {
            const int i = sx > 0 ? ii : nx - 1 - ii;
            const size_t id = g.index(i, j, k);
            if (exact[id]) continue;
            const Eigen::Vector3f p = g.point(i, j, k).cast<float>();
            for (int d = 1; d < 8; ++d) {  // the 7 upstream neighbours of the octant
              const int di = (d & 1) ? -sx : 0, dj = (d & 2) ? -sy : 0, dk = (d & 4) ? -sz : 0;
              const int ni = i + di, nj = j + dj, nk = k + dk;
              if (ni < 0 || nj < 0 || nk < 0 || ni >= nx || nj >= ny || nk >= nz) continue;
              const size_t nid = g.index(ni, nj, nk);
              if (!std::isfinite(dist[nid])) continue;
              const float dd = (p - closest[nid]).norm();
              if (dd < dist[id]) {
                dist[id] = dd;
                closest[id] = closest[nid];
              }
            }
          }
        }
      }
    }
  }
  ctx.report("signed distance", 0.8);
  const std::vector<char> inside = inside_mask(mesh, g);
  g.values.resize(n);
  for (size_t id = 0; id < n; ++id) g.values[id] = inside[id] ? -dist[id] : dist[id];
  ctx.report("signed distance", 1.0);
  return g;
}

}  // namespace qs::dfi
