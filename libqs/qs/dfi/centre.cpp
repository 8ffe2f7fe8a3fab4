#include "qs/dfi/centre.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace qs::dfi {
namespace {

Vec3 gradient(const Grid& g, const Vec3& p) {
  const double h = 0.5 * g.spacing;
  return Vec3(g.sample(p + Vec3(h, 0, 0)) - g.sample(p - Vec3(h, 0, 0)),
              g.sample(p + Vec3(0, h, 0)) - g.sample(p - Vec3(0, h, 0)),
              g.sample(p + Vec3(0, 0, h)) - g.sample(p - Vec3(0, 0, h))) /
         (2 * h);
}

}  // namespace

CentreReport centre_skeleton(Skeleton& s, const Grid& sdf) {
  CentreReport report;
  const size_t n = s.nodes.size();
  std::vector<std::vector<int>> adjacent(n);
  for (const auto& e : s.edges) {
    adjacent[e[0]].push_back(e[1]);
    adjacent[e[1]].push_back(e[0]);
  }
  const std::vector<Vec3> before = s.nodes;
  for (size_t v = 0; v < n; ++v) {
    Vec3 tangent = Vec3::Zero();
    if (adjacent[v].size() == 2) tangent = before[adjacent[v][1]] - before[adjacent[v][0]];
    else if (adjacent[v].size() == 1) tangent = before[v] - before[adjacent[v][0]];
    const bool free = tangent.norm() == 0;
    if (!free) tangent.normalize();
    Vec3 x = before[v];
    double d = sdf.sample(x);
    if (d >= 0) ++report.outside_before;
    if (free && d < 0) continue;  // a junction inside stays where the flow put it
    double step = sdf.spacing;
    for (int it = 0; it < 200 && step > 0.05 * sdf.spacing; ++it) {
      if (free && d < 0) break;
      Vec3 g = gradient(sdf, x);
      if (!free) g -= g.dot(tangent) * tangent;
      const double len = g.norm();
      if (!(len > 1e-12)) break;
      const Vec3 y = x - step * g / len;
      const double e = sdf.sample(y);
      if (e < d) {
        x = y;
        d = e;
      } else {
        step *= 0.5;
      }
    }
    if (d >= 0) ++report.outside_after;
    const double move = (x - before[v]).norm();
    if (move > 0) {
      ++report.moved;
      report.largest_move = std::max(report.largest_move, move);
    }
    s.nodes[v] = x;
  }
  return report;
}

}  // namespace qs::dfi
