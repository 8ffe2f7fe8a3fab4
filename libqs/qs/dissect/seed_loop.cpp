// The seed loop (paper 3.3): routing through given seeds, rerouting for sides, the guided loop and
// the two seed patches. The rules in full: docs/algorithms.md.

#include "qs/dissect/seed_loop.h"

#include <algorithm>
#include <functional>
#include <queue>
#include <string>
#include <utility>

#include "qs/core/error.h"
#include "qs/core/geometry2d.h"
#include "qs/dissect/seed_routing_detail.h"

namespace qs::dissect {

using namespace routing;

SeedLoop trace_seed_loop(const TriMesh& mesh, const std::array<int, 4>& seeds,
                         const Context& context) {
  return trace_seed_loop(mesh, seeds, {}, context);
}

namespace {

void check_trace_inputs(const TriMesh& mesh, const std::array<int, 4>& seeds, const std::vector<int>& avoid) {
  check_seeds(mesh, seeds);
  for (int v : avoid)
    if (v < 0 || v >= static_cast<int>(mesh.positions.size()))
      throw InvalidInput("seed loop: vertex to avoid " + std::to_string(v) + " is out of range");
}

// trace_seed_loop once its inputs are checked.
SeedLoop trace_checked(const TriMesh& mesh, const Graph& g, const std::array<int, 4>& seeds,
                       const std::vector<int>& avoid, const Context& context) {
  Dijkstra dijkstra(g);
  Attempt attempt = try_route(mesh, g, dijkstra, seeds, context, avoid);
  if (!attempt.ok)
    throw InvalidInput("cannot route the seed loop: " + attempt.why +
                       (avoid.empty() ? "; move the seeds apart" : "; move the seeds or the features apart"));
  if (context.log) {
    std::string m = "seed loop: path lengths";
    for (const auto& p : attempt.loop.paths)
      m.append(" ").append(std::to_string(path_length(mesh, p))).append(" (")
          .append(std::to_string(p.size() - 1)).append(" edges)");
    if (attempt.order_index > 0)
      m += "; routed in fallback order #" + std::to_string(attempt.order_index);
    context.info(m);
  }
  return std::move(attempt.loop);
}

}  // namespace

SeedLoop trace_seed_loop(const TriMesh& mesh, const std::array<int, 4>& seeds, const std::vector<int>& avoid,
                         const Context& context) {
  check_trace_inputs(mesh, seeds, avoid);  // before the graph: a bad seed is reported before a bad mesh
  return trace_checked(mesh, build_graph(mesh), seeds, avoid, context);
}

SeedLoop routing::trace_seed_loop(const TriMesh& mesh, const Graph& g, const std::array<int, 4>& seeds,
                                  const std::vector<int>& avoid, const Context& context) {
  check_trace_inputs(mesh, seeds, avoid);
  return trace_checked(mesh, g, seeds, avoid, context);
}

namespace {

/// The side of each vertex (-1 on the loop) from the face labels.
std::vector<int> vertex_sides(const TriMesh& mesh, const std::vector<int>& labels, const std::vector<int>& vertices) {
  std::vector<int> want(mesh.num_vertices(), -2);
  for (size_t k = 0; k < vertices.size(); ++k) want[vertices[k]] = -1;
  std::vector<int> side(mesh.num_vertices(), -2);  // -2 untouched, -1 mixed (on the loop)
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int v : mesh.faces[f]) {
      if (want[v] == -2) continue;
      if (side[v] == -2) side[v] = labels[f];
      else if (side[v] != labels[f]) side[v] = -1;
    }
  std::vector<int> out;
  for (int v : vertices) out.push_back(side[v] < 0 ? -1 : side[v]);
  return out;
}

int count_wrong(const TriMesh& mesh, const std::vector<int>& labels, const std::vector<SideConstraint>& sides) {
  std::vector<int> vs;
  for (const auto& c : sides) vs.push_back(c.vertex);
  const std::vector<int> got = vertex_sides(mesh, labels, vs);
  int wrong = 0;
  for (size_t k = 0; k < sides.size(); ++k) wrong += got[k] != sides[k].side;
  return wrong;
}

double loop_length(const TriMesh& mesh, const SeedLoop& loop) {
  double l = 0;
  for (const auto& p : loop.paths) l += path_length(mesh, p);
  return l;
}

}  // namespace

std::vector<int> sides_of_vertices(const TriMesh& mesh, const SeedLoop& loop, const std::vector<int>& vertices) {
  return vertex_sides(mesh, seed_patch_of_faces(mesh, loop), vertices);
}

std::vector<int> sides_of_vertices(const TriMesh& mesh, const std::vector<int>& face_patches,
                                   const std::vector<int>& vertices) {
  if (face_patches.size() != mesh.faces.size())
    throw InvalidInput("sides_of_vertices: " + std::to_string(face_patches.size()) + " face patches for " +
                       std::to_string(mesh.faces.size()) + " faces");
  for (int v : vertices)
    if (v < 0 || v >= mesh.num_vertices())
      throw InvalidInput("sides_of_vertices: vertex " + std::to_string(v) + " is out of range");
  return vertex_sides(mesh, face_patches, vertices);
}

SeedLoop reroute_for_sides(const TriMesh& mesh, const SeedLoop& loop, const std::vector<int>& avoid,
                           const std::vector<SideConstraint>& sides, const Context& context) {
  check_seeds(mesh, loop.seeds);
  const Graph g = build_graph(mesh);
  Dijkstra dijkstra(g);
  std::string why;
  std::vector<int> labels = label_faces(mesh, g, loop, why);
  if (labels.empty()) throw InvalidInput("seed loop does not cut the mesh into two patches: " + why);
  SeedLoop cur = loop;
  int wrong = count_wrong(mesh, labels, sides);
  double mean_edge = 0;
  for (const Tri& t : mesh.faces)
    for (int k = 0; k < 3; ++k) mean_edge += (mesh.positions[t[k]] - mesh.positions[t[(k + 1) % 3]]).norm();
  mean_edge /= std::max<size_t>(1, 3 * mesh.faces.size());
  const int nv = mesh.num_vertices();
  for (int round = 0; wrong > 0 && round < 2 * static_cast<int>(sides.size()) + 2; ++round) {
    context.check_cancel();
    // The first vertex on the wrong side.
    std::vector<int> vs;
    for (const auto& c : sides) vs.push_back(c.vertex);
    const std::vector<int> got = vertex_sides(mesh, labels, vs);
    int f = -1;
    for (size_t k = 0; k < sides.size() && f < 0; ++k)
      if (got[k] != sides[k].side) f = sides[k].vertex;
    const std::vector<double> df = dijkstra.all_distances(f);
    SeedLoop best;
    int best_wrong = wrong;
    double best_len = kInf;
    std::vector<char> blocked(nv, 0);
    for (int i = 0; i < 4; ++i) {
      const std::vector<int>& old = cur.paths[i];
      int x = old.front();
      for (int v : old)
        if (df[v] < df[x]) x = v;
      if (!(df[x] < kInf)) continue;
      // Waypoints at 1, 1.5 and 2.5 times the vertex's distance from the path, and, when the path
      // passes within two mean edge lengths (no room there), at 2, 3 and 5 of them.
      std::vector<double> radii;
      if (df[x] > 0) radii = {df[x], 1.5 * df[x], 2.5 * df[x]};
      if (df[x] < 2 * mean_edge)
        for (double factor : {2.0, 3.0, 5.0}) radii.push_back(factor * mean_edge);
      const std::vector<double> dx = dijkstra.all_distances(x);
      for (double r : radii) {
        // The waypoint: about r from the feature, as far as possible from x.
        std::fill(blocked.begin(), blocked.end(), 0);
        for (int s : cur.seeds) blocked[s] = 1;
        for (int v : avoid) blocked[v] = 1;
        blocked[f] = 1;
        for (int j = 0; j < 4; ++j)
          if (j != i)
            for (size_t k = 1; k + 1 < cur.paths[j].size(); ++k) blocked[cur.paths[j][k]] = 1;
        int w = -1;
        for (int v = 0; v < nv; ++v) {
          if (blocked[v] || !(df[v] >= 0.8 * r && df[v] <= 1.25 * r)) continue;
          if (w < 0 || dx[v] > dx[w]) w = v;
        }
        if (w < 0) continue;
        const int a = cur.seeds[i], b = cur.seeds[(i + 1) % 4];
        std::vector<int> p1, p2;
        blocked[a] = blocked[b] = 0;
        blocked[b] = 1;
        if (!dijkstra.path(a, w, blocked, p1)) continue;
        for (int v : p1) blocked[v] = 1;
        blocked[w] = 0;
        blocked[b] = 0;
        if (!dijkstra.path(w, b, blocked, p2)) continue;
        SeedLoop cand = cur;
        cand.paths[i] = p1;
        cand.paths[i].insert(cand.paths[i].end(), p2.begin() + 1, p2.end());
        std::string w2;
        const std::vector<int> lab = label_faces(mesh, g, cand, w2);
        if (lab.empty()) continue;
        const int cw = count_wrong(mesh, lab, sides);
        const double len = loop_length(mesh, cand);
        if (cw < best_wrong || (cw == best_wrong && cw < wrong && len < best_len)) {
          best = std::move(cand);
          best_wrong = cw;
          best_len = len;
        }
      }
    }
    if (best_wrong >= wrong) break;
    cur = std::move(best);
    labels = label_faces(mesh, g, cur, why);
    wrong = best_wrong;
  }
  if (wrong > 0) {
    std::vector<int> vs;
    for (const auto& c : sides) vs.push_back(c.vertex);
    const std::vector<int> got = vertex_sides(mesh, labels, vs);
    std::string list;
    for (size_t k = 0; k < sides.size(); ++k)
      if (got[k] != sides[k].side) list += (list.empty() ? "" : ", ") + std::to_string(sides[k].vertex);
    throw InvalidInput("no seed loop through these seeds puts vertices " + list +
                       " on the required side (found by rerouting one path at a time)");
  }
  return cur;
}

SeedLoop trace_weighted_loop(const TriMesh& mesh, const std::array<int, 4>& seeds, const EdgeFactor& factor,
                             const std::vector<int>& avoid) {
  check_seeds(mesh, seeds);
  const Graph g = build_graph(mesh);
  const int nv = g.num_vertices();
  std::vector<char> blocked(nv, 0);
  for (int v : avoid)
    if (v >= 0 && v < nv) blocked[v] = 1;
  for (int s : seeds) blocked[s] = 1;
  SeedLoop loop;
  loop.seeds = seeds;
  std::vector<double> dist(nv);
  std::vector<int> from(nv);
  for (int i = 0; i < 4; ++i) {
    // Dijkstra from seeds[i] to seeds[i+1] (ties by vertex id: deterministic).
    const int a = seeds[i], b = seeds[(i + 1) % 4];
    std::fill(dist.begin(), dist.end(), kInf);
    std::fill(from.begin(), from.end(), -1);
    using Item = std::pair<double, int>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
    dist[a] = 0;
    heap.push({0.0, a});
    while (!heap.empty()) {
      const auto [d, v] = heap.top();
      heap.pop();
      if (d > dist[v]) continue;
      if (v == b) break;
      for (int k = g.start[v]; k < g.start[v + 1]; ++k) {
        const int w = g.neighbor[k];
        if (blocked[w] && w != b) continue;
        const double nd = d + g.length[k] * factor(i, v, w);
        if (nd < dist[w]) {
          dist[w] = nd;
          from[w] = v;
          heap.push({nd, w});
        }
      }
    }
    if (from[b] < 0)
      throw InvalidInput("seed loop: no path from " + seed_name(seeds, i) + " to " + seed_name(seeds, (i + 1) % 4) +
                         " avoids the paths already routed");
    std::vector<int> path;
    for (int v = b; v != -1; v = from[v]) path.push_back(v);
    std::reverse(path.begin(), path.end());
    for (size_t k = 1; k + 1 < path.size(); ++k) blocked[path[k]] = 1;
    loop.paths[i] = std::move(path);
  }
  seed_patch_of_faces(mesh, loop);  // throws when the loop does not cut the mesh in two
  return loop;
}

SeedLoop trace_guided_loop(const TriMesh& mesh, const std::array<int, 4>& seeds,
                           const std::array<std::vector<Vec3>, 4>& guides, double sigma,
                           const std::vector<int>& avoid) {
  if (!(sigma > 0)) throw InvalidInput("trace_guided_loop: sigma must be > 0");
  for (int i = 0; i < 4; ++i)
    if (guides[i].empty()) throw InvalidInput("trace_guided_loop: guide " + std::to_string(i) + " is empty");
  const std::array<PolylineDistance, 4> to_guide{PolylineDistance(guides[0]), PolylineDistance(guides[1]),
                                                 PolylineDistance(guides[2]), PolylineDistance(guides[3])};
  return trace_weighted_loop(
      mesh, seeds,
      [&](int i, int v, int w) {
        const double r = to_guide[i](0.5 * (mesh.positions[v] + mesh.positions[w])) / sigma;
        return 1 + r * r;
      },
      avoid);
}

std::vector<int> seed_patch_of_faces(const TriMesh& mesh, const SeedLoop& loop) {
  check_seeds(mesh, loop.seeds);
  const Graph g = build_graph(mesh);
  std::string why;
  std::vector<int> labels = label_faces(mesh, g, loop, why);
  if (labels.empty())
    throw InvalidInput("seed loop does not cut the mesh into two patches: " + why);
  return labels;
}

}  // namespace qs::dissect
