// DissectOptions::same_pose_maps: a node's map taken over from mesh 0 by nearest points, so that
// the cuts of a split, straight segments at equal (u, v) in every mesh, run along the same
// curves on every surface (see transfer_node_map in dissect_detail.h).

#include <algorithm>
#include <vector>

#include "qs/core/error.h"
#include "qs/dissect/dissect_detail.h"
#include "qs/landmarks/landmarks.h"
#include "qs/metro/metro.h"

namespace qs::dissect::detail {

bool transfer_node_map(const Param& ref, const metro::SurfaceDistance& on_ref, const Eigen::Matrix4d& to_ref,
                       double reach, Param& p) {
  const param::PatchMesh& pm = p.ex.pm;
  const int n = static_cast<int>(pm.positions.size());
  std::vector<char> border(n, 0), fixed = feature_mask(p);
  for (int v : pm.boundary) border[v] = fixed[v] = 1;

  // Every free vertex at the (u, v) of mesh 0's nearest point among the faces that face as the
  // vertex does (its normal turned into mesh 0's frame), so that it does not jump across a thin
  // part to the next finger; one farther than `reach` is left to the repair below.
  const std::vector<Vec3> normal = vertex_normals(pm.positions, pm.faces);
  const Eigen::Matrix3d turn = to_ref.topLeftCorner<3, 3>();
  std::vector<Vec2> uv = p.sp.uv;
  std::vector<char> unplaced(n, 0);
  int placed = 0;
  for (int v = 0; v < n; ++v) {
    if (fixed[v]) continue;
    const Vec3 q = (to_ref * pm.positions[v].homogeneous()).head<3>();
    const auto c = on_ref.closest_facing(q, turn * normal[v], kSamePoseFacingCos);
    if (c.face < 0 || c.distance > reach) {
      unplaced[v] = 1;
      continue;
    }
    const Tri& t = ref.ex.pm.faces[c.face];
    const auto l = landmarks::closest_on_triangle(q, ref.ex.pm.positions[t[0]], ref.ex.pm.positions[t[1]],
                                                  ref.ex.pm.positions[t[2]]);
    uv[v] = l[0] * ref.sp.uv[t[0]] + l[1] * ref.sp.uv[t[1]] + l[2] * ref.sp.uv[t[2]];
    ++placed;
  }
  if (placed == 0) return false;

  std::vector<std::vector<int>> ring(n);
  for (const Tri& t : pm.faces)
    for (int k = 0; k < 3; ++k) {
      ring[t[k]].push_back(t[(k + 1) % 3]);
      ring[t[k]].push_back(t[(k + 2) % 3]);
    }
  for (auto& r : ring) {
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
  }

  // Folds (and unplaced vertices) mended by solves of the node's own weights over the free
  // vertices around them, one ring wider each round; the map is kept only when it ends with
  // every face positive. Only the free vertices take the solve's (u, v): the border stays where
  // the node's map put it (parameterize_square places it by the same rule).
  for (int round = 0; round <= kTransferRepairRounds; ++round) {
    std::vector<char> free(n, 0);
    bool any = false;
    for (int v = 0; v < n; ++v)
      if (unplaced[v]) free[v] = any = true;
    for (const Tri& t : pm.faces)
      if (signed_area(uv[t[0]], uv[t[1]], uv[t[2]]) <= param::kZeroUvArea)
        for (int k = 0; k < 3; ++k)
          if (!fixed[t[k]]) free[t[k]] = any = true;
    if (!any) {
      param::SquareParam sp = p.sp;
      sp.uv = std::move(uv);
      param::count_uv_faces(pm.faces, sp);
      if (!sp.bijective()) return false;
      p.sp = std::move(sp);
      return true;
    }
    if (round == kTransferRepairRounds) break;
    for (int grow = 0; grow < round + 1; ++grow) {
      std::vector<char> wider = free;
      for (int v = 0; v < n; ++v)
        if (free[v])
          for (int w : ring[v])
            if (!fixed[w]) wider[w] = 1;
      free.swap(wider);
    }
    // The free vertices by the node's own weights, every other interior vertex pinned where
    // it is: in the limit (all free) the node's own map.
    param::SquareParamOptions po;
    po.weights = p.weights;
    for (int v = 0; v < n; ++v)
      if (!free[v] && !border[v]) po.pinned.emplace_back(v, uv[v]);
    try {
      const param::SquareParam solved = param::parameterize_square(pm, po);
      for (int v = 0; v < n; ++v)
        if (free[v]) uv[v] = solved.uv[v];
    } catch (const Error&) {
      return false;
    }
    std::fill(unplaced.begin(), unplaced.end(), 0);
  }
  return false;
}

}  // namespace qs::dissect::detail
