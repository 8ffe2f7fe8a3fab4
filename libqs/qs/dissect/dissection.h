#pragma once
// Dissection of closed genus-0 meshes into quad patches by recursive quinary subdivision
// (paper sections 3.1-3.4), each patch parameterized onto the unit square. A set of meshes is
// dissected together: one union quinary tree, so that every mesh ends with the same patches, and
// named feature points aligned in every patch by a foldover-free warp before it is split.

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"
#include "qs/landmarks/landmarks.h"
#include "qs/dissect/geodesic_loop.h"
#include "qs/dissect/seed_loop.h"
#include "qs/param/square_param.h"
#include "qs/register/registration.h"

namespace qs::dissect {

/// Moves the (u, v) of one mesh's patch towards the reference mesh's map of the same patch
/// (DissectOptions::refine_before_split): `ref` and `ref_uv` are the reference's patch and map,
/// `patch` and `uv` the other mesh's; vertices with held[v] != 0 (and the boundary loop) stay.
/// Returns whether uv changed; a changed uv must stay bijective (every face positive).
using NodeMapRefiner = std::function<bool(const param::PatchMesh& ref, const std::vector<Vec2>& ref_uv,
                                          const param::PatchMesh& patch, std::vector<Vec2>& uv,
                                          const std::vector<char>& held)>;

/// Untangles one mesh's map of a node toward target (u, v) (DissectOptions::same_pose_untangle):
/// `uv` starts bijective and moves toward target[v] where has_target[v] != 0, never folding;
/// held vertices (and the boundary loop) stay. `polish`: a repaired map near its targets but
/// where it was repaired (a few steps suffice). Returns whether uv changed; a changed uv must
/// stay bijective.
using NodeMapPuller =
    std::function<bool(const param::PatchMesh& patch, std::vector<Vec2>& uv, const std::vector<char>& held,
                       const std::vector<Vec2>& target, const std::vector<char>& has_target, bool polish)>;

/// same_pose_detect's default: 1% of the first mesh's bounding-box diagonal (a body and its
/// re-tessellation lie 0.1% apart, two registered bodies 0.2-0.3%, two shapes of a generated
/// family 1.4-2.9%; docs/algorithms.md, "Same pose").
inline constexpr double kSamePoseDetect = 0.01;
/// DissectOptions::register_poses: a registration puts its meshes in one pose when 99% of the
/// area of each lies within this fraction of the diagonal of the other (pose pairs: 0.1-0.4%;
/// spot, the cat and the koala registered onto each other: 3-8%) ...
inline constexpr double kRegisteredFit = 0.01;
/// ... and its distortion (symmetric Dirichlet / 4, 1: isometric) is at most this (pose pairs:
/// 1.00-1.15, limbs bent 60-110 degrees with few landmarks 1.3-1.55; the examples' shapes onto
/// each other: 1.17-6.7, and 3-8% apart; docs/decisions/0015-registration-distortion-bound.md).
inline constexpr double kRegisteredDistortion = 1.6;
/// A registration that fits but not within this fraction of the diagonal is tried again with more
/// points held (the farthest from the landmarks), and the closer of the two kept: a free limb bent
/// the wrong way can still fit within kRegisteredFit.
inline constexpr double kRegisteredTight = 0.002;
/// One pose also needs 99% of the area within this multiple of same_pose_detect: a shape whose
/// limbs moved (a pose change) lies close on average but far at the limbs (docs/algorithms.md).
inline constexpr double kSamePoseTail = 2.0;
/// A set within both bounds whose 99% quantile is over this multiple of its mean distance has
/// the distance in a small part (a limb turned about itself, which lies where it lay): it is
/// registered as other poses are, and keeps one pose by the similarity when that does not fit.
/// Re-tessellations and two bodies in one pose spread the distance evenly (docs/pose-pairs.md,
/// "A part moved in place") ...
inline constexpr double kPartMoved = 10.0;
/// ... and the 99% quantile must be over this fraction of the diagonal: the rounding that
/// separates one mesh given twice is no part that moved.
inline constexpr double kPartMovedFloor = 0.001;

/// The options of a dissection. The defaults are qs-dissect's except for the two hooks, which
/// qs::pipeline::dissect sets (they are empty here: the dissect module does not depend on
/// maprefine). Measurements behind each default: docs/tools/qs-dissect.md.
struct DissectOptions {
  /// A patch whose normalized L2 stretch (1 = isometric up to scale) exceeds tau is split. \pre >= 1
  double tau = 3.0;
  int max_depth = 6;             ///< seed patches have depth 0
  int min_faces_to_split = 150;  ///< smaller patches are not split (stop reason "too_few_faces")
  /// The w rule: w = clamp(w_bias + log10(s_peak), w_min, w_max), s_peak the smoothed peak
  /// stretch (paper eq. 4 with psi = w_bias).
  double w_bias = 0.45;
  double w_min = 0.5;
  double w_max = 0.65;
  /// A node stretched more than this (a protrusion squeezed into a point of the square) is split
  /// with its raw stretch peak inside the centre child, 0.05 inside its square, w unchanged; a
  /// node holding features keeps the rule's centre. 0: off. \pre >= 0
  double protrusion_stretch = 1000;
  /// The stretch peak is clamped into [peak_margin, 1 - peak_margin]^2.
  double peak_margin = 0.35;
  /// Features (in the aligned domain of the patch being split) stay at least this far from the
  /// 8 cuts and 4 inner corners: the peak is nudged to keep them clear.
  double feature_cut_margin = 0.02;
  /// Features closer than this in a node's domain (in any mesh, or their targets) are aligned as
  /// one group by their centroid; groups nearer the border than this are held.
  double feature_group_distance = 1e-3;
  /// Straighten the four seed curves into geodesics cut into the mesh (straighten_seed_loop);
  /// false: the shortest edge paths as traced.
  bool geodesic_seed_curves = true;
  /// Interior weights of every patch map: cotangent weights on the patch's intrinsic Delaunay
  /// triangulation (a patch whose own triangles fold under them keeps mean-value weights);
  /// false: Floater's mean-value weights everywhere.
  bool intrinsic_cotan = true;
  /// When a dissection with geodesic seed curves or cotangent weights ends with folded leaves,
  /// dissect the set again with edge paths and mean-value weights and keep that result if it
  /// folds less (DissectionSet::maps_fallback says why).
  bool fallback_maps = true;
  /// Rounds of stretch minimization of every leaf's final map (features pinned at their aligned
  /// (u,v)); no patch changes. A leaf keeps its map when the minimized one is not bijective or
  /// not less stretched.
  int stretch_iterations = 10;
  /// A patch whose 3D area exceeds this fraction of its mesh's area is split too. 0: no limit.
  double max_patch_area = 0.15;
  /// A patch over tau by its stretch alone (bijective in every mesh, under the area cap) holding
  /// less than this fraction of its mesh's area is not split (stop reason "small_area"); the
  /// leaf repair takes it. 0: off. \pre in [0, 1]
  double min_split_area = 0.01;
  /// A patch still over tau after the leaf repair holding at least this fraction of its mesh's
  /// area is split even when the no-progress rule would stop it. 0: off. \pre in [0, 1]
  double force_split_area = 0.03;
  /// A patch over tau (or folded) holding at least force_split_area of its mesh's area may be
  /// split this many levels past max_depth. 0: off. \pre in [0, 12]
  int area_extra_depth = 4;
  /// Before a node is split, the node's map of every mesh but mesh 0 is refined against mesh 0's
  /// by this function (qs::maprefine::node_refiner), so that the split points, taken at equal
  /// (u, v), correspond better; a refined map is kept only when it stays bijective and the
  /// children's predicted stretch stays within tau or within the node's own map's. Not run with
  /// same_pose and same_pose_maps. Empty: off.
  NodeMapRefiner refine_before_split;
  /// The meshes are in one pose (registered scans, re-tessellations of one surface): every split's
  /// inner corners are placed in each mesh but the first at its points nearest the first mesh's,
  /// after the landmarks' least-squares similarity (Umeyama); a split keeps the common (u, v) when
  /// a posed corner lies over 5% of the diagonal from its target, the posed quad would not make a
  /// quinary split, a feature would be too near a cut, or the split fails. Wrong for meshes in
  /// different poses.
  bool same_pose = false;
  /// With same_pose: before every split, each mesh's map of the node (but the first's) is taken
  /// over from the first mesh's by nearest points (folds mended; kept only when bijective).
  bool same_pose_maps = true;
  /// With same_pose: a node map that folds here and there still places its posed corners by its
  /// other faces; false: such a node keeps the common (u, v). The safety nets turn it off when the
  /// set ends with folded leaves (DissectionSet::posed_corners_fallback).
  bool same_pose_folded_maps = true;
  /// With same_pose_maps: a node whose taken-over map still folds after the repair is untangled by
  /// this function (qs::maprefine::untangler) instead of keeping its own map, and a repaired map is
  /// polished by it. Empty: repaired maps stay as repaired, a node still folded keeps its own.
  NodeMapPuller same_pose_untangle;
  /// Turn same_pose on when every mesh, moved onto the first by the landmarks' similarity, lies at
  /// a mean distance of at most this fraction of the first mesh's diagonal from it, and 99% of
  /// its area within kSamePoseTail times that (pose_distance; needs seeds in every mesh; one mesh
  /// given twice is one pose, and its copies' charts are the first's). 0: off. \pre >= 0
  double same_pose_detect = kSamePoseDetect;
  /// Meshes of one surface in other poses (their landmarks' geodesic distances within 5% of the
  /// first mesh's) and not in one pose: the first mesh is registered onto each other mesh
  /// (qs::registration::register_surface); when every registration fits (kRegisteredFit,
  /// kRegisteredDistortion), the set is dissected in one pose through the registrations. Needs
  /// same_pose_detect > 0.
  bool register_poses = true;
  /// Set by dissect_set (empty here): per mesh, the first mesh's registration onto it (the first
  /// entry the identity), which same_pose then uses instead of the landmarks' similarity.
  std::vector<registration::Pose> pose_registrations;
  /// Meshes in other poses: every mesh's seed loop but the first's is routed to follow the
  /// first's in geodesic coordinates of the landmarks (trace_intrinsic_loop), which a change of
  /// pose keeps, instead of each mesh's own shortest loop. Not with same_pose (the loops follow
  /// the first's by pose then).
  bool intrinsic_loops = true;
  /// Measurement only, empty in every tool: called with every mesh's seed loop (input order) once
  /// they are routed and straightened (geodesic_seed_curves; else each mesh as it is with its edge
  /// paths), before the seed patches are cut. qs-bench-stage-attribution puts exact loops there to
  /// measure what the loop's routing costs. \pre it keeps each loop valid on its mesh.
  std::function<void(std::vector<GeodesicLoop>&)> replace_seed_loops;
  /// Measurement only, empty in every tool: called with every mesh's map of a node (input order):
  /// the node's vertices (local -> global id) and their (u, v), which it may replace. Called once
  /// a node is parameterized, before its features are aligned (`before_split` false), and before
  /// it is split (true: the cuts run where these maps put them). qs-bench-stage-attribution puts
  /// the first mesh's map there (exact splits, exact maps). \pre it keeps each map bijective.
  struct NodeMapRef {
    const std::vector<int>* vertices;
    std::vector<Vec2>* uv;
  };
  std::function<void(std::vector<NodeMapRef>&, bool before_split)> replace_node_maps;
};

/// Meshes in one pose: a nearest point on the first mesh (the posed corners, the node maps taken
/// over, the refinement's pull) counts only on faces whose unit normal has at least this cosine
/// with the query's normal turned by the landmarks' similarity, so that it keeps to the query's
/// side of a thin part (the next finger's back is nearer than the finger's own front). Measured
/// (README, "Same pose"): human-same's worst point 3.07 -> 2.02% with three border iterations.
inline constexpr double kSamePoseFacingCos = 0.0;

/// Why a patch over tau was left as it is.
enum class StopReason { None, MaxDepth, TooFewFaces, SplitFailed, NoProgress, SmallArea };
const char* stop_reason_name(StopReason r);

/// A leaf patch of the final dissection.
struct PatchInfo {
  std::string name;                ///< path in the quinary tree: "0", "1", "0.3", "0.3.4", ...
  std::array<int, 4> corners{};    ///< chart vertex ids, CCW: uv (0,0) (1,0) (1,1) (0,1)
  int faces = 0;
  double stretch = 0;              ///< normalized L2 stretch of its parameterization
  int flipped_faces = 0;
  int zero_area_faces = 0;
  double uv_area_sum = 0;
  StopReason stop = StopReason::None;  ///< set when stretch > tau
  std::string stop_detail;         ///< a sentence for SplitFailed
};

/// One node of the quinary tree (leaves and split nodes).
struct TreeNode {
  std::string name;
  int depth = 0;
  double stretch = 0;              ///< of the node's own parameterization (max over the set)
  std::vector<double> mesh_stretch;  ///< per mesh of the set, after feature alignment
  int features = 0;                ///< features inside the node (aligned before splitting)
  int warp_events = 0;             ///< edge flips of the alignment warps, summed over the set
  int feature_groups = 0;          ///< features closer than feature_group_distance move as one
  int features_held = 0;           ///< groups left in place (too near the border)
  int pinned_solves = 0;           ///< meshes whose warped map folded and was solved again pinned
  int split_mesh = -1;             ///< split nodes: the mesh whose peak was used
  /// Faces added per mesh by local refinement of this node (empty: none). A node that would have
  /// ended folded, or whose split failed, has its patch's edges split at their midpoints (the
  /// surface is unchanged, only its sampling) and is evaluated again, at most 3 times.
  std::vector<int> refined_faces;
  bool split = false;              ///< children are name + ".0" .. ".4"
  Vec2 peak_uv = Vec2::Zero();     ///< split nodes: the peak point used
  Vec2 raw_peak_uv = Vec2::Zero(); ///< split nodes: the smoothed stretch peak, before any clamp or nudge
  double w = 0;                    ///< split nodes: the w used
  /// Split nodes with DissectOptions::same_pose: the inner corners of meshes 2.. were placed by
  /// pose (false: at the common (u, v) of peak_uv and w).
  bool posed = false;
};

/// The cut mesh with one patch label and one (u,v) per face corner.
struct Chart {
  TriMesh mesh;
  std::vector<int> face_patch;                ///< #F, index into `patches`
  std::vector<std::array<Vec2, 3>> face_uv;   ///< #F, wedge (u,v) in the face's patch
  std::vector<PatchInfo> patches;             ///< the leaves, sorted by name
};

/// The base domain: patch corners as vertices, patches as quads.
struct BaseDomain {
  std::vector<int> vertices;                  ///< base vertex -> chart vertex id
  std::vector<std::array<int, 4>> quads;      ///< per leaf patch (same order), base vertex ids
  int edges = 0;
  int euler_characteristic = 0;               ///< V - E + F
  bool closed_conforming = false;             ///< every quad side shared with exactly one other
};

/// Where a named feature ended: a vertex of the chart, inside (never on the border of) a leaf.
struct FeaturePlacement {
  std::string name;
  int vertex = -1;            ///< chart vertex id
  int patch = -1;             ///< index into chart.patches
  Vec2 uv = Vec2::Zero();     ///< in that patch; equal across the set (the aligned mean)
};

/// Where a seed of the loop ended: a chart vertex (an input vertex, or one inserted at the given
/// surface point so that the seed is exactly the patch corner).
struct SeedPlacement {
  int vertex = -1;                  ///< chart vertex id (input vertex ids are kept by the chart)
  bool inserted = false;            ///< true: a new vertex at `where`; false: an input vertex
  landmarks::SurfacePoint where;    ///< on the input mesh, when inserted (face -1 otherwise)
  Vec3 position = Vec3::Zero();
};

struct Dissection {
  std::array<int, 4> seeds{};                 ///< chart vertex ids of the seed-loop corners
  std::array<SeedPlacement, 4> seed_placements{};
  std::vector<TreeNode> tree;                 ///< parents before children, siblings by name
  Chart chart;
  BaseDomain base;
  double max_stretch = 0;
  std::vector<FeaturePlacement> features;     ///< sorted by name
};

/// A named feature point of one mesh: a vertex (vertex >= 0) or a point on a face.
struct Feature {
  std::string name;
  int vertex = -1;
  landmarks::SurfacePoint where;
};

/// One mesh of a set to dissect. Seeds correspond by order across the set, features by name.
struct MeshToDissect {
  const TriMesh* mesh = nullptr;                 ///< validated (closed, manifold, genus 0)
  std::optional<std::array<int, 4>> seeds;       ///< vertex ids; nullopt: choose_seeds
  std::vector<Feature> features;                 ///< the same names in every mesh of the set
  std::string name;                              ///< for messages (e.g. the file)
  /// Seeds as surface points: each is inserted into the mesh (an edge or face split, as features
  /// are) unless it lies on a vertex, so that it is exactly a corner of the seed patches. When
  /// set, it takes the place of `seeds`.
  std::optional<std::array<landmarks::SurfacePoint, 4>> seed_points{};
};

/// The common dissection of a set: one union tree, and per mesh a chart whose patches have the
/// same names, order and base-domain connectivity as every other mesh's.
struct DissectionSet {
  std::vector<TreeNode> tree;
  std::vector<Dissection> meshes;
  double max_stretch = 0;
  int warp_events = 0;
  /// The maps the result was made with (the options', or the old ones after a fallback).
  bool geodesic_seed_curves = false;
  bool intrinsic_cotan = false;
  /// Empty, or why the old maps were used (DissectOptions::fallback_maps): e.g. "28 folded uv
  /// faces with geodesic+cotan (patch 1.4.3.1.3.2.4 of lion.obj)".
  std::string maps_fallback;
  /// DissectOptions::same_pose: splits whose inner corners were placed by pose in every mesh, and
  /// splits that kept the common (u, v) (no posed quad, or the split failed with it).
  int same_pose_splits = 0;
  int same_pose_common = 0;
  /// Splits that succeeded only when tried again with cuts that keep to their segments (the first
  /// try's cuts, passing through vertices near them, crossed: a patch squeezed in (u, v)).
  int retried_splits = 0;
  int same_pose_loops = 0;  ///< meshes but the first whose seed loop follows the first's by pose
  /// DissectOptions::same_pose_maps: node maps (of meshes but the first, before a split) taken
  /// over from the first mesh's; of those, the ones left folded (no bijective map near the
  /// first's, in another pose: they cut where the first mesh's map does), polished after the
  /// repair, and untangled from their own by DissectOptions::same_pose_untangle; and those that
  /// kept their own (no bijective map near the first's, in one pose).
  int same_pose_maps = 0;
  int same_pose_folded_taken = 0;
  int same_pose_own_maps = 0;
  int same_pose_polished = 0;
  int same_pose_untangled = 0;
  /// Leaves of meshes but the first whose map was taken over from the first mesh's leaf.
  int same_pose_leaves = 0;
  /// DissectOptions::refine_before_split: node maps (of meshes but the first, before a split)
  /// refined against the first mesh's, and those that kept their own (the refinement failed, or
  /// its children's predicted stretch was higher).
  int before_split_refined = 0;
  int before_split_own = 0;
  /// Empty, or why the set was dissected again with the common (u, v) (DissectOptions::same_pose:
  /// the posed result ended with folded leaves, the common one folds less).
  std::string same_pose_fallback;
  /// Empty, or why the posed corners were taken from unfolded node maps only
  /// (DissectOptions::same_pose_folded_maps off by the safety nets): e.g. "250 folded uv faces
  /// with corners from folded node maps too (patch 1.4.4.3.0.0.1 of camel_r.obj)".
  std::string posed_corners_fallback;
  /// DissectOptions::same_pose_detect: the set's pose_distance (-1: not measured) and whether it
  /// turned same_pose on.
  double pose_distance = -1;
  double pose_distance_p99 = -1;  ///< the 99% quantile (-1: not measured)
  bool same_pose_detected = false;
  /// Within the bounds, but the distance in a small part (kPartMoved): the registration was tried.
  bool pose_part_moved = false;
  /// DissectOptions::register_poses: the registrations that put the set in one pose (empty when
  /// not registered; else one per mesh, the first the identity), their largest distance from the
  /// meshes (99% of the area within, a fraction of a mesh's diagonal) and largest distortion.
  std::vector<registration::Pose> poses;
  double registration_fit = -1;
  double registration_distortion = -1;
  /// Points held besides the landmarks in a second try of a registration that did not fit closely
  /// (the first mesh's points farthest from them, the tips of its protrusions first, matched by
  /// geodesic distances to the landmarks): the most over the kept tries, or, when the set is not
  /// registered, over all tries; 0 when none.
  int registration_tips = 0;
  /// The seeds' cyclic order used (seed k of the result is seed seed_order[k] as given): the
  /// set's shortest loop (shortest_seed_order), and the three orders' loop lengths (0 when the
  /// seeds were automatic).
  std::array<int, 4> seed_order{0, 1, 2, 3};
  std::array<double, 3> seed_loop_lengths{};
  int intrinsic_loops = 0;  ///< meshes but the first whose loop follows the first's (intrinsic_loops)
  /// Per mesh, how far its landmarks' geodesic distances to each other are from the first
  /// mesh's (a fraction of their sum; empty when not measured): intrinsic_loops routes only
  /// meshes within 5%, one shape in another pose.
  std::vector<double> landmark_discrepancy;
};

/// How far a set is from one pose: for every mesh but the first, the least-squares similarity
/// (Umeyama) of its landmarks (the 4 seeds, then the features both have) onto the first mesh's
/// moves it onto the first, and the distances between the two surfaces are taken (from each one's
/// vertices to the other, weighted by vertex area): their mean and the distance within which 99%
/// of the area lies; the largest of each over the meshes, as fractions of the first mesh's
/// bounding-box diagonal. nullopt when a mesh has no seeds or the set has fewer than 2 meshes.
/// \throws InvalidInput for a landmark outside its mesh.
struct PoseDistance {
  double mean = 0;
  double p99 = 0;
};
std::optional<PoseDistance> pose_distance(const std::vector<MeshToDissect>& meshes, const Context& context = {});

/// "geodesic+cotan", "edge+mean-value", ...: the seed curves and patch weights of a dissection.
std::string maps_name(bool geodesic_seed_curves, bool intrinsic_cotan);

/// Dissects a validated mesh. `seeds` are vertex ids of `mesh`; nullopt chooses them
/// automatically (choose_seeds). \throws InvalidInput for unroutable seeds, SolverError when a
/// parameterization fails.
Dissection dissect(const TriMesh& mesh, const std::optional<std::array<int, 4>>& seeds,
                   const DissectOptions& options = {}, const Context& context = {});

/// Dissects a set of meshes together (paper 3.4): a leaf over tau in ANY mesh is split in every
/// mesh at one peak point of the aligned parameter domain (the peak of the mesh with the greatest
/// stretch), after the features inside it were moved to their mean (u,v) over the set by
/// warp::warp_square. \throws InvalidInput for a feature missing from a mesh, features on
/// different seed patches or on a cut line, features too close, tau below 1, min_split_area or
/// force_split_area outside [0, 1], area_extra_depth outside [0, 12]; SolverError as dissect().
/// With options.fallback_maps, a result with folded leaves under the new maps is replaced by the
/// old maps' when that folds less.
DissectionSet dissect_set(const std::vector<MeshToDissect>& meshes, const DissectOptions& options = {},
                          const Context& context = {});

/// Builds and checks the base domain of a chart's leaves. Base vertices are numbered by first
/// appearance walking the patches in order, corners 0..3, so that meshes with corresponding
/// patches get identical quads.
BaseDomain build_base_domain(const std::vector<PatchInfo>& patches);

}  // namespace qs::dissect
