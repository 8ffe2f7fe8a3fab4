#include "qs/mesh/connectivity.h"

#include <algorithm>
#include <cstdint>
#include <string>

#include "qs/core/error.h"

namespace qs::mesh {

EdgeGroups group_halfedges(const std::vector<Tri>& faces, int num_vertices) {
  const std::size_t num_h = 3 * faces.size();
  // Counting sort by the lower vertex of each halfedge ...
  std::vector<int> start(static_cast<std::size_t>(num_vertices) + 1, 0);
  for (const Tri& t : faces)
    for (int k = 0; k < 3; ++k) ++start[std::min(t[k], t[(k + 1) % 3]) + 1];
  for (int v = 0; v < num_vertices; ++v) start[v + 1] += start[v];
  // ... carrying (higher vertex << 32 | halfedge) so that a plain sort of each bucket orders it.
  std::vector<std::uint64_t> keys(num_h);
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (std::size_t f = 0; f < faces.size(); ++f) {
      const Tri& t = faces[f];
      for (int k = 0; k < 3; ++k) {
        const int a = t[k], b = t[(k + 1) % 3];
        const auto hi = static_cast<std::uint64_t>(std::max(a, b));
        keys[fill[std::min(a, b)]++] = (hi << 32) | static_cast<std::uint64_t>(3 * f + k);
      }
    }
  }

  EdgeGroups g;
  g.halfedges.resize(num_h);
  g.offsets.reserve(num_h / 2 + 2);
  g.vertices.reserve(num_h / 2 + 1);
  for (int v = 0; v < num_vertices; ++v) {
    const int b = start[v], e = start[v + 1];
    if (e - b > 1) std::sort(keys.begin() + b, keys.begin() + e);
    std::uint64_t prev_hi = ~std::uint64_t{0};
    for (int i = b; i < e; ++i) {
      const std::uint64_t hi = keys[i] >> 32;
      if (hi != prev_hi) {
        g.offsets.push_back(i);
        g.vertices.push_back({v, static_cast<int>(hi)});
        prev_hi = hi;
      }
      g.halfedges[i] = static_cast<int>(keys[i] & 0xffffffffu);
    }
  }
  g.offsets.push_back(static_cast<int>(num_h));
  return g;
}

namespace {

std::string edge_name(const EdgeGroups& g, int e) {
  return std::to_string(g.vertices[e][0]) + "-" + std::to_string(g.vertices[e][1]);
}

}  // namespace

Connectivity build_connectivity(const TriMesh& mesh) {
  const int nv = mesh.num_vertices(), nf = mesh.num_faces();
  for (int f = 0; f < nf; ++f) {
    const Tri& t = mesh.faces[f];
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || t[k] >= nv)
        throw InvalidInput("build_connectivity: face " + std::to_string(f) + " has vertex index " +
                           std::to_string(t[k]) + " outside [0, " + std::to_string(nv) + ")");
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0])
      throw InvalidInput("build_connectivity: face " + std::to_string(f) +
                         " uses a vertex twice; validate() the mesh first");
  }

  Connectivity c;
  c.opposite.assign(3 * static_cast<std::size_t>(nf), -1);
  c.halfedge_vertex.resize(3 * static_cast<std::size_t>(nf));
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) c.halfedge_vertex[3 * f + k] = mesh.faces[f][k];

  const EdgeGroups g = group_halfedges(mesh.faces, nv);
  for (int e = 0; e < g.num_edges(); ++e) {
    const int n = g.size(e);
    if (n == 1) continue;
    const int* hs = &g.halfedges[g.offsets[e]];
    if (n > 2)
      throw InvalidInput("build_connectivity: non-manifold edge " + edge_name(g, e) + " has " +
                         std::to_string(n) + " faces (first: " + std::to_string(hs[0] / 3) + ", " +
                         std::to_string(hs[1] / 3) + ", " + std::to_string(hs[2] / 3) +
                         "); each edge must have at most two faces");
    if (c.tail(hs[0]) == c.tail(hs[1]))
      throw InvalidInput("build_connectivity: edge " + edge_name(g, e) +
                         " is used in the same direction by faces " + std::to_string(hs[0] / 3) +
                         " and " + std::to_string(hs[1] / 3) + " (inconsistent orientation)");
    c.opposite[hs[0]] = hs[1];
    c.opposite[hs[1]] = hs[0];
  }

  // One outgoing halfedge per vertex, a boundary one where there is one.
  c.vertex_halfedge.assign(nv, -1);
  std::vector<int> degree(nv, 0);
  for (int h = 0; h < c.num_halfedges(); ++h) {
    const int v = c.halfedge_vertex[h];
    ++degree[v];
    int& vh = c.vertex_halfedge[v];
    if (vh < 0 || (c.opposite[h] < 0 && c.opposite[vh] >= 0)) vh = h;
  }
  // A single fan per vertex: the sweep from vertex_halfedge must see every outgoing halfedge.
  for (int v = 0; v < nv; ++v) {
    int seen = 0;
    c.for_each_outgoing(v, [&](int) { ++seen; });
    if (seen != degree[v])
      throw InvalidInput("build_connectivity: vertex " + std::to_string(v) +
                         " is non-manifold (its faces form more than one fan)");
  }
  return c;
}

std::vector<int> Connectivity::one_ring(int v) const {
  std::vector<int> ring;
  int last = -1;
  for_each_outgoing(v, [&](int h) {
    ring.push_back(head(h));
    last = h;
  });
  if (last >= 0 && opposite[prev(last)] < 0) ring.push_back(tail(prev(last)));
  return ring;
}

int Connectivity::valence(int v) const {
  int n = 0, last = -1;
  for_each_outgoing(v, [&](int h) {
    ++n;
    last = h;
  });
  if (last >= 0 && opposite[prev(last)] < 0) ++n;
  return n;
}

}  // namespace qs::mesh
