#pragma once
// Anisotropic even remesh: like remesh_even (adaptive.h), leaves of about equal surface area, but a
// node may be split in u only or in v only, so that cells on a long, anisotropically mapped patch
// (a leg, an arm) end near square on the surface. One connectivity for a set of charts; the
// vertices are a subset of a uniform level-L grid's, numbered in its order (semi_regular.h). The
// refinement, balancing, triangulation, smoothing, sliding and edge flips: docs/algorithms.md.

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
/// for the area goes along the long side alone when the aspect exceeds sqrt(2).
inline constexpr double kDefaultMaxAspect = 2.0;

/// Default AnisotropicOptions::smooth_iterations and smooth_below.
inline constexpr int kDefaultSmoothIterations = 8;
inline constexpr double kDefaultSmoothBelow = 40.0;

/// Default AnisotropicOptions::flip_rounds.
inline constexpr int kDefaultFlipRounds = 3;

struct AnisotropicOptions {
  double max_area = 0;      ///< bound on A_C, a node's largest share of its mesh's surface over the set; > 0
  double max_aspect = kDefaultMaxAspect;  ///< bound on a leaf's aspect on the surface; >= 1.5
  int max_level = 10;       ///< no node is split in u beyond lu = max_level, nor in v beyond lv = max_level;
                            ///< 0..kMaxAnisotropicLevel
  int smooth_iterations = kDefaultSmoothIterations;  ///< sweeps of the interior smoothing (below); 0: off; 0..100
  double smooth_below = kDefaultSmoothBelow;  ///< only vertices with a ring angle under this many degrees move,
                                              ///< only edges whose triangles have one under it flip; 0..60
  int flip_rounds = kDefaultFlipRounds;  ///< rounds of edge flips, each but the last followed by the
                                         ///< smoothing; 0: no flips; 0..10
  bool slide_sides = true;  ///< with the smoothing, in a set of two or more charts: patch-side vertices slide
                            ///< along their side; one chart: no effect
};

/// A node of an anisotropic tree: it covers [i, i+1] / 2^lu x [j, j+1] / 2^lv of its patch's unit square.
/// A split is U (children (lu+1, lv, 2i+a, j)), V (children (lu, lv+1, i, 2j+b)) or UV (the four
/// (lu+1, lv+1, 2i+a, 2j+b), in the order ab = 00, 10, 01, 11).
struct AnisoNode {
  int patch = 0, lu = 0, lv = 0, i = 0, j = 0;
};

struct AnisotropicStats {
  int area_splits = 0;       ///< nodes split because A_C exceeded max_area
  int aspect_splits = 0;     ///< nodes split only because their aspect exceeded max_aspect
  int balance_splits = 0;    ///< nodes split only to keep neighbours within one level along a side
  int unresolved_leaves = 0; ///< leaves at max_level still above max_area or max_aspect
  int fan_leaves = 0;        ///< leaves cut as a fan around their centre
  double max_leaf_aspect = 1;  ///< the largest leaf_aspect (the worst mesh's)
  int finest_level = 0;      ///< the largest max(lu, lv) over the leaves
  int smoothed_moves = 0;    ///< vertex moves accepted by the interior smoothing, all sweeps and rounds together
  int slid_moves = 0;        ///< side-vertex moves accepted by the sliding, all sweeps and rounds
  int flips = 0;             ///< edges flipped, all rounds together
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
