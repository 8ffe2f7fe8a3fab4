#pragma once
// Internal to the remesh module: the pieces of the anisotropic remesh (anisotropic.h) that its
// files share: the tree (anisotropic_tree.cpp), the smoothing and sliding (anisotropic_smooth.cpp)
// and the edge flips (anisotropic_flip.cpp). Not part of the API. The method: docs/algorithms.md.

#include <array>
#include <cstddef>
#include <functional>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"
#include "qs/remesh/anisotropic.h"
#include "qs/remesh/base_topology.h"
#include "qs/remesh/chart_sampler.h"
#include "qs/remesh/semi_regular.h"

namespace qs::remesh::aniso {

/// A leaf cell emitted as two triangles (faces first_face, first_face + 1), cut along 0-2 or 1-3.
struct LeafCut {
  size_t first_face;
  bool diag02;
};

/// Refines every patch's tree (progress "remesh" 0 .. 0.6, the cancel flag checked per patch),
/// balances the trees and lists the leaves: sets out.leaves, out.leaf_aspect and the split counts of
/// out.stats. \pre samplers not empty, matching chart 0 (set_samplers); options checked.
void build_leaves(const std::vector<ChartSampler>& samplers, const AnisotropicOptions& options,
                  const Context& context, AnisotropicRemesh& out);

/// The faces of the leaves (two triangles, a 3-triangle template or a fan per leaf), the cells cut
/// in two listed in `cuts`, the template cells' first faces in `templates`; face_leaf (#F) names
/// each face's leaf and fan_leaves counts the fans.
SemiRegularConnectivity leaf_connectivity(const BaseTopology& t, const std::vector<AnisoNode>& leaves,
                                          std::vector<LeafCut>& cuts, std::vector<size_t>& templates,
                                          int& fan_leaves, std::vector<int>& face_leaf);

/// The uv of vertex v in patch p's frame: its own (patch, uv) when that is p, else (a patch corner
/// or a side sample recorded in another patch) the point of p's border that it is, the nearest one
/// to `near` when several are. \throws InternalError when v is not on p's border.
Vec2 uv_in_patch(const BaseTopology& t, const SemiRegularConnectivity& c, int v, int p, const Vec2& near);

/// sin of the smallest angle of triangle (a, b, c) (0 when degenerate).
double sin_min_angle(const Vec3& a, const Vec3& b, const Vec3& c);

/// A remesh vertex strictly inside its patch's square (not a base vertex, not on a side).
bool patch_interior(const SemiRegularConnectivity& c, int v);

/// A 3-triangle template cell (A, M, B, C, D counter-clockwise, M the hanging vertex between A and
/// B), emitted as (A, M, D), (M, B, C), (M, C, D): re-cut as the fan from C or from D when that
/// raises the smallest angle over the set. With `accept`, only the present cut and the cuts it
/// accepts are candidates.
void recut_template_best_angle(Tri* f, const std::array<int, 5>& amcbd, const std::vector<std::vector<Vec3>>& positions,
                               const std::function<bool(const std::array<Tri, 3>&)>& accept = {});

/// Tangential smoothing of the patch-interior vertices whose ring has a smallest angle under
/// below_degrees (Gauss-Seidel in vertex order, one uv per vertex for the whole set, at most
/// `iterations` sweeps). With `active` (#V flags), only the flagged vertices and the neighbours of
/// the moved ones are tried. Returns the number of accepted moves.
int smooth_interior(const std::vector<ChartSampler>& samplers, SemiRegularConnectivity& c,
                    std::vector<std::vector<Vec3>>& positions, int iterations, double below_degrees,
                    std::vector<char>* active = nullptr);

/// Sliding of the patch-side vertices along their side, one fraction per vertex shared by the two
/// patches of the side; otherwise as smooth_interior. Returns the number of accepted moves.
int slide_sides(const std::vector<ChartSampler>& samplers, SemiRegularConnectivity& c,
                std::vector<std::vector<Vec3>>& positions, int iterations, double below_degrees,
                const std::vector<char>* active = nullptr);

/// Edge flips inside patches that raise the smallest angle of the pair over the set (its worst under
/// below_degrees), keep the new edge near the surface and the pair counter-clockwise in the patch's
/// (u,v). Faces are replaced in place; `touched` (#V) flags the corners of every flipped pair.
/// Returns the number of flips.
int flip_for_angles(const std::vector<ChartSampler>& samplers, SemiRegularConnectivity& c,
                    const std::vector<std::vector<Vec3>>& positions, double below_degrees,
                    std::vector<char>& touched);

}  // namespace qs::remesh::aniso
