#pragma once
// Foldover-free warp of the unit square by "triangulation over time" (Fujimura & Makarov 1998),
// used to move feature points to common positions across meshes before dissection (paper 3.4.1).

#include <array>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"

namespace qs::warp {

struct WarpOptions {
  /// Features (and targets) closer than this to each other or to the square's border are rejected
  /// (InvalidInput). A moving feature keeps at least half of this from every other feature (see
  /// warp_square). In (0, 0.25).
  double min_feature_distance = 1e-4;
  /// The motion is split into this many rounds; in each, every feature in index order advances by
  /// its share of the straight path to its target. 1 moves each feature all the way at once (the
  /// paper's order); more rounds let neighbours move together, which spreads the deformation: a
  /// warped mesh stays free of flipped triangles under much larger displacements. >= 1.
  int rounds = 16;
  /// More edge flips than this in one call: SolverError ("meshes too different to align"). >= 0.
  int max_events = 100000;
};

struct WarpResult {
  std::vector<Vec2> points;  ///< #P warped points, in the input's order
  int events = 0;            ///< edge flips performed
  int detours = 0;           ///< intermediate stops made to keep a moving feature clear of others
  int warp_triangles = 0;    ///< triangles of the warp mesh: 2 * (4 + #features) - 6
  double min_warp_area = 0;  ///< smallest signed area of a warp triangle at the end (> 0: bijective)
  /// The warp mesh at the end, CCW: vertex ids 0..3 the corners (0,0) (1,0) (1,1) (0,1), 4 + k
  /// feature k. With events == 0 it is also the mesh at the start, and the warp is one affine map
  /// per triangle: a mesh cut along these edges (at the input positions) is warped without folds.
  std::vector<std::array<int, 3>> triangles;
};

/// Moves each feature features[k] to targets[k] inside the unit square and carries `points` along
/// by a piecewise-linear map that is a bijection of the square onto itself (Fujimura & Makarov
/// 1998, "triangulation over time"; paper 3.4.1).
///
/// The warp mesh is the Delaunay triangulation (CGAL) of the corners (0,0) (1,0) (1,1) (0,1) and
/// the features; every point is bound to its warp triangle by barycentric coordinates. One feature
/// moves at a time along a straight leg. The mesh is kept Delaunay while it moves (kinetic
/// Delaunay): the exact time at which an edge around the moving feature stops being Delaunay is
/// the root of a quadratic, and the edge is flipped at that moment; the points of the two
/// triangles are re-bound to the new ones at their current positions. A triangle about to
/// degenerate always stops being Delaunay first, so no triangle ever folds over, and triangles
/// stay as fat as the features allow. (If rounding ever hides that, the edge opposite the middle
/// vertex of the collinear triple is flipped before the exact degeneration time, where the four
/// triangles involved are fattest.)
///
/// Order and paths: options.rounds rounds; in each, every feature in index order advances by its
/// share of the straight path to its target, unless that step would come closer than
/// min_feature_distance / 2 to another feature or end closer than min_feature_distance to one (it
/// then waits for a later round). The rest is done feature by feature, lowest index first among
/// those with a clear straight path to the target; when none has one, a feature stops at an
/// intermediate point beside its blocker (a detour: two straight legs), or, when targets block each
/// other in a cycle (e.g. two features swapping places), a feature of the cycle steps aside
/// first. Each feature ends exactly (bit for bit) on its target.
///
/// Exact guarantees: points on the square's border (after clamping) are returned unchanged (the
/// border edges never flip and the corners never move); a point that coincides with a warp vertex
/// (a corner or a feature's start, or within barycentric weight 1e-14 of one) follows that vertex
/// exactly, so a point equal to features[k] comes back bit-equal to targets[k]. Points within
/// 1e-12 outside the square are clamped onto it first. The result is deterministic.
///
/// The map is bijective, but it is only piecewise linear (with kinks along warp edges at every
/// moment): a mesh whose vertices are warped keeps its triangles unflipped only while the motion
/// is moderate for the feature spacing (neighbouring features moving alike, as when they move to
/// their mean over similar meshes); check the warped mesh.
///
/// \pre features.size() == targets.size(); all coordinates finite; features and targets each at
/// least min_feature_distance from the border and pairwise at least that far apart (a target may
/// coincide with another feature's start); points inside the square up to 1e-12.
/// \throws InvalidInput naming every offending index and position, or a bad option value.
/// \throws SolverError if more than options.max_events flips are needed, no collision-free path is
/// found, or a numerical breakdown leaves a non-positive warp triangle (never seen in tests).
/// \throws qs::Error (Internal, "cancelled") when context.cancel is raised.
WarpResult warp_square(const std::vector<Vec2>& features, const std::vector<Vec2>& targets,
                       const std::vector<Vec2>& points, const WarpOptions& options = {},
                       const Context& context = {});

}  // namespace qs::warp
