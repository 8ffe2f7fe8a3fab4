#pragma once
// Distance-field interpolation (DFI) morphs between two closed shapes of any genus: the stages
// chained (skeleton-guided DFI, ../shared/papers/skeleton-guided-dfi-metamorphosis.md).
//
//   prepare_morph: align the target to the source (optional similarity), one grid over both,
//                  signed distance fields of both shapes on it.
//   morph_frame:   the field of frame t, polygonized, mapped back along the interpolated alignment.
//
// Everything runs in morph space: the source's coordinates translated and scaled (uniformly) so
// that the box around both shapes has diagonal 1, and the alignment computed on both shapes
// scaled to unit size. Any finite coordinates the mesh validation accepts (up to 1e100, down to
// the smallest sizes double holds) therefore give the same frames, relative to the shapes' size,
// as the shapes scaled to unit size would; the frames come back in the inputs' own units.
//
// With the warp (the default), prepare_morph also builds the paper's correspondence: curve
// skeletons of both shapes, branch matching, anchors along matched branches, harmonic fields on
// the interior voxels of a coarse grid, the transport per matched part (or globally, the
// ablation), and from it a displacement field per shape, checked for folds; where branches are
// matched, the rotation-aware part warp of bones.h replaces that displacement (with
// Interpolation::Arap, the as-rigid-as-possible centres and thin-plate warps of arap.h). Frame t then
// blends the two fields warped toward each other. Without it, the plain blend (1 - t) d_0 + t d_1.

#include <array>
#include <string>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"
#include "qs/dfi/arap.h"
#include "qs/dfi/bones.h"
#include "qs/dfi/centre.h"
#include "qs/dfi/grid.h"
#include "qs/dfi/harmonic.h"
#include "qs/dfi/matching.h"
#include "qs/dfi/polygonize.h"
#include "qs/dfi/sdf.h"
#include "qs/dfi/skeleton.h"
#include "qs/dfi/topology.h"
#include "qs/dfi/warp.h"

namespace qs::dfi {

enum class Align {
  None,       ///< both shapes as given
  Similarity  ///< the target moved onto the source: volume centroids, a uniform scale that equals
              ///< the volumes, and the rotation between the principal axes of inertia (of the 24
              ///< that map one principal frame onto the other, the one whose target vertices lie
              ///< closest to the source surface on average); frames travel from the source's
              ///< placement to the target's (scale, rotation and centre interpolated)
};

/// How the volume of the frames between the ends is set.
enum class FrameVolume {
  Free,   ///< the zero level of the blended field, whatever volume it encloses
  Linear  ///< the iso level of each frame's blended field shifted (by at most max_iso_shift cells) so
          ///< that the volume it encloses follows (1 - t) V_0 + t V_1, both sides measured on the
          ///< fields with the same estimator (volume_below); the ends are never shifted
};

/// How the in-between positions of the correspondence are interpolated (with the warp).
enum class Interpolation {
  Arap,  ///< the paper's: as-rigid-as-possible positions of corresponding centres and thin-plate
         ///< RBF backward warps with a global affine part (arap.h)
  Parts  ///< the rotation-aware part warp along matched branches (bones.h), else the linear warp
};

struct MorphOptions {
  int grid = 150;          ///< cells along the longest side of the common bounding box
  int pad = 3;             ///< empty cells around it
  Align align = Align::None;
  SdfOptions sdf;          ///< band and threads
  PolygonizeOptions polygonize;
  bool warp = true;              ///< the skeleton-guided warp; false: the plain blend
  bool part_transport = true;    ///< transport per matched part (the paper); false: one global solve
  int anchors_per_branch = 3;    ///< interior anchors sampled on each matched branch
  /// The rotation-aware part warp (bones.h): each matched branch pair cut into this many segments
  /// whose transforms are interpolated as-rigidly-as-possible; 0: the linear warp of the transport
  /// displacement (warp.h), which is also what runs when no branch is matched or the part warp
  /// folds (a Jacobian determinant <= 0 at s = 0.5 or 1, after its smoothing).
  int bone_segments = 8;
  Interpolation interpolation = Interpolation::Parts;
  int arap_centres = 200;        ///< centre pairs of the ARAP interpolation (Interpolation::Arap)
  /// Skeleton nodes moved to the centre of their cross-section in the distance fields before the
  /// matching (centre.h); false: where mean curvature flow left them.
  bool centre_skeletons = true;
  double prune_fraction = 0.08;  ///< skeleton spurs shorter than this times the source's bounding-box
                                 ///< diagonal are pruned (prune_skeleton)
  FrameVolume volume = FrameVolume::Linear;
  double max_iso_shift = 4;      ///< cells: the largest iso-level shift of FrameVolume::Linear (0 to 64)
  /// Topology control (topology.h, make_ball): when both inputs are genus 0, every frame's inside
  /// set is grown from its deepest sample by simple points only, so that each frame is one closed
  /// genus-0 surface (the inside samples that would close a handle or belong to another piece are
  /// set just outside); an end frame whose own input is genus 0 too. Frames of shapes of other
  /// genus are left as blended. false: no control.
  bool topology_control = true;
  int emd_voxels = 1500;         ///< at most this many interior voxels per shape on the coarse grid
  double position_weight = 0.1;  ///< weight of the voxel distance (per bounding-box diagonal) added to
                                 ///< the harmonic-vector distance in the transport cost (breaks ties)
  /// Feature nodes matched by the electors' votes (matching.h); false: nearest-first alone.
  bool voting = true;
  /// Named landmarks forcing skeleton matches: the skeleton nodes nearest to these points (source
  /// coordinates, target coordinates) are matched first.
  struct Landmark {
    std::string name;
    Vec3 source, target;
  };
  std::vector<Landmark> landmarks;
};

/// A similarity: y = s R (x - from) + to.
struct Similarity {
  double scale = 1;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Vec3 from = Vec3::Zero(), to = Vec3::Zero();
  Vec3 apply(const Vec3& x) const { return scale * (rotation * (x - from)) + to; }
  Similarity inverse() const;
  /// This after `first`: x -> apply(first.apply(x)).
  Similarity after(const Similarity& first) const;
};

struct PreparedMorph {
  Similarity target_to_source;  ///< target coordinates -> source coordinates; identity when Align::None
  /// Source coordinates -> morph space (a translation and a uniform scale: the box around both
  /// shapes gets diagonal 1); identity when built by hand.
  Similarity source_to_morph;
  Similarity target_to_morph;   ///< target coordinates -> morph space (source_to_morph after target_to_source)
  Vec3 source_centroid = Vec3::Zero();  ///< the source's volume centroid, in morph space
  Grid source_sdf, target_sdf;  ///< on the same samples, in morph space
  double source_volume = 0, target_volume = 0;  ///< of the input meshes, in their own units
  FrameVolume volume = FrameVolume::Free;       ///< from MorphOptions (prepare_morph); Free when built by hand
  double max_iso_shift = 4;                     ///< from MorphOptions (cells)
  bool topology_control = false;                ///< from MorphOptions; false when built by hand
  int source_genus = 0, target_genus = 0;       ///< of the input meshes (mesh_stats)
  // The correspondence (only with options.warp), everything in morph space.
  bool warp = false;
  Skeleton source_skeleton, target_skeleton;
  std::vector<Branch> source_branches, target_branches;
  CentreReport source_centring, target_centring;  ///< what centre_skeleton did (centre_skeletons)
  SkeletonMatching matching;
  std::vector<AnchorPair> anchors;     ///< the ones kept (distinct voxels on both sides)
  int emd_cells = 0;                   ///< coarse grid cells along the longest side
  int source_voxels = 0, target_voxels = 0, parts = 0;
  double transport_cost = 0;           ///< sum over parts of the optimal cost (mass-weighted)
  double harmonic_agreement = 0;       ///< fraction of source voxel mass whose partners' harmonic
                                       ///< vectors are within 0.002 * #anchors (the paper's figure 10)
  Displacement source_warp, target_warp;
  FoldCheck source_folds, target_folds;
  // The rotation-aware part warp (when bone_segments > 0 and a branch is matched): used instead
  // of source_warp / target_warp.
  std::vector<Bone> bones;             ///< source -> target segments
  Grid bone_grid;                      ///< where the per-frame displacements are sampled (values unused)
  double bone_min_det = 1;             ///< smallest Jacobian determinant of the part warps (both ways,
                                       ///< s = 0.5 and 1); <= 0: they fold, bones is left empty and the
                                       ///< linear warp runs
  // The ARAP interpolation (Interpolation::Arap): used instead of both warps above when not empty.
  ArapInterpolation arap;
  double arap_lambda = 0;              ///< the thin-plate smoothing that keeps every frame's warps unfolded
  double arap_min_det = 1;             ///< smallest Jacobian determinant of the backward warps checked
  /// The grid spacing in the source's units.
  double spacing() const { return source_sdf.spacing / source_to_morph.scale; }
};

/// \pre both meshes closed, manifold, outward oriented, one component (qs::mesh::validate with
/// allow_any_genus). \throws InvalidInput for options out of range.
PreparedMorph prepare_morph(const TriMesh& source, const TriMesh& target, const MorphOptions& options = {},
                            const Context& ctx = {});

/// What blend_field did to one frame's field.
struct BlendInfo {
  double iso_shift = 0;       ///< world units subtracted from the blend (> 0 grows the shape); 0 at the ends
  double volume_wanted = 0;   ///< (1 - t) V_0 + t V_1 by volume_below (FrameVolume::Linear between the ends)
  double volume_blended = 0;  ///< volume_below of the blend before the shift
  bool clamped = false;       ///< the wanted volume needed more than max_iso_shift cells
  bool topology_controlled = false;  ///< make_ball ran on the frame (controls_topology)
  BallReport ball;                   ///< what it removed
};

/// Whether the frame at t gets the topology control: the morph's topology_control on, and the
/// ends' input (t = 0: the source, t = 1: the target) or, between them, both inputs genus 0.
bool controls_topology(const PreparedMorph& morph, double t);

/// The volume enclosed by the level c of a sampled field (negative inside): each sample counts
/// its cell volume times clamp(1/2 + (c - value) / spacing, 0, 1), a smoothed step one cell wide
/// (exact for a plane, within O(spacing^2) of the polygonization's volume for a distance field).
/// Non-decreasing in c.
double volume_below(const Grid& field, double c = 0);

/// The iso value c whose volume_below equals `volume` (bisection to 1e-6 cells), clamped to
/// [-max_shift, max_shift] (world units). \pre field has values.
double iso_for_volume(const Grid& field, double volume, double max_shift);

/// The field of frame t in [0, 1]: (1 - t) d_0 + t d_1, each warped toward the other when the
/// morph has a warp (the part warp of bones.h when it has bones: each frame's displacement
/// smoothed by Jacobi steps (32 on a 150-cell grid), inverted by Newton steps). Boundary samples are kept outside
/// (>= one spacing). For 0 < t < 1, outside regions that do not reach the boundary (cavities,
/// which neither input has) are filled, and inside islands of at most 8 samples or 0.2% of the
/// frame's inside samples (specks and pieces of parts thinner than the grid) dropped, both along the edges of the polygonization's tetrahedra. With
/// FrameVolume::Linear (the default) the blend's iso level is shifted first, for 0 < t < 1, so
/// that the frame's volume follows the linear interpolation of the ends' (iso_for_volume).
/// Last, where controls_topology(morph, t), the inside set is made a ball (make_ball).
Grid blend_field(const PreparedMorph& morph, double t, int threads = 0, BlendInfo* info = nullptr);

/// The frame at t: the zero set of `field`, mapped from morph space to the placement at t (the
/// source's at 0, the target's at 1, interpolated in between), in the inputs' units. \throws
/// InvalidInput if a position would not be finite there.
TriMesh frame_mesh(const PreparedMorph& morph, const Grid& field, double t, const PolygonizeOptions& options = {});

/// Frame 0 (is_target false) or frame K-1 (true) polygonized from the input's own signed distance
/// field on a grid over the input's bounding box alone, `refine` times finer than the morph's grid
/// (in the input's own units), in the input's coordinates (what frame_mesh gives at t = 0 or 1):
/// parts thinner than a morph voxel (ears, tails) that the morph's grid loses. refine 1: the
/// morph's spacing. The input is scaled to unit size for the distance field and the polygonization
/// (its coordinates may be of any finite magnitude). With the morph's topology control and a genus-0 input, the field's inside set
/// is made a ball first (make_ball; `ball` says what it removed). \throws InvalidInput when
/// refine is not 1 to 8 or the grid would exceed 2048 cells.
TriMesh endpoint_frame(const PreparedMorph& morph, const TriMesh& input, bool is_target, int refine,
                       const SdfOptions& sdf = {}, const PolygonizeOptions& options = {}, BallReport* ball = nullptr);

/// The similarity's inverse interpolated at t (identity at 0): source space -> output space.
Vec3 placement(const Similarity& s, double t, const Vec3& y);

/// What a morph will hold, for an estimate of its memory before any large allocation: the
/// shapes placed as prepare_morph places them (the alignment included), nothing sampled.
struct MorphSize {
  std::array<int, 3> grid_dims{0, 0, 0};                  ///< the morph's grid (both fields)
  std::array<int, 3> source_end_dims{0, 0, 0}, target_end_dims{0, 0, 0};  ///< endpoint_frame's grids
  double source_area = 0, target_area = 0;  ///< surface areas in morph space
  double spacing = 0;                       ///< the grid spacing in morph space
};

/// The sizes prepare_morph and endpoint_frame(refine) would use. Cheap: the alignment (when
/// asked for) and bounding boxes only. \throws InvalidInput as prepare_morph does.
MorphSize morph_size(const TriMesh& source, const TriMesh& target, const MorphOptions& options, int endpoint_refine);

/// What the memory estimate of a run counts besides the grids.
struct MemoryRequest {
  int frames = 11;           ///< frames written (one at a time unless kept for a GLB)
  int endpoint_refine = 3;   ///< endpoint_frame's refinement (1: the ends from the morph's grid)
  bool even_timing = true;   ///< even_frame_times runs (its dense frames are held together)
  bool keep_frames = false;  ///< every frame is held until the end (a GLB of all frames)
  int samples_per_frame = 4, refine_passes = 3, coarsen = 2;  ///< RetimeOptions
};

/// A conservative estimate of the peak memory (bytes) of a run; the formula is in
/// docs/tools/qs-dfi.md. Finite for any request (it saturates at DBL_MAX).
double estimate_memory(const MorphSize& size, const MemoryRequest& request, bool warp);

}  // namespace qs::dfi
