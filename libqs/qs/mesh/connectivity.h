#pragma once
// Compact half-edge connectivity over a TriMesh's own face array, and the sort-based grouping of
// halfedges by undirected edge that both validate() and build_connectivity() use.
//
// Halfedge h = 3*f + k runs from faces[f][k] to faces[f][(k+1)%3]; next/prev stay inside face f.
// Nothing is stored per face or per edge beyond what is below: the TriMesh stays the geometry.

#include <array>
#include <vector>

#include "qs/core/mesh.h"

namespace qs::mesh {

/// Halfedges grouped by undirected edge, edges sorted by (lower vertex id, higher vertex id).
/// Built with a counting sort on the lower vertex and a small sort inside each bucket: O(F).
struct EdgeGroups {
  std::vector<int> halfedges;  ///< all 3F halfedges, edge by edge, ascending within an edge
  std::vector<int> offsets;    ///< #E+1: edge e owns halfedges[offsets[e] .. offsets[e+1])
  std::vector<std::array<int, 2>> vertices;  ///< #E: (lower, higher) vertex id of each edge
  int num_edges() const { return static_cast<int>(vertices.size()); }
  /// How many halfedges (= face sides) edge e has: 1 boundary, 2 manifold, >2 non-manifold.
  int size(int e) const { return offsets[e + 1] - offsets[e]; }
};

/// Groups the 3F halfedges of `faces` by undirected edge.
/// \pre every index is in [0, num_vertices) and no face repeats a vertex (not checked here:
///      validate() filters such faces first, build_connectivity() checks and throws).
EdgeGroups group_halfedges(const std::vector<Tri>& faces, int num_vertices);

/// Half-edge connectivity of an edge-manifold, consistently oriented, vertex-manifold TriMesh
/// (typically one that validate() accepted; open meshes are allowed: opposite[h] = -1 there).
struct Connectivity {
  std::vector<int> opposite;         ///< 3F: the halfedge running the other way, -1 on a boundary
  std::vector<int> vertex_halfedge;  ///< #V: one outgoing halfedge, -1 for an isolated vertex;
                                     ///< on a boundary vertex the outgoing boundary halfedge, so
                                     ///< that a counter-clockwise sweep from it sees the whole fan
  std::vector<int> halfedge_vertex;  ///< 3F: the tail (start vertex) of each halfedge

  int num_halfedges() const { return static_cast<int>(opposite.size()); }
  int num_faces() const { return num_halfedges() / 3; }
  int num_vertices() const { return static_cast<int>(vertex_halfedge.size()); }

  static int next(int h) { return h % 3 == 2 ? h - 2 : h + 1; }
  static int prev(int h) { return h % 3 == 0 ? h + 2 : h - 1; }
  static int face(int h) { return h / 3; }
  /// The first halfedge of face f (the others are +1 and +2).
  static int face_halfedge(int f) { return 3 * f; }

  int tail(int h) const { return halfedge_vertex[h]; }
  int head(int h) const { return halfedge_vertex[next(h)]; }
  bool is_boundary_halfedge(int h) const { return opposite[h] < 0; }
  bool is_boundary_vertex(int v) const {
    return vertex_halfedge[v] >= 0 && opposite[vertex_halfedge[v]] < 0;
  }
  /// The outgoing halfedge of tail(h) that follows h counter-clockwise (seen from outside),
  /// -1 when h is the last one before a boundary.
  int rotate_ccw(int h) const { return opposite[prev(h)]; }

  /// Calls fn(h) for every outgoing halfedge of v, counter-clockwise, starting at
  /// vertex_halfedge[v]. On a boundary vertex the last neighbour, tail(prev(last h)), is reached by
  /// no outgoing halfedge; one_ring() adds it.
  template <class Fn>
  void for_each_outgoing(int v, Fn&& fn) const {
    const int start = vertex_halfedge[v];
    if (start < 0) return;
    int h = start;
    do {
      fn(h);
      h = rotate_ccw(h);
    } while (h >= 0 && h != start);
  }

  /// Neighbouring vertices of v in counter-clockwise order (first and last are on the boundary
  /// when v is a boundary vertex).
  std::vector<int> one_ring(int v) const;
  /// Number of neighbouring vertices of v.
  int valence(int v) const;
};

/// Builds the half-edge connectivity of `mesh`.
/// \pre the faces reference vertices in range, each edge has at most two faces and is used in
///      opposite directions by them, and the faces around each vertex form a single fan.
/// \throws InvalidInput naming the first offending face, edge ("edge 3-7") or vertex otherwise.
Connectivity build_connectivity(const TriMesh& mesh);

}  // namespace qs::mesh
