#include "qs/remesh/quality.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "qs/core/error.h"

namespace qs::remesh {

namespace {

constexpr double kPi = 3.14159265358979323846;

void check_faces(const TriMesh& mesh, const char* what) {
  const int nv = mesh.num_vertices();
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int v : mesh.faces[static_cast<size_t>(f)])
      if (v < 0 || v >= nv)
        throw InvalidInput(std::string(what) + ": face " + std::to_string(f) + " has vertex index " + std::to_string(v) +
                           ", outside [0, " + std::to_string(nv) + ")");
}

/// The angle between two edge vectors in degrees, 0 when either has zero length. atan2 of the
/// cross and dot products: accurate for tiny angles, unlike acos of a normalized dot product.
double angle_deg(const Vec3& a, const Vec3& b) {
  const double c = a.cross(b).norm(), d = a.dot(b);
  if (!(c > 0) && !(d != 0)) return 0;
  return std::atan2(c, d) * (180.0 / kPi);
}

/// Area-weighted percentiles of (value, weight) pairs; pairs of zero weight are ignored.
DensitySpread weighted_spread(std::vector<std::pair<double, double>> vw) {
  vw.erase(std::remove_if(vw.begin(), vw.end(), [](const auto& p) { return !(p.second > 0) || std::isnan(p.first); }),
           vw.end());
  DensitySpread s;
  if (vw.empty()) return s;
  std::sort(vw.begin(), vw.end());
  double total = 0;
  for (const auto& p : vw) total += p.second;
  auto at = [&](double q) {
    const double target = q * total;
    double acc = 0;
    for (const auto& p : vw) {
      acc += p.second;
      if (acc >= target) return p.first;
    }
    return vw.back().first;
  };
  s.p5 = at(0.05);
  s.p50 = at(0.5);
  s.p95 = at(0.95);
  s.spread = s.p5 > 0 ? s.p95 / s.p5 : std::numeric_limits<double>::infinity();
  return s;
}

}  // namespace

AngleStats smallest_angle_stats(const TriMesh& mesh) {
  check_faces(mesh, "angle statistics");
  AngleStats s;
  s.faces = mesh.num_faces();
  if (s.faces == 0) return s;
  std::vector<double> smallest(static_cast<size_t>(s.faces));
  long n5 = 0, n10 = 0, n20 = 0;
  for (size_t f = 0; f < smallest.size(); ++f) {
    const Tri& t = mesh.faces[f];
    const Vec3& a = mesh.positions[static_cast<size_t>(t[0])];
    const Vec3& b = mesh.positions[static_cast<size_t>(t[1])];
    const Vec3& c = mesh.positions[static_cast<size_t>(t[2])];
    double m = std::min({angle_deg(b - a, c - a), angle_deg(a - b, c - b), angle_deg(a - c, b - c)});
    if (!std::isfinite(m)) m = 0;
    smallest[f] = m;
    n5 += m < 5;
    n10 += m < 10;
    n20 += m < 20;
  }
  const double n = static_cast<double>(s.faces);
  s.under_5 = static_cast<double>(n5) / n;
  s.under_10 = static_cast<double>(n10) / n;
  s.under_20 = static_cast<double>(n20) / n;
  std::sort(smallest.begin(), smallest.end());
  const size_t mid = smallest.size() / 2;
  s.median = smallest.size() % 2 ? smallest[mid] : 0.5 * (smallest[mid - 1] + smallest[mid]);
  s.min = smallest.front();
  return s;
}

DensitySpread vertex_density(const TriMesh& mesh) {
  check_faces(mesh, "vertex density");
  std::vector<std::pair<double, double>> vw;
  vw.reserve(mesh.faces.size());
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const double a = face_area(mesh, f);
    if (a > 0) vw.emplace_back(1.0 / (2.0 * a), a);
  }
  if (vw.empty())
    throw InvalidInput("vertex density: the mesh has no area (" + std::to_string(mesh.num_faces()) + " faces)");
  return weighted_spread(std::move(vw));
}

DensitySpread chart_density(const dissect::Chart& chart, double samples_per_side) {
  if (!(samples_per_side > 0) || !std::isfinite(samples_per_side))
    throw InvalidInput("chart density: samples per side is " + std::to_string(samples_per_side) +
                       "; expected a positive number");
  size_t patches = chart.patches.size();
  for (int p : chart.face_patch) patches = std::max(patches, static_cast<size_t>(std::max(p, 0)) + 1);
  return chart_density(chart, std::vector<double>(patches, samples_per_side));
}

DensitySpread chart_density(const dissect::Chart& chart, const std::vector<double>& samples_per_side) {
  for (size_t p = 0; p < samples_per_side.size(); ++p)
    if (!(samples_per_side[p] > 0) || !std::isfinite(samples_per_side[p]))
      throw InvalidInput("chart density: samples per side of patch " + std::to_string(p) + " is " +
                         std::to_string(samples_per_side[p]) + "; expected a positive number");
  check_faces(chart.mesh, "chart density");
  if (chart.face_uv.size() != chart.mesh.faces.size() || chart.face_patch.size() != chart.mesh.faces.size())
    throw InvalidInput("chart density: " + std::to_string(chart.face_uv.size()) + " uv triples and " +
                       std::to_string(chart.face_patch.size()) + " patch ids for " +
                       std::to_string(chart.mesh.faces.size()) + " faces");
  std::vector<std::pair<double, double>> vw;
  vw.reserve(chart.mesh.faces.size());
  for (int f = 0; f < chart.mesh.num_faces(); ++f) {
    const double a = face_area(chart.mesh, f);
    if (!(a > 0)) continue;
    const int p = chart.face_patch[static_cast<size_t>(f)];
    if (p < 0 || p >= static_cast<int>(samples_per_side.size()))
      throw InvalidInput("chart density: face " + std::to_string(f) + " is in patch " + std::to_string(p) + ", but " +
                         std::to_string(samples_per_side.size()) + " patches have a sample count");
    const double k = samples_per_side[static_cast<size_t>(p)] * samples_per_side[static_cast<size_t>(p)];
    const auto& uv = chart.face_uv[static_cast<size_t>(f)];
    const Vec2 e1 = uv[1] - uv[0], e2 = uv[2] - uv[0];
    const double uv_area = 0.5 * std::abs(e1.x() * e2.y() - e1.y() * e2.x());
    vw.emplace_back(k * uv_area / a, a);
  }
  if (vw.empty())
    throw InvalidInput("chart density: the chart has no area (" + std::to_string(chart.mesh.num_faces()) + " faces)");
  return weighted_spread(std::move(vw));
}

std::vector<double> patch_area_shares(const std::vector<const dissect::Chart*>& charts) {
  if (charts.empty()) throw InvalidInput("patch areas: no charts");
  const size_t np = charts.front()->patches.size();
  std::vector<double> out(np, 0.0);
  for (size_t m = 0; m < charts.size(); ++m) {
    const dissect::Chart& chart = *charts[m];
    check_faces(chart.mesh, "patch areas");
    if (chart.patches.size() != np || chart.face_patch.size() != chart.mesh.faces.size())
      throw InvalidInput("patch areas: chart " + std::to_string(m) + " has " + std::to_string(chart.patches.size()) +
                         " patches and " + std::to_string(chart.face_patch.size()) + " face patch ids for " +
                         std::to_string(chart.mesh.faces.size()) + " faces; chart 0 has " + std::to_string(np) +
                         " patches");
    std::vector<double> area(np, 0.0);
    double total = 0;
    for (int f = 0; f < chart.mesh.num_faces(); ++f) {
      const int p = chart.face_patch[static_cast<size_t>(f)];
      if (p < 0 || p >= static_cast<int>(np))
        throw InvalidInput("patch areas: chart " + std::to_string(m) + ", face " + std::to_string(f) + " is in patch " +
                           std::to_string(p) + "; expected 0.." + std::to_string(np - 1));
      const double a = face_area(chart.mesh, f);
      area[static_cast<size_t>(p)] += a;
      total += a;
    }
    if (!(total > 0) || !std::isfinite(total))
      throw InvalidInput("patch areas: chart " + std::to_string(m) + " has no finite positive area");
    for (size_t p = 0; p < np; ++p) out[p] = std::max(out[p], area[p] / total);
  }
  return out;
}

std::vector<double> patch_texel_shares(const std::vector<const dissect::Chart*>& charts) {
  if (charts.empty()) throw InvalidInput("patch texel shares: no charts");
  const size_t np = charts.front()->patches.size();
  std::vector<double> out(np, 0.0);
  for (size_t m = 0; m < charts.size(); ++m) {
    const dissect::Chart& chart = *charts[m];
    check_faces(chart.mesh, "patch texel shares");
    if (chart.patches.size() != np || chart.face_patch.size() != chart.mesh.faces.size() ||
        chart.face_uv.size() != chart.mesh.faces.size())
      throw InvalidInput("patch texel shares: chart " + std::to_string(m) + " has " +
                         std::to_string(chart.patches.size()) + " patches, " + std::to_string(chart.face_patch.size()) +
                         " face patch ids and " + std::to_string(chart.face_uv.size()) + " uv triples for " +
                         std::to_string(chart.mesh.faces.size()) + " faces; chart 0 has " + std::to_string(np) +
                         " patches");
    // Per patch the (uv area / 3D area, 3D area) of its faces.
    std::vector<std::vector<std::pair<double, double>>> ratio(np);
    double total = 0;
    for (int f = 0; f < chart.mesh.num_faces(); ++f) {
      const int p = chart.face_patch[static_cast<size_t>(f)];
      if (p < 0 || p >= static_cast<int>(np))
        throw InvalidInput("patch texel shares: chart " + std::to_string(m) + ", face " + std::to_string(f) +
                           " is in patch " + std::to_string(p) + "; expected 0.." + std::to_string(np - 1));
      const double a = face_area(chart.mesh, f);
      if (!(a > 0)) continue;
      total += a;
      const auto& uv = chart.face_uv[static_cast<size_t>(f)];
      const Vec2 e1 = uv[1] - uv[0], e2 = uv[2] - uv[0];
      ratio[static_cast<size_t>(p)].emplace_back(0.5 * std::abs(e1.x() * e2.y() - e1.y() * e2.x()) / a, a);
    }
    if (!(total > 0) || !std::isfinite(total))
      throw InvalidInput("patch texel shares: chart " + std::to_string(m) + " has no finite positive area");
    for (size_t p = 0; p < np; ++p) {
      auto& r = ratio[p];
      if (r.empty()) continue;  // no area: no texels needed beyond the minimum tile
      std::sort(r.begin(), r.end());
      double weight = 0;
      for (const auto& x : r) weight += x.second;
      double acc = 0, median = r.back().first;
      for (const auto& x : r) {
        acc += x.second;
        if (acc >= 0.5 * weight) {
          median = x.first;
          break;
        }
      }
      if (median > 0) out[p] = std::max(out[p], 1.0 / (median * total));
    }
  }
  return out;
}

}  // namespace qs::remesh
