#include "qs/dfi/polygonize.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <string>
#include <unordered_map>

#include "qs/core/error.h"

namespace qs::dfi {
namespace {

// Corner c of a cell is at offset (c & 1, c >> 1 & 1, c >> 2 & 1).
Vec3 corner_offset(int c) { return Vec3(c & 1, (c >> 1) & 1, (c >> 2) & 1); }

// The 6 Kuhn tetrahedra (0, a, a|b, 7), reordered to positive orientation.
std::array<std::array<int, 4>, 6> kuhn_tets() {
  std::array<std::array<int, 4>, 6> tets{};
  const int axes[3] = {1, 2, 4};
  int perm[3] = {0, 1, 2};
  int n = 0;
  do {
    std::array<int, 4> t{0, axes[perm[0]], axes[perm[0]] | axes[perm[1]], 7};
    const Vec3 p0 = corner_offset(t[0]);
    const double det = (corner_offset(t[1]) - p0).dot((corner_offset(t[2]) - p0).cross(corner_offset(t[3]) - p0));
    if (det < 0) std::swap(t[2], t[3]);
    tets[n++] = t;
  } while (std::next_permutation(perm, perm + 3));
  return tets;
}

// Even permutations of (0,1,2,3) starting with each index: (i, j, k, l) keeps the orientation.
constexpr int kEven[4][4] = {{0, 1, 2, 3}, {1, 0, 3, 2}, {2, 0, 1, 3}, {3, 0, 2, 1}};
// Even permutations (i, j, k, l) for each pair {i, j} (first two entries).
constexpr int kEvenPairs[6][4] = {{0, 1, 2, 3}, {0, 2, 3, 1}, {0, 3, 1, 2},
                                  {1, 2, 0, 3}, {1, 3, 2, 0}, {2, 3, 0, 1}};

}  // namespace

TriMesh polygonize(const Grid& field, const PolygonizeOptions& options) {
  const int nx = field.dims[0], ny = field.dims[1], nz = field.dims[2];
  if (nx < 2 || ny < 2 || nz < 2 || field.values.size() != field.size())
    throw InvalidInput("polygonize: the grid needs at least 2 samples per axis and one value per sample");
  const double tol = options.snap_tolerance * field.spacing;
  std::vector<float> v(field.values);
  for (size_t id = 0; id < v.size(); ++id) {
    if (!std::isfinite(v[id]))
      throw InvalidInput("polygonize: sample " + std::to_string(id) + " is not finite");
    if (std::abs(v[id]) < tol) v[id] = static_cast<float>(tol);
  }
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        if (i != 0 && j != 0 && k != 0 && i != nx - 1 && j != ny - 1 && k != nz - 1) continue;
        if (v[field.index(i, j, k)] < 0)
          throw InvalidInput("polygonize: boundary sample (" + std::to_string(i) + ", " + std::to_string(j) + ", " +
                             std::to_string(k) + ") is inside the shape; the grid must enclose it with a margin");
      }

  const auto tets = kuhn_tets();
  size_t corner_step[8];
  for (int c = 0; c < 8; ++c) corner_step[c] = field.index(c & 1, (c >> 1) & 1, (c >> 2) & 1);
  TriMesh mesh;
  std::unordered_map<uint64_t, int> edge_vertex;
  // The surface vertex on the grid edge from corner cu to corner cv (cu's bits a subset of cv's).
  auto vertex_on = [&](size_t base, int i, int j, int k, int cu, int cv) {
    const size_t u = base + corner_step[cu], w = base + corner_step[cv];
    const uint64_t key = static_cast<uint64_t>(u) * 7 + static_cast<uint64_t>((cv ^ cu) - 1);
    auto [it, fresh] = edge_vertex.try_emplace(key, mesh.num_vertices());
    if (fresh) {
      const Vec3 pu = field.point(i, j, k) + field.spacing * corner_offset(cu);
      const Vec3 pw = field.point(i, j, k) + field.spacing * corner_offset(cv);
      const double t = static_cast<double>(v[u]) / (static_cast<double>(v[u]) - v[w]);
      mesh.positions.push_back(pu + t * (pw - pu));
    }
    return it->second;
  };
  for (int k = 0; k + 1 < nz; ++k)
    for (int j = 0; j + 1 < ny; ++j)
      for (int i = 0; i + 1 < nx; ++i) {
        const size_t base = field.index(i, j, k);
        int negative = 0;
        for (int c = 0; c < 8; ++c) negative += v[base + corner_step[c]] < 0;
        if (negative == 0 || negative == 8) continue;
        for (const auto& tet : tets) {
          bool in[4];
          int count = 0;
          for (int q = 0; q < 4; ++q) count += (in[q] = v[base + corner_step[tet[q]]] < 0);
          if (count == 0 || count == 4) continue;
          // The surface vertex on tet edge (a, b), named by tet-local indices.
          auto ev = [&](int a, int b) {
            int ca = tet[a], cb = tet[b];
            if ((ca & cb) != ca) std::swap(ca, cb);  // the lower corner first
            return vertex_on(base, i, j, k, ca, cb);
          };
          if (count == 1 || count == 3) {
            int lone = 0;
            while (in[lone] != (count == 1)) ++lone;
            const int* p = kEven[lone];
            Tri t{ev(p[0], p[1]), ev(p[0], p[2]), ev(p[0], p[3])};  // normal away from p[0]
            if (count == 3) std::swap(t[1], t[2]);                  // p[0] is the outside one
            mesh.faces.push_back(t);
          } else {
            int pair = 0;
            while (!(in[kEvenPairs[pair][0]] && in[kEvenPairs[pair][1]]) &&
                   !(!in[kEvenPairs[pair][0]] && !in[kEvenPairs[pair][1]]))
              ++pair;
            const int* p = kEvenPairs[pair];
            // (i, j) on one side, (k, l) on the other: quad e_ik, e_il, e_jl, e_jk is outward
            // when i, j are inside.
            int q0 = ev(p[0], p[2]), q1 = ev(p[0], p[3]), q2 = ev(p[1], p[3]), q3 = ev(p[1], p[2]);
            if (!in[p[0]]) std::swap(q1, q3);
            mesh.faces.push_back({q0, q1, q2});
            mesh.faces.push_back({q0, q2, q3});
          }
        }
      }
  return mesh;
}

MeshStats mesh_stats(const TriMesh& mesh) {
  MeshStats s;
  s.vertices = mesh.num_vertices();
  s.faces = mesh.num_faces();
  // Directed edges: a closed oriented manifold has each undirected edge once per direction.
  std::vector<std::pair<uint64_t, int>> directed;
  directed.reserve(mesh.faces.size() * 3);
  const uint64_t nv = static_cast<uint64_t>(mesh.num_vertices());
  for (const Tri& t : mesh.faces)
    for (int c = 0; c < 3; ++c) {
      const uint64_t a = t[c], b = t[(c + 1) % 3];
      directed.push_back({std::min(a, b) * nv + std::max(a, b), a < b ? 1 : -1});
    }
  std::sort(directed.begin(), directed.end());
  bool ok = true;
  for (size_t e = 0; e < directed.size();) {
    size_t f = e;
    while (f < directed.size() && directed[f].first == directed[e].first) ++f;
    ++s.edges;
    if (f - e != 2 || directed[e].second == directed[e + 1].second) ok = false;
    e = f;
  }
  // Components by union-find over face corners; a vertex used by no face is not counted.
  std::vector<int> parent(mesh.num_vertices());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  std::vector<char> used(mesh.num_vertices(), 0);
  for (const Tri& t : mesh.faces)
    for (int c = 0; c < 3; ++c) {
      used[t[c]] = 1;
      const int a = find(t[c]), b = find(t[(c + 1) % 3]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  int used_count = 0;
  for (int x = 0; x < mesh.num_vertices(); ++x)
    if (used[x]) {
      ++used_count;
      if (find(x) == x) ++s.components;
    }
  s.closed_manifold = ok && !mesh.faces.empty() && used_count == mesh.num_vertices();
  // Per-vertex fans would be needed for a full manifold check; for our polygonizer's output the
  // edge check above is the one that can fail. chi summed over components: sum (2 - 2 g_c).
  const long long chi = static_cast<long long>(used_count) - s.edges + s.faces;
  s.genus = static_cast<int>((2LL * s.components - chi) / 2);
  // Signed volume about the bounding-box centre.
  const Box3 box = bounding_box(mesh.positions);
  const Vec3 o = 0.5 * (box.min + box.max);
  double vol = 0;
  for (const Tri& t : mesh.faces)
    vol += (mesh.positions[t[0]] - o).dot((mesh.positions[t[1]] - o).cross(mesh.positions[t[2]] - o));
  s.volume = vol / 6.0;
  return s;
}

}  // namespace qs::dfi
