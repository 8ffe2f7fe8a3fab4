#pragma once
// Anisotropic even remesh (issue 13): like remesh_even (adaptive.h), leaves of about equal surface
// area, but a node may be split in u only or in v only, so that cells on a long, anisotropically
// mapped patch (a leg, an arm) end near square on the surface instead of keeping the patch's 5:1.
//
// Nodes: node (lu, lv, i, j) of a patch covers [i, i+1] / 2^lu x [j, j+1] / 2^lv of its unit
// square. A split is U (children (lu+1, lv, 2i+a, j), a = 0, 1), V (children (lu, lv+1, i, 2j+b))
// or UV (the four (lu+1, lv+1, 2i+a, 2j+b), in the order ab = 00, 10, 01, 11). Every node corner,
// side midpoint and centre is a point of the uniform grid of level max(lu, lv) + 1, so the
// vertices are a subset of a uniform level-L grid's, numbered in its order (semi_regular.h), and
// points on patch sides are evaluated exactly as in the uniform remesh.
//
// Measures of a node in one mesh, from the 3D points at its 3 x 3 grid points (corners C, side
// midpoints M, centre X): area(q) = the area of the 8 triangles; Su = the length along u (mean of
// the polylines C0 M0 C1, M3 X M1 (counted twice) and C3 M2 C2), Sv the same along v. Over the set:
// A_C(q) = the largest area(q) / area(mesh) (as remesh_even); the aspect log r(q) = the midrange
// of log(Su / Sv) over the meshes (> 0: long along u) and its spread w(q) = half their range, so
// that |log r| + w is the worst mesh's |log(Su / Sv)| and a split that shifts every mesh's log by
// log 2 helps the worst mesh exactly when |log r| > log(2) / 2 (one mesh: the plain aspect).
//
// Refinement (all meshes together, so the set keeps one connectivity): a node is split when
// A_C(q) > max_area, or when the worst mesh's aspect exceeds max_aspect (|log r| + w >
// log max_aspect), a split along the long direction helps it (|log r| > log(2) / 2) and
// A_C(q) > max_area / 16 (so that a map that degenerates at a point is not refined to max_level).
// The split is U when log r > log(max_aspect) / 2, V when log r < -log(max_aspect) / 2, UV
// otherwise (a split for the aspect alone: U or V by the sign of log r). A direction already at
// max_level is not split (the other one alone when the area asks for it; a node that can split in
// neither stays an unresolved leaf). A split along the long direction halves the aspect, so the
// leaves stay near max_aspect or below (up to the map's variation inside the node, and where the
// meshes of a set disagree). A node that spans its whole patch in one direction (lu = 0 or lv = 0)
// is never split in the other direction alone (UV instead): no leaf side inside a patch then joins
// two points of the patch's border, which another patch could join too (the two seed patches
// share all four sides).
//
// Balancing (shape, not correctness): across every side of every leaf, the leaf on the other side
// (in the twin patch across a patch side) is at most one level coarser along that side than the
// leaf: side d = 0, 2 runs along u (level lu), d = 1, 3 along v (level lv); across a patch side the
// twin's side runs along its own u or v. A leaf that is too coarse is split along the needed
// direction: U or V alone when that direction is its long one (log r beyond log(max_aspect) / 2),
// UV otherwise, so that balancing never makes a leaf longer than its parent. So every leaf side
// has at most one hanging vertex (its midpoint).
//
// Triangulation of a leaf (C0..C3 its corners CCW; a hanging vertex of a side is any leaf corner
// strictly inside it; across a patch side the twin patch's leaf corners count, through the shared
// side samples):
//  - no hanging vertex and at most one side on the patch's border: two triangles, cut along the
//    diagonal with the larger smallest angle over the set (ties: uniform.h's quadrant pattern);
//    the diagonal joins at most one point of the border, so no other patch can emit the edge;
//  - no hanging vertex at a patch corner (two adjacent border sides): two triangles cut through
//    the patch corner, or along the other diagonal when that has the larger smallest angle and
//    the corner's base vertex has valence >= 3 (at valence 2 the other diagonal's two border
//    points are the neighbour patch's too);
//  - one hanging vertex M on side d and at most one border side: (C_d, M, C_d+3),
//    (M, C_d+1, C_d+2), (M, C_d+2, C_d+3) (adaptive.h's template), re-cut as the fan from C_d+2 or
//    from C_d+3 over the pentagon when that has the larger smallest angle over the set (before and
//    after the smoothing; each inner edge still joins at most one border point);
//  - otherwise: a fan around the leaf's centre (an interior point of the patch, used by no other
//    patch) over the leaf's border with its hanging vertices: 4 + (hanging vertices) triangles.
// Each leaf side piece is shared by exactly the two leaves beside it (or the two patches of a
// base edge), so the result is closed, 2-manifold, with no T-junction, whatever the tree.
//
// Smoothing (after the cut): the vertices inside a patch's square whose ring of triangles has a
// smallest angle under smooth_below degrees (in the worst mesh of the set) move within their
// patch, sweep after sweep (Gauss-Seidel in vertex order, at most smooth_iterations sweeps): each
// mesh proposes the step in uv that takes the vertex to its ring's area-weighted centroid of
// triangle centroids in 3D, mapped back to uv through the least-squares affine map of the ring's
// edges; the set moves by the mean of the proposals (one uv per vertex, so the connectivity and
// the correspondence stay common), halved up to twice when a ring face would flip or shrink to
// under 5% in uv, and kept only when the ring's worst smallest angle over the set rises, or when
// the sum over the set of its triangles' sin(smallest angle), each capped at sin(smooth_below),
// rises while the worst keeps at least 0.9 of its sine (so the smallest angle may drop a little
// where the ring as a whole gains; figures in README). A moved
// vertex is evaluated through the chart at its new uv, so it stays on the surface; corners (seeds)
// and the connectivity do not move, patch-side vertices move only along their side (see
// "Sliding" below). The two-triangle cells are cut again
// by the better diagonal afterwards. vertex_uv then holds the moved (u, v).
//
// Edge flips (after the smoothing and the re-cuts; issue 13): where the chart's map shears (the u
// and v directions meet at a small angle on the surface) every cell is a thin parallelogram, and
// no cut of a cell, no split and no affine-invariant smoothing gives its triangles a smallest angle
// above the shear angle (qs-bench-slivers: on camel and lion 99% of the level-4 faces under 10
// degrees are in cells with a 3D corner angle under 30 degrees, 92-95% with leaf_aspect < 1.5).
// Flipping edges across cells finds the lattice's short vectors instead. An edge is flipped when
// its two triangles lie in one patch (each has a patch-interior corner in it), the worst smallest
// angle of the two over the set is under smooth_below and rises with the flip, the new edge has a
// patch-interior end and is not an edge yet, and both new triangles are counter-clockwise in the
// patch's (u,v) (so qs-bake still finds every face's patch). One decision for the whole set (the
// connectivity stays common), no vertex moves (features stay exact), no edge along a patch side
// changes (no T-junction, the patch structure stays). The new edge must also stay as close to the
// surface as the old one (its 3D midpoint's distance along the pair's normal from the chart's
// point at its (u,v) midpoint: at most the old edge's, 0.005 of its length, or the largest of the
// pair's four sides' distances, measured the same way, in a set: there a mesh sampled more
// coarsely than the remesh has chords off its surface everywhere, and its old diagonal happening
// to lie on one chart face must not block the flip another mesh needs) and the pair's area
// may grow by 5% at most (a flip across a bend or a fold would cut the surface: without these the
// bodies' and polygirl_20k's level-5 errors rose). flip_rounds rounds of flips, each but the last
// followed by the interior smoothing again (of the flipped pairs' corners, and of the neighbours
// of the vertices it moves). Faces are replaced in place: face_leaf then names
// the leaf of the face a flipped face replaced.
// Sliding (with the smoothing, slide_sides; issue 13): the vertices on a patch side (not the
// corners) move along their side, one unknown per vertex (its fraction along the side) shared by
// the two patches of the side, so that the side stays one polyline for both and the set one
// connectivity. As in the smoothing: only vertices whose ring has a smallest angle under
// smooth_below in the worst mesh, the mean over the set of each mesh's step toward its ring's
// area-weighted centroid (projected on the side's tangent), halved up to twice when a ring face
// would flip or shrink to under 5% in its patch's (u,v) (so a vertex never passes its
// neighbours on the side), kept when the ring's worst angle rises or its summed quality rises as
// above. Only vertices whose every ring face has a patch-interior corner (its patch known) in one
// of the side's two distinct patches move. The sides move after the interior's first smoothing
// and after each flip round's smoothing (the flipped rings' side vertices). The corners
// (seeds, and every base vertex) never move; features are not remesh vertices. In a set only (two
// or more charts): one mesh keeps the result it had before (measured on the 26 shared meshes,
// sliding and the flips' side allowance changed single meshes by a few faces and up to 2% of
// the level-5 error either way, e.g. elephant_12k's level-4 faces under 10 degrees 7 -> 9).
// Before the smoothing every vertex is a point of the uniform level-L grid (L = the finest max(lu, lv) + 1, the leaf
// centres), numbered in its order; SemiRegularConnectivity::level is the finest level a vertex
// needs.

#include <vector>

#include "qs/core/context.h"
#include "qs/dissect/dissection.h"
#include "qs/remesh/base_topology.h"
#include "qs/remesh/semi_regular.h"

namespace qs::remesh {

/// Finest split level of the anisotropic remesh (its centres use one level more: kMaxUniformLevel).
inline constexpr int kMaxAnisotropicLevel = 11;

/// The anisotropic even remesh's bound for a level n is kAnisoAreaFactor * s / (P 4^n) of the
/// surface (s, P as in even_options): about the uniform level n's face count on the shared meshes.
inline constexpr double kAnisoAreaFactor = 2.3;

/// Default AnisotropicOptions::max_aspect: cells stay within about 2:1 on the surface; a split
/// for the area goes along the long side alone when the aspect exceeds sqrt(2), which leaves cells
/// within [0.71, 1.41]. Other bounds change little (qs-bench-defaults, mean share of level-4 faces
/// under 10 degrees over the 26 shared meshes, before the corner and template cuts: 1.5 4.3%,
/// 2 4.2%, 3 4.1%; 3 gives a lower median angle, 40.4 degrees against 41.7).
inline constexpr double kDefaultMaxAspect = 2.0;

/// Default AnisotropicOptions::smooth_iterations and smooth_below (see "Smoothing" above).
inline constexpr int kDefaultSmoothIterations = 8;
inline constexpr double kDefaultSmoothBelow = 40.0;

/// Default AnisotropicOptions::flip_rounds (see "Edge flips" above). Share of level-4 faces under
/// 10 degrees on camel_4k_fixed / lion_sumner_10k (qs-bench-slivers): 0 rounds 4.68% / 5.18%, 1
/// 2.68% / 3.60%, 2 1.69% / 3.01%, 3 1.50% / 2.84%, 4 1.43% / 2.79% (each round after the first
/// costs a smoothing: the example set's level-4 remesh step 0.22 s with none, 0.44 s with 3).
inline constexpr int kDefaultFlipRounds = 3;

struct AnisotropicOptions {
  double max_area = 0;      ///< bound on A_C (a share of the surface, 0..1); > 0
  double max_aspect = kDefaultMaxAspect;  ///< bound on a leaf's aspect on the surface; >= 1.5
  int max_level = 10;       ///< no node is split in u beyond lu = max_level, nor in v beyond lv = max_level;
                            ///< 0..kMaxAnisotropicLevel
  int smooth_iterations = kDefaultSmoothIterations;  ///< sweeps of the interior smoothing (below); 0: off; 0..100
  double smooth_below = kDefaultSmoothBelow;  ///< only vertices with a ring angle under this many degrees move,
                                              ///< only edges whose triangles have one under it flip; 0..60
  int flip_rounds = kDefaultFlipRounds;  ///< rounds of edge flips (see above), each but the last followed by the
                                         ///< smoothing; 0: no flips; 0..10
  bool slide_sides = true;  ///< with the smoothing, in a set of two or more charts: patch-side vertices slide
                            ///< along their side (see "Sliding"); one chart: no effect
};

/// A node of an anisotropic tree (see the top of this file).
struct AnisoNode {
  int patch = 0, lu = 0, lv = 0, i = 0, j = 0;
};

struct AnisotropicStats {
  int area_splits = 0;       ///< nodes split because A_C exceeded max_area
  int aspect_splits = 0;     ///< nodes split only because their aspect exceeded max_aspect
  int balance_splits = 0;    ///< nodes split only to keep neighbours within one level along a side
  int unresolved_leaves = 0; ///< leaves at max_level still above max_area or max_aspect
  int fan_leaves = 0;        ///< leaves cut as a fan around their centre (see above)
  double max_leaf_aspect = 1;  ///< the largest leaf_aspect (the worst mesh's, see above)
  int finest_level = 0;      ///< the largest max(lu, lv) over the leaves
  int smoothed_moves = 0;    ///< vertex moves accepted by the interior smoothing, all sweeps and rounds together
  int slid_moves = 0;        ///< side-vertex moves accepted by the sliding (see "Sliding"), all sweeps and rounds
  int flips = 0;             ///< edges flipped (see "Edge flips"), all rounds together
};

struct AnisotropicRemesh {
  SemiRegularSet remesh;          ///< one connectivity, one position array per chart
  std::vector<AnisoNode> leaves;  ///< patch by patch, depth first; faces come leaf by leaf
  std::vector<double> leaf_aspect;  ///< #leaves: the worst mesh's aspect exp(|log r| + w) of each leaf (>= 1)
  std::vector<int> face_leaf;       ///< #F: the leaf (index into leaves) whose cell holds each face
  AnisotropicStats stats;
};

/// Anisotropic even remesh of a set of charts with one connectivity (for one mesh, pass one chart).
/// Reports progress as "remesh" and checks the cancel flag.
/// \pre the charts' patch lists have the same structure, as dissect_set produces.
/// \throws InvalidInput for max_area <= 0 or not finite, max_aspect < 1.5 or not finite, max_level,
///         smooth_iterations, smooth_below or flip_rounds out of range, an empty set, or charts that do not match chart 0 (see set_samplers).
AnisotropicRemesh remesh_anisotropic(const std::vector<const dissect::Chart*>& charts,
                                     const AnisotropicOptions& options, const Context& context = {});

/// Options for a level n: max_area = kAnisoAreaFactor * share_sum / (P 4^n), max_level =
/// min(n + 6, kMaxAnisotropicLevel), max_aspect = kDefaultMaxAspect.
/// \throws InvalidInput for a level outside 0..kMaxAnisotropicLevel, patches < 1 or share_sum < 1.
AnisotropicOptions anisotropic_options(int level, int patches, double share_sum = 1.0);

/// The anisotropic even remesh for a level n: remesh_anisotropic with anisotropic_options(n, patch
/// count, the sum of patch_area_shares).
AnisotropicRemesh remesh_even_anisotropic(const std::vector<const dissect::Chart*>& charts, int level,
                                          const Context& context = {});

}  // namespace qs::remesh
