#pragma once
// Internal to the dissect module: the vertex graph, shortest paths and the cut check that the seed
// loop's routing (seed_loop.cpp) and the automatic seed rules (seed_choice.cpp) share. Not part of
// the API.

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"
#include "qs/dissect/cut_mesh.h"
#include "qs/dissect/seed_loop.h"

namespace qs::dissect::routing {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// Vertex adjacency in compressed rows, one slot per halfedge (a closed oriented manifold has
/// each directed edge exactly once), plus the face across each face side for the flood fill.
/// Built once in O(F) with a counting sort on the tail vertex; rows keep face order.
struct Graph {
  std::vector<int> start;       ///< #V+1: the neighbours of v are slots start[v] .. start[v+1]
  std::vector<int> neighbor;    ///< per slot (v, w): w
  std::vector<double> length;   ///< per slot: 3D edge length
  std::vector<int> left;        ///< per slot (v, w): the face with halfedge v->w
  std::vector<int> across;      ///< 3F: the face across side k of face f (halfedge 3f+k)
  const std::vector<Vec3>* position = nullptr;  ///< the mesh's, for the A* heuristic
  int num_vertices() const { return static_cast<int>(start.size()) - 1; }

  /// The slot of edge (v, w) in v's row, or -1.
  int find(int v, int w) const {
    for (int k = start[v]; k < start[v + 1]; ++k)
      if (neighbor[k] == w) return k;
    return -1;
  }
};

/// The graph of a mesh. \throws InvalidInput for a vertex index out of range, a face that repeats a
/// vertex, a non-finite or too large coordinate, or an edge with one face or more than two (or two
/// running the same way).
Graph build_graph(const TriMesh& mesh);

/// A* / Dijkstra with a binary heap; ties broken by vertex id (the heap orders (key, id)). With a
/// target the key adds the straight-line distance to it, a consistent lower bound for 3D edge
/// lengths, so the path found is a shortest one (the same length Dijkstra finds) after visiting
/// far fewer vertices. Arrays are reset lazily with a stamp.
class Dijkstra {
 public:
  explicit Dijkstra(const Graph& g) : g_(g), node_(g.num_vertices()) {}

  /// Shortest path src -> dst through vertices not blocked (src and dst are never blocked).
  /// Returns false when dst cannot be reached.
  bool path(int src, int dst, const std::vector<char>& blocked, std::vector<int>& out) {
    run(src, dst, blocked);
    if (!reached(dst)) return false;
    out.clear();
    for (int v = dst; v != -1; v = node_[v].parent) out.push_back(v);
    std::reverse(out.begin(), out.end());
    return true;
  }

  /// The distance to v found by the last search that reached it.
  double distance_to(int v) const { return reached(v) ? node_[v].dist : kInf; }

  /// Distances from src to every vertex (kInf when unreachable), nothing blocked.
  std::vector<double> all_distances(int src) {
    static const std::vector<char> none;
    run(src, -1, none);
    std::vector<double> d(g_.num_vertices(), kInf);
    for (int v = 0; v < g_.num_vertices(); ++v)
      if (reached(v)) d[v] = node_[v].dist;
    return d;
  }

 private:
  struct Node {
    double dist = kInf;
    int parent = -1;
    std::uint32_t stamp = 0;
  };
  struct Item {
    double key;
    double dist;
    int v;
    bool operator>(const Item& o) const { return key > o.key || (key == o.key && v > o.v); }
  };

  bool reached(int v) const { return node_[v].stamp == stamp_ && node_[v].dist < kInf; }

  Node& touch(int v) {
    Node& n = node_[v];
    if (n.stamp != stamp_) {
      n.stamp = stamp_;
      n.dist = kInf;
      n.parent = -1;
    }
    return n;
  }

  void run(int src, int dst, const std::vector<char>& blocked) {
    ++stamp_;
    heap_.clear();
    const bool guided = dst >= 0;
    const Vec3 target = guided ? (*g_.position)[dst] : Vec3::Zero();
    auto heuristic = [&](int v) { return guided ? ((*g_.position)[v] - target).norm() : 0.0; };
    auto push = [&](double d, int v) {
      heap_.push_back({d + heuristic(v), d, v});
      std::push_heap(heap_.begin(), heap_.end(), std::greater<Item>());
    };
    touch(src).dist = 0;
    push(0.0, src);
    while (!heap_.empty()) {
      std::pop_heap(heap_.begin(), heap_.end(), std::greater<Item>());
      const Item item = heap_.back();
      heap_.pop_back();
      const int v = item.v;
      if (item.dist > node_[v].dist) continue;  // stale entry
      if (v == dst) return;
      for (int k = g_.start[v]; k < g_.start[v + 1]; ++k) {
        const int w = g_.neighbor[k];
        if (!blocked.empty() && blocked[w]) continue;
        Node& n = touch(w);
        const double nd = item.dist + g_.length[k];
        if (nd < n.dist) {
          n.dist = nd;
          n.parent = v;
          push(nd, w);
        }
      }
    }
  }

  const Graph& g_;
  std::vector<Node> node_;
  std::uint32_t stamp_ = 0;
  std::vector<Item> heap_;
};

/// Flood fill of the faces across edges that are not on the loop. Returns the per-face labels
/// (0 = the part left of the loop, 1 = the part right of it), or an empty vector with `why` set
/// when the loop does not cut the mesh into two parts each bounded by the whole loop.
std::vector<int> label_faces(const TriMesh& mesh, const Graph& g, const SeedLoop& loop, std::string& why);
/// The same on a cut mesh (its half-edges give the faces across; no graph is built).
std::vector<int> label_faces(const CutMesh& cm, const SeedLoop& loop, std::string& why);

/// choose_seeds() that also hands over the routing graph of `mesh` it built (valid while `mesh`
/// lives: it points to its positions).
std::array<int, 4> choose_seeds(const TriMesh& mesh, const Context& context, Graph& graph);
/// trace_seed_loop() on the routing graph of `mesh` built already.
SeedLoop trace_seed_loop(const TriMesh& mesh, const Graph& g, const std::array<int, 4>& seeds,
                         const std::vector<int>& avoid, const Context& context);

/// "seed i (vertex v)", for messages.
std::string seed_name(const std::array<int, 4>& seeds, int i);

struct Attempt {
  bool ok = false;
  SeedLoop loop;
  std::vector<int> labels;
  std::string why;        ///< the failure, a sentence fragment naming the seeds
  int order_index = -1;   ///< which order succeeded
};

/// Routes the loop trying the orders in turn (the four paths by increasing unobstructed length
/// first, then the other 23 orders), avoiding the seeds other than a path's ends, the paths already
/// routed and `avoid`; the first order whose paths route and pass label_faces wins. Never throws for
/// an unroutable configuration (ok false, why set); checks the cancel flag.
Attempt try_route(const TriMesh& mesh, const Graph& g, Dijkstra& dijkstra, const std::array<int, 4>& seeds,
                  const Context& context, const std::vector<int>& avoid = {});

/// \throws InvalidInput for a seed out of range or two equal seeds.
void check_seeds(const TriMesh& mesh, const std::array<int, 4>& seeds);

/// The 3D length of the edge path p.
double path_length(const TriMesh& mesh, const std::vector<int>& p);

}  // namespace qs::dissect::routing
