#pragma once
// The base domain's connectivity (patches as quads), made from the patch list alone so that
// meshes with corresponding patches get identical numbers, whatever their chart vertex ids.
//
// Numbering, by first appearance walking the patches in order:
//  - base vertex: corners 0..3 of patch 0, then of patch 1, ... (a corner seen before keeps its id);
//  - base edge: sides 0..3 of patch 0, then of patch 1, ... where side k of a patch runs from its
//    corner k to corner k+1 (mod 4). The patch that meets an edge first (the lower patch index)
//    is its OWNER, and the edge's direction is the owner's side direction. The other patch runs
//    the same edge the other way.

#include <array>
#include <vector>

#include "qs/dissect/dissection.h"

namespace qs::remesh {

/// A (patch, side) pair: side k of a patch runs from corner k to corner (k+1) % 4.
struct PatchSide {
  int patch = -1;
  int side = -1;
};

struct BaseTopology {
  int num_vertices = 0;
  std::vector<std::array<int, 4>> quads;         ///< #P: base vertex of corner k (CCW)
  std::vector<std::array<int, 2>> edges;         ///< #E: (from, to) base vertex, owner's direction
  std::vector<std::array<PatchSide, 2>> edge_sides;  ///< #E: [0] the owner's side, [1] the twin
  std::vector<std::array<int, 4>> side_edge;     ///< #P x 4: base edge of side k
  std::vector<std::array<bool, 4>> side_forward; ///< #P x 4: side k runs its edge's direction
                                                 ///< (true exactly for the owner)
  std::vector<int> valence;                      ///< #V: patches around each base vertex
  std::vector<PatchSide> vertex_corner;          ///< #V: first (patch, corner) that has it
  /// #P: the diagonal used when a whole patch is one cell (uniform level 0, adaptive roots):
  /// true = corner 0 - corner 2, false = corner 1 - corner 3. Rule: corner 0 - corner 2, unless
  /// that pair of base vertices is already joined (by a base edge or an earlier patch's level-0
  /// diagonal) and the other pair is not. With the two seed patches (all four corners of
  /// valence 2) this makes a tetrahedron instead of two copies of the same two triangles.
  std::vector<bool> level0_diagonal02;
  /// #V: chart vertex id of each base vertex. The ONLY field that depends on the chart vertex
  /// ids rather than on the patch structure; equal topologies may differ here.
  std::vector<int> chart_vertex;

  int num_patches() const { return static_cast<int>(quads.size()); }
  int num_edges() const { return static_cast<int>(edges.size()); }
  int euler_characteristic() const { return num_vertices - num_edges() + num_patches(); }
  /// The (patch, side) across side `side` of `patch`.
  PatchSide twin(int patch, int side) const {
    const auto& s = edge_sides[side_edge[patch][side]];
    return (s[0].patch == patch && s[0].side == side) ? s[1] : s[0];
  }
  /// Same patch structure: quads equal (everything else but chart_vertex follows from them).
  bool same_structure(const BaseTopology& other) const { return quads == other.quads; }
};

/// Builds the base topology of a patch list.
/// \pre at least one patch; each patch has 4 distinct corners; the sides form a closed
///      conforming quad mesh: every directed side a->b appears once and its twin b->a once.
/// \throws InvalidInput naming the patch (index and name) and the offending corner or side.
BaseTopology build_base_topology(const std::vector<dissect::PatchInfo>& patches);

}  // namespace qs::remesh
