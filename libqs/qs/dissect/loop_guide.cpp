#include "qs/dissect/loop_guide.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "qs/core/error.h"
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

GeodesicCoordinates geodesic_coordinates(const TriMesh& mesh, const std::vector<int>& landmarks) {
  const routing::Graph g = routing::build_graph(mesh);
  routing::Dijkstra dijkstra(g);
  const int nv = mesh.num_vertices();
  const double scale = 1.0 / std::sqrt(std::max(surface_area(mesh), 1e-300));
  GeodesicCoordinates out;
  out.dims = static_cast<int>(landmarks.size());
  out.values.resize(static_cast<size_t>(nv) * out.dims);
  for (int l = 0; l < out.dims; ++l) {
    const std::vector<double> dist = dijkstra.all_distances(landmarks[l]);
    for (int v = 0; v < nv; ++v) out.values[static_cast<size_t>(v) * out.dims + l] = dist[v] * scale;
  }
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

}  // namespace qs::dissect
