// Routing of the seed loop: the vertex graph, A* shortest paths, the routing orders and the cut
// check (paper 3.3; docs/algorithms.md).

#include <algorithm>
#include <cmath>
#include <iterator>
#include <numeric>
#include <string>
#include <utility>

#include "qs/core/error.h"
#include "qs/core/finite.h"
#include "qs/dissect/seed_routing_detail.h"

namespace qs::dissect::routing {

namespace {

std::string edge_name(int a, int b) {
  return std::to_string(std::min(a, b)) + "-" + std::to_string(std::max(a, b));
}

/// The loop as one cycle of vertices: paths[0] .. paths[3] without each one's last vertex.
std::vector<int> loop_cycle(const SeedLoop& loop) {
  std::vector<int> cycle;
  for (const auto& p : loop.paths)
    if (!p.empty()) cycle.insert(cycle.end(), p.begin(), p.end() - 1);
  return cycle;
}

/// The four unobstructed shortest paths free[i] = seeds[i] -> seeds[i+1] and their lengths
/// (kInf and an empty path when unreachable).
void free_paths(Dijkstra& dijkstra, const std::array<int, 4>& s,
                std::array<std::vector<int>, 4>& free, std::array<double, 4>& length) {
  static const std::vector<char> none;
  for (int i = 0; i < 4; ++i) {
    free[i].clear();
    const int b = s[(i + 1) % 4];
    length[i] = dijkstra.path(s[i], b, none, free[i]) ? dijkstra.distance_to(b) : kInf;
  }
}

/// Every routing order: increasing unobstructed length first, then the other permutations.
std::vector<std::array<int, 4>> routing_orders(const std::array<double, 4>& length) {
  std::array<int, 4> first{0, 1, 2, 3};
  std::stable_sort(first.begin(), first.end(),
                   [&](int a, int b) { return length[a] < length[b]; });
  std::vector<std::array<int, 4>> orders{first};
  std::array<int, 4> p{0, 1, 2, 3};
  do {
    if (p != first) orders.push_back(p);
  } while (std::next_permutation(p.begin(), p.end()));
  return orders;
}

}  // namespace

/// Rows up to this long are scanned for each slot (O(d^2)); longer ones are sorted (O(d log d)).
constexpr int kScanValence = 16;

Graph build_graph(const TriMesh& mesh) {
  const int nv = mesh.num_vertices();
  const int nf = mesh.num_faces();
  for (int f = 0; f < nf; ++f) {
    const Tri& t = mesh.faces[f];
    for (int k = 0; k < 3; ++k) {
      if (t[k] < 0 || t[k] >= nv)
        throw InvalidInput("seed loop: face " + std::to_string(f) + " has vertex index " +
                           std::to_string(t[k]) + " outside [0, " + std::to_string(nv) +
                           "); validate the mesh first");
    }
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0])
      throw InvalidInput("seed loop: face " + std::to_string(f) +
                         " repeats a vertex; validate the mesh first");
  }
  // Edge lengths must be finite: an infinite one makes every distance infinite and no seed routes.
  for (int v = 0; v < nv; ++v)
    if (!usable_position(mesh.positions[v]))
      throw InvalidInput("seed loop: vertex " + std::to_string(v) +
                         " has a non-finite or too large coordinate (|x| > 1e100); validate the mesh first");
  Graph g;
  g.position = &mesh.positions;
  g.start.assign(static_cast<std::size_t>(nv) + 1, 0);
  for (const Tri& t : mesh.faces)
    for (int k = 0; k < 3; ++k) ++g.start[t[k] + 1];
  for (int v = 0; v < nv; ++v) g.start[v + 1] += g.start[v];
  const std::size_t slots = static_cast<std::size_t>(3) * nf;
  g.neighbor.resize(slots);
  g.length.resize(slots);
  g.left.resize(slots);
  // Per slot v->w of face f: the corner of f before v, and the halfedge id 3f+k.
  std::vector<int> before(slots), halfedge(slots);
  {
    std::vector<int> fill(g.start.begin(), g.start.end() - 1);
    for (int f = 0; f < nf; ++f) {
      const Tri& t = mesh.faces[f];
      for (int k = 0; k < 3; ++k) {
        const int a = t[k], b = t[(k + 1) % 3];
        const int s = fill[a]++;
        g.neighbor[s] = b;
        g.length[s] = (mesh.positions[a] - mesh.positions[b]).norm();
        g.left[s] = f;
        before[s] = t[(k + 2) % 3];
        halfedge[s] = 3 * f + k;
      }
    }
  }
  // Everything about edge v-w is in v's row: the face with v->w is the slot's face, the face with
  // w->v is the one whose corner before v is w.
  // A long row has its neighbours and its corners before v sorted (with their slots): O(d log d)
  // per vertex of valence d, not O(d^2) (fans of 100k faces around one vertex occur in CAD files).
  g.across.assign(slots, -1);
  std::vector<std::pair<int, int>> by_neighbor, by_before;
  auto check = [&](int v, int w, std::ptrdiff_t same, int back) {
    if (same > 1)
      throw InvalidInput("seed loop: edge " + edge_name(v, w) +
                         " has more than two faces or two faces running the same way; the "
                         "seed loop needs a validated closed manifold mesh");
    if (back < 0)
      throw InvalidInput("seed loop: edge " + edge_name(v, w) +
                         " has a single face (the mesh is open); the seed loop needs a "
                         "validated closed mesh");
  };
  for (int v = 0; v < nv; ++v) {
    const int first = g.start[v], last = g.start[v + 1];
    if (last - first <= kScanValence) {  // a plain scan of the row costs less than sorting it
      for (int s = first; s < last; ++s) {
        const int w = g.neighbor[s];
        int same = 0, back = -1;
        for (int r = first; r < last; ++r) {
          same += g.neighbor[r] == w;
          if (before[r] == w) back = r;
        }
        check(v, w, same, back);
        g.across[halfedge[s]] = g.left[back];
      }
      continue;
    }
    by_neighbor.clear();
    by_before.clear();
    for (int r = first; r < last; ++r) {
      by_neighbor.emplace_back(g.neighbor[r], r);
      by_before.emplace_back(before[r], r);
    }
    std::sort(by_neighbor.begin(), by_neighbor.end());
    std::sort(by_before.begin(), by_before.end());
    for (int s = first; s < last; ++s) {
      const int w = g.neighbor[s];
      const std::pair<int, int> lo(w, std::numeric_limits<int>::min()), hi(w, std::numeric_limits<int>::max());
      const auto same = std::upper_bound(by_neighbor.begin(), by_neighbor.end(), hi) -
                        std::lower_bound(by_neighbor.begin(), by_neighbor.end(), lo);
      // The last slot whose corner before v is w (what a scan in slot order would keep).
      const auto bb = std::upper_bound(by_before.begin(), by_before.end(), hi);
      const int back = bb != by_before.begin() && std::prev(bb)->first == w ? std::prev(bb)->second : -1;
      check(v, w, same, back);
      g.across[halfedge[s]] = g.left[back];
    }
  }
  return g;
}

namespace {

// label_faces on any mesh: across(h) is the face across half-edge h = 3 f + k, left_of(a, b) the
// face with half-edge a -> b (-1 when a and b are not joined).
template <class Across, class LeftOf>
std::vector<int> label_faces_by(const std::vector<Tri>& faces, int nv, const Across& across, const LeftOf& left_of,
                                const SeedLoop& loop, std::string& why) {
  for (int i = 0; i < 4; ++i) {
    const auto& p = loop.paths[i];
    if (p.size() < 2 || p.front() != loop.seeds[i] || p.back() != loop.seeds[(i + 1) % 4]) {
      why = "path " + std::to_string(i) + " does not run from seed " + std::to_string(i) +
            " to seed " + std::to_string((i + 1) % 4);
      return {};
    }
    for (int v : p)
      if (v < 0 || v >= nv) {
        why = "path " + std::to_string(i) + " has vertex " + std::to_string(v) + " out of range";
        return {};
      }
  }
  const std::vector<int> cycle = loop_cycle(loop);
  const int n = static_cast<int>(cycle.size());
  std::vector<int> position(nv, -1);
  for (int i = 0; i < n; ++i) {
    if (position[cycle[i]] >= 0) {
      why = "the loop visits vertex " + std::to_string(cycle[i]) + " twice";
      return {};
    }
    position[cycle[i]] = i;
  }
  std::vector<int> left(n);  // the face left of loop edge i
  for (int i = 0; i < n; ++i) {
    left[i] = left_of(cycle[i], cycle[(i + 1) % n]);
    if (left[i] < 0) {
      why = "loop vertices " + std::to_string(cycle[i]) + " and " +
            std::to_string(cycle[(i + 1) % n]) + " are not joined by an edge";
      return {};
    }
  }
  auto on_loop = [&](int a, int b) {
    const int pa = position[a], pb = position[b];
    if (pa < 0 || pb < 0) return false;
    const int d = std::abs(pa - pb);
    return d == 1 || d == n - 1;
  };
  // Union-find over the faces, joined across every side that is not on the loop. A sweep in
  // face order touches memory in order (a flood fill jumps around and is several times slower).
  const int nf = static_cast<int>(faces.size());
  std::vector<int> root(nf);
  std::iota(root.begin(), root.end(), 0);
  auto find = [&](int f) {
    while (root[f] != f) f = root[f] = root[root[f]];
    return f;
  };
  for (int f = 0; f < nf; ++f) {
    const Tri& t = faces[f];
    for (int k = 0; k < 3; ++k) {
      const int other = across(3 * f + k);
      if (other < f || on_loop(t[k], t[(k + 1) % 3])) continue;
      const int x = find(f), y = find(other);
      if (x != y) root[std::max(x, y)] = std::min(x, y);
    }
  }
  // The face right of loop edge i is the face left of its reverse.
  std::vector<int> right(n);
  for (int i = 0; i < n; ++i) right[i] = left_of(cycle[(i + 1) % n], cycle[i]);
  const int root0 = find(left[0]), root1 = find(right[0]);
  if (root0 == root1) {
    why = "the loop does not separate the mesh (both faces beside loop edge " +
          edge_name(cycle[0], cycle[1]) + " are joined around it); is the mesh genus 0?";
    return {};
  }
  std::vector<int> label(nf);
  int extra = 0;
  for (int f = 0; f < nf; ++f) {
    const int r = find(f);
    label[f] = r == root0 ? 0 : r == root1 ? 1 : 2;
    extra += label[f] == 2 && r == f;
  }
  if (extra > 0) {
    why = "the loop leaves " + std::to_string(2 + extra) + " parts instead of 2";
    return {};
  }
  for (int i = 0; i < n; ++i) {
    if (label[left[i]] != 0 || label[right[i]] != 1) {
      why = "loop edge " + edge_name(cycle[i], cycle[(i + 1) % n]) +
            " does not have one part on each side";
      return {};
    }
  }
  return label;
}

}  // namespace

std::vector<int> label_faces(const TriMesh& mesh, const Graph& g, const SeedLoop& loop, std::string& why) {
  return label_faces_by(
      mesh.faces, g.num_vertices(), [&](int h) { return g.across[h]; },
      [&](int a, int b) {
        const int slot = g.find(a, b);
        return slot < 0 ? -1 : g.left[slot];
      },
      loop, why);
}

std::vector<int> label_faces(const CutMesh& cm, const SeedLoop& loop, std::string& why) {
  return label_faces_by(
      cm.faces(), cm.num_vertices(), [&](int h) { return CutMesh::face_of(cm.opposite(h)); },
      [&](int a, int b) {
        const int h = cm.find_halfedge(a, b);
        return h < 0 ? -1 : CutMesh::face_of(h);
      },
      loop, why);
}

std::string seed_name(const std::array<int, 4>& seeds, int i) {
  return "seed " + std::to_string(i) + " (vertex " + std::to_string(seeds[i]) + ")";
}

Attempt try_route(const TriMesh& mesh, const Graph& g, Dijkstra& dijkstra,
                  const std::array<int, 4>& seeds, const Context& context, const std::vector<int>& avoid) {
  Attempt result;
  std::array<std::vector<int>, 4> free;
  std::array<double, 4> length{};
  free_paths(dijkstra, seeds, free, length);
  for (int i = 0; i < 4; ++i)
    if (length[i] == kInf) {
      result.why = seed_name(seeds, i) + " and " + seed_name(seeds, (i + 1) % 4) +
                   " are not connected by mesh edges; is the mesh one component?";
      return result;
    }
  const std::vector<std::array<int, 4>> orders = routing_orders(length);
  std::vector<char> blocked(g.num_vertices(), 0);
  std::vector<int> path;
  for (std::size_t o = 0; o < orders.size(); ++o) {
    context.check_cancel();
    std::fill(blocked.begin(), blocked.end(), 0);
    for (int s : seeds) blocked[s] = 1;
    for (int v : avoid) blocked[v] = 1;
    SeedLoop loop;
    loop.seeds = seeds;
    std::string why;
    for (int i : orders[o]) {
      const int a = seeds[i], b = seeds[(i + 1) % 4];
      // The unobstructed shortest path is still a shortest one if it avoids everything blocked.
      bool found = std::none_of(free[i].begin() + 1, free[i].end() - 1,
                                [&](int v) { return blocked[v] != 0; });
      if (found) {
        path = free[i];
      } else {
        blocked[a] = blocked[b] = 0;
        found = dijkstra.path(a, b, blocked, path);
        blocked[a] = blocked[b] = 1;
      }
      if (!found) {
        why = "no path from " + seed_name(seeds, i) + " to " + seed_name(seeds, (i + 1) % 4) +
              " avoids the other paths and seeds";
        break;
      }
      for (std::size_t k = 1; k + 1 < path.size(); ++k) blocked[path[k]] = 1;
      loop.paths[i] = path;
    }
    if (why.empty()) {
      std::vector<int> labels = label_faces(mesh, g, loop, why);
      if (!labels.empty()) {
        result.ok = true;
        result.loop = std::move(loop);
        result.labels = std::move(labels);
        result.order_index = static_cast<int>(o);
        result.why.clear();
        return result;
      }
    }
    if (o == 0) result.why = why;  // report the failure of the preferred order
  }
  return result;
}

void check_seeds(const TriMesh& mesh, const std::array<int, 4>& seeds) {
  for (int i = 0; i < 4; ++i)
    if (seeds[i] < 0 || seeds[i] >= mesh.num_vertices())
      throw InvalidInput("seed loop: seed " + std::to_string(i) + " is vertex " +
                         std::to_string(seeds[i]) + ", outside [0, " +
                         std::to_string(mesh.num_vertices()) + ")");
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j)
      if (seeds[i] == seeds[j])
        throw InvalidInput("seed loop: seeds " + std::to_string(i) + " and " + std::to_string(j) +
                           " are the same vertex " + std::to_string(seeds[i]) +
                           "; the four seeds must be distinct vertices");
}

double path_length(const TriMesh& mesh, const std::vector<int>& p) {
  double sum = 0;
  for (std::size_t k = 1; k < p.size(); ++k)
    sum += (mesh.positions[p[k]] - mesh.positions[p[k - 1]]).norm();
  return sum;
}

}  // namespace qs::dissect::routing
