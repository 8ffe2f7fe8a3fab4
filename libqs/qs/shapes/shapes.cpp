#include "qs/shapes/shapes.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <utility>

#include "qs/core/error.h"

namespace qs::shapes {

namespace {

constexpr double kPi = 3.14159265358979323846;

void require(bool ok, const std::string& message) {
  if (!ok) throw InvalidInput(message);
}

void require_range(const char* function, const char* name, long long value, long long lo,
                   long long hi) {
  require(value >= lo && value <= hi, std::string(function) + ": " + name + " = " +
                                          std::to_string(value) + " is outside [" +
                                          std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

/// Orients every face of a mesh that is star-shaped about the origin so that its normal points
/// away from the origin.
void orient_outward_from_origin(TriMesh& m) {
  for (Tri& t : m.faces) {
    const Vec3& a = m.positions[t[0]];
    const Vec3& b = m.positions[t[1]];
    const Vec3& c = m.positions[t[2]];
    if (a.dot(b.cross(c)) < 0) std::swap(t[1], t[2]);
  }
}

TriMesh icosahedron() {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  TriMesh m;
  m.positions = {{-1, g, 0},  {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
                 {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
  for (Vec3& p : m.positions) p.normalize();
  m.faces = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
             {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
             {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  orient_outward_from_origin(m);
  return m;
}

/// Splits every face in four through its edge midpoints, projected to the unit sphere.
TriMesh subdivide_on_sphere(const TriMesh& m) {
  TriMesh r;
  r.positions = m.positions;
  r.positions.reserve(m.positions.size() + 3 * m.faces.size() / 2);
  r.faces.reserve(4 * m.faces.size());
  std::unordered_map<std::uint64_t, int> midpoint;
  midpoint.reserve(3 * m.faces.size() / 2);
  auto mid = [&](int a, int b) {
    const auto key = (static_cast<std::uint64_t>(std::min(a, b)) << 32) |
                     static_cast<std::uint32_t>(std::max(a, b));
    auto [it, inserted] = midpoint.try_emplace(key, static_cast<int>(r.positions.size()));
    if (inserted) r.positions.push_back((m.positions[a] + m.positions[b]).normalized());
    return it->second;
  };
  for (const Tri& t : m.faces) {
    const int ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
    r.faces.push_back({t[0], ab, ca});
    r.faces.push_back({t[1], bc, ab});
    r.faces.push_back({t[2], ca, bc});
    r.faces.push_back({ab, bc, ca});
  }
  return r;
}

}  // namespace

TriMesh icosphere(int subdivisions) {
  require_range("icosphere", "subdivisions", subdivisions, 0, 9);
  TriMesh m = icosahedron();
  for (int i = 0; i < subdivisions; ++i) m = subdivide_on_sphere(m);
  return m;
}

TriMesh ellipsoid(double a, double b, double c, int subdivisions) {
  require(a > 0 && b > 0 && c > 0 && std::isfinite(a) && std::isfinite(b) && std::isfinite(c),
          "ellipsoid: semi-axes must be positive and finite, got (" + std::to_string(a) + ", " +
              std::to_string(b) + ", " + std::to_string(c) + ")");
  TriMesh m = icosphere(subdivisions);
  const Vec3 s(a, b, c);
  for (Vec3& p : m.positions) p = p.cwiseProduct(s);
  return m;
}

TriMesh displaced_sphere(const std::function<double(const Vec3&)>& radius, int subdivisions) {
  require(static_cast<bool>(radius), "displaced_sphere: no radius function given");
  TriMesh m = icosphere(subdivisions);
  for (std::size_t v = 0; v < m.positions.size(); ++v) {
    const double r = radius(m.positions[v]);
    require(r > 0 && std::isfinite(r), "displaced_sphere: radius " + std::to_string(r) +
                                           " at vertex " + std::to_string(v) +
                                           " must be positive and finite");
    m.positions[v] *= r;
  }
  return m;
}

TriMesh bumpy_sphere(double amplitude, int frequency, int subdivisions) {
  require(std::abs(amplitude) < 1, "bumpy_sphere: amplitude " + std::to_string(amplitude) +
                                       " must be in (-1, 1) so that the radius stays positive");
  require_range("bumpy_sphere", "frequency", frequency, 0, 1000);
  const double k = frequency;
  return displaced_sphere(
      [&](const Vec3& d) {
        return 1.0 +
               amplitude * (std::sin(k * d.x()) + std::sin(k * d.y()) + std::sin(k * d.z())) / 3.0;
      },
      subdivisions);
}

std::vector<Vec3> fibonacci_directions(int n) {
  require_range("fibonacci_directions", "n", n, 0, 1 << 24);
  const double golden_angle = kPi * (3.0 - std::sqrt(5.0));
  std::vector<Vec3> dirs(n);
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / n;
    const double rho = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden_angle * i;
    dirs[i] = Vec3(rho * std::cos(phi), rho * std::sin(phi), z);
  }
  return dirs;
}

TriMesh star_blob(int arms, double arm_length, int subdivisions) {
  require_range("star_blob", "arms", arms, 0, 1000);
  require(arm_length >= 0 && arm_length <= 100,
          "star_blob: arm_length " + std::to_string(arm_length) + " is outside [0, 100]");
  const std::vector<Vec3> dirs = fibonacci_directions(arms);
  return displaced_sphere(
      [&](const Vec3& d) {
        double sum = 0;
        for (const Vec3& a : dirs) {
          const double c = d.dot(a);
          if (c > 0) sum += std::pow(c, 48);
        }
        return 1.0 + arm_length * sum;
      },
      subdivisions);
}

TriMesh cube_sphere(int n) {
  require_range("cube_sphere", "n", n, 1, 1024);
  TriMesh m;
  const auto side = static_cast<std::uint64_t>(n) + 1;
  std::unordered_map<std::uint64_t, int> index;
  index.reserve(6 * side * side);
  m.positions.reserve(6 * static_cast<std::size_t>(n) * n + 2);
  m.faces.reserve(12 * static_cast<std::size_t>(n) * n);
  // Grid coordinate 0..n -> cube coordinate in [-1, 1], equiangular so cells are more even.
  auto coord = [n](int c) { return std::tan((2.0 * c / n - 1.0) * kPi / 4.0); };
  auto vertex = [&](const std::array<int, 3>& g) {
    const std::uint64_t key = (g[0] * side + g[1]) * side + g[2];
    auto [it, inserted] = index.try_emplace(key, static_cast<int>(m.positions.size()));
    if (inserted) m.positions.push_back(Vec3(coord(g[0]), coord(g[1]), coord(g[2])).normalized());
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;  // e_u x e_v = e_axis
    for (int positive = 0; positive < 2; ++positive) {
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          auto at = [&](int di, int dj) {
            std::array<int, 3> g{};
            g[axis] = positive ? n : 0;
            g[u] = i + di;
            g[v] = j + dj;
            return vertex(g);
          };
          const int p00 = at(0, 0), p10 = at(1, 0), p11 = at(1, 1), p01 = at(0, 1);
          if (positive) {
            m.faces.push_back({p00, p10, p11});
            m.faces.push_back({p00, p11, p01});
          } else {
            m.faces.push_back({p00, p11, p10});
            m.faces.push_back({p00, p01, p11});
          }
        }
      }
    }
  }
  return m;
}

TriMesh open_disk(int rings) {
  require_range("open_disk", "rings", rings, 1, 1000);
  const int r = rings, w = 2 * r + 1;
  TriMesh m;
  std::vector<int> index(static_cast<std::size_t>(w) * w, -1);
  auto inside = [r](int q, int s) {
    return std::max({std::abs(q), std::abs(s), std::abs(q + s)}) <= r;
  };
  auto id = [&](int q, int s) -> int& { return index[(q + r) * w + (s + r)]; };
  // Axial lattice coordinates (q, s): position q * (1, 0) + s * (1/2, sqrt(3)/2), scaled by 1/r.
  const double h = std::sqrt(3.0) / 2.0;
  for (int s = -r; s <= r; ++s)
    for (int q = -r; q <= r; ++q)
      if (inside(q, s)) {
        id(q, s) = static_cast<int>(m.positions.size());
        m.positions.emplace_back((q + 0.5 * s) / r, h * s / r, 0.0);
      }
  // Every lattice triangle with its three corners inside: "up" (q,s) (q+1,s) (q,s+1) and
  // "down" (q+1,s) (q+1,s+1) (q,s+1), both counter-clockwise.
  for (int s = -r - 1; s <= r; ++s)
    for (int q = -r - 1; q <= r; ++q) {
      if (inside(q, s) && inside(q + 1, s) && inside(q, s + 1))
        m.faces.push_back({id(q, s), id(q + 1, s), id(q, s + 1)});
      if (inside(q + 1, s) && inside(q + 1, s + 1) && inside(q, s + 1))
        m.faces.push_back({id(q + 1, s), id(q + 1, s + 1), id(q, s + 1)});
    }
  return m;
}

TriMesh torus(int major, int minor) {
  require_range("torus", "major", major, 3, 4096);
  require_range("torus", "minor", minor, 3, 4096);
  const double big = 1.0, small = 0.4;
  TriMesh m;
  m.positions.reserve(static_cast<std::size_t>(major) * minor);
  for (int i = 0; i < major; ++i) {
    const double u = 2 * kPi * i / major;
    for (int j = 0; j < minor; ++j) {
      const double v = 2 * kPi * j / minor;
      const double rho = big + small * std::cos(v);
      m.positions.emplace_back(rho * std::cos(u), rho * std::sin(u), small * std::sin(v));
    }
  }
  auto id = [&](int i, int j) { return (i % major) * minor + (j % minor); };
  // d/du x d/dv is the outward normal, so (i,j) -> (i+1,j) -> (i+1,j+1) is counter-clockwise.
  for (int i = 0; i < major; ++i)
    for (int j = 0; j < minor; ++j) {
      const int a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      m.faces.push_back({a, b, c});
      m.faces.push_back({a, c, d});
    }
  return m;
}

TriMesh two_components() {
  TriMesh m = icosphere(1);
  const TriMesh second = icosphere(1);
  const int offset = m.num_vertices();
  for (const Vec3& p : second.positions) m.positions.push_back(p + Vec3(3, 0, 0));
  for (const Tri& t : second.faces)
    m.faces.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  return m;
}

TriMesh nonmanifold_fan() {
  TriMesh m;
  m.positions = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  m.faces = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
  orient_outward_from_origin(m);
  m.positions.emplace_back(2.5, 0, 0);  // beyond the midpoint (1, 0, 0) of edge 0-1
  m.faces.push_back({0, 1, 4});
  return m;
}

}  // namespace qs::shapes
