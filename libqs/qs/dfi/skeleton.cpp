// The one translation unit that instantiates CGAL's mean curvature flow skeletonization.
#include "qs/dfi/skeleton.h"

#include <sys/mman.h>

#include <cstddef>
#include <memory>
#include <new>

// CGAL's skeletonization copies the mesh into a Polyhedron_3 and collapses edges in the order of a
// std::set of edge handles, that is by memory address: with the default allocator the skeleton
// depends on what the process allocated and freed before (horse_5k: 267 then 248 nodes when called
// twice in one process). Its containers take their allocator from CGAL_ALLOCATOR; ours hands out
// memory from one reserved range in allocation order, so addresses, and with them the skeleton,
// depend on the mesh alone. Frees are no-ops; the range is unmapped after each skeleton.
namespace qs::dfi::skeleton_arena {
struct Arena {
  char* base = nullptr;
  size_t size = 0, used = 0;
};
inline thread_local Arena* current = nullptr;
inline bool owns(const void* p) {
  return current && static_cast<const char*>(p) >= current->base && static_cast<const char*>(p) < current->base + current->size;
}
template <class T>
struct Allocator {
  using value_type = T;
  Allocator() = default;
  template <class U>
  Allocator(const Allocator<U>&) {}
  template <class U>
  struct rebind {
    using other = Allocator<U>;
  };
  T* allocate(size_t n) {
    if (!current) return std::allocator<T>().allocate(n);
    const size_t align = alignof(T) > alignof(std::max_align_t) ? alignof(T) : alignof(std::max_align_t);
    const size_t start = (current->used + align - 1) / align * align;
    if (n > (current->size - start) / sizeof(T)) throw std::bad_alloc();
    current->used = start + n * sizeof(T);
    return reinterpret_cast<T*>(current->base + start);
  }
  void deallocate(T* p, size_t n) {
    if (!owns(p)) std::allocator<T>().deallocate(p, n);
  }
  template <class U>
  bool operator==(const Allocator<U>&) const { return true; }
  template <class U>
  bool operator!=(const Allocator<U>&) const { return false; }
};
}  // namespace qs::dfi::skeleton_arena
#define CGAL_ALLOCATOR(T) qs::dfi::skeleton_arena::Allocator<T>

#include <CGAL/Simple_cartesian.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/extract_mean_curvature_flow_skeleton.h>

#include <algorithm>
#include <map>
#include <string>

#include "qs/core/error.h"

namespace qs::dfi {
namespace {
using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
using Skeletonization = CGAL::Mean_curvature_flow_skeletonization<SurfaceMesh>;
}  // namespace

Skeleton curve_skeleton(const TriMesh& mesh) {
  SurfaceMesh sm;
  std::vector<SurfaceMesh::Vertex_index> vs;
  vs.reserve(mesh.positions.size());
  for (const Vec3& p : mesh.positions) vs.push_back(sm.add_vertex(Point(p.x(), p.y(), p.z())));
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Tri& t = mesh.faces[f];
    if (sm.add_face(vs[t[0]], vs[t[1]], vs[t[2]]) == SurfaceMesh::null_face())
      throw InvalidInput("skeleton: face " + std::to_string(f) + " cannot be added (not a manifold oriented surface)");
  }
  Skeletonization::Skeleton sk;
  {
    // The arena: 4 GiB of address space, pages committed as they are touched.
    skeleton_arena::Arena arena;
    arena.size = size_t(4) << 30;
    void* base = mmap(nullptr, arena.size, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    if (base == MAP_FAILED) throw SolverError("skeleton: cannot reserve address space for CGAL's skeletonization");
    arena.base = static_cast<char*>(base);
    struct Guard {
      skeleton_arena::Arena& a;
      ~Guard() {
        skeleton_arena::current = nullptr;
        munmap(a.base, a.size);
      }
    } guard{arena};
    skeleton_arena::current = &arena;
    try {
      CGAL::extract_mean_curvature_flow_skeleton(sm, sk);
    } catch (const std::bad_alloc&) {
      throw SolverError("skeleton: CGAL's mean curvature flow used more than 4 GiB");
    } catch (const std::exception& e) {
      throw SolverError(std::string("skeleton: CGAL's mean curvature flow failed: ") + e.what());
    }
  }
  Skeleton out;
  const auto n = boost::num_vertices(sk);
  out.nodes.resize(n);
  out.node_vertices.resize(n);
  for (auto v : CGAL::make_range(boost::vertices(sk))) {
    const Point& p = sk[v].point;
    out.nodes[v] = Vec3(p.x(), p.y(), p.z());
    for (auto mv : sk[v].vertices) out.node_vertices[v].push_back(static_cast<int>(mv.idx()));
    std::sort(out.node_vertices[v].begin(), out.node_vertices[v].end());
  }
  for (auto e : CGAL::make_range(boost::edges(sk))) {
    int a = static_cast<int>(boost::source(e, sk)), b = static_cast<int>(boost::target(e, sk));
    if (a == b) continue;
    out.edges.push_back({std::min(a, b), std::max(a, b)});
  }
  std::sort(out.edges.begin(), out.edges.end());
  out.edges.erase(std::unique(out.edges.begin(), out.edges.end()), out.edges.end());
  if (out.nodes.empty()) throw SolverError("skeleton: CGAL returned an empty skeleton");
  return out;
}

void prune_skeleton(Skeleton& s, double min_length) {
  for (int round = 0; round < 32; ++round) {
    const std::vector<int> deg = node_degrees(s);
    std::vector<char> removed(s.nodes.size(), 0);
    bool changed = false;
    for (const Branch& b : skeleton_branches(s)) {
      const bool a_tip = deg[b.a] == 1 && deg[b.b] >= 3, b_tip = deg[b.b] == 1 && deg[b.a] >= 3;
      if ((!a_tip && !b_tip) || b.length >= min_length) continue;
      const int junction = a_tip ? b.b : b.a;
      bool clash = false;  // two spurs of one junction in the same round: keep it simple, one at a time
      for (int v : b.nodes) clash |= v != junction && removed[v];
      if (clash) continue;
      for (int v : b.nodes) {
        if (v == junction) continue;
        removed[v] = 1;
        auto& into = s.node_vertices[junction];
        into.insert(into.end(), s.node_vertices[v].begin(), s.node_vertices[v].end());
      }
      std::sort(s.node_vertices[junction].begin(), s.node_vertices[junction].end());
      changed = true;
    }
    if (!changed) return;
    std::vector<int> renum(s.nodes.size(), -1);
    Skeleton t;
    for (size_t v = 0; v < s.nodes.size(); ++v)
      if (!removed[v]) {
        renum[v] = static_cast<int>(t.nodes.size());
        t.nodes.push_back(s.nodes[v]);
        t.node_vertices.push_back(s.node_vertices[v]);
      }
    for (const auto& e : s.edges)
      if (renum[e[0]] >= 0 && renum[e[1]] >= 0) t.edges.push_back({renum[e[0]], renum[e[1]]});
    s = std::move(t);
  }
}

std::vector<int> node_degrees(const Skeleton& s) {
  std::vector<int> d(s.nodes.size(), 0);
  for (const auto& e : s.edges) {
    ++d[e[0]];
    ++d[e[1]];
  }
  return d;
}

Vec3 Branch::at(const Skeleton& s, double fraction) const {
  if (nodes.size() == 1 || length <= 0) return s.nodes[nodes.front()];
  double want = std::clamp(fraction, 0.0, 1.0) * length, walked = 0;
  for (size_t k = 1; k < nodes.size(); ++k) {
    const Vec3 p = s.nodes[nodes[k - 1]], q = s.nodes[nodes[k]];
    const double l = (q - p).norm();
    if (walked + l >= want && l > 0) return p + (want - walked) / l * (q - p);
    walked += l;
  }
  return s.nodes[nodes.back()];
}

std::vector<Branch> skeleton_branches(const Skeleton& s) {
  const int n = static_cast<int>(s.nodes.size());
  std::vector<std::vector<int>> adj(n);
  for (const auto& e : s.edges) {
    adj[e[0]].push_back(e[1]);
    adj[e[1]].push_back(e[0]);
  }
  for (auto& a : adj) std::sort(a.begin(), a.end());
  const std::vector<int> deg = node_degrees(s);
  std::map<std::pair<int, int>, bool> used;  // undirected edges walked
  auto edge_key = [](int a, int b) { return std::make_pair(std::min(a, b), std::max(a, b)); };
  std::vector<Branch> out;
  auto walk = [&](int start, int next) {
    Branch br;
    br.a = start;
    br.nodes = {start};
    int prev = start, cur = next;
    used[edge_key(prev, cur)] = true;
    br.length += (s.nodes[cur] - s.nodes[prev]).norm();
    br.nodes.push_back(cur);
    while (deg[cur] == 2 && cur != start) {
      const int nxt = adj[cur][0] == prev ? adj[cur][1] : adj[cur][0];
      if (used[edge_key(cur, nxt)]) break;
      used[edge_key(cur, nxt)] = true;
      br.length += (s.nodes[nxt] - s.nodes[cur]).norm();
      prev = cur;
      cur = nxt;
      br.nodes.push_back(cur);
    }
    br.b = cur;
    out.push_back(br);
  };
  for (int v = 0; v < n; ++v)
    if (deg[v] != 2)
      for (int w : adj[v])
        if (!used[edge_key(v, w)]) walk(v, w);
  // Cycles made only of degree-2 nodes.
  for (int v = 0; v < n; ++v)
    if (deg[v] == 2)
      for (int w : adj[v])
        if (!used[edge_key(v, w)]) walk(v, w);
  if (out.empty() && n > 0) {  // a single node
    Branch br;
    br.a = br.b = 0;
    br.nodes = {0};
    out.push_back(br);
  }
  return out;
}

}  // namespace qs::dfi
