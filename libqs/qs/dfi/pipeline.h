#pragma once
// Distance-field interpolation (DFI) morphs between two closed shapes of any genus: the stages
// chained (skeleton-guided DFI, ../shared/papers/skeleton-guided-dfi-metamorphosis.md).
//
//   prepare_morph: align the target to the source (optional similarity), one grid over both,
//                  signed distance fields of both shapes on it.
//   morph_frame:   the field of frame t, polygonized, mapped back along the interpolated alignment.
//
// What is implemented today is the plain blend d_t = (1 - t) d_0 + t d_1 (the paper's baseline,
// `--no-warp`); see README "qs-dfi" for the stages of the skeleton-guided warp and their state.

#include <string>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"
#include "qs/dfi/grid.h"
#include "qs/dfi/polygonize.h"
#include "qs/dfi/sdf.h"

namespace qs::dfi {

enum class Align {
  None,       ///< both shapes as given
  Similarity  ///< the target moved onto the source: volume centroids, a uniform scale that equals
              ///< the volumes, and the rotation between the principal axes of inertia (of the 24
              ///< that map one principal frame onto the other, the one whose target vertices lie
              ///< closest to the source surface on average); frames travel from the source's
              ///< placement to the target's (scale, rotation and centre interpolated)
};

struct MorphOptions {
  int grid = 150;          ///< cells along the longest side of the common bounding box
  int pad = 3;             ///< empty cells around it
  Align align = Align::None;
  SdfOptions sdf;          ///< band and threads
  PolygonizeOptions polygonize;
};

/// Target space to morph space: y = s R (x - from) + to.
struct Similarity {
  double scale = 1;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Vec3 from = Vec3::Zero(), to = Vec3::Zero();
  Vec3 apply(const Vec3& x) const { return scale * (rotation * (x - from)) + to; }
};

struct PreparedMorph {
  Similarity target_to_source;  ///< identity when Align::None
  Grid source_sdf, target_sdf;  ///< on the same samples, in morph (source) space
  double source_volume = 0, target_volume = 0;  ///< of the input meshes, in their own units
};

/// \pre both meshes closed, manifold, outward oriented, one component (qs::mesh::validate with
/// allow_any_genus). \throws InvalidInput for options out of range.
PreparedMorph prepare_morph(const TriMesh& source, const TriMesh& target, const MorphOptions& options = {},
                            const Context& ctx = {});

/// The plain blend's field at t in [0, 1]: (1 - t) d_0 + t d_1.
Grid blend_field(const PreparedMorph& morph, double t);

/// The frame at t: the zero set of `field`, mapped from morph space to the placement at t (the
/// source's at 0, the target's at 1, interpolated in between).
TriMesh frame_mesh(const PreparedMorph& morph, const Grid& field, double t, const PolygonizeOptions& options = {});

/// The similarity's inverse interpolated at t (identity at 0): morph space -> output space.
Vec3 placement(const Similarity& s, double t, const Vec3& y);

}  // namespace qs::dfi
