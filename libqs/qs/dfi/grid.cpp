#include "qs/dfi/grid.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "qs/core/error.h"

namespace qs::dfi {

void Grid::locate(const Vec3& p, int c[3], double f[3]) const {
  const Vec3 q = (p - origin) / spacing;
  for (int a = 0; a < 3; ++a) {
    const double x = std::clamp(q[a], 0.0, static_cast<double>(dims[a] - 1));
    c[a] = std::min(static_cast<int>(std::floor(x)), dims[a] - 2);
    f[a] = x - c[a];
  }
}

double Grid::sample(const Vec3& p) const {
  int c[3];
  double f[3];
  locate(p, c, f);
  double v = 0;
  for (int corner = 0; corner < 8; ++corner) {
    const int dx = corner & 1, dy = (corner >> 1) & 1, dz = (corner >> 2) & 1;
    const double w = (dx ? f[0] : 1 - f[0]) * (dy ? f[1] : 1 - f[1]) * (dz ? f[2] : 1 - f[2]);
    if (w != 0) v += w * values[index(c[0] + dx, c[1] + dy, c[2] + dz)];
  }
  return v;
}

Grid grid_over(const Box3& box, int cells, int pad) {
  if (cells < 4) throw InvalidInput("grid: " + std::to_string(cells) + " cells along the longest side; expected at least 4");
  const Vec3 extent = box.max - box.min;
  const double longest = extent.maxCoeff();
  if (!(longest > 0) || !std::isfinite(longest))
    throw InvalidInput("grid: the bounding box is empty or not finite");
  Grid g;
  g.spacing = longest / cells;
  for (int a = 0; a < 3; ++a) {
    const int inner = std::max(1, static_cast<int>(std::ceil(extent[a] / g.spacing - 1e-9)));
    g.dims[a] = inner + 2 * pad + 1;
    // centre the box in the grid along this axis
    g.origin[a] = box.min[a] - (pad + 0.5 * (inner * g.spacing - extent[a]) / g.spacing) * g.spacing;
  }
  return g;
}

}  // namespace qs::dfi
