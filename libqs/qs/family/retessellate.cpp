#include "qs/family/retessellate.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Surface_mesh.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "qs/core/error.h"
#include "qs/mesh/validate.h"
#include "qs/metro/metro.h"

namespace qs::family {

namespace {

/// Barycentric weights of the point of triangle (a, b, c) closest to p (p is on or very near it).
Vec3 closest_weights(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& p) {
  const Vec3 e0 = b - a, e1 = c - a, r = p - a;
  const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1), d20 = r.dot(e0), d21 = r.dot(e1);
  const double den = d00 * d11 - d01 * d01;
  Vec3 w(1, 0, 0);
  if (den > 0) {
    const double v = (d11 * d20 - d01 * d21) / den, u = (d00 * d21 - d01 * d20) / den;
    w = Vec3(1 - v - u, v, u);
  }
  if (w.minCoeff() < 0) {  // outside by rounding (or on a degenerate face): the nearest edge point
    double best = 1e300;
    const Vec3 pts[3] = {a, b, c};
    for (int i = 0; i < 3; ++i) {
      const Vec3 &s = pts[i], &t = pts[(i + 1) % 3];
      const double len2 = (t - s).squaredNorm();
      const double f = len2 > 0 ? std::clamp((p - s).dot(t - s) / len2, 0.0, 1.0) : 0.0;
      const double d = (s + f * (t - s) - p).squaredNorm();
      if (d < best) {
        best = d;
        w = Vec3::Zero();
        w[i] = 1 - f;
        w[(i + 1) % 3] = f;
      }
    }
  }
  return w;
}

}  // namespace

Retessellation retessellate(const TriMesh& mesh, const RetessellateOptions& options, const Context& context) {
  if (options.faces != 0 && options.faces < 100)
    throw InvalidInput("retessellate: faces = " + std::to_string(options.faces) + " (expected 0 or at least 100)");
  if (options.iterations < 1 || options.iterations > 20)
    throw InvalidInput("retessellate: iterations = " + std::to_string(options.iterations) + " is outside [1, 20]");
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using SM = CGAL::Surface_mesh<K::Point_3>;
  namespace PMP = CGAL::Polygon_mesh_processing;
  SM sm;
  std::vector<SM::Vertex_index> vid;
  vid.reserve(mesh.positions.size());
  for (const Vec3& p : mesh.positions) vid.push_back(sm.add_vertex(K::Point_3(p.x(), p.y(), p.z())));
  double area = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Tri& t = mesh.faces[f];
    if (sm.add_face(vid[t[0]], vid[t[1]], vid[t[2]]) == SM::null_face())
      throw InvalidInput("retessellate: face " + std::to_string(f) + " cannot be added (the mesh is not a validated manifold)");
    area += face_area(mesh, f);
  }
  const int target = options.faces != 0 ? options.faces : mesh.num_faces();
  const double edge = std::sqrt(4 * area / (std::sqrt(3.0) * target));
  context.report("retessellate", 0);
  PMP::isotropic_remeshing(faces(sm), edge, sm, CGAL::parameters::number_of_iterations(options.iterations));
  sm.collect_garbage();
  context.report("retessellate", 0.8);

  Retessellation r;
  std::vector<int> index(sm.number_of_vertices() + sm.number_of_removed_vertices(), -1);
  for (SM::Vertex_index v : sm.vertices()) {
    index[v] = r.mesh.num_vertices();
    const auto& p = sm.point(v);
    r.mesh.positions.emplace_back(p.x(), p.y(), p.z());
  }
  for (SM::Face_index f : sm.faces()) {
    Tri t{};
    int k = 0;
    for (SM::Vertex_index v : vertices_around_face(sm.halfedge(f), sm)) {
      if (k == 3) throw SolverError("retessellate: the remesher produced a face with more than 3 corners");
      t[k++] = index[v];
    }
    r.mesh.faces.push_back(t);
  }
  // Exact origins: each vertex moves to its closest point of the input (it was projected there
  // already, up to rounding) and that point is recorded.
  const metro::SurfaceDistance input(mesh, "input");
  r.origins.resize(r.mesh.positions.size());
  for (int v = 0; v < r.mesh.num_vertices(); ++v) {
    const auto c = input.closest(r.mesh.positions[v]);
    r.max_origin_distance = std::max(r.max_origin_distance, c.distance);
    const Tri& t = mesh.faces[c.face];
    const Vec3 w = closest_weights(mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]], c.point);
    r.origins[v].face = c.face;
    r.origins[v].bary = {w.x(), w.y(), w.z()};
    r.mesh.positions[v] = w.x() * mesh.positions[t[0]] + w.y() * mesh.positions[t[1]] + w.z() * mesh.positions[t[2]];
  }
  const mesh::ValidationResult valid = mesh::validate(r.mesh);
  if (!valid.report.accepted || valid.report.orientation_flipped || mesh::find_problem(valid.report, "zero_area_faces"))
    throw SolverError("retessellate: the new tessellation is not usable (try another --faces):\n" +
                      mesh::format_report("retessellation", valid.report));
  context.report("retessellate", 1);
  return r;
}

}  // namespace qs::family
