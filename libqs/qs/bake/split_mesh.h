#pragma once
// The coarse (remesh) mesh as the baker and the GLB see it: every remesh face belongs to one
// patch, and a remesh vertex on a patch side or corner is split into one copy per patch that uses
// it, because its atlas coordinates differ per patch. Copies keep the identical position and the
// same smooth normal (the surface and its shading stay watertight); each copy gets the tangent
// frame of its own patch's (u, v).

#include <array>
#include <vector>

#include "qs/core/mesh.h"
#include "qs/remesh/base_topology.h"
#include "qs/remesh/semi_regular.h"

namespace qs::bake {

struct SplitMesh {
  std::vector<Vec3> positions;                  ///< #S, copies of remesh vertices
  std::vector<Tri> faces;                       ///< #F, the remesh faces in their order, on split ids
  std::vector<int> face_patch;                  ///< #F
  std::vector<int> source_vertex;               ///< #S: the remesh vertex of each split vertex
  std::vector<int> vertex_patch;                ///< #S
  std::vector<Vec2> vertex_uv;                  ///< #S: (u, v) in vertex_patch
  std::vector<Vec3> normals;                    ///< #S unit: the remesh vertex's angle-weighted normal
  std::vector<std::array<double, 4>> tangents;  ///< #S: xyz unit, perpendicular to the normal; w = +-1
  int num_vertices() const { return static_cast<int>(positions.size()); }
  int num_faces() const { return static_cast<int>(faces.size()); }
};

/// Angle-weighted vertex normals (Thuermer & Wuethrich): each face adds its unit normal times its
/// corner angle. Faces with a zero-length edge or zero area add nothing; a vertex left without
/// any contribution gets the area-weighted normal of its faces, or (0, 0, 1).
std::vector<Vec3> vertex_normals(const TriMesh& mesh);

/// Splits a remesh per patch and gives it normals and tangents.
///
/// A face's patch is the patch that holds all three corners (a corner of the square belongs to
/// every patch around its base vertex, a side point to the two patches of its side, with the side
/// fraction mirrored for the twin) in which the face's (u, v) triangle is counter-clockwise; when
/// several do, the one with the largest (u, v) area. Tangents: per split vertex the sum over its
/// faces of dP/du weighted by the face's (u, v) area, Gram-Schmidt against the normal; w = +1 when
/// (N x T) points along dP/dv (the usual case), else -1.
/// \pre `topology` is the base topology of the dissection the remesh was made from.
/// \throws InvalidInput when sizes disagree, a vertex's (patch, u, v) is out of range or a face's
///         corners share no patch with a counter-clockwise (u, v) triangle (naming the face).
SplitMesh split_by_patch(const remesh::SemiRegularConnectivity& connectivity, const std::vector<Vec3>& positions,
                         const remesh::BaseTopology& topology);

}  // namespace qs::bake
