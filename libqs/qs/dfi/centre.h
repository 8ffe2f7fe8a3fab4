#pragma once
// Skeleton nodes moved to the centre of the shape's cross-section. Mean curvature flow contracts a
// curved thin part (a camel's S-shaped neck) toward the chord of its bend, so some nodes of its
// skeleton lie outside the shape (measured: 0.3 to 0.8 of the neck's radius outside at its bend);
// the part warp (bones.h) then carries the segments there, not the part, and the two warped necks
// miss each other half-way. Each node descends the signed distance field within the plane normal
// to its branch (the deepest point of the cross-section, where the medial axis runs), so nodes
// keep their order along the branch.

#include "qs/dfi/grid.h"
#include "qs/dfi/skeleton.h"

namespace qs::dfi {

struct CentreReport {
  int moved = 0;           ///< nodes that moved
  int outside_before = 0;  ///< nodes with sdf >= 0 before
  int outside_after = 0;   ///< and after
  double largest_move = 0; ///< world units
};

/// Moves every node of `s` to the deepest point of `sdf` (negative inside) near it in the plane
/// normal to the skeleton there (for a node of degree 2 the direction between its neighbours, for
/// a terminal the direction from its neighbour; a junction or an isolated node descends freely,
/// but only while it is outside), by a descent with halving steps from one grid spacing down to
/// 1/20 of it. Edges and node numbering are unchanged; recompute the branches' lengths after.
/// Deterministic (each node on its own, from the positions before any moved).
CentreReport centre_skeleton(Skeleton& s, const Grid& sdf);

}  // namespace qs::dfi
