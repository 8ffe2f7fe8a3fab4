#pragma once
// A coarser tessellation of a closed manifold surface by edge collapses, in passes. Each pass takes
// the edges shortest first and collapses each to its midpoint, unless a vertex of its two rings was
// moved in this pass, the collapse would change the topology (link condition), or a face would turn
// by more than about 70 degrees or become a sliver worse than the faces it replaces. Linear in the
// faces per pass; the passes shrink geometrically. For a coarse proxy (the registration's early
// stages), not for a faithful simplification: tips are rounded off.

#include "qs/core/mesh.h"

namespace qs::mesh {

/// `mesh` collapsed to about `faces` faces (more where every remaining collapse is refused), its
/// vertices in the order of the input's that remain. Deterministic.
/// \pre mesh a closed manifold triangle mesh (qs::mesh::validate).
TriMesh simplify(const TriMesh& mesh, int faces);

}  // namespace qs::mesh
