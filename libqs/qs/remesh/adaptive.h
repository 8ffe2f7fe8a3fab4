#pragma once
// Adaptive semi-regular remeshing (paper 4.2): one quadtree per patch, refined while the node's
// error exceeds epsilon, balanced so that neighbouring leaves differ by at most one level
// (across patch sides too), then triangulated with T-vertex templates. One connectivity for the
// whole set: a node's error is the maximum over the meshes (paper eq. 7).
//
// Quadtree nodes: node (level l, i, j) of a patch covers [i, i+1] x [j, j+1] / 2^l of its unit
// square; its children are (l+1, 2i+a, 2j+b). Every node corner and side midpoint is a point of
// the uniform grid of the finest level L, so the vertices are a subset of the uniform level-L
// vertices, numbered in the same order (semi_regular.h), and shared points along patch sides are
// evaluated exactly as in the uniform remesh.
//
// Error of a node q in one mesh (a better-measured form of eq. 5-6):
//   E(q) = max over samples s of q of dist(s, A(q)) / B,
// where A(q) is q's own flat approximation, the two triangles over its 4 corner points (the
// 3D points at q's uv corners) split by the same diagonal rule as the uniform remesh; dist is the
// Euclidean distance from a 3D point to the nearer of the two triangles; B is the diagonal of the
// mesh's bounding box. The samples of q are (a) every chart vertex whose uv in q's patch lies in
// q's uv square (a chart vertex on a split line goes to one child only) and (b) the 3D points at
// q's 5 level-(l+1) grid points (its centre and side midpoints: the vertices that splitting q
// would add), so that a node smaller than the chart's triangles is measured too.
// The paper's E(q) is the distance to a best-fitting plane; the distance to the triangles that
// are actually output also catches a quad that is flat but does not follow the surface.
// E_C(q) = max over the meshes of the set (eq. 7).
//
// Refinement: a node of level l is split when l < min_level, or when E_C(q) > epsilon and
// l < max_level.
//
// Even sampling (AdaptiveCriterion::Size, remesh_even): instead of E_C, a node is split while its
// share of the surface, A_C(q) = max over the meshes of area(q) / area(mesh), exceeds max_area
// (and l < max_level). area(q) is the area of the 8 triangles over q's 3 x 3 level-(l+1) grid
// points (corners, side midpoints, centre) in that mesh, area(mesh) the chart's surface area. So
// leaves cover about the same area whatever the size of their patch: samples follow the surface,
// not the patch count. remesh_even picks max_area = kEvenAreaFactor / (P 4^n) for a level n: a set
// whose P patches are equal and evenly mapped gets exactly the uniform level-n faces (a level-n
// node covers 1 / (P 4^n) of the surface, its parent 4 / (P 4^n)).
//
// Balancing (2:1, edge neighbours): for every existing node at level k >= 2, the four same-level
// edge neighbours of its parent must exist (be nodes of the trees); a missing one is created by
// splitting its ancestors. The edge neighbour of a node across a patch side is found through the
// base topology: side d of patch p runs opposite to side d' of its twin patch q, so the node at
// position s along side d (counted from corner d, 2^l nodes per side) faces the node at position
// 2^l - 1 - s along side d' of q. Diagonal (corner-only) neighbours are not balanced.
//
// Triangulation of a leaf (C0..C3 its corners CCW, M_d the midpoint of its side d = C_d C_{d+1};
// side d has a T-vertex when the same-level neighbour across it is split):
//  - no T-vertex: two triangles by the uniform diagonal rule (quadrant rule for l >= 1,
//    BaseTopology::level0_diagonal02 for roots), so tiny epsilon gives exactly the uniform
//    level-max_level faces and large epsilon exactly the uniform level-0 faces;
//  - one T-vertex on side d (4 templates): (C_d, M_d, C_{d+3}), (M_d, C_{d+1}, C_{d+2}),
//    (M_d, C_{d+2}, C_{d+3});
//  - two to four T-vertices (11 templates): a fan around the leaf's centre (a grid point of level
//    l+1) over the leaf's border: 4 + (number of T-vertices) triangles.
// A base vertex of valence 2 is never left with a single triangle in a patch, so no two patches
// emit the same triangle there. The result is closed, 2-manifold, with no T-junction.

#include <array>
#include <compare>
#include <vector>

#include "qs/core/context.h"
#include "qs/dissect/dissection.h"
#include "qs/remesh/base_topology.h"
#include "qs/remesh/semi_regular.h"

namespace qs::remesh {

inline constexpr int kMaxAdaptiveLevel = 12;

/// The even remesh's bound for a level n is kEvenAreaFactor / (P 4^n) of the surface (see the top
/// of this file). Any factor in (1, 4) gives equal, evenly mapped patches exactly the uniform level
/// n; 2.3 gives the 26 shared meshes about the uniform level's face count (2 gave 1.14x on average).
inline constexpr double kEvenAreaFactor = 2.3;

/// What splits a quadtree node: its error (the paper's eq. 7) or its share of the surface.
enum class AdaptiveCriterion { Error, Size };

struct AdaptiveOptions {
  AdaptiveCriterion criterion = AdaptiveCriterion::Error;
  double epsilon = 0.0025;  ///< Error: bound on E_C (normalized by the bounding-box diagonal); > 0.
                            ///< 0.0025 is the paper's figure 17
  double max_area = 0;      ///< Size: bound on A_C (a share of the surface, 0..1); > 0 with Size
  int min_level = 0;        ///< every patch is refined at least this far
  int max_level = 6;        ///< no node is split beyond this level; <= kMaxAdaptiveLevel
  /// Cut each leaf without a T-vertex along the diagonal with the larger smallest angle over the
  /// set (uniform.h's DiagonalRule::BestAngle, same exceptions) instead of the pattern's.
  bool best_angle_diagonals = false;
};

/// A quadtree node: (level, i, j) of a patch (see the top of this file).
struct QuadNode {
  int patch = 0, level = 0, i = 0, j = 0;
  auto operator<=>(const QuadNode&) const = default;
};

/// Balanced quadtrees, one per patch.
struct QuadForest {
  std::vector<QuadNode> split;   ///< the split (inner) nodes, sorted by (patch, level, i, j)
  std::vector<QuadNode> leaves;  ///< patch by patch, depth first, children in the order
                                 ///< (2i,2j), (2i+1,2j), (2i,2j+1), (2i+1,2j+1)
  int max_level = 0;             ///< the finest leaf level
};

/// Closes a set of split nodes under "ancestors of a split node are split" and the 2:1 balance
/// rule above, and lists the leaves. The result depends on the split set only (not its order).
/// \throws InvalidInput for a node outside the patches, levels (0..kMaxAdaptiveLevel - 1) or grid.
QuadForest balance_forest(const BaseTopology& topology, const std::vector<QuadNode>& split_nodes);

/// The connectivity of the adaptive remesh of a balanced forest (no geometry needed): vertex
/// order of the uniform level forest.max_level restricted to the vertices used; faces leaf by
/// leaf in forest.leaves order. \pre forest comes from balance_forest for this topology.
SemiRegularConnectivity adaptive_connectivity(const BaseTopology& topology, const QuadForest& forest);

struct AdaptiveStats {
  int evaluated_nodes = 0;       ///< nodes whose E_C (or A_C with Size) was measured
  int error_splits = 0;          ///< nodes split by the refinement rule
  int balance_splits = 0;        ///< nodes split only to keep neighbours within one level
  int unresolved_leaves = 0;     ///< leaves at max_level whose E_C still exceeds epsilon
  double max_unresolved_error = 0;  ///< the largest E_C among them (0 if none)
  double max_leaf_error = 0;     ///< the largest E_C over the leaves the refinement measured
  std::vector<int> leaves_per_level;  ///< index = level
};

struct AdaptiveRemesh {
  SemiRegularSet remesh;         ///< one connectivity, one position array per chart
  QuadForest forest;
  AdaptiveStats stats;
};

/// Adaptive remesh of a set of charts with one connectivity (for one mesh, pass one chart).
/// Reports progress as "remesh" and checks the cancel flag.
/// \pre the charts' patch lists have the same structure (same count, names and base-domain
///      quads), as dissect_set produces.
/// \throws InvalidInput for epsilon <= 0 or not finite, levels out of range, an empty set, charts
///         that do not match chart 0, or an inconsistent chart (see ChartSampler).
AdaptiveRemesh remesh_adaptive(const std::vector<const dissect::Chart*>& charts, const AdaptiveOptions& options = {},
                               const Context& context = {});
AdaptiveRemesh remesh_adaptive(const std::vector<dissect::Chart>& charts, const AdaptiveOptions& options = {},
                               const Context& context = {});

/// Options of the even remesh for a level n (see the top of this file): criterion Size, max_area
/// = kEvenAreaFactor * share_sum / (P 4^n), max_level = min(n + 6, kMaxAdaptiveLevel), min_level 0,
/// best-angle diagonals. share_sum is the sum over the patches of their largest share of a mesh's
/// surface over the set (patch_area_shares; 1 for one mesh): a set's leaves follow the largest
/// share, so the bound grows with it to keep about the uniform level's face count.
/// \throws InvalidInput for a level outside 0..kMaxAdaptiveLevel, patches < 1 or share_sum < 1.
AdaptiveOptions even_options(int level, int patches, double share_sum = 1.0);

/// The even remesh for a level n: remesh_adaptive with even_options(n, patch count, the sum of
/// patch_area_shares). About the uniform level n's face count, spread over the surface by area.
AdaptiveRemesh remesh_even(const std::vector<const dissect::Chart*>& charts, int level, const Context& context = {});

}  // namespace qs::remesh
