#pragma once
// Curve skeletons of closed triangle meshes of any genus: CGAL's mean curvature flow
// skeletonization (Tagliasacchi et al. 2012), kept behind this header (CGAL is slow to compile).

#include <array>
#include <vector>

#include "qs/core/mesh.h"

namespace qs::dfi {

/// A curve skeleton: a graph of points inside the shape; cycles where the shape has handles.
struct Skeleton {
  std::vector<Vec3> nodes;
  std::vector<std::array<int, 2>> edges;
  std::vector<std::vector<int>> node_vertices;  ///< per node, the mesh vertices that collapsed onto it
};

/// \pre mesh closed, manifold, oriented (any genus). \throws SolverError when CGAL fails.
/// CGAL's skeletonization collapses edges in the order of their handles' addresses; its
/// containers allocate from an arena of their own (skeleton.cpp), in allocation order, so the
/// result depends on the mesh alone, not on what the process allocated before (with the default
/// allocator horse_5k gave 267 then 248 nodes when called twice in one process).
Skeleton curve_skeleton(const TriMesh& mesh);

/// A skeleton path between two feature nodes (degree != 2), through nodes of degree 2. A cycle
/// without feature nodes is one branch that starts and ends at its lowest node.
struct Branch {
  int a = 0, b = 0;          ///< end nodes
  std::vector<int> nodes;    ///< a ... b along the path
  double length = 0;
  /// The point at arc-length fraction s in [0, 1] from a.
  Vec3 at(const Skeleton& s, double fraction) const;
};

/// Every branch, in a deterministic order (by the lowest end node, then the first step).
std::vector<Branch> skeleton_branches(const Skeleton& s);

/// Removes terminal branches (a degree-1 end, the other end a junction) shorter than
/// `min_length`, repeatedly, their mesh vertices handed to the junction; nodes renumbered in order.
/// Mean curvature flow leaves such short spurs where a surface bulges slightly.
void prune_skeleton(Skeleton& s, double min_length);

/// Node degrees.
std::vector<int> node_degrees(const Skeleton& s);

}  // namespace qs::dfi
