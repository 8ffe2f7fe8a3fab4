#pragma once
// Map refinement after the common dissection: refine_maps() moves the chart (u, v) of every mesh
// of a set but the reference so that its map to the reference (point -> (patch, u, v) -> point)
// has low isometric distortion: the symmetric Dirichlet energy against the reference's metric,
// minimized patch by patch by projected Newton with a flip-free line search, in the spirit of
// Schmidt et al. 2019 ("Distortion-minimizing injective maps between surfaces") and Smith and
// Schaefer 2015 (the flip-free step). Optionally the patch curves (across_borders) and the patch
// corners (move_corners) move too, on charts glued across sides and around corners. A change is
// kept only if every uv face stays positive and the energy goes down. The result does not depend
// on the thread count. The method: docs/algorithms.md, "Map refinement".

#include <vector>

#include "qs/core/context.h"
#include "qs/dissect/dissection.h"

namespace qs::maprefine {

/// The length at which RefineOptions::pose_pull costs as much per unit area as its weight: 1% of
/// the reference's bounding-box diagonal.
inline constexpr double kPullLength = 0.01;

/// The pipeline's RefineOptions::pose_pull for meshes in one pose (qs::pipeline::DissectConfig).
inline constexpr double kDefaultPosePull = 10.0;
/// ... and its RefineOptions::border_iterations with that pull (docs/algorithms.md, "Map refinement").
inline constexpr int kPoseBorderIterations = 5;
/// Through a registration (RefineOptions::poses) the pipeline multiplies that pull by
/// kRegisteredPullScale and those steps by kRegisteredStepScale, and takes at least
/// kRegisteredBorderSweeps passes over the sides (unless none): the first mesh carried through a
/// registration is a closer map than the dissection's own, so the pull outweighs the distortion
/// (left to keep the map injective), and a side moves far enough to follow it, settling once its
/// neighbours have moved. Nearest points after a similarity are not trusted so far: two people in
/// one pose correspond by their shapes, not by nearest points (docs/pose-pairs.md).
inline constexpr double kRegisteredPullScale = 100.0;
inline constexpr int kRegisteredStepScale = 4;
inline constexpr int kRegisteredBorderSweeps = 2;

struct RefineOptions {
  int reference = 0;         ///< the mesh of the set that is not moved. \pre 0 <= reference < #meshes
  int iterations = 30;       ///< Newton steps per patch at most. \pre >= 0
  /// A patch stops when a step lowers its energy by less than this fraction. \pre >= 0
  double tolerance = 1e-4;
  int threads = 0;           ///< 0: all cores; the result does not depend on it
  /// Move the patch curves too: every side shared by two patches (and no other side of theirs),
  /// in patch order, is refined on the two squares glued into one chart on [0,2] x [0,1] (the
  /// union's border, corners, seeds and features held) and the union cut again along u = 1 (new
  /// chart vertices exactly on the surface). A side is left as it was when the union is folded,
  /// gains nothing, or a piece of the cut is not a positive uv triangle.
  bool across_borders = true;
  /// With across_borders: passes over the shared sides (a pass that changes no side ends them).
  /// \pre >= 0
  int border_sweeps = 1;
  /// With across_borders: Newton steps per glued pair of patches at most (and at most
  /// `iterations`); the final interior pass polishes. \pre >= 0
  int border_iterations = 1;
  /// Move the patch corners too (after a first interior pass, before the across-border and final
  /// interior passes): every corner that is not a seed or a feature, met by k >= 3 distinct
  /// patches once each, is refined on its k squares glued into one disk chart (sector_glue; the
  /// outer border held) and the union cut again along the k rays from the origin; the new corner
  /// is the chart vertex at the origin. A corner is left as it was when its star is irregular, the
  /// union is folded, the energy does not go down, or a piece of the cut is not a positive uv
  /// triangle inside its square. Off by default (its cost: docs/tools/qs-dissect.md).
  bool move_corners = false;
  /// With move_corners: passes over the corners (in base-domain order; a pass that moves none
  /// ends them). \pre >= 0
  int corner_sweeps = 1;
  /// With move_corners: Newton steps per corner star at most (and at most `iterations`). \pre >= 0
  int corner_iterations = 5;
  /// The pose pull (for meshes in one pose): the interior passes, the side moves of
  /// across_borders and the corner moves of move_corners also pull
  /// every free vertex of B toward the reference's point nearest to it, B moved into the
  /// reference's frame by the landmarks' similarity (Umeyama on the seeds and features), the
  /// nearest point taken in the vertex's own patch (in the nearest of the two patches of a side,
  /// or of the k patches of a corner, being moved), among the faces that face as the vertex does
  /// (dissect::kSamePoseFacingCos). Energy: pose_pull * sum over B's vertices of
  /// area(v) * |d(u, v)|^2 / (kPullLength * the reference's diagonal)^2, with |d|^2 the squared 3D
  /// distance on the reference's patch (its metric at the target). 0: off. \pre >= 0
  double pose_pull = 0;
  /// With pose_pull and reference 0: per mesh, the first mesh registered onto it
  /// (DissectionSet::poses), which the pull takes instead of the landmarks' similarity where given.
  std::vector<registration::Pose> poses;
};

/// What refinement did to one mesh of the set.
struct MeshRefineReport {
  bool reference = false;       ///< this mesh was the reference (not moved)
  /// Its chart equals the reference's (the same mesh, seeds and features given twice): its map to
  /// the reference is the identity, which needs no refinement, so it is left as dissected.
  bool identity = false;
  int free_vertices = 0;        ///< chart vertices that were free to move
  int held_vertices = 0;        ///< patch-border vertices, seeds, features, inconsistent wedges
  int patches_refined = 0;      ///< patches whose (u, v) changed
  int patches_skipped = 0;      ///< patches left as they were (folded to start with, or no gain)
  int newton_steps = 0;         ///< summed over the patches
  /// Normalized distortion energy of the map to the reference (area-weighted mean of
  /// symDirichlet / 4 over the mesh's faces: 1 = isometric up to each patch's scale).
  double energy_before = 0;
  double energy_after = 0;
  int flipped_faces = 0;        ///< uv faces with signed area < -param::kZeroUvArea after refinement
  int zero_area_faces = 0;      ///< uv faces with |signed area| <= param::kZeroUvArea after refinement
  /// With RefineOptions::across_borders: side refinements kept (summed over the sweeps), sides
  /// left as they were in the first sweep, and chart vertices added by the cuts.
  int sides_refined = 0;
  int sides_skipped = 0;
  int cut_vertices = 0;
  /// With RefineOptions::move_corners: corner moves kept (summed over the sweeps); corners left as
  /// they were in the first sweep because their star is irregular (fewer than 3 patches, a patch
  /// met twice, an inconsistent glue), or because the move failed (folded union, no gain, a bad
  /// piece); chart vertices added by the cuts (the new corners inside faces included).
  int corners_moved = 0;
  int corners_irregular = 0;
  int corners_skipped = 0;
  int corner_cut_vertices = 0;
};

struct RefineReport {
  std::vector<MeshRefineReport> meshes;  ///< one per mesh of the set, in order
};

/// Refines the charts of a dissected set in place (see the top of this file). Without
/// across_borders only chart.face_uv of non-reference meshes changes; with it, their chart meshes
/// gain vertices (appended: existing vertex ids and positions stay) and faces (a split face keeps
/// its id for its first piece, the others are appended), and faces change patch where the patch
/// curves moved. The PatchInfo figures that depend on the chart (faces, stretch, flipped and
/// zero-area counts, uv area sum) and Dissection::max_stretch are recomputed; patch names,
/// corners, the base domain, features (vertex, patch, uv) and seeds are unchanged, so every later
/// stage reads the refined charts as before. With move_corners, a moved corner is another chart
/// vertex (PatchInfo::corners and BaseDomain::vertices name it; the base domain's quads and every
/// (patch, corner) incidence stay), and the chart gains vertices and faces as with across_borders.
/// \pre the meshes come from one dissect_set (same patches in the same order, base domains
/// identical). \throws InvalidInput for an empty set, a reference out of range, options out of
/// range (iterations, tolerance, border or corner sweeps or iterations below 0) or charts that do
/// not share their patches (naming the mesh and patch count);
/// Error(Internal "cancelled") when context's cancel flag is raised.
/// Progress stage: "refine maps".
RefineReport refine_maps(std::vector<dissect::Dissection>& meshes, const RefineOptions& options = {},
                         const Context& context = {});

/// How refine_patch refines one node (DissectOptions::refine_before_split).
struct NodeRefineOptions {
  /// A node whose composed map starts with a normalized distortion (area-weighted symmetric
  /// Dirichlet / 4; 1 = isometric) above this is left as it is (docs/algorithms.md, "Map refinement").
  /// 0: no limit. \pre >= 0
  double max_start_distortion = 10;
  /// A node's refinement stops when a Newton step lowers its energy by less than this fraction
  /// (instead of RefineOptions::tolerance; the leaves' maps are refined again by refine_maps).
  /// 0: RefineOptions::tolerance. \pre >= 0
  double tolerance = 1e-4;
};

/// Refines one patch of one mesh against the same patch of the reference, as refine_maps refines a
/// patch's interior (the same solver and safety rules; the energy is the symmetric Dirichlet
/// energy of the composed map B -> uv -> A itself, A's points located exactly in its uv
/// triangles, linearized at the current uv): `patch`'s (u, v) in `uv` move, its
/// boundary loop and the vertices with held[v] != 0 stay. Keeps the result only if every uv face
/// stays positive, inside the square, and the energy went down. Returns whether uv changed.
/// \pre ref_uv.size() == ref.positions.size(), uv.size() == held.size() == patch.positions.size(),
/// node.max_start_distortion >= 0. \throws InvalidInput naming the sizes or the bad value.
/// Deterministic, single-threaded.
bool refine_patch(const param::PatchMesh& ref, const std::vector<Vec2>& ref_uv, const param::PatchMesh& patch,
                  std::vector<Vec2>& uv, const std::vector<char>& held, const RefineOptions& options = {},
                  const NodeRefineOptions& node = {});

/// refine_patch with `options` and `node` as a dissect::NodeMapRefiner: the value to put in
/// DissectOptions::refine_before_split.
dissect::NodeMapRefiner node_refiner(const RefineOptions& options = {}, const NodeRefineOptions& node = {});

/// untangle_patch's pull (DissectOptions::same_pose_untangle): a vertex 6e-4 of the square from
/// its target costs as much as its area's distortion at rest (4 per unit area); chosen by
/// measurement (docs/algorithms.md, "Map refinement").
inline constexpr double kUntanglePull = 1e7;
/// Newton steps of a polish by untangler() at most.
inline constexpr int kPolishIterations = 10;

/// Moves a patch's bijective map `uv` toward target (u, v) without folding it: the free vertices
/// (neither held nor on the boundary loop) minimize the symmetric Dirichlet energy of the map from
/// their start (u, v) triangles (area-weighted) plus pull x a third of their faces' start uv area
/// x |uv - target[v]|^2 where has_target[v] != 0, by refine_maps's Newton solver, whose line search
/// keeps every face positive. The untangler of a same-pose take-over that folds: the targets fold
/// somewhere, the result follows them elsewhere. Keeps the result only if every uv face stays
/// positive, inside the square, and the energy went down; returns whether uv changed (false for a
/// start with a non-positive face that has a free vertex; faces without one are left out).
/// \pre uv.size() == held.size() == target.size() == has_target.size() == patch.positions.size(),
/// pull finite and >= 0. \throws InvalidInput naming the sizes or the bad value. Deterministic.
bool untangle_patch(const param::PatchMesh& patch, std::vector<Vec2>& uv, const std::vector<char>& held,
                    const std::vector<Vec2>& target, const std::vector<char>& has_target, double pull = kUntanglePull,
                    const RefineOptions& options = {});

/// untangle_patch with `options` and `pull` as a dissect::NodeMapPuller: the value to put in
/// DissectOptions::same_pose_untangle. A polish (a repaired map, its repaired region free) takes at
/// most kPolishIterations Newton steps.
dissect::NodeMapPuller untangler(const RefineOptions& options = {}, double pull = kUntanglePull);

/// The normalized distortion energy of mesh `b`'s map to mesh `a` (as MeshRefineReport::
/// energy_after): for tests and reports. \pre as refine_maps.
double map_energy(const dissect::Dissection& a, const dissect::Dissection& b);

/// The sector glue of a patch corner met by k patches (RefineOptions::move_corners): a point q
/// of the unit square turned so that the corner is at the origin goes to q.x a + q.y b, a and b the unit vectors at
/// angles 2 pi sector / k and 2 pi (sector + 1) / k; sector_unglue is its inverse. Exposed for tests.
Vec2 sector_glue(const Vec2& q, int k, int sector);
Vec2 sector_unglue(const Vec2& g, int k, int sector);

/// symDirichlet(J) = |J|_F^2 + |J^-1|_F^2 of a 2x2 matrix with det > 0, its gradient and the
/// Hessian with respect to J's entries in row-major order (J00, J01, J10, J11). Exposed for tests.
/// Returns +infinity (gradient and Hessian untouched) when det(J) <= 0.
double sym_dirichlet(const Eigen::Matrix2d& J, Eigen::Vector4d* gradient = nullptr,
                     Eigen::Matrix4d* hessian = nullptr);

/// The Hessian of sym_dirichlet at J made positive semi-definite (its eigenvalues clamped at 0), in
/// closed form from J's conformal and anticonformal parts (no SVD, no eigen-solver). Exposed for
/// tests. \pre det(J) > 0.
Eigen::Matrix4d projected_hessian(const Eigen::Matrix2d& J);

}  // namespace qs::maprefine
