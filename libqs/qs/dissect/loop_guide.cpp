#include "qs/dissect/loop_guide.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>

#include "qs/core/error.h"

namespace qs::dissect {

GeodesicCoordinates geodesic_coordinates(const TriMesh& mesh, const std::vector<int>& landmarks) {
  const int nv = mesh.num_vertices();
  std::vector<int> start(nv + 1, 0), adj;
  for (const Tri& t : mesh.faces)
    for (int k = 0; k < 3; ++k) start[t[k] + 1] += 2;
  for (int v = 0; v < nv; ++v) start[v + 1] += start[v];
  adj.resize(start[nv]);
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (const Tri& t : mesh.faces)
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      adj[fill[a]++] = b;
      adj[fill[b]++] = a;
    }
  const double scale = 1.0 / std::sqrt(std::max(surface_area(mesh), 1e-300));
  GeodesicCoordinates out;
  out.dims = static_cast<int>(landmarks.size());
  out.values.assign(static_cast<size_t>(nv) * out.dims, std::numeric_limits<double>::infinity());
  std::vector<double> dist(nv);
  using Item = std::pair<double, int>;
  for (int l = 0; l < out.dims; ++l) {
    std::fill(dist.begin(), dist.end(), std::numeric_limits<double>::infinity());
    std::priority_queue<Item, std::vector<Item>, std::greater<>> heap;
    dist[landmarks[l]] = 0;
    heap.emplace(0.0, landmarks[l]);
    while (!heap.empty()) {
      const auto [du, u] = heap.top();
      heap.pop();
      if (du > dist[u]) continue;
      for (int k = start[u]; k < start[u + 1]; ++k) {
        const int w = adj[k];
        const double nd = du + (mesh.positions[u] - mesh.positions[w]).norm();
        if (nd < dist[w]) {
          dist[w] = nd;
          heap.emplace(nd, w);
        }
      }
    }
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
