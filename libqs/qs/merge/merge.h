#pragma once
// Exact merge of two charts of one dissection (Lee & Huang, "Fast and Intuitive Metamorphosis of
// 3D Polyhedral Models Using SMCC Mesh Merging Scheme", sections 3.5-3.7): in every common patch
// the uv triangulations of mesh A and mesh B are overlaid, and the overlay is triangulated. The
// merged mesh has one face list; its positions on A are exactly A's surface (every input vertex
// of A bitwise) and its positions on B exactly B's, so a linear morph starts and ends on the
// inputs themselves.
//
// Every decision is exact (CGAL's filtered exact predicates on the double uv, exact constructions
// for the crossings): whether a vertex of one mesh lies inside, on an edge of, or on a vertex of
// the other's triangle, whether two edges cross. An overlay face is the intersection of one A
// triangle and one B triangle (convex); its vertices are ordered with exact orientation tests and
// it is cut into triangles that maximize the smallest uv angle (flips of the face's own
// unconstrained diagonals; no vertex moves). Points on a patch side are the chart vertices of A
// and B on it, identified by their chart vertex ids, so that both patches sharing the side use
// the same points in the same order (no cracks, no T-vertices).

#include <string>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"
#include "qs/dissect/dissection.h"

namespace qs::merge {

struct MergeOptions {
  /// Merged faces whose smallest corner angle is below this (degrees) count as slivers
  /// (in uv, and in 3D at t = 0 and t = 1).
  double sliver_degrees = 1.0;
  /// Cut every overlay polygon into the triangles that maximize its smallest uv angle; false: a
  /// fan from its first vertex.
  bool improve_slivers = true;
  /// Worker threads, one patch at a time; 0: Context::threads. Never changes the output.
  int threads = 0;
};

struct MergeStats {
  int patches = 0;
  int input_faces_a = 0, input_faces_b = 0;      ///< chart faces
  int vertices_from_a = 0;                       ///< merged vertices that are A chart vertices
  int vertices_from_b = 0;                       ///< ... that are B chart vertices
  int coincident_vertices = 0;                   ///< ... that are both (corners, features, ...)
  int crossings = 0;                             ///< proper crossings of an A edge and a B edge
  int a_on_b_edge = 0, b_on_a_edge = 0;          ///< a vertex on the other mesh's edge
  int overlay_polygons = 0;
  /// B side points whose uv in the second patch of their side was moved (by a few units in the
  /// last place) to keep the place among A's side points they have in the first.
  int side_points_moved = 0;                      ///< non-empty A triangle x B triangle overlaps
  int slivers_uv = 0, slivers_a = 0, slivers_b = 0;  ///< faces below sliver_degrees
  int input_slivers_a = 0, input_slivers_b = 0;  ///< chart faces below it in 3D, for comparison
  /// Faces with less than 1e-12 of their parent A (B) face's area at t = 0 (t = 1): exact in uv
  /// but too thin for their double positions to have a normal (crossings a rounding apart).
  int thin_faces_a = 0, thin_faces_b = 0;
  /// Other faces whose 3D normal at t = 0 (t = 1) does not point the way of their parent's.
  int normal_disagreements_a = 0, normal_disagreements_b = 0;
  double min_angle_uv = 180, min_angle_a = 180, min_angle_b = 180;  ///< degrees
};

/// The merged mesh: one connectivity, a position array per shape, where each vertex came from.
struct Merged {
  std::vector<Tri> faces;            ///< #F, counter-clockwise seen from outside (as the charts)
  std::vector<Vec3> positions_a;     ///< #V, on A's surface (t = 0)
  std::vector<Vec3> positions_b;     ///< #V, on B's surface (t = 1)
  std::vector<int> vertex_patch;     ///< #V, the lowest-index patch holding the vertex
  std::vector<Vec2> vertex_uv;       ///< #V, its (u, v) there, the exact point rounded to double
  std::vector<int> vertex_a;         ///< #V, the A chart vertex it is, or -1
  std::vector<int> vertex_b;         ///< #V, the B chart vertex it is, or -1
  std::vector<int> face_patch;       ///< #F
  std::vector<int> face_parent_a;    ///< #F, the A chart face that contains it
  std::vector<int> face_parent_b;    ///< #F, the B chart face that contains it
  MergeStats stats;
  TriMesh mesh_a() const { return {positions_a, faces}; }
  TriMesh mesh_b() const { return {positions_b, faces}; }
};

/// Checks a chart's uv exactly: every face's uv triangle is strictly counter-clockwise in its
/// patch (CGAL's exact orientation), every corner of a face that lies on the patch border is on
/// the unit square's border, every vertex has one (u, v) per patch, and the uv areas of each
/// patch sum to 1. \throws InvalidInput naming `name`, the patch and the face.
void check_chart_uv(const dissect::Chart& chart, const std::string& name);

/// Merges the charts of two meshes of one dissection (same patch list, same base domain).
/// The order of A's and B's points along a patch side is decided in the side's lower-index patch;
/// B's uv in the other patch are moved by a few ulps where they disagree (stats.side_points_moved).
/// \throws InvalidInput (from check_chart_uv, or charts whose patches differ); SolverError when a
/// B side point cannot be put between the same two A points in both patches (no double between
/// them) or the merged mesh is not closed.
Merged merge_charts(const dissect::Chart& a, const dissect::Chart& b, const MergeOptions& options = {},
                    const Context& context = {});

}  // namespace qs::merge
