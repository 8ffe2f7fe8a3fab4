#include "qs/mesh/simplify.h"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace qs::mesh {
namespace {

/// A collapse may turn a face's normal this far (cos).
constexpr double kMinNormalCos = 0.35;

/// Faces after a collapse worse than this (quality below) are refused unless the collapse
/// replaces a worse one.
constexpr double kMinQuality = 0.2;

/// 4 sqrt(3) area / (sum of squared edges): 1 for an equilateral triangle, 0 for a flat one.
double quality(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double e = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  return e > 0 ? 2 * std::sqrt(3.0) * (b - a).cross(c - a).norm() / e : 0;
}

}  // namespace

TriMesh simplify(const TriMesh& mesh, int faces) {
  std::vector<Vec3> pos = mesh.positions;
  std::vector<Tri> tri = mesh.faces;
  const int nv = static_cast<int>(pos.size());
  std::vector<char> alive(tri.size(), 1), locked(nv);
  std::vector<int> start(nv + 1), incident;
  std::vector<std::tuple<double, int, int>> edges;
  std::vector<int> ring_i, ring_j;
  int alive_faces = static_cast<int>(tri.size());
  const int target = std::max(faces, 4);
  while (alive_faces > target) {
    // Vertex -> faces (CSR) over the living faces.
    std::fill(start.begin(), start.end(), 0);
    for (size_t f = 0; f < tri.size(); ++f)
      if (alive[f])
        for (int v : tri[f]) ++start[v + 1];
    for (int v = 0; v < nv; ++v) start[v + 1] += start[v];
    incident.resize(start[nv]);
    {
      std::vector<int> fill(start.begin(), start.end() - 1);
      for (size_t f = 0; f < tri.size(); ++f)
        if (alive[f])
          for (int v : tri[f]) incident[fill[v]++] = static_cast<int>(f);
    }
    // Each edge once (from the face where it runs from the lower index), shortest first.
    edges.clear();
    for (size_t f = 0; f < tri.size(); ++f)
      if (alive[f])
        for (int c = 0; c < 3; ++c) {
          const int i = tri[f][c], j = tri[f][(c + 1) % 3];
          if (i < j) edges.emplace_back((pos[i] - pos[j]).squaredNorm(), i, j);
        }
    std::sort(edges.begin(), edges.end());
    std::fill(locked.begin(), locked.end(), 0);
    auto ring = [&](int v, std::vector<int>& out) {
      out.clear();
      for (int p = start[v]; p < start[v + 1]; ++p)
        for (int u : tri[incident[p]])
          if (u != v) out.push_back(u);
      std::sort(out.begin(), out.end());
      out.erase(std::unique(out.begin(), out.end()), out.end());
    };
    int collapsed = 0;
    for (const auto& [len2, i, j] : edges) {
      if (alive_faces - 2 < target) break;
      if (locked[i] || locked[j]) continue;
      ring(i, ring_i);
      ring(j, ring_j);
      // Link condition: the two rings share exactly the two vertices opposite the edge.
      int common = 0;
      for (size_t a = 0, b = 0; a < ring_i.size() && b < ring_j.size();) {
        if (ring_i[a] < ring_j[b]) ++a;
        else if (ring_j[b] < ring_i[a]) ++b;
        else ++common, ++a, ++b;
      }
      if (common != 2 || ring_i.size() + ring_j.size() <= 6) continue;  // keeps a tetrahedron
      const Vec3 mid = 0.5 * (pos[i] + pos[j]);
      bool ok = true;
      for (int v : {i, j})
        for (int p = start[v]; p < start[v + 1] && ok; ++p) {
          const Tri& t = tri[incident[p]];
          if ((t[0] == i || t[1] == i || t[2] == i) && (t[0] == j || t[1] == j || t[2] == j)) continue;  // removed
          const Vec3 before[3] = {pos[t[0]], pos[t[1]], pos[t[2]]};
          Vec3 after[3] = {before[0], before[1], before[2]};
          for (int c = 0; c < 3; ++c)
            if (t[c] == v) after[c] = mid;
          const Vec3 n0 = (before[1] - before[0]).cross(before[2] - before[0]);
          const Vec3 n1 = (after[1] - after[0]).cross(after[2] - after[0]);
          const double q0 = quality(before[0], before[1], before[2]), q1 = quality(after[0], after[1], after[2]);
          if (!(n0.dot(n1) > kMinNormalCos * n0.norm() * n1.norm()) || (q1 < kMinQuality && q1 < q0)) ok = false;
        }
      if (!ok) continue;
      // j into i.
      pos[i] = mid;
      for (int p = start[j]; p < start[j + 1]; ++p) {
        const int f = incident[p];
        Tri& t = tri[f];
        if (t[0] == i || t[1] == i || t[2] == i) {
          alive[f] = 0;
          --alive_faces;
        } else {
          for (int& c : t)
            if (c == j) c = i;
        }
      }
      locked[i] = locked[j] = 1;
      for (int u : ring_i) locked[u] = 1;
      for (int u : ring_j) locked[u] = 1;
      ++collapsed;
    }
    if (collapsed == 0) break;
  }
  // The remaining vertices in their input order, the living faces in theirs.
  std::vector<int> index(nv, -1);
  for (size_t f = 0; f < tri.size(); ++f)
    if (alive[f])
      for (int v : tri[f]) index[v] = 0;
  TriMesh out;
  for (int v = 0; v < nv; ++v)
    if (index[v] == 0) {
      index[v] = out.num_vertices();
      out.positions.push_back(pos[v]);
    }
  for (size_t f = 0; f < tri.size(); ++f)
    if (alive[f]) out.faces.push_back({index[tri[f][0]], index[tri[f][1]], index[tri[f][2]]});
  return out;
}

}  // namespace qs::mesh
