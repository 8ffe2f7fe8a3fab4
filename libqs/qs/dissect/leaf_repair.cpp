// Repairs of folded or over-stretched maps: local untangling, and the stretch minimization of
// leaves left over tau or not bijective (run after the subdivision, in parallel over leaves).

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>
#include "qs/warp/warp.h"

#include "qs/core/error.h"
#include "qs/dissect/dissect_detail.h"
#include "qs/metro/metro.h"

namespace qs::dissect::detail {

// Batches of 10 Gauss-Seidel sweeps per untangling round (see untangle).
constexpr int kUntangleBatches = 20;

// Local untangling of a folded map: the free vertices of folded faces and two rings around them
// move to the average of their neighbours (Gauss-Seidel), the border and `fixed` vertices stay.
// Each round smooths until the map is bijective or kUntangleBatches * 10 sweeps are done; repeated
// while folds remain (at most `rounds` times). Returns the map with fewer folds.
param::SquareParam untangle(const param::PatchMesh& pm, const param::SquareParam& in, const std::vector<char>& fixed,
                            int rounds) {
  const int nv = static_cast<int>(pm.positions.size());
  std::vector<std::vector<int>> nb(nv);
  for (const Tri& t : pm.faces)
    for (int k = 0; k < 3; ++k) nb[t[k]].push_back(t[(k + 1) % 3]), nb[t[k]].push_back(t[(k + 2) % 3]);
  for (auto& n : nb) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  std::vector<char> pinned = fixed;
  pinned.resize(nv, 0);
  for (int b : pm.boundary) pinned[b] = 1;
  param::SquareParam best = in, cur = in;
  for (int r = 0; r < rounds && !best.bijective(); ++r) {
    std::vector<char> mark(nv, 0);
    for (const Tri& t : pm.faces)
      if (signed_area(cur.uv[t[0]], cur.uv[t[1]], cur.uv[t[2]]) <= param::kZeroUvArea)
        for (int v : t) mark[v] = 1;
    for (int ring = 0; ring < 2 + std::min(r, 6); ++ring) {  // a wider region every round
      std::vector<char> grown = mark;
      for (int v = 0; v < nv; ++v)
        if (mark[v])
          for (int w : nb[v]) grown[w] = 1;
      mark.swap(grown);
    }
    // Gauss-Seidel converges slowly on a region of many rings (the rings around a feature deep in a
    // squeezed protrusion): up to kUntangleBatches batches of 10 sweeps, until no fold is left.
    // The sweeps visit only the region's free vertices (in vertex order), not the whole patch.
    std::vector<int> moving;
    std::vector<char> moves(nv, 0);
    for (int v = 0; v < nv; ++v)
      if (mark[v] && !pinned[v] && !nb[v].empty()) moving.push_back(v), moves[v] = 1;
    // Only the faces of moving vertices change in this round: the others' folds are counted once,
    // and the whole map is counted at the round's end.
    auto bad = [&](const Tri& t) {
      return signed_area(cur.uv[t[0]], cur.uv[t[1]], cur.uv[t[2]]) <= param::kZeroUvArea;
    };
    std::vector<int> changing;
    long still = 0;  // folded faces that this round cannot change
    for (size_t f = 0; f < pm.faces.size(); ++f) {
      const Tri& t = pm.faces[f];
      if (moves[t[0]] || moves[t[1]] || moves[t[2]]) changing.push_back(static_cast<int>(f));
      else still += bad(t);
    }
    for (int batch = 0; batch < kUntangleBatches; ++batch) {
      for (int sweep = 0; sweep < 10; ++sweep)
        for (int v : moving) {
          Vec2 c = Vec2::Zero();
          for (int w : nb[v]) c += cur.uv[w];
          cur.uv[v] = c / static_cast<double>(nb[v].size());
        }
      long folded = still;
      for (int f : changing) folded += bad(pm.faces[static_cast<size_t>(f)]);
      if (folded == 0) break;
    }
    param::count_uv_faces(pm.faces, cur);
    if (cur.flipped_faces + cur.zero_area_faces < best.flipped_faces + best.zero_area_faces) best = cur;
  }
  return best;
}

// A stretch-minimized map of a leaf (see keep_leaf), or an empty map when none is better.
// Pure: it reads the leaf only, so leaves are repaired in parallel.
param::SquareParam minimized_leaf(const Param& p, int rounds, const Context& context) {
  // Minimize without pins (pins inside a squeezed protrusion defeat it), then warp the features
  // back onto their aligned (u,v): the spread-out map folds far less under the warp.
  param::SquareParamOptions po;
  po.stretch_iterations = rounds;
  po.weights = p.weights;
  po.plain = &p.plain;
  param::SquareParam min_sp;
  try {
    min_sp = param::parameterize_square(p.ex.pm, po, context);
    if (!p.features.empty()) {
      std::vector<Vec2> from, to;
      for (const auto& [k, local] : p.features) {
        from.push_back(min_sp.uv[local]);
        to.push_back(p.sp.uv[local]);
      }
      min_sp.uv = warp::warp_square(from, to, min_sp.uv, {}, context).points;
      param::count_uv_faces(p.ex.pm.faces, min_sp);
      if (!min_sp.bijective()) {
        std::vector<char> fixed(p.ex.verts.size(), 0);
        for (const auto& f : p.features) fixed[f.second] = 1;
        min_sp = untangle(p.ex.pm, min_sp, fixed, 20);
      }
      if (!min_sp.bijective()) {  // then try minimizing with the features pinned
        for (const auto& [k, local] : p.features) po.pinned.emplace_back(local, p.sp.uv[local]);
        param::SquareParam pinned = param::parameterize_square(p.ex.pm, po, context);
        if (pinned.flipped_faces + pinned.zero_area_faces < min_sp.flipped_faces + min_sp.zero_area_faces)
          min_sp = std::move(pinned);
      }
    }
  } catch (const Error& e) {
    if (e.code() == ErrorCode::Internal) throw;  // cancelled, or a bug
    return {};  // a singular system or features the warp cannot place: keep the given map
  }
  if (!min_sp.bijective()) {
    if (p.weights == param::InteriorWeights::MeanValue) return {};
    Param mv = p;  // cotangent weights folded: try mean-value weights before giving up
    mv.weights = param::InteriorWeights::MeanValue;
    mv.plain = {};  // solved with the other weights
    return minimized_leaf(mv, rounds, context);
  }
  return min_sp;
}

void MeshDissector::run_repairs() {
  // Independent leaves, one result slot each: the outcome does not depend on the thread count.
  Context quiet = ctx_.without_progress();
  quiet.log = nullptr;  // the minimization's fold warnings are expected; the result is counted
  std::vector<param::SquareParam> result(repairs_.size());
  size_t faces = 0;
  for (const auto& r : repairs_) faces += r.param.ex.faces.size();
  // The largest leaves first, so that the threads end together.
  std::vector<size_t> order(repairs_.size());
  for (size_t r = 0; r < order.size(); ++r) order[r] = r;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return repairs_[a].param.ex.faces.size() > repairs_[b].param.ex.faces.size();
  });
  parallel_for(repairs_.size(), faces >= kParallelFaces / 8 ? 0 : 1, ctx_, [&](size_t k) {
    const size_t r = order[k];
    result[r] = minimized_leaf(repairs_[r].param, repairs_[r].rounds, quiet);
  });
  for (size_t r = 0; r < repairs_.size(); ++r) {
    const Param& p = repairs_[r].param;
    if (result[r].uv.empty()) continue;
    const param::Stretch st = param::l2_stretch(p.ex.pm.positions, p.ex.pm.faces, result[r].uv);
    if (!p.sp.bijective() || st.patch < p.st.patch) set_leaf_map(repairs_[r].leaf, p, result[r], st);
  }
  repairs_.clear();
}

int MeshDissector::take_over_leaves(const MeshDissector& ref, const registration::Pose& pose, double reach,
                                    const NodeMapPuller& untangle) {
  const size_t n = leaf_params_.size();
  bool same = n == ref.leaf_params_.size() && leaves_.size() == ref.leaves_.size();
  for (size_t j = 0; same && j < leaves_.size(); ++j) same = leaves_[j].name == ref.leaves_[j].name;
  if (!same) throw InternalError("take_over_leaves: the meshes' leaves differ");
  Context quiet = ctx_.without_progress();
  quiet.log = nullptr;
  std::vector<std::optional<Param>> taken(n);  // the leaves whose map was taken over
  size_t faces = 0;
  for (const Param& p : leaf_params_) faces += p.ex.faces.size();
  parallel_for(n, faces >= kParallelFaces / 8 ? 0 : 1, ctx_, [&](size_t j) {
    const Param& r = ref.leaf_params_[j];
    if (!r.sp.bijective()) return;
    const metro::SurfaceDistance on_ref(TriMesh{r.ex.pm.positions, r.ex.pm.faces}, "the first mesh's leaf");
    Param p = leaf_params_[j];
    const Transfer t = transfer_node_map(r, on_ref, pose, reach, untangle, quiet, p);
    if ((t == Transfer::Taken || t == Transfer::Polished || t == Transfer::Untangled) && p.sp.bijective())
      taken[j] = std::move(p);
  });
  int count = 0;
  for (size_t j = 0; j < n; ++j)
    if (const auto& p = taken[j]) {
      set_leaf_map(j, *p, p->sp, param::l2_stretch(p->ex.pm.positions, p->ex.pm.faces, p->sp.uv));
      ++count;
    }
  repairs_.erase(std::remove_if(repairs_.begin(), repairs_.end(), [&](const Repair& r) { return taken[r.leaf].has_value(); }),
                 repairs_.end());
  return count;
}

}  // namespace qs::dissect::detail
