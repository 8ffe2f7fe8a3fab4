// Feature alignment of one node across the set (paper 3.4): features move to their mean (u,v) by a
// foldover-free warp of the square; folds left by the warp are solved again pinned or untangled.

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>
#include <functional>
#include "qs/warp/warp.h"

#include "qs/core/error.h"
#include "qs/dissect/dissect_detail.h"

namespace qs::dissect::detail {

// Moves the features of one node to their mean (u,v) over the set. Features closer than
// feature_group_distance to each other (in any mesh, or as targets) move as one group, by their
// centroid, and so do features that near to the border: a warp cannot separate them at this
// level, and the next split's fresh maps will spread them apart.
void SetDissector::align(const std::vector<Node>& nodes, std::vector<Param>& ps, TreeNode& tn) {
  const size_t nf = ps[0].features.size(), nm = ps.size();
  auto uv = [&](size_t i, size_t k) -> const Vec2& { return ps[i].sp.uv[ps[i].features[k].second]; };
  std::vector<Vec2> target(nf, Vec2::Zero());
  for (size_t i = 0; i < nm; ++i)
    for (size_t k = 0; k < nf; ++k) target[k] += uv(i, k);
  for (auto& t : target) t /= static_cast<double>(nm);
  const double d = opt_.feature_group_distance;
  std::vector<int> group(nf);
  for (size_t k = 0; k < nf; ++k) group[k] = static_cast<int>(k);
  std::function<int(int)> find = [&](int k) { return group[k] == k ? k : group[k] = find(group[k]); };
  std::vector<std::vector<Vec2>> rep(nm);  // per mesh, per group root: centroid
  std::vector<Vec2> rep_target;
  std::vector<int> roots;
  for (bool merged = true; merged;) {
    merged = false;
    roots.clear();
    for (size_t k = 0; k < nf; ++k)
      if (find(static_cast<int>(k)) == static_cast<int>(k)) roots.push_back(static_cast<int>(k));
    auto centroid = [&](const std::function<Vec2(size_t)>& at, int root) {
      Vec2 c = Vec2::Zero();
      int n = 0;
      for (size_t k = 0; k < nf; ++k)
        if (find(static_cast<int>(k)) == root) {
          c += at(k);
          ++n;
        }
      return Vec2(c / n);
    };
    rep_target.clear();
    for (int r : roots) rep_target.push_back(centroid([&](size_t k) { return target[k]; }, r));
    for (size_t i = 0; i < nm; ++i) {
      rep[i].clear();
      for (int r : roots) rep[i].push_back(centroid([&](size_t k) { return uv(i, k); }, r));
    }
    for (size_t a = 0; a < roots.size() && !merged; ++a)
      for (size_t b = a + 1; b < roots.size() && !merged; ++b) {
        bool close = (rep_target[a] - rep_target[b]).norm() < d;
        for (size_t i = 0; i < nm && !close; ++i) close = (rep[i][a] - rep[i][b]).norm() < d;
        if (close) {
          group[roots[b]] = roots[a];
          merged = true;
        }
      }
  }
  // Groups too near the border stay where they are in this node.
  // Only a point practically on the border is held: the warp moves any point strictly inside.
  const double hold = 1e-6;
  auto near_border = [&](const Vec2& q) { return q.minCoeff() < hold || q.maxCoeff() > 1 - hold; };
  std::vector<size_t> moving;
  for (size_t g = 0; g < roots.size(); ++g) {
    bool ok = !near_border(rep_target[g]);
    for (size_t i = 0; i < nm && ok; ++i) ok = !near_border(rep[i][g]);
    if (ok) moving.push_back(g);
  }
  tn.feature_groups = static_cast<int>(roots.size());
  tn.features_held = static_cast<int>(roots.size() - moving.size());
  std::vector<Vec2> to;
  for (size_t g : moving) to.push_back(rep_target[g]);
  std::vector<int> events(nm, 0), pinned_solves(nm, 0);
  size_t faces = 0;
  for (const auto& p : ps) faces += p.ex.faces.size();
  // Warp vertex 4 + m is group moving[m]; when every moving group is one feature, it is that
  // feature's vertex, and the warp's edges can be cut into the mesh (below).
  bool singletons = true;
  for (size_t g : moving)
    for (size_t k = 0; k < nf && singletons; ++k)
      singletons = k == static_cast<size_t>(roots[g]) || find(static_cast<int>(k)) != roots[g];
  parallel_for(nm, faces >= kParallelFaces ? 0 : 1, ctx_, [&](size_t i) {
    Param& p = ps[i];
    std::vector<Vec2> from;
    for (size_t g : moving) from.push_back(rep[i][g]);
    auto run_warp = [&] {
      try {
        warp::WarpOptions wo;
        wo.min_feature_distance = 0.5 * hold;
        // The warp maps the unit square. A folded map (a squeezed patch, or landmarks that do not
        // correspond; left to the leaf repair) can put interior vertices outside it, by 1e-6 or by
        // several units: they are warped from the nearest point of the square, which only changes
        // where a map that folds anyway folds.
        std::vector<Vec2> points = p.sp.uv;
        if (!p.sp.bijective())
          for (Vec2& q : points) q = q.cwiseMax(0.0).cwiseMin(1.0);
        return warp::warp_square(from, to, points, wo, ctx_.without_progress());
      } catch (const Error& e) {
        const std::string m = "aligning the features of patch " + tn.name + " on " + meshes_[i].name() + ": " + e.what();
        if (e.code() == ErrorCode::InvalidInput) throw InvalidInput(m);
        throw SolverError(m);
      }
    };
    warp::WarpResult wr = run_warp();
    param::SquareParam warped = p.sp;
    warped.uv = std::move(wr.points);
    events[i] = wr.events;
    param::count_uv_faces(p.ex.pm.faces, warped);
    if (!warped.bijective() && wr.events == 0 && singletons) {
      // The warp maps points bijectively, but it is only piecewise linear: a mesh face whose
      // corners lie in different warp triangles is mapped by its corners alone and folds where the
      // affine maps of the triangles differ much (a feature moved far). Whether it folds depends on
      // the face's shape, not its size, so refining the mesh does not help. Without flip events the
      // warp is one affine map per triangle of its mesh (at the input positions): cut those edges
      // into the patch (new vertices on the segments, the map unchanged) and every face lies in one
      // warp triangle, warped by one affine map of positive determinant, so none folds.
      std::vector<std::array<int, 2>> segments;
      auto local = [&](int w) {
        return w < 4 ? p.ex.pm.boundary[p.ex.pm.corner_index[w]] : p.features[roots[moving[w - 4]]].second;
      };
      for (const auto& t : wr.triangles)
        for (int j = 0; j < 3; ++j) {
          const int a = std::min(t[j], t[(j + 1) % 3]), b = std::max(t[j], t[(j + 1) % 3]);
          if (b >= 4) segments.push_back({b, a});  // from the feature (inside) to its neighbour
        }
      std::sort(segments.begin(), segments.end());
      segments.erase(std::unique(segments.begin(), segments.end()), segments.end());
      for (auto& s : segments) s = {local(s[0]), local(s[1])};
      try {
        meshes_[i].cut_segments(nodes[i], p, segments);
      } catch (const SplitFailure&) {
        // p is the same map on the partly cut patch; the fallbacks below take it
      }
      wr = run_warp();
      warped = p.sp;
      warped.uv = std::move(wr.points);
      param::count_uv_faces(p.ex.pm.faces, warped);
    }
    if (!warped.bijective()) {
      // The warp is a bijection of the square, but a mesh face whose corners lie in different
      // warp triangles is mapped by its corners only and can fold where a feature moved far.
      // Then solve the mean-value map again with the features pinned where the warp put them,
      // and keep whichever folds less (ties: the warp).
      param::SquareParamOptions po;
      po.weights = p.weights;
      for (size_t k = 0; k < nf; ++k) po.pinned.emplace_back(p.features[k].second, warped.uv[p.features[k].second]);
      Context quiet = ctx_.without_progress();
      quiet.log = nullptr;  // its fold warning is expected here: the folds are compared below
      param::SquareParam pinned = param::parameterize_square(p.ex.pm, po, quiet);
      if (!pinned.bijective() && po.weights != param::InteriorWeights::MeanValue) {
        po.weights = param::InteriorWeights::MeanValue;  // cotangent weights folded: mean-value too
        param::SquareParam mv = param::parameterize_square(p.ex.pm, po, quiet);
        if (mv.flipped_faces + mv.zero_area_faces < pinned.flipped_faces + pinned.zero_area_faces) pinned = std::move(mv);
      }
      if (pinned.flipped_faces + pinned.zero_area_faces < warped.flipped_faces + warped.zero_area_faces) {
        warped = pinned;
        pinned_solves[i] = 1;
      }
    }
    if (!warped.bijective()) {
      std::vector<char> fixed(p.ex.verts.size(), 0);
      for (const auto& f : p.features) fixed[f.second] = 1;
      warped = untangle(p.ex.pm, warped, fixed, 20);
    }
    p.sp = std::move(warped);
    p.st = param::l2_stretch(p.ex.pm.positions, p.ex.pm.faces, p.sp.uv);
  });
  for (size_t i = 0; i < nm; ++i) {
    tn.warp_events += events[i];
    tn.pinned_solves += pinned_solves[i];
  }
}

}  // namespace qs::dissect::detail
