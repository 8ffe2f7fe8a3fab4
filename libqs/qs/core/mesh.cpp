#include "qs/core/mesh.h"

#include <cmath>

namespace qs {

Box3 bounding_box(const std::vector<Vec3>& positions) {
  Box3 box;
  if (positions.empty()) return box;
  box.min = box.max = positions.front();
  for (const Vec3& p : positions) {
    box.min = box.min.cwiseMin(p);
    box.max = box.max.cwiseMax(p);
  }
  return box;
}

double face_area(const TriMesh& mesh, int f) {
  const Tri& t = mesh.faces[f];
  const Vec3& a = mesh.positions[t[0]];
  return 0.5 * (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a).norm();
}

double surface_area(const TriMesh& mesh) {
  double s = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) s += face_area(mesh, f);
  return s;
}

std::vector<Vec3> vertex_normals(const std::vector<Vec3>& positions, const std::vector<Tri>& faces) {
  std::vector<Vec3> n(positions.size(), Vec3::Zero());
  for (const Tri& t : faces) {
    // |cross| = twice the area: the sum is area-weighted.
    const Vec3 c = (positions[t[1]] - positions[t[0]]).cross(positions[t[2]] - positions[t[0]]);
    for (int v : t) n[v] += c;
  }
  for (Vec3& v : n) {
    const double len = v.norm();
    v = len > 0 && std::isfinite(len) ? Vec3(v / len) : Vec3(0, 0, 1);
  }
  return n;
}

Eigen::Matrix4d fit_similarity(const std::vector<Vec3>& from, const std::vector<Vec3>& to, bool with_scale) {
  const Eigen::Index n = static_cast<Eigen::Index>(from.size());
  Eigen::Matrix3Xd a(3, n), b(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    a.col(i) = from[static_cast<size_t>(i)];
    b.col(i) = to[static_cast<size_t>(i)];
  }
  return Eigen::umeyama(a, b, with_scale);
}

}  // namespace qs
