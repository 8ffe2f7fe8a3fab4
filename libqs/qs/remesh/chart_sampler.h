#pragma once
// Evaluation of a dissected mesh at a patch point (patch, u, v): the inverse of the patch's
// parameterization (paper 4.1). Built once per chart, then reused by the uniform and adaptive
// remeshers (and by anything that resamples per patch, e.g. a normal-map baker).
//
// How a point is evaluated, so that points shared by patches come out bit-identical:
//  - a corner of the square (u and v each 0 or 1): the corner's chart vertex position;
//  - a point on a side (u or v exactly 0 or 1): linear interpolation along that side's chart
//    polyline, by the side coordinate seen from the edge's OWNER patch (the lower patch index,
//    see base_topology.h); the polyline's vertices carry the owner's uv. Both patches of a side
//    therefore get the same 3D point for the same side fraction (e.g. i / 2^n);
//  - an interior point: point location among the patch's uv triangles through a uniform grid
//    (about one cell per face), then barycentric interpolation of the 3D positions.

#include <memory>
#include <mutex>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"
#include "qs/dissect/dissection.h"
#include "qs/remesh/base_topology.h"

namespace qs::remesh {

class ChartSampler {
 public:
  /// Indexes `chart`, which must outlive the sampler (it is referenced, not copied).
  /// O(F log F) in the worst case, about 1-2 ms per 10k faces; the point-location grid is built on
  /// the first locate() / point() of an interior point. Movable, not copyable; const calls may
  /// run concurrently.
  /// \throws InvalidInput for a chart that is not a closed manifold dissection with consistent
  ///         face_patch / face_uv / patches (naming the face, edge, patch or side).
  explicit ChartSampler(const dissect::Chart& chart, const Context& context = {});

  const dissect::Chart& chart() const { return *chart_; }
  const BaseTopology& topology() const { return topology_; }
  int num_patches() const { return topology_.num_patches(); }
  /// Diagonal of the chart's bounding box (the error normalization of the adaptive remesher).
  double bbox_diagonal() const { return bbox_diagonal_; }

  /// A point on a chart face: face id and barycentric weights of its 3 corners (sum 1, >= 0).
  struct Location {
    int face = -1;
    Vec3 bary = Vec3(1, 0, 0);
  };
  /// The chart face of `patch` whose uv triangle contains uv (uv clamped to the unit square).
  /// Points on a shared uv edge go to either face; a point in no triangle (rounding gaps) goes to
  /// the nearest one, with its weights clamped to >= 0. \pre 0 <= patch < num_patches().
  /// `hint`: a face to try first (e.g. the previous answer for a nearby point), or -1.
  Location locate(int patch, const Vec2& uv, int hint = -1) const;

  /// Locates a whole regular grid of points of one patch at once, by scanning each face's rows of
  /// grid points (O(faces x rows they span + points), whatever the face distribution): the points
  /// (first + a * step, first + b * step) for a, b = 0..count-1, row by row (b outer). Gives the
  /// same kind of answer as locate() (a point on a shared uv edge goes to the face that contains it
  /// best, ties to the lower face id); points in no face fall back to locate().
  /// \pre 0 <= patch < num_patches(), count >= 0, step > 0.
  std::vector<Location> locate_grid(int patch, int count, double first, double step) const;
  /// The 3D point of a Location (barycentric combination of its face's corner positions).
  Vec3 position(const Location& location) const;

  /// The 3D point at (patch, uv), evaluated as described at the top of this file.
  /// \pre 0 <= patch < num_patches(); uv in [0,1]^2 (clamped otherwise).
  Vec3 point(int patch, const Vec2& uv) const;
  /// The same, with a face hint for the interior case (in: a face to try first or -1; out: the
  /// face used, unchanged for corner and side points). Fast for runs of nearby points.
  Vec3 point(int patch, const Vec2& uv, int& hint) const;

  /// Chart vertices along base edge e in the edge's direction (owner's side, corner to corner).
  const std::vector<int>& edge_vertices(int e) const { return edge_vertices_[e]; }
  /// Their side fractions in [0,1] (owner's uv), non-decreasing, first 0, last 1.
  const std::vector<double>& edge_fractions(int e) const { return edge_fractions_[e]; }
  /// The chart faces of a patch.
  const int* patch_faces_begin(int patch) const { return patch_faces_.data() + patch_face_offsets_[patch]; }
  const int* patch_faces_end(int patch) const { return patch_faces_.data() + patch_face_offsets_[patch + 1]; }

 private:
  Vec3 edge_point(int e, double t) const;
  int best_face(int patch, const Vec2& uv, const int* begin, const int* end, Vec3& bary, double& score) const;

  const dissect::Chart* chart_;
  BaseTopology topology_;
  double bbox_diagonal_ = 0;
  std::vector<std::vector<int>> edge_vertices_;
  std::vector<std::vector<double>> edge_fractions_;
  std::vector<int> patch_face_offsets_, patch_faces_;
  // Point-location grid, built on the first locate() (thread-safe): patch p has size[p]^2 cells
  // (about one per face) from cell index first[p]; cell c holds faces[offsets[c] .. offsets[c+1]).
  struct LocationGrid {
    std::once_flag once;
    std::vector<int> size, first, offsets, faces;
  };
  const LocationGrid& grid() const;
  std::unique_ptr<LocationGrid> grid_;
};

}  // namespace qs::remesh
