#include "qs/dissect/loop_guide.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "qs/core/error.h"
#include "qs/core/parallel.h"
#include "qs/dissect/seed_routing_detail.h"

namespace qs::dissect {

double landmark_discrepancy(const GeodesicCoordinates& a, const std::vector<int>& la, const GeodesicCoordinates& b,
                            const std::vector<int>& lb) {
  double diff = 0, sum = 0;
  for (size_t p = 0; p < la.size(); ++p)
    for (size_t q = p + 1; q < la.size(); ++q) {
      const double da = a.at(la[q])[p], db = b.at(lb[q])[p];
      diff += std::abs(da - db);
      sum += da;
    }
  return sum > 0 && std::isfinite(diff) ? diff / sum : std::numeric_limits<double>::infinity();
}

GeodesicCoordinates geodesic_coordinates(const TriMesh& mesh, const std::vector<int>& landmarks,
                                         const Context& context) {
  const routing::Graph g = routing::build_graph(mesh);
  const int nv = mesh.num_vertices();
  const double scale = 1.0 / std::sqrt(std::max(surface_area(mesh), 1e-300));
  GeodesicCoordinates out;
  out.dims = static_cast<int>(landmarks.size());
  out.values.resize(static_cast<size_t>(nv) * out.dims);
  parallel_for(out.dims, inside_parallel_loop() ? 1 : 0, context, [&](int l) {
    routing::Dijkstra dijkstra(g);
    const std::vector<double> dist = dijkstra.all_distances(landmarks[l]);
    for (int v = 0; v < nv; ++v) out.values[static_cast<size_t>(v) * out.dims + l] = dist[v] * scale;
  });
  return out;
}

std::array<std::vector<std::vector<double>>, 4> loop_coordinates(const GeodesicCoordinates& coords,
                                                                 const SeedLoop& loop, int samples) {
  std::array<std::vector<std::vector<double>>, 4> out;
  for (int i = 0; i < 4; ++i) {
    const auto& path = loop.paths[i];
    const size_t n = path.size();
    const size_t m = std::min<size_t>(n, std::max(samples, 2));
    for (size_t s = 0; s < m; ++s) {
      const size_t k = m == 1 ? 0 : (s * (n - 1)) / (m - 1);
      const double* c = coords.at(path[k]);
      out[i].emplace_back(c, c + coords.dims);
    }
  }
  return out;
}

SeedLoop trace_intrinsic_loop(const TriMesh& mesh, const std::array<int, 4>& seeds, const GeodesicCoordinates& coords,
                              const std::array<std::vector<std::vector<double>>, 4>& reference, double sigma,
                              const std::vector<int>& avoid) {
  if (!(sigma > 0)) throw InvalidInput("trace_intrinsic_loop: sigma must be > 0");
  const int nv = mesh.num_vertices(), dims = coords.dims;
  // Per path, every vertex's coordinate distance to the nearest reference point, over sigma.
  std::array<std::vector<float>, 4> off;
  for (int i = 0; i < 4; ++i) {
    if (reference[i].empty()) throw InvalidInput("trace_intrinsic_loop: reference " + std::to_string(i) + " is empty");
    off[i].resize(nv);
    for (int v = 0; v < nv; ++v) {
      const double* c = coords.at(v);
      double best = std::numeric_limits<double>::infinity();
      for (const auto& r : reference[i]) {
        double d2 = 0;
        for (int k = 0; k < dims && d2 < best; ++k) d2 += (c[k] - r[k]) * (c[k] - r[k]);
        best = std::min(best, d2);
      }
      off[i][v] = static_cast<float>(std::sqrt(best) / sigma);
    }
  }
  return trace_weighted_loop(
      mesh, seeds,
      [&](int i, int v, int w) {
        const double r = 0.5 * (static_cast<double>(off[i][v]) + off[i][w]);
        return 1 + r * r;
      },
      avoid);
}

namespace {

// matched_extremities takes no point nearer to the landmarks and the points already taken than
// this fraction of the first point's distance.
constexpr double kStop = 0.25;
// ... and takes a match only when every vertex of B away from it differs at least this many
// times as much (the other of two symmetric limbs)...
constexpr double kAmbiguous = 1.5;
// ... and at least this fraction of the tolerance (a mirror image of an exact match differs by 0).
constexpr double kDistinct = 0.2;

// Relative root-mean-square difference of two coordinate rows (against `x`'s size).
double coordinate_difference(const double* x, const double* y, int dims) {
  double d = 0, n = 0;
  for (int l = 0; l < dims; ++l) {
    d += (x[l] - y[l]) * (x[l] - y[l]);
    n += x[l] * x[l];
  }
  return n > 0 && std::isfinite(d) ? std::sqrt(d / n) : std::numeric_limits<double>::infinity();
}

// The vertex of `c` whose row differs least from `x` among those with within[v]; -1 when none.
int best_match(const GeodesicCoordinates& c, const double* x, int dims, const std::vector<char>& within,
               double& difference) {
  int best = -1;
  difference = std::numeric_limits<double>::infinity();
  const int nv = static_cast<int>(c.values.size() / std::max(c.dims, 1));
  for (int v = 0; v < nv; ++v) {
    if (!within.empty() && !within[v]) continue;
    const double d = coordinate_difference(x, c.at(v), dims);
    if (d < difference) {
      difference = d;
      best = v;
    }
  }
  return best;
}

}  // namespace

std::vector<std::pair<int, int>> matched_extremities(const TriMesh& a, const GeodesicCoordinates& ca, const TriMesh& b,
                                                     const GeodesicCoordinates& cb, int count, double tolerance) {
  std::vector<std::pair<int, int>> out;
  const int dims = ca.dims;
  if (dims == 0 || cb.dims != dims) return out;
  const int na = a.num_vertices(), nb = b.num_vertices();
  const routing::Graph ga = routing::build_graph(a), gb = routing::build_graph(b);
  routing::Dijkstra da(ga), db(gb);
  const double scale_a = 1.0 / std::sqrt(std::max(surface_area(a), 1e-300));
  const double scale_b = 1.0 / std::sqrt(std::max(surface_area(b), 1e-300));
  // Distance to the nearest landmark or point taken, per vertex of A.
  std::vector<double> nearest(na, std::numeric_limits<double>::infinity());
  for (int v = 0; v < na; ++v)
    for (int l = 0; l < dims; ++l) nearest[v] = std::min(nearest[v], ca.at(v)[l]);
  double first = -1;
  for (int k = 0; k < count; ++k) {
    int p = -1;
    for (int v = 0; v < na; ++v)
      if (std::isfinite(nearest[v]) && (p < 0 || nearest[v] > nearest[p])) p = v;
    if (p < 0 || !(nearest[p] > 0)) break;
    if (first < 0) first = nearest[p];
    if (nearest[p] < kStop * first) break;
    const double radius = 0.5 * nearest[p];
    std::vector<double> from_p = da.all_distances(p);
    for (double& d : from_p) d *= scale_a;
    for (int v = 0; v < na; ++v) nearest[v] = std::min(nearest[v], from_p[v]);
    double best = 0;
    const int q = best_match(cb, ca.at(p), dims, {}, best);
    if (q < 0 || !(best <= tolerance)) continue;
    std::vector<double> from_q = db.all_distances(q);
    std::vector<char> far(nb, 0);
    for (int v = 0; v < nb; ++v) far[v] = from_q[v] * scale_b > radius;
    double second = 0;
    const int sv = best_match(cb, ca.at(p), dims, far, second);
    if (sv >= 0 && !(second >= std::max(kAmbiguous * best, kDistinct * tolerance))) continue;
    double back = 0;
    const int r = best_match(ca, cb.at(q), dims, {}, back);
    if (r < 0 || !(from_p[r] <= radius)) continue;
    out.emplace_back(p, q);
  }
  return out;
}

}  // namespace qs::dissect
