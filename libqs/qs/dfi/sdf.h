#pragma once
// Signed distance fields of closed, outward-oriented triangle meshes of any genus, sampled on a
// regular grid (our own; OpenVDB is not used: see README "qs-dfi", the measured choice).
//
// Distance: the exact Euclidean distance to the nearest surface point (qs::metro's bounding-volume
// tree) at every sample within `band` cells of a triangle's bounding box; farther samples take the
// nearest of their neighbours' closest surface points, propagated by eight raster sweeps (a
// closest-point transform: exact near the surface, within a small fraction of a cell elsewhere).
// Sign: negative inside. A sample is inside when the winding number of the surface around it is
// non-zero, counted along the grid row through it in +x (each triangle crossing the row adds +1
// when entering, -1 when leaving; rows are offset by 1e-7 cells to avoid hitting edges exactly,
// and an edge shared by two triangles is evaluated once, so a row never slips between them).

#include <functional>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"
#include "qs/dfi/grid.h"

namespace qs::dfi {

struct SdfOptions {
  int band = 3;     ///< cells around each triangle with exact distances; 0: exact everywhere
  int threads = 0;  ///< 0: Context::threads; the result does not depend on it
};

/// Samples the signed distance of `mesh` on `domain`'s samples (domain.values is ignored).
/// \pre mesh is closed and consistently oriented outward (qs::mesh::validate accepted it,
///      genus aside); positions are finite.
/// \throws InvalidInput for a mesh with no faces or an option out of range.
Grid signed_distance(const TriMesh& mesh, const Grid& domain, const SdfOptions& options = {},
                     const Context& ctx = {});

/// The inside/outside classification alone (true = inside), as used by signed_distance().
std::vector<char> inside_mask(const TriMesh& mesh, const Grid& domain);

}  // namespace qs::dfi
