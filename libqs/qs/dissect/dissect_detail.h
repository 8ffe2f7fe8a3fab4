#pragma once
// Internal to the dissect module: the per-mesh dissection state (MeshDissector) and the set driver
// (SetDissector) share these types. Not installed, not part of the API.

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_set>
#include <utility>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/geometry2d.h"
#include "qs/core/parallel.h"
#include "qs/dissect/cut_mesh.h"
#include "qs/dissect/dissection.h"
#include "qs/dissect/geodesic_loop.h"
#include "qs/dissect/seed_loop.h"
#include "qs/landmarks/landmarks.h"
#include "qs/param/square_param.h"
#include "qs/register/registration.h"

namespace qs::metro {
class SurfaceDistance;
}

namespace qs::dissect::routing {
struct Graph;
}

namespace qs::dissect::detail {

// A split that could not be completed; the parent is restored and kept as a leaf.
struct SplitFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

inline std::uint64_t edge_key(int a, int b) {
  return (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint64_t>(std::max(a, b));
}

inline double signed_area(const Vec2& a, const Vec2& b, const Vec2& c) { return 0.5 * cross2(b - a, c - a); }

/// Among n triangles with uv corners uv_of(i) (a std::array<Vec2, 3>), the positive one that holds
/// q best (largest smallest barycentric weight: q's own triangle, else the one it is least outside
/// of) and q's weights in it; (-1, 0) when none is positive.
template <typename UvOf>
std::pair<int, Vec3> best_uv_face(const Vec2& q, size_t n, UvOf&& uv_of) {
  int best = -1;
  Vec3 best_bary(0, 0, 0);
  double best_min = -std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < n; ++i) {
    const std::array<Vec2, 3> t = uv_of(i);
    try_uv_triangle(t[0], t[1], t[2], q, static_cast<int>(i), best, best_bary, best_min);
  }
  return {best, best_bary};
}

inline const std::array<Vec2, 4> kSquare = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};

struct Node {
  std::string name;
  int depth = 0;
  int label = 0;
  std::array<int, 4> corners{};
  double parent_stretch = std::numeric_limits<double>::infinity();  ///< this mesh's, at the parent
  double grandparent_stretch = std::numeric_limits<double>::infinity();
  int refinements = 0;  ///< local refinement rounds this node had (no_dead_ends)
};

// A patch as a PatchMesh, with its local -> global maps.
struct Extracted {
  param::PatchMesh pm;
  std::vector<int> verts;  // local -> global vertex
  std::vector<int> faces;  // local -> global face
};

enum Flag : char { kFree = 0, kBoundary = 1, kOnPath = 2, kCorner = 3, kFeature = 4 };

/// Per-mesh work on a node of a set runs on several threads from this many faces (all meshes).
constexpr size_t kParallelFaces = 8000;
/// Stretch-minimization rounds tried on a leaf left over tau or not bijective.
constexpr int kRepairRounds = 12;
// A quinary split's cut passes through a free vertex when it crosses an edge this near it (in edge
// parameter): no sliver is cut into the surface, and the cut moves off its segment by that little.
constexpr double kSplitSnap = 0.05;
// Where such detours make two cuts cross (a patch squeezed in (u, v): its edges long across a cut),
// the split is tried once more with this snap before it fails.
constexpr double kSplitRetrySnap = 0.002;

// The per-node result of one mesh: its patch extracted and parameterized (after alignment).
struct Param {
  Extracted ex;
  param::SquareParam sp;
  param::Stretch st;
  std::vector<std::pair<int, int>> features;  // (feature index, local vertex), by feature index
  param::InteriorWeights weights = param::InteriorWeights::MeanValue;  // of every solve of this patch
  // One plain solve of ex with `weights` (no pins, no rounds), or empty: where stretch
  // minimization starts without solving or ordering it again.
  param::PlainSolve plain;
};

// 1 at the local vertices of p's features, 0 elsewhere (the vertices a node map must keep).
inline std::vector<char> feature_mask(const Param& p) {
  std::vector<char> held(p.sp.uv.size(), 0);
  for (const auto& [k, local] : p.features) held[local] = 1;
  return held;
}

// The dissection state of one mesh of the set: the cut mesh and the faces of every tree node.
// The set driver (SetDissector) walks the union tree and asks each mesh to parameterize, split,

class MeshDissector {
 public:
  MeshDissector(const MeshToDissect& in, int index, const std::vector<std::string>& feature_names,
                const DissectOptions& options, const Context& context);

  /// Traces the shortest seed loop through `seeds`, avoiding the features; on `input_graph`, the
  /// input mesh's routing graph, where nothing has been inserted into the mesh yet.
  SeedLoop trace_loop(const std::array<int, 4>& seeds, const routing::Graph* input_graph = nullptr) const;
  /// The side of the loop (0 or 1) of every feature, by feature index.
  std::vector<int> feature_sides(const SeedLoop& loop) const;
  /// Re-routes the loop so that feature k lies on side want[k], and every vertex of `more` on its
  /// side (InvalidInput when impossible).
  SeedLoop reroute_loop(const SeedLoop& loop, const std::vector<int>& want,
                        const std::vector<SideConstraint>& more = {}) const;
  /// The points of `seeds` (vertex ids) and then of the features (by index) on the surface.
  std::vector<Vec3> landmark_points(const std::array<int, 4>& seeds) const;
  const std::vector<Vec3>& positions() const { return cm_.positions(); }
  const std::vector<int>& feature_vertices() const { return feature_vertex_; }
  TriMesh trimesh() const { return cm_.to_trimesh(); }
  /// Labels the two seed patches of a traced loop (straightened into geodesics and relaxed first
  /// when the options ask; `straightened`: straighten()'s result for `loop`, made already).
  std::array<Node, 2> seed(SeedLoop loop, std::optional<GeodesicLoop> straightened = std::nullopt);
  /// DissectOptions::geodesic_seed_curves: `loop` straightened on this mesh (its features avoided).
  GeodesicLoop straighten(const SeedLoop& loop) const;
  /// The four seed curves as seed() cut them into the mesh: 3D points along each path.
  const std::array<std::vector<Vec3>, 4>& seed_curves() const { return seed_curves_; }
  /// The node's patch extracted (edges that would give border faces zero uv area split first) and
  /// mapped with the options' weights; its stretch and features filled in. Whether a map that
  /// folds takes mean-value weights instead is the set's choice (SetDissector::evaluate).
  Param parameterize(const Node& node);
  /// p's patch mapped with mean-value weights.
  param::SquareParam mean_value_map(const Param& p) const;
  /// p's map replaced by its mean-value map `mv` (p.weights, p.plain and p.st follow).
  void use_mean_value(Param& p, param::SquareParam mv) const;
  /// p's map stretch-minimized (kRepairRounds, p's weights), kept when it folds less, or, both
  /// bijective, when it is less stretched.
  void spread(Param& p) const;
  /// `snap`: a cut's crossing this near a free vertex (in edge parameter) passes through it.
  std::array<Node, 5> split(const Node& node, const Param& p, const Vec2& peak_uv, double w,
                            double snap = kSplitSnap);
  /// The same split with its four inner corners given (counter-clockwise from the one of corner
  /// 0): DissectOptions::same_pose places them per mesh. \pre a convex quad whose 8 cuts cross
  /// nowhere (inner_quad_ok).
  std::array<Node, 5> split(const Node& node, const Param& p, const std::array<Vec2, 4>& inner,
                            double snap = kSplitSnap);

  /// Puts a node's faces back after a failed split (in any mesh of the set).
  void restore(const Node& node, size_t first_new_label);
  /// Local refinement: splits the edges inside the node's patch at their midpoints (the surface
  /// is unchanged, only its sampling): every edge, or (with `p`) those of the faces that p's map
  /// folds and two rings around them. Neighbouring patches are untouched. Returns faces added.
  int refine(const Node& node, const Param* p = nullptr);
  /// Cuts straight segments of p's parameter domain (between local vertices of p: features and
  /// corners) into the node's patch, as the quinary split cuts its 8 segments but without snapping
  /// to nearby vertices (new vertices lie exactly on the segments, on the surface; the map is
  /// unchanged as a function on the surface), then re-extracts p (same map, new vertices).
  /// Throws SplitFailure when a segment cannot be traced (p is re-extracted all the same).
  void cut_segments(const Node& node, Param& p, const std::vector<std::array<int, 2>>& segments);
  size_t labels() const { return patch_faces_.size(); }
  size_t node_faces(const Node& node) const { return patch_faces_[node.label].size(); }
  /// Drops the parent's face list once every mesh of the set has split it.
  void commit_split(const Node& node) { patch_faces_[node.label].clear(); }
  /// Records a node as a leaf with its (aligned) parameterization.
  void keep_leaf(const Node& node, const Param& p, PatchInfo info);
  /// Keeps every leaf's parameterization from now on (take_over_leaves needs them).
  void keep_leaf_params() { keep_params_ = true; }
  /// Every leaf's map taken over from `ref`'s same leaf (kept in the same order, ref finished) by
  /// transfer_node_map, where the result is bijective; such a leaf is not repaired on its own.
  /// Returns the number of leaves taken over.
  int take_over_leaves(const MeshDissector& ref, const registration::Pose& pose, double reach,
                       const NodeMapPuller& untangle);
  Dissection finish(const std::vector<TreeNode>& tree);
  const std::string& name() const { return name_; }
  /// The label of the patch holding feature k (features never lie on a patch border).
  int feature_label(int k) const { return cm_.patch(CutMesh::face_of(cm_.out_halfedge(feature_vertex_[k]))); }

  /// Smoothed per-face stretch peak: (face, value). One sliver cannot decide.
  std::pair<int, double> peak(const Param& p) const;

 private:
  void grow() {
    const size_t n = cm_.num_vertices();
    if (local_of_.size() < n) {
      local_of_.resize(n, -1);
      uv_of_.resize(n, Vec2::Zero());
      flag_.resize(n, kFree);
    }
    face_uv_.resize(cm_.num_faces());
  }
  int split_edge(int h, double t) {
    const int m = cm_.split_edge(h, t);
    const int nf = cm_.num_faces();
    patch_faces_[cm_.patch(nf - 2)].push_back(nf - 2);
    patch_faces_[cm_.patch(nf - 1)].push_back(nf - 1);
    grow();
    return m;
  }
  int split_face(int f, const Vec3& bary) {
    const int m = cm_.split_face(f, bary);
    const int nf = cm_.num_faces();
    patch_faces_[cm_.patch(f)].push_back(nf - 2);
    patch_faces_[cm_.patch(f)].push_back(nf - 1);
    grow();
    return m;
  }
  int new_label() {
    patch_faces_.emplace_back();
    return static_cast<int>(patch_faces_.size()) - 1;
  }
  bool interior_edge(int h, int label) const {
    return cm_.patch(CutMesh::face_of(h)) == label && cm_.patch(CutMesh::face_of(cm_.opposite(h))) == label;
  }
  int insert_feature(const Feature& f);
  /// Inserts a vertex at a point of the input surface (or returns the vertex it lies on).
  int insert_surface_point(const landmarks::SurfacePoint& where, bool* inserted = nullptr);
  Extracted extract(const Node& node);
  /// param::border_degeneracies() of an extracted patch of `label`, its interior edges read off
  /// the cut mesh instead of validating the patch twice (parameterize_square() does).
  std::vector<std::array<int, 2>> border_degeneracies(const Extracted& ex, int label) const;
  /// p.features from p.ex: (feature index, local vertex), sorted.
  void collect_features(Param& p) const {
    p.features.clear();
    for (size_t i = 0; i < p.ex.verts.size(); ++i) {
      const int v = p.ex.verts[i];
      if (v < static_cast<int>(feature_of_.size()) && feature_of_[v] >= 0)
        p.features.emplace_back(feature_of_[v], static_cast<int>(i));
    }
    std::sort(p.features.begin(), p.features.end());
  }
  int insert_point(int label, const Vec2& q, bool snap);
  /// `snap`: a crossing this near a free vertex (in edge parameter) passes through it; `project`:
  /// and that vertex's uv moves onto the segment.
  std::vector<int> trace(int label, int a, int b, double snap, bool project);
  void project_onto_segment(int label, int v, const Vec2& q);

  const TriMesh& mesh_;  // the input, before any cut
  std::string name_;
  CutMesh cm_;
  DissectOptions opt_;
  const Context& ctx_;
  std::vector<int> feature_vertex_;            // by feature index (names sorted)
  std::vector<int> feature_of_;                // by vertex: feature index or -1
  std::vector<std::vector<int>> patch_faces_;  // by label
  std::vector<int> local_of_;                  // scratch: global vertex -> local, -1
  std::vector<Vec2> uv_of_;                    // scratch: uv of the patch being split
  std::vector<char> flag_;                     // scratch: Flag of the patch being split
  std::vector<std::array<Vec2, 3>> face_uv_;   // leaves' wedge uv, by global face
  std::unordered_set<std::uint64_t> cut_edges_;  // edges of the cuts of the split under way
  std::vector<Node> leaves_;
  std::vector<PatchInfo> infos_;
  struct Repair {
    size_t leaf;  // index into leaves_ / infos_
    Param param;  // the leaf as kept
    int rounds;
  };
  std::vector<Repair> repairs_;  // leaves to minimize in finish()
  bool keep_params_ = false;
  std::vector<Param> leaf_params_;  // keep_leaf_params: by leaf, as repaired
  void set_leaf_map(size_t leaf, const Param& p, const param::SquareParam& sp, const param::Stretch& st);
  void run_repairs();
  std::array<int, 4> seeds_{};
  std::array<std::vector<Vec3>, 4> seed_curves_;
  std::array<SeedPlacement, 4> seed_placements_{};

 public:
  /// The seeds given as surface points, inserted by the constructor (nullopt: none given).
  std::optional<std::array<int, 4>> inserted_seeds;
};

/// Local refinement rounds a node may get when it would otherwise end folded (set_dissector.cpp).
constexpr int kMaxRefinements = 3;
/// Only patches of at most this many faces are refined (each round about quadruples them).
constexpr size_t kRefineFaces = 2000;

/// Local untangling of a folded map (leaf_repair.cpp).
param::SquareParam untangle(const param::PatchMesh& pm, const param::SquareParam& in, const std::vector<char>& fixed,
                            int rounds);
/// A stretch-minimized, bijective map of a leaf, or an empty map when none is better (leaf_repair.cpp).
param::SquareParam minimized_leaf(const Param& p, int rounds, const Context& context);

/// Whether four inner corners make a quinary split: inside the unit square by at least `margin`,
/// a convex counter-clockwise quad, and no two of the 8 cuts (outer corner i to inner corner i,
/// inner corner i to i + 1) crossing (split_choice.cpp).
bool inner_quad_ok(const std::array<Vec2, 4>& inner, double margin);

/// Whether one mesh's node map asks for mean-value weights: its cotangent map `cot` folds, and the
/// mean-value map `mv` folds fewer faces and either `cot` flips a triangle (not only squeezes
/// faces to zero area) or `mv` is bijective. A squeeze that both weights leave does not ask,
/// unless the map's tessellation is the only one it must agree with (`one_tessellation`: a mesh
/// choosing alone, or meshes of one surface sharing one face list, whose mean-value maps then
/// differ only as the surfaces do).
bool wants_mean_value(const param::SquareParam& cot, const param::SquareParam& mv, bool one_tessellation);

/// The meshes whose node maps choose their weights together (1) rather than each alone (0):
/// mesh 0 and every mesh whose landmarks' geodesic distances differ from mesh 0's by at most
/// kIntrinsicLoopIsometry of their sum (`discrepancy`, route_intrinsic), when there are two or
/// more such meshes; all 0 when `discrepancy` is empty (not measured).
std::vector<char> joint_weights(const std::vector<double>& discrepancy);

/// The inner corners of a split at (peak, w): (1 - w) p_i + w peak for the square's corners p_i.
inline std::array<Vec2, 4> inner_corners(const Vec2& peak, double w) {
  std::array<Vec2, 4> inner;
  for (int i = 0; i < 4; ++i) inner[i] = (1 - w) * kSquare[i] + w * peak;
  return inner;
}

/// Smallest distance from the features to the 8 cuts of a split with inner corners `inner`
/// (split_choice.cpp); infinity without features.
double feature_clearance(const std::vector<Vec2>& features, const std::array<Vec2, 4>& inner);
/// The same for a split at (peak, w).
inline double feature_clearance(const std::vector<Vec2>& features, const Vec2& peak, double w) {
  return feature_clearance(features, inner_corners(peak, w));
}
/// The children's stretch predicted from the parent's map for a split at (peak, w) (split_choice.cpp).
double predicted_children_stretch(const Param& p, const Vec2& peak, double w);

/// A squeezed protrusion's peak lies at least this far inside the centre child's square (u,v)...
constexpr double kProtrusionMargin = 0.05;
/// ... which stays at least this far from the parent's sides, so that no outer child is a sliver.
constexpr double kProtrusionSideMargin = 0.1;
/// The centre nearest `peak` whose inner square (w) holds `raw` kProtrusionMargin inside and stays
/// kProtrusionSideMargin off the sides; `peak` when there is none (raw too near a side)
/// (split_choice.cpp, DissectOptions::protrusion_stretch).
Vec2 centre_holding(const Vec2& raw, const Vec2& peak, double w);

// Walks the union quinary tree over every mesh of the set at once (set_dissector.cpp; the
// alignment in feature_alignment.cpp, the choice of the split in split_choice.cpp).
class SetDissector {
 public:
  SetDissector(const std::vector<MeshToDissect>& in, const DissectOptions& options, const Context& context);
  DissectionSet run();

 private:
  // Parameterizes a node in every mesh and aligns its features to their mean (u,v).
  // `nodes` holds the node of every mesh (same name and label, each mesh's own corner ids).
  std::vector<Param> evaluate(const std::vector<Node>& nodes, TreeNode& tn);
  void align(const std::vector<Node>& nodes, std::vector<Param>& ps, TreeNode& tn);
  std::pair<Vec2, double> choose_split(const Node& node, const std::vector<Param>& ps, TreeNode& tn,
                                       const std::vector<bool>& over);
  // DissectOptions::same_pose: mesh 0 -> every mesh, the landmarks' similarity or the
  // registration given (DissectOptions::pose_registrations).
  void fit_poses(const std::vector<SeedLoop>& loops);
  // DissectOptions::same_pose: four curves of mesh 0 moved into mesh i's pose.
  std::array<std::vector<Vec3>, 4> in_pose(size_t i, const std::array<std::vector<Vec3>, 4>& curves) const;
  // DissectOptions::same_pose: mesh i's loop through its seeds routed along `guide` (curves of
  // mesh 0, moved into mesh i's pose), with the features on the sides `want`; nullopt when that
  // is impossible.
  std::optional<SeedLoop> pose_loop(size_t i, const SeedLoop& own, const std::vector<int>& want,
                                    const std::array<std::vector<Vec3>, 4>& guide) const;
  // DissectOptions::same_pose: fits the poses and seeds every mesh (mesh 0 first, then each other
  // mesh along mesh 0's curves, see pose_loop), pushing the seed patches onto roots.
  void seed_posed(std::vector<SeedLoop>& loops, std::array<std::vector<Node>, 2>& roots, DissectionSet& out);
  // DissectOptions::intrinsic_loops: routes every mesh's loop but the first's along the first's
  // in geodesic coordinates; returns how many were routed so (the others keep their own).
  // `discrepancy` gets per mesh how far its landmarks' geodesic distances are from mesh 0's.
  int route_intrinsic(std::vector<SeedLoop>& loops, std::vector<double>& discrepancy) const;
  // The inner corners of a split at (peak, w) in every mesh (mesh 0: the common ones; mesh i: its
  // points nearest mesh 0's, see same_pose), or empty when a mesh has none that make a split.
  std::vector<std::array<Vec2, 4>> posed_corners(const std::vector<Param>& ps, const Vec2& peak, double w) const;

  const std::vector<MeshToDissect>& in_;
  DissectOptions opt_;
  const Context& ctx_;
  std::vector<std::string> feature_names_;
  std::vector<MeshDissector> meshes_;
  std::vector<char> joint_weights_;    // per mesh: node weights chosen with the set (joint_weights)
  bool one_tessellation_ = false;      // the meshes choosing together share one face list
  std::vector<registration::Pose> pose_;  // same_pose: mesh 0 -> mesh i
  std::vector<double> pose_diagonal_;  // same_pose: each input's bounding-box diagonal
  // same_pose: why the meshes' own loops could not put every feature on one side (thrown only
  // when a mesh must keep its own loop, its loop not routed along mesh 0's).
  std::optional<InvalidInput> own_loops_failure_;
};

/// same_pose_maps: rounds of the fold repair of transfer_node_map that solve the folded vertices
/// alone, then rounds that free r + 1 rings around the folds (r = 0, 1, ...).
constexpr int kTransferLocalRounds = 10;
constexpr int kTransferRepairRounds = 6;
/// same_pose_maps: transfer_node_map takes the node's own map within one ring of a feature and
/// blends it into the taken-over map over this many rings; where folds outlast the repair, it does
/// the same around them over 2x as many rings, then repairs again (kTransferBlendAttempts times;
/// more attempts, over 4x and 8x the rings, mended larger tangles into worse cuts: a horse
/// against its re-tessellation 0.26 -> 0.43% mean) before the node keeps its own map.
constexpr int kTransferBlendRings = 3;
constexpr int kTransferBlendAttempts = 1;
/// Through a registration, where a map that stays folded serves the split as it is (Transfer::Folded)
/// and its cuts tangle the children's maps, a tangle left after kTransferBlendAttempts on at most
/// this share of the node's vertices gets one attempt more (over 4x the rings): smpl_man (100k
/// faces) against its pose re-tessellated to 140k then mends the nodes around its left heel (11 of
/// 6,396 vertices left), whose folded leaf had the whole set dissected again. Larger tangles mended
/// that way cut elsewhere (the posed horse: 46-276 vertices left, 2.6 -> 19% max error).
constexpr double kTransferSmallTangle = 0.01;
/// Through a registration, a small tangle (kTransferSmallTangle) that outlasts every attempt on a
/// node of at least this many vertices keeps the repaired map, folded there, for the split
/// (Transfer::Folded) instead of the untangler's pull of the own map over the whole node, which
/// is slow there (a coarse first mesh against a fine second one) and measured no closer; on
/// smaller nodes the pull is cheap and measured slightly closer (docs/pose-pairs.md).
constexpr int kTransferUntangleVertices = 10000;
/// Through a registration, a node map untangled from the node's own map (Transfer::Untangled) with
/// a face under this share of the square per share of the node's area gives way to the
/// nearest-point (u, v) as they are (Transfer::Folded): cuts through such a crushed region run
/// where nothing corresponds (docs/pose-pairs.md, "An untangled map squeezed to nothing").
constexpr double kUntangledSqueeze = 1e-6;
/// The smallest ratio, over the faces of `pm` with a positive area, of a face's signed uv area to
/// its share of the patch's area (1 everywhere for a map that keeps area ratios).
double smallest_area_share(const param::PatchMesh& pm, const std::vector<Vec2>& uv);
/// same_pose_maps: after a repair, the untangler frees the vertices the repair left off their
/// targets and this many rings around them (4 rings: the same result, slower).
constexpr int kTransferPolishRings = 2;

/// DissectOptions::same_pose_maps: mesh i's map of a node (`p`) taken over from mesh 0's (`ref`):
/// every vertex of p but its border and its features goes to the (u, v) of ref's point nearest to
/// it once moved into mesh 0's frame by `to_ref`, among ref's faces that face as the vertex does
/// (kSamePoseFacingCos; a vertex farther than `reach` from ref is left to the repair), except
/// around the features, where p's own map is blended in (kTransferBlendRings); then folded faces
/// are mended by solves of the node's own weights (p.weights) over the folded vertices
/// (kTransferLocalRounds), then over the free vertices around them, every other interior vertex
/// pinned, a ring wider each round (kTransferRepairRounds); where folds remain, p's own map is
/// blended in around them and the repair runs again (kTransferBlendAttempts; through a
/// registration once more for a small tangle, kTransferSmallTangle). p's own map may
/// fold (the take-over can mend a node that folds in this mesh), and so may ref's (its (u, v) are
/// read as they are). With `untangle` (DissectOptions::same_pose_untangle), a repaired map is
/// polished: the vertices the repair moved off their nearest-point (u, v), and
/// kTransferPolishRings rings around them, are pulled back toward them under an injectivity
/// barrier (Polished); where folds remain after the repair, p's own map, or its
/// stretch-minimized map (minimized_leaf) when the own map folds, is pulled toward them over the
/// whole node instead (Untangled), except through a registration where the repair left a small
/// tangle on a large node (kTransferUntangleVertices): then p.sp takes the repaired map, folded
/// only there (Folded); through a registration an untangled map squeezed below
/// kUntangledSqueeze is not kept either.
/// When no bijective map results, p.sp takes the nearest-point (u, v) as they are, folded, if
/// `pose` is a registration (Folded: the map serves the split only, whose cuts then run where
/// ref's do); otherwise, or when no vertex has a nearest point, p keeps its own map (Own).
enum class Transfer { Own, Taken, Polished, Untangled, Folded };
Transfer transfer_node_map(const Param& ref, const metro::SurfaceDistance& on_ref, const registration::Pose& pose,
                           double reach, const NodeMapPuller& untangle, const Context& context, Param& p);

/// same_pose: a posed corner farther than this fraction of its mesh's diagonal from the point it
/// stands for means the meshes are not in one pose there; the split keeps its common (u, v).
constexpr double kSamePoseReach = 0.05;
/// same_pose: the seed loop of mesh i follows mesh 0's (moved into its pose) with edge costs
/// length x (1 + (d / sigma)^2), sigma this fraction of mesh i's diagonal (trace_guided_loop).
constexpr double kPoseLoopSigma = 0.005;
/// One seed loop for the set (DissectOptions::intrinsic_loops): the width, in geodesic
/// coordinates (distances over the square root of the area), of the band around the first mesh's
/// loop that another mesh's loop is routed in.
constexpr double kIntrinsicLoopSigma = 0.2;
/// ... used only for a mesh whose landmarks' geodesic distances to each other differ from the
/// first mesh's by at most this fraction of their sum (one shape in another pose).
constexpr double kIntrinsicLoopIsometry = 0.05;
/// same_pose: posed inner corners stay this far inside the square.
constexpr double kSamePoseMargin = 0.03;

}  // namespace qs::dissect::detail
