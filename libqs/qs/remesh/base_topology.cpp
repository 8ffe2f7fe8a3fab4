#include "qs/remesh/base_topology.h"

#include <algorithm>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include "qs/core/error.h"

namespace qs::remesh {

namespace {

std::uint64_t pair_key(int a, int b) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}
std::uint64_t unordered_key(int a, int b) { return pair_key(std::min(a, b), std::max(a, b)); }

}  // namespace

BaseTopology build_base_topology(const std::vector<dissect::PatchInfo>& patches) {
  if (patches.empty()) throw InvalidInput("remesh: the chart has no patches; remeshing needs a dissected chart");
  const int np = static_cast<int>(patches.size());
  auto patch_name = [&](int p) { return "patch " + std::to_string(p) + " ('" + patches[p].name + "')"; };

  BaseTopology t;
  t.quads.resize(np);
  t.side_edge.assign(np, {-1, -1, -1, -1});
  t.side_forward.assign(np, {false, false, false, false});
  std::unordered_map<int, int> base_of;  // chart vertex -> base vertex
  base_of.reserve(2 * np + 4);
  for (int p = 0; p < np; ++p) {
    const auto& c = patches[p].corners;
    for (int k = 0; k < 4; ++k) {
      if (c[k] < 0)
        throw InvalidInput("remesh: " + patch_name(p) + " has corner " + std::to_string(k) + " = " +
                           std::to_string(c[k]) + "; corners must be chart vertex ids >= 0");
      for (int m = 0; m < k; ++m)
        if (c[m] == c[k])
          throw InvalidInput("remesh: " + patch_name(p) + " has chart vertex " + std::to_string(c[k]) +
                             " as corners " + std::to_string(m) + " and " + std::to_string(k) +
                             "; a patch needs 4 distinct corners");
    }
    for (int k = 0; k < 4; ++k) {
      const auto [it, fresh] = base_of.emplace(c[k], t.num_vertices);
      if (fresh) {
        ++t.num_vertices;
        t.chart_vertex.push_back(c[k]);
        t.vertex_corner.push_back({p, k});
        t.valence.push_back(0);
      }
      t.quads[p][k] = it->second;
      ++t.valence[it->second];
    }
  }

  std::unordered_map<std::uint64_t, PatchSide> directed;  // (from, to) base vertex -> side
  directed.reserve(8 * np);
  for (int p = 0; p < np; ++p)
    for (int k = 0; k < 4; ++k) {
      const int a = t.quads[p][k], b = t.quads[p][(k + 1) % 4];
      const auto [it, fresh] = directed.emplace(pair_key(a, b), PatchSide{p, k});
      if (!fresh)
        throw InvalidInput("remesh: the side from chart vertex " + std::to_string(t.chart_vertex[a]) + " to " +
                           std::to_string(t.chart_vertex[b]) + " is side " + std::to_string(it->second.side) +
                           " of " + patch_name(it->second.patch) + " and side " + std::to_string(k) + " of " +
                           patch_name(p) + "; the base domain must be a conforming quad mesh");
    }
  for (int p = 0; p < np; ++p)
    for (int k = 0; k < 4; ++k) {
      if (t.side_edge[p][k] >= 0) continue;
      const int a = t.quads[p][k], b = t.quads[p][(k + 1) % 4];
      const auto it = directed.find(pair_key(b, a));
      if (it == directed.end())
        throw InvalidInput("remesh: side " + std::to_string(k) + " of " + patch_name(p) + " (chart vertex " +
                           std::to_string(t.chart_vertex[a]) + " to " + std::to_string(t.chart_vertex[b]) +
                           ") is shared with no other patch; the base domain must be closed");
      const int e = t.num_edges();
      t.edges.push_back({a, b});
      t.edge_sides.push_back({PatchSide{p, k}, it->second});
      t.side_edge[p][k] = e;
      t.side_forward[p][k] = true;
      t.side_edge[it->second.patch][it->second.side] = e;
      t.side_forward[it->second.patch][it->second.side] = false;
    }

  std::unordered_set<std::uint64_t> joined;
  joined.reserve(4 * t.edges.size());
  for (const auto& e : t.edges) joined.insert(unordered_key(e[0], e[1]));
  t.level0_diagonal02.resize(np);
  for (int p = 0; p < np; ++p) {
    const auto& q = t.quads[p];
    const std::uint64_t a = unordered_key(q[0], q[2]), b = unordered_key(q[1], q[3]);
    const bool use02 = !(joined.count(a) && !joined.count(b));
    t.level0_diagonal02[p] = use02;
    joined.insert(use02 ? a : b);
  }
  return t;
}

}  // namespace qs::remesh
