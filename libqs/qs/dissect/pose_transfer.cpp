// DissectOptions::same_pose_maps: a node's map taken over from mesh 0 by nearest points, so that
// the cuts of a split, straight segments at equal (u, v) in every mesh, run along the same
// curves on every surface (see transfer_node_map in dissect_detail.h).

#include <algorithm>
#include <limits>
#include <optional>
#include <vector>

#include "qs/core/error.h"
#include "qs/core/parallel.h"
#include "qs/dissect/dissect_detail.h"
#include "qs/landmarks/landmarks.h"
#include "qs/metro/metro.h"

namespace qs::dissect::detail {

double smallest_area_share(const param::PatchMesh& pm, const std::vector<Vec2>& uv) {
  double total = 0;
  std::vector<double> area(pm.faces.size());
  for (size_t f = 0; f < pm.faces.size(); ++f) {
    const Tri& t = pm.faces[f];
    area[f] = 0.5 * (pm.positions[t[1]] - pm.positions[t[0]]).cross(pm.positions[t[2]] - pm.positions[t[0]]).norm();
    total += area[f];
  }
  double smallest = std::numeric_limits<double>::infinity();
  for (size_t f = 0; f < pm.faces.size(); ++f) {
    if (!(area[f] > 0)) continue;
    const Tri& t = pm.faces[f];
    smallest = std::min(smallest, signed_area(uv[t[0]], uv[t[1]], uv[t[2]]) * total / area[f]);
  }
  return smallest;
}

Transfer transfer_node_map(const Param& ref, const metro::SurfaceDistance& on_ref, const registration::Pose& pose,
                           double reach, const NodeMapPuller& untangle, const Context& context, Param& p) {
  const param::PatchMesh& pm = p.ex.pm;
  const int n = static_cast<int>(pm.positions.size());
  std::vector<char> fixed = feature_mask(p);
  for (int v : pm.boundary) fixed[v] = 1;

  // Every free vertex at the (u, v) of mesh 0's nearest point among the faces that face as the
  // vertex does (its normal turned into mesh 0's frame), so that it does not jump across a thin
  // part to the next finger; one farther than `reach` is left to the repair below.
  const std::vector<Vec3> normal = vertex_normals(pm.positions, pm.faces);
  std::vector<Vec2> uv = p.sp.uv;
  std::vector<char> unplaced(n, 0), has_target(n, 0);
  constexpr int kBlock = 256;
  parallel_for((n + kBlock - 1) / kBlock, inside_parallel_loop() ? 1 : 0, context, [&](int b) {
    for (int v = b * kBlock; v < std::min(n, (b + 1) * kBlock); ++v) {
      if (fixed[v]) continue;
      const auto [q, facing] = pose.inverse(pm.positions[v], normal[v]);
      const auto c = on_ref.closest_facing(q, facing, kSamePoseFacingCos);
      if (c.face < 0 || c.distance > reach) {
        unplaced[v] = 1;
        continue;
      }
      const Tri& t = ref.ex.pm.faces[c.face];
      const auto l = landmarks::closest_on_triangle(q, ref.ex.pm.positions[t[0]], ref.ex.pm.positions[t[1]],
                                                    ref.ex.pm.positions[t[2]]);
      uv[v] = l[0] * ref.sp.uv[t[0]] + l[1] * ref.sp.uv[t[1]] + l[2] * ref.sp.uv[t[2]];
      has_target[v] = 1;
    }
  });
  if (std::find(has_target.begin(), has_target.end(), 1) == has_target.end()) return Transfer::Own;
  const std::vector<Vec2> target = uv;

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
  // `mask` grown by `rings` rings (over the vertices with skip[v] == 0 only, when given).
  auto widen = [&](std::vector<char>& mask, int rings, const std::vector<char>* skip) {
    for (int g = 0; g < rings; ++g) {
      std::vector<char> wider = mask;
      for (int v = 0; v < n; ++v)
        if (mask[v])
          for (int w : ring[v])
            if (!skip || !(*skip)[w]) wider[w] = 1;
      mask.swap(wider);
    }
  };

  // The node's own map and the taken-over one agree on the border and at the features (both at
  // their common (u, v)), and the own map is mostly a good local shape (bijective unless the node
  // folds in this mesh, which the take-over can mend). Around a held vertex the taken-over rings
  // can still fold against it: the two landmarks of a feature are one point only up to each
  // mesh's tessellation, which a squeezed map magnifies, and an inserted feature or a cut vertex
  // next to a sliver turns over at the slightest offset. There the own map's shape is taken:
  // within one ring of `from` entirely, then blended into the taken-over map over `rings` rings.
  auto blend_own = [&](std::vector<Vec2>& at, const std::vector<int>& from, int rings) {
    std::vector<int> hops(n, -1), frontier;
    for (int v : from)
      if (hops[v] < 0) {
        hops[v] = 0;
        frontier.push_back(v);
      }
    for (int h = 1; h <= rings && !frontier.empty(); ++h) {
      std::vector<int> next;
      for (int v : frontier)
        for (int w : ring[v])
          if (hops[w] < 0) {
            hops[w] = h;
            next.push_back(w);
          }
      frontier.swap(next);
    }
    for (int v = 0; v < n; ++v) {
      if (hops[v] < 0 || fixed[v]) continue;
      const double own = hops[v] <= 1 ? 1.0 : 1.0 - static_cast<double>(hops[v] - 1) / rings;
      at[v] = (1 - own) * at[v] + own * p.sp.uv[v];
      unplaced[v] = 0;
    }
  };
  std::vector<int> features;
  for (const auto& [k, local] : p.features) features.push_back(local);
  blend_own(uv, features, kTransferBlendRings);

  // Folds (and unplaced vertices) mended by solves of the node's own weights over the free
  // vertices around them: first the folded vertices alone, again and again, then one ring wider
  // each round. Only the free vertices take the solve's (u, v): the border stays where the node's
  // map put it (parameterize_square places it by the same rule). Returns the vertices of the
  // faces still folded (empty: every face positive), nullopt when a solve fails.
  std::optional<param::HeldSolver> held;  // the node's weights, built at the first solve
  auto repair = [&](std::vector<Vec2>& at) -> std::optional<std::vector<int>> {
    std::vector<int> left;
    for (int round = 0; round <= kTransferLocalRounds + kTransferRepairRounds; ++round) {
      std::vector<char> free(n, 0);
      bool any = false;
      for (int v = 0; v < n; ++v)
        if (unplaced[v]) free[v] = any = true;
      for (const Tri& t : pm.faces)
        if (signed_area(at[t[0]], at[t[1]], at[t[2]]) <= param::kZeroUvArea)
          for (int k = 0; k < 3; ++k)
            if (!fixed[t[k]]) free[t[k]] = any = true;
      left.clear();
      for (int v = 0; v < n; ++v)
        if (free[v]) left.push_back(v);
      if (!any || round == kTransferLocalRounds + kTransferRepairRounds) break;
      widen(free, round < kTransferLocalRounds ? 0 : round - kTransferLocalRounds + 1, &fixed);
      // The free vertices by the node's own weights, every other interior vertex held where it
      // is: in the limit (all free) the node's own map.
      try {
        if (!held) held.emplace(pm, p.weights);
        held->solve(free, at);
      } catch (const Error&) {
        return std::nullopt;
      }
      std::fill(unplaced.begin(), unplaced.end(), 0);
    }
    return left;
  };

  int folded = 0;  // faces the nearest points fold, before the repair
  for (const Tri& t : pm.faces) folded += signed_area(uv[t[0]], uv[t[1]], uv[t[2]]) <= param::kZeroUvArea;
  // Where folds remain, the own map's shape around them, over more rings each attempt; through a
  // registration, a small tangle (at most kTransferSmallTangle of the node's vertices) that
  // outlasts those attempts gets one more.
  auto small_tangle = [&](size_t vertices) {
    return pose.registered() && static_cast<double>(vertices) <= kTransferSmallTangle * n;
  };
  std::optional<param::SquareParam> repaired;
  size_t tangle = 0;  // vertices the last repair left folded (0 once a repair unfolded the map)
  for (int attempt = 0;; ++attempt) {
    const std::optional<std::vector<int>> left = repair(uv);
    tangle = left ? left->size() : 0;
    if (!left) break;
    if (left->empty()) {
      param::SquareParam sp = p.sp;
      sp.uv = std::move(uv);
      param::count_uv_faces(pm.faces, sp);
      if (sp.bijective()) repaired = std::move(sp);
      break;
    }
    if (attempt >= kTransferBlendAttempts + (small_tangle(tangle) ? 1 : 0)) break;
    blend_own(uv, *left, kTransferBlendRings << (attempt + 1));
  }
  // No bijective map near the targets (mesh 0's map folds there: a leg squeezed to zero uv area).
  // In another pose (a registration), the targets as they are: the map serves only the split,
  // whose cuts then run where mesh 0's do, and the children are parameterized afresh; the own map
  // of a limb bent otherwise cuts elsewhere (a posed horse's hoof: 21% of the diagonal). In one
  // pose (a similarity: the same shape), the own map cuts close to mesh 0's, and folded targets
  // can tangle the cuts (a camel against its re-tessellation: 214 folded uv faces, pose given up).
  auto as_targets = [&] {
    if (!pose.registered()) return Transfer::Own;
    for (int v = 0; v < n; ++v)
      if (has_target[v]) p.sp.uv[v] = target[v];
    param::count_uv_faces(pm.faces, p.sp);
    return Transfer::Folded;
  };
  if (repaired && (folded == 0 || !untangle)) {
    p.sp = std::move(*repaired);
    return Transfer::Taken;
  }
  if (!untangle) return as_targets();
  // Through a registration, a small tangle that outlasted every attempt on a large node: the
  // repaired map, folded only there, serves the split, whose cuts then follow the targets
  // everywhere else. The untangler's pull of the own map over a whole large node costs much, and
  // the cuts it gives measured no closer there (kTransferUntangleVertices).
  if (tangle > 0 && small_tangle(tangle) && n >= kTransferUntangleVertices) {
    p.sp.uv = std::move(uv);
    param::count_uv_faces(pm.faces, p.sp);
    return Transfer::Folded;
  }
  // The untangler (the map pulled toward the targets under an injectivity barrier). After a
  // repair, from the repaired map, free only where it left the targets (kTransferPolishRings
  // rings around): the repair's solves of the own weights put those vertices by the own map's
  // shape, not near the targets. Without one (a tangle no repair mends), from the own map over
  // the whole node, or, in one pose by the similarity, from its stretch-minimized map when the
  // own map folds or is squeezed to zero area (a thin leg). Through a registration such a node
  // keeps the targets: there the stretch-minimized start costs much and gains nothing measurable
  // (docs/pose-pairs.md).
  std::vector<Vec2> start = p.sp.uv;
  std::vector<char> hold = fixed;
  if (repaired) {
    start = repaired->uv;
    std::vector<char> off(n, 0);
    for (int v = 0; v < n; ++v) off[v] = !has_target[v] || start[v] != target[v];
    widen(off, kTransferPolishRings, nullptr);
    for (int v = 0; v < n; ++v)
      if (!off[v]) hold[v] = 1;
  } else if (!p.sp.bijective()) {
    if (pose.registered()) return as_targets();
    const param::SquareParam m = minimized_leaf(p, kRepairRounds, context);
    if (m.uv.empty() || !m.bijective()) return as_targets();
    start = m.uv;
  }
  param::SquareParam sp = p.sp;
  if (untangle(pm, start, hold, target, has_target, repaired.has_value())) {
    sp.uv = std::move(start);
    param::count_uv_faces(pm.faces, sp);
  }
  if (sp.uv == p.sp.uv || !sp.bijective()) {
    if (!repaired) return as_targets();
    p.sp = std::move(*repaired);
    return Transfer::Taken;
  }
  // Through a registration, an untangled own map squeezed to nothing somewhere gives way to the
  // targets: the pull of a map that folds against them can crush faces, and cuts through such a
  // region run anywhere (kUntangledSqueeze).
  if (!repaired && pose.registered() && smallest_area_share(pm, sp.uv) < kUntangledSqueeze) return as_targets();
  p.sp = std::move(sp);
  return repaired ? Transfer::Polished : Transfer::Untangled;
}

}  // namespace qs::dissect::detail
