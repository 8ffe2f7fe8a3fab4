// Sander et al. 2001 L2 stretch of a parameterized patch (paper 3.2), normalized for scale.

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <string>

#include "qs/core/error.h"
#include "qs/param/square_param.h"

namespace qs::param {

Stretch l2_stretch(const std::vector<Vec3>& positions, const std::vector<Tri>& faces,
                   const std::vector<Vec2>& uv) {
  const int nv = static_cast<int>(positions.size());
  if (uv.size() != positions.size())
    throw InvalidInput("l2_stretch: " + std::to_string(uv.size()) + " uv coordinates for " +
                       std::to_string(nv) + " vertices (expected one per vertex)");
  for (std::size_t f = 0; f < faces.size(); ++f)
    for (int v : faces[f])
      if (v < 0 || v >= nv)
        throw InvalidInput("l2_stretch: face " + std::to_string(f) + " has vertex id " + std::to_string(v) +
                           " outside [0, " + std::to_string(nv) + ")");

  constexpr double kInf = std::numeric_limits<double>::infinity();
  Stretch result;
  result.face.assign(faces.size(), 0.0);
  double area_uv = 0;
  double weighted = 0;  // sum of L2_f^2 * A3D_f (raw, before normalization)
  bool any_bad = false;
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const Tri& t = faces[f];
    const Vec3 &q1 = positions[t[0]], &q2 = positions[t[1]], &q3 = positions[t[2]];
    const double s1 = uv[t[0]].x(), s2 = uv[t[1]].x(), s3 = uv[t[2]].x();
    const double t1 = uv[t[0]].y(), t2 = uv[t[1]].y(), t3 = uv[t[2]].y();
    const double a3 = 0.5 * (q2 - q1).cross(q3 - q1).norm();
    result.area3d += a3;
    const double a = 0.5 * ((s2 - s1) * (t3 - t1) - (s3 - s1) * (t2 - t1));  // signed UV area
    if (!(a > 0)) {  // flipped, zero or NaN: the map is not a parameterization here
      result.face[f] = kInf;
      any_bad = true;
      continue;
    }
    area_uv += a;
    const Vec3 ss = (q1 * (t2 - t3) + q2 * (t3 - t1) + q3 * (t1 - t2)) / (2 * a);
    const Vec3 st = (q1 * (s3 - s2) + q2 * (s1 - s3) + q3 * (s2 - s1)) / (2 * a);
    const double l2sq = 0.5 * (ss.squaredNorm() + st.squaredNorm());
    result.face[f] = std::sqrt(l2sq);
    if (a3 > 0) weighted += l2sq * a3;  // zero-area 3D faces weigh nothing
  }

  // Normalization: with sigma = sqrt(total UV area / total 3D area), every value is multiplied
  // by sigma. Scaling the surface by k multiplies the raw stretch by k and sigma by 1/k.
  // Without any 3D area there is nothing to stretch: values are left raw and the patch is 0.
  const double sigma = result.area3d > 0 ? std::sqrt(area_uv / result.area3d) : 1.0;
  if (std::isfinite(sigma) && sigma != 1.0)
    for (double& x : result.face)
      if (std::isfinite(x)) x *= sigma;
  if (any_bad) result.patch = kInf;
  else if (result.area3d > 0) result.patch = sigma * std::sqrt(weighted / result.area3d);
  else result.patch = 0;
  return result;
}

}  // namespace qs::param
