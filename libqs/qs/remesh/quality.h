#pragma once
// Shape and sampling measures of a remesh: the smallest-angle distribution of its
// triangles, and how evenly samples (remesh vertices, normal-map texels) cover the surface.

#include <vector>

#include "qs/core/mesh.h"
#include "qs/dissect/dissection.h"

namespace qs::remesh {

/// The distribution of the smallest interior angle of each triangle, in degrees.
struct AngleStats {
  long faces = 0;          ///< triangles measured (all of the mesh's)
  double under_5 = 0;      ///< share of the triangles (0..1) whose smallest angle is < 5 degrees
  double under_10 = 0;     ///< ... < 10 degrees
  double under_20 = 0;     ///< ... < 20 degrees
  double median = 0;       ///< median smallest angle (mean of the two middle values for an even count)
  double min = 0;          ///< the smallest angle of any triangle
};

/// Smallest-angle statistics of every face of `mesh`. A degenerate triangle (two coincident
/// vertices, or three on a line) has a smallest angle of 0. An equilateral triangle scores 60,
/// a right isosceles one 45 (the most a regular split of a square grid can give).
/// \throws InvalidInput for a face index out of range. A mesh without faces gives all zeros.
AngleStats smallest_angle_stats(const TriMesh& mesh);

/// How evenly a density (samples per unit of surface area) is spread over a surface:
/// area-weighted percentiles, each the value below which that share of the surface area lies.
struct DensitySpread {
  double p5 = 0, p50 = 0, p95 = 0;  ///< samples per unit area (in the mesh's units squared)
  double spread = 0;  ///< p95 / p5 (1 = perfectly even; infinity when p5 is 0)
};

/// Vertex density of a remesh: on each face f, 1 / (2 area(f)) vertices per unit area (a closed
/// triangle mesh has about twice as many faces as vertices), weighted by area(f). Faces of zero
/// area carry no surface and are skipped.
/// \throws InvalidInput for a face index out of range or a mesh with no area.
DensitySpread vertex_density(const TriMesh& mesh);

/// Density of a regular grid of `samples_per_side` x `samples_per_side` cells per unit square of
/// every patch, mapped onto the surface by the chart's parameterization: on each chart face,
/// samples_per_side^2 * (uv area) / (3D area) samples per unit area, weighted by the 3D area. With
/// samples_per_side = 2^n it is the cell density of a level-n uniform remesh at full resolution;
/// with S - 1 (S the tile size) the texel density of a normal-map atlas.
/// \throws InvalidInput for samples_per_side <= 0 or a chart with no area.
DensitySpread chart_density(const dissect::Chart& chart, double samples_per_side);

/// The same with a count per patch (index = patch; e.g. S_p - 1 for an atlas whose tiles differ).
/// \throws InvalidInput for a count <= 0, or a face in a patch without a count.
DensitySpread chart_density(const dissect::Chart& chart, const std::vector<double>& samples_per_side);

/// Each patch's share of its mesh's surface area (0..1), the largest over the charts of a set.
/// \throws InvalidInput for no charts, charts with other patch counts, or a chart with no area.
std::vector<double> patch_area_shares(const std::vector<const dissect::Chart*>& charts);

/// What each patch's texture tile must cover, as a share of its mesh's surface, for an even texel
/// density: 1 / (median of uv area / 3D area over the patch's faces, weighted by 3D area) divided
/// by the mesh's area, the largest over the charts. For an evenly mapped patch (uv area in
/// proportion to 3D area) it equals the patch's area share; for a distorted map it follows the
/// density of the patch's median face, not its mean, so that a squeezed corner does not set the
/// tile size of the whole patch. A patch without area gets 0.
/// \throws InvalidInput for no charts, charts with other patch counts, or a chart with no area.
std::vector<double> patch_texel_shares(const std::vector<const dissect::Chart*>& charts);

}  // namespace qs::remesh
