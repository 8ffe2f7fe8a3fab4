#pragma once
// Polygonization of the zero level set of a sampled field by marching tetrahedra.
//
// Every grid cell is cut into the 6 tetrahedra of its Kuhn (Freudenthal) subdivision, the same
// for all cells, so neighbouring cells agree on their shared faces. In a tetrahedron the trilinear
// field is replaced by the linear one through its 4 samples, whose zero set is a planar triangle
// or quad. The result is the exact zero set of one continuous piecewise-linear function: closed
// (when every boundary sample is positive), a 2-manifold, free of self-intersections and, with
// negative = inside, oriented outward. Samples exactly 0 count as outside. A vertex is created
// once per crossed grid edge, so the surface is watertight by construction.

#include "qs/core/mesh.h"
#include "qs/dfi/grid.h"

namespace qs::dfi {

struct PolygonizeOptions {
  /// A sample closer to zero than this (times the spacing) is moved to +tolerance, so that no
  /// surface vertex lands on a grid sample (two coincident vertices).
  double snap_tolerance = 1e-4;
};

/// The zero level set of `field` (negative inside), triangles counter-clockwise seen from outside.
/// Positions are in world units. \throws InvalidInput when a sample on the grid's boundary is
/// negative (the surface would be cut open) or a value is not finite, naming the sample.
TriMesh polygonize(const Grid& field, const PolygonizeOptions& options = {});

/// Topology and size of a closed triangle mesh (what dfi.json reports per frame).
struct MeshStats {
  int vertices = 0, faces = 0, edges = 0;
  int components = 0;      ///< connected through shared vertices
  int genus = 0;           ///< sum over components of (2 - chi_c) / 2
  double volume = 0;       ///< signed volume (positive for an outward closed mesh)
  bool closed_manifold = false;  ///< every edge has exactly two faces, in opposite directions
};
MeshStats mesh_stats(const TriMesh& mesh);

}  // namespace qs::dfi
