#include "qs/family/retessellate.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Bounded_normal_change_filter.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Count_stop_predicate.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/LindstromTurk_cost.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/LindstromTurk_placement.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "qs/core/error.h"
#include "qs/landmarks/landmarks.h"
#include "qs/mesh/validate.h"
#include "qs/metro/metro.h"

namespace qs::family {

namespace {

// 4 sqrt(3) area / (sum of squared edges): 1 for an equilateral triangle, 0 for a flat one.
template <class P>
double triangle_quality(const P& a, const P& b, const P& c) {
  const Vec3 x(a.x(), a.y(), a.z()), y(b.x(), b.y(), b.z()), z(c.x(), c.y(), c.z());
  const double e = (y - x).squaredNorm() + (z - y).squaredNorm() + (x - z).squaredNorm();
  return e > 0 ? 2 * std::sqrt(3.0) * (y - x).cross(z - x).norm() / e : 0;
}

// Refuses a collapse whose new triangles would be worse than kMinQuality and than the worst of
// those it replaces (Lindstrom-Turk alone leaves needles and caps along ridges).
struct ShapeFilter {
  static constexpr double kMinQuality = 0.2;
  template <typename Profile>
  boost::optional<typename Profile::Point> operator()(const Profile& profile,
                                                      boost::optional<typename Profile::Point> op) const {
    if (!op) return op;
    const auto& vpm = profile.vertex_point_map();
    const auto& triangles = profile.triangles();
    auto it = triangles.begin();
    double before = 1, after = 1;
    for (int k = 0; it != triangles.end(); ++it, ++k) {
      const auto& t = *it;
      before = std::min(before, triangle_quality(get(vpm, t.v0), get(vpm, t.v1), get(vpm, t.v2)));
      const bool removed = (k == 0 && profile.left_face_exists()) ||
                           (k == (profile.left_face_exists() ? 1 : 0) && profile.right_face_exists());
      if (!removed) after = std::min(after, triangle_quality(get(vpm, t.v0), *op, get(vpm, t.v2)));
    }
    if (after < kMinQuality && after < before) return boost::none;
    return op;
  }
};

}  // namespace

Retessellation retessellate(const TriMesh& mesh, const RetessellateOptions& options, const Context& context) {
  if (options.faces != 0 && (options.faces < 100 || options.faces > kMaxFaces))
    throw InvalidInput("retessellate: faces = " + std::to_string(options.faces) + " (expected 0 or 100.." +
                       std::to_string(kMaxFaces) + ")");
  if (options.faces == 0 && mesh.num_faces() > kMaxFaces)
    throw InvalidInput("retessellate: the mesh has " + std::to_string(mesh.num_faces()) +
                       " faces; give --faces (at most " + std::to_string(kMaxFaces) + ")");
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
  if (options.keep_shape) {
    // 9 times the faces, then back to the count: the collapses go first where they change the
    // volume and shape least (flat parts), which leaves the triangles where the surface bends.
    namespace SMS = CGAL::Surface_mesh_simplification;
    PMP::isotropic_remeshing(faces(sm), edge / 3, sm, CGAL::parameters::number_of_iterations(options.iterations));
    sm.collect_garbage();
    context.report("retessellate", 0.5);
    SMS::Count_stop_predicate<SM> stop(static_cast<std::size_t>(1.5 * target));  // edges = 1.5 faces
    SMS::Bounded_normal_change_filter<ShapeFilter> filter;
    SMS::edge_collapse(sm, stop,
                       CGAL::parameters::get_cost(SMS::LindstromTurk_cost<SM>())
                           .get_placement(SMS::LindstromTurk_placement<SM>())
                           .filter(filter));
  } else {
    PMP::isotropic_remeshing(faces(sm), edge, sm, CGAL::parameters::number_of_iterations(options.iterations));
  }
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
    const auto w = landmarks::closest_on_triangle(c.point, mesh.positions[t[0]], mesh.positions[t[1]],
                                                  mesh.positions[t[2]]);
    r.origins[v].face = c.face;
    r.origins[v].bary = w;
    r.mesh.positions[v] = w[0] * mesh.positions[t[0]] + w[1] * mesh.positions[t[1]] + w[2] * mesh.positions[t[2]];
  }
  const mesh::ValidationResult valid = mesh::validate(r.mesh);
  if (!valid.report.accepted || valid.report.orientation_flipped || mesh::find_problem(valid.report, "zero_area_faces"))
    throw SolverError("retessellate: the new tessellation is not usable (try another --faces):\n" +
                      mesh::format_report("retessellation", valid.report));
  context.report("retessellate", 1);
  return r;
}

}  // namespace qs::family
