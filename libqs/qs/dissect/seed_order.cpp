#include "qs/dissect/seed_order.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "qs/dissect/dissection.h"
#include "qs/dissect/loop_guide.h"

namespace qs::dissect {

namespace {

constexpr std::array<std::array<int, 4>, 3> kOrders{{{0, 1, 2, 3}, {0, 1, 3, 2}, {0, 2, 1, 3}}};

// The vertex that stands for a seed: the seed vertex, or the corner of a seed point's face with
// the largest barycentric weight.
std::optional<std::array<int, 4>> seed_vertices(const MeshToDissect& m) {
  const int nv = m.mesh->num_vertices(), nf = m.mesh->num_faces();
  if (m.seeds) {
    for (const int v : *m.seeds)
      if (v < 0 || v >= nv) return std::nullopt;  // reported by the seed loop
    return m.seeds;
  }
  if (!m.seed_points) return std::nullopt;
  std::array<int, 4> v{};
  for (int k = 0; k < 4; ++k) {
    const auto& p = (*m.seed_points)[k];
    if (p.face < 0 || p.face >= nf) return std::nullopt;
    const auto& b = p.bary;
    const int c = static_cast<int>(std::max_element(b.begin(), b.end()) - b.begin());
    v[k] = m.mesh->faces[p.face][c];
  }
  return v;
}

}  // namespace

SeedOrderChoice shortest_seed_order(const std::vector<MeshToDissect>& meshes, double margin,
                                    const Context& context) {
  SeedOrderChoice out;
  if (meshes.empty()) return out;
  std::vector<std::array<int, 4>> vertices;
  for (const auto& m : meshes) {
    const auto v = m.mesh ? seed_vertices(m) : std::nullopt;
    if (!v) return out;
    vertices.push_back(*v);
  }
  for (size_t i = 0; i < meshes.size(); ++i) {
    const auto& m = meshes[i];
    const std::vector<int> v(vertices[i].begin(), vertices[i].end());
    const GeodesicCoordinates c = geodesic_coordinates(*m.mesh, v, context);
    for (size_t o = 0; o < kOrders.size(); ++o) {
      const auto& q = kOrders[o];
      double len = 0;
      for (int k = 0; k < 4; ++k) len += c.at(v[q[(k + 1) % 4]])[q[k]];
      out.lengths[o] += len;
    }
  }
  size_t best = 0;
  for (size_t o = 1; o < kOrders.size(); ++o)
    if (out.lengths[o] < out.lengths[best]) best = o;
  if (std::isfinite(out.lengths[best]) && out.lengths[0] > (1 + margin) * out.lengths[best]) out.order = kOrders[best];
  return out;
}

}  // namespace qs::dissect
