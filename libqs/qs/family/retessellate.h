#pragma once
// A new tessellation of the same surface, with each new vertex's exact origin on the input: for
// "a shape against its own re-tessellation" and for re-tessellating one mesh of a registered pair
// (README "Correspondence").

#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"
#include "qs/landmarks/landmarks.h"

namespace qs::family {

/// The largest face count retessellate makes (with keep_shape the finer remesh has 9 times as
/// many: koala_100k at its own 100k faces takes 54 s and 0.3 GB, against 2 s isotropically).
inline constexpr int kMaxFaces = 2000000;

struct RetessellateOptions {
  int faces = 0;        ///< target face count (about); 0: the input's. \pre 0 or 100..kMaxFaces
  int iterations = 3;   ///< rounds of isotropic remeshing. \pre 1..20
  /// Keep the shape: remesh isotropically 3 times finer, then collapse edges back to the face
  /// count at the least Lindstrom-Turk cost, so that triangles crowd where the surface bends and
  /// thin parts (fingers, toes) keep their shape. Off: isotropic at the face count, whose chords
  /// cut such parts.
  bool keep_shape = false;
};

struct Retessellation {
  TriMesh mesh;                                  ///< closed, manifold, genus 0 (checked)
  std::vector<landmarks::SurfacePoint> origins;  ///< #V: the input face and weights of each vertex
  double max_origin_distance = 0;  ///< before snapping, the farthest a vertex was from the input
};

/// Isotropic remeshing (CGAL Polygon_mesh_processing, target edge length from the face count,
/// vertices projected onto the input; with keep_shape finer, then simplified back by CGAL
/// Surface_mesh_simplification), then every vertex is placed exactly at its closest point
/// of the input, recorded as (face, barycentric weights). \pre `mesh` is validated (closed,
/// manifold, genus 0). \throws InvalidInput for an option out of range, SolverError when the
/// result is not a closed genus-0 mesh without zero-area faces.
Retessellation retessellate(const TriMesh& mesh, const RetessellateOptions& options = {},
                            const Context& context = {});

}  // namespace qs::family
