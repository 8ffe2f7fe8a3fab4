#pragma once
// Small helpers that several test files share.

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

#include "qs/core/mesh.h"

namespace qs::test {

/// The vertex whose direction from the origin is closest to `d` (the first on ties).
inline int vertex_towards(const TriMesh& m, const Vec3& d) {
  int best = 0;
  for (int v = 1; v < m.num_vertices(); ++v)
    if (m.positions[v].normalized().dot(d.normalized()) > m.positions[best].normalized().dot(d.normalized())) best = v;
  return best;
}

/// The vertex nearest to p (the first on ties).
inline int nearest_vertex(const TriMesh& m, const Vec3& p) {
  int best = 0;
  for (int v = 1; v < m.num_vertices(); ++v)
    if ((m.positions[v] - p).squaredNorm() < (m.positions[best] - p).squaredNorm()) best = v;
  return best;
}

/// A regular tetrahedron, outward, vertices 0-3 (faces 0-3), moved by `offset`.
inline TriMesh tetrahedron(const Vec3& offset = Vec3::Zero()) {
  TriMesh m;
  m.positions = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  for (Vec3& p : m.positions) p += offset;
  m.faces = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
  return m;
}

/// `m` scaled by `s` about the origin.
inline TriMesh scaled(TriMesh m, double s) {
  for (Vec3& p : m.positions) p *= s;
  return m;
}

/// The bytes of a file ("" when it cannot be read).
inline std::string read_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// Every entry under `dir` (relative name -> bytes; folders as "<dir>"); empty when `dir` does not exist.
inline std::map<std::string, std::string> snapshot(const std::filesystem::path& dir) {
  std::map<std::string, std::string> out;
  if (!std::filesystem::exists(dir)) return out;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
    out[std::filesystem::relative(e.path(), dir).string()] = e.is_directory() ? "<dir>" : read_bytes(e.path());
  return out;
}

}  // namespace qs::test
