#pragma once
// Floater mean-value parameterization of a quad patch onto the unit square (paper 3.1), and
// Sander et al. 2001 L2 stretch (paper 3.2).

#include <array>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"

namespace qs::param {

/// One patch as its own small mesh. A topological disk, faces CCW seen from outside.
struct PatchMesh {
  std::vector<Vec3> positions;  ///< #V local vertices
  std::vector<Tri> faces;       ///< #F, local ids
  /// The boundary loop in CCW order (the patch on the left when walking it), starting at
  /// corner 0; each consecutive pair is a boundary edge, and the last joins back to the first.
  std::vector<int> boundary;
  /// Indices into `boundary` of corners 0..3: corner_index[0] == 0 < [1] < [2] < [3].
  std::array<int, 4> corner_index{};
};

struct SquareParamOptions {
  double min_edge_length = 1e-12;  ///< shorter 3D edges get this length in the weights
};

/// A parameterization: corners at (0,0) (1,0) (1,1) (0,1), CCW.
struct SquareParam {
  std::vector<Vec2> uv;     ///< #V
  int flipped_faces = 0;    ///< UV faces with negative signed area (computed, never assumed)
  int zero_area_faces = 0;  ///< UV faces with |signed area| <= 1e-14
  double uv_area_sum = 0;   ///< sum of signed UV areas; 1 for a valid map
  bool bijective() const { return flipped_faces == 0 && zero_area_faces == 0; }
};

/// Interior edges joining two boundary vertices of the same square side (a corner counts on both
/// of its sides), and faces with all three vertices on one side: both make zero-area UV faces.
/// Returns the local vertex pairs (a, b) of the edges to split (at their midpoints) before
/// solving so that every face gets an interior vertex; empty when the patch is clean.
std::vector<std::array<int, 2>> border_degeneracies(const PatchMesh& patch);

/// Border by arc length on each side (3D edge lengths), interior by mean-value weights, one
/// sparse LU solve (Eigen SparseLU, COLAMD) for u and v together.
/// \pre patch is a disk with a valid boundary loop and 4 distinct corners (checked: InvalidInput).
/// \throws SolverError if the factorization fails.
SquareParam parameterize_square(const PatchMesh& patch, const SquareParamOptions& options = {},
                                const Context& context = {});

/// L2 stretch (Sander, Snyder, Gortler, Hoppe 2001), normalized by sqrt(total UV area / total 3D
/// area) so that a map that is an isometry up to scale scores exactly 1.
struct Stretch {
  std::vector<double> face;  ///< #F per-face normalized L2 stretch (infinity for zero-area UV)
  double patch = 0;          ///< area-weighted RMS over the faces (3D area weights), normalized
  double area3d = 0;         ///< total 3D area of the patch
};
Stretch l2_stretch(const std::vector<Vec3>& positions, const std::vector<Tri>& faces,
                   const std::vector<Vec2>& uv);

}  // namespace qs::param
