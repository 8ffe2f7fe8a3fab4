#include "qs/dfi/matching.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

namespace qs::dfi {

int nearest_node(const Skeleton& s, const Vec3& p) {
  int best = 0;
  double bd = std::numeric_limits<double>::infinity();
  for (int i = 0; i < static_cast<int>(s.nodes.size()); ++i) {
    const double d = (s.nodes[i] - p).squaredNorm();
    if (d < bd) {
      bd = d;
      best = i;
    }
  }
  return best;
}

SkeletonMatching match_skeletons(const Skeleton& s0, const std::vector<Branch>& b0, const Skeleton& s1,
                                 const std::vector<Branch>& b1, const std::vector<NodePair>& forced,
                                 double diagonal, const MatchOptions& options) {
  SkeletonMatching m;
  const std::vector<int> d0 = node_degrees(s0), d1 = node_degrees(s1);
  std::vector<int> match0(s0.nodes.size(), -1), match1(s1.nodes.size(), -1);
  for (const NodePair& f : forced) {
    if (match0[f.source] >= 0 || match1[f.target] >= 0) continue;
    match0[f.source] = f.target;
    match1[f.target] = f.source;
    m.nodes.push_back(f);
  }
  // Feature nodes: branch ends (so that a pure cycle's start node counts too).
  std::vector<char> feat0(s0.nodes.size(), 0), feat1(s1.nodes.size(), 0);
  for (const Branch& b : b0) feat0[b.a] = feat0[b.b] = 1;
  for (const Branch& b : b1) feat1[b.a] = feat1[b.b] = 1;
  std::vector<std::tuple<double, int, int>> cand;
  for (int i = 0; i < static_cast<int>(s0.nodes.size()); ++i) {
    if (!feat0[i]) continue;
    for (int j = 0; j < static_cast<int>(s1.nodes.size()); ++j) {
      if (!feat1[j]) continue;
      if ((d0[i] == 1) != (d1[j] == 1)) continue;  // terminal to terminal, junction to junction
      const double d = (s0.nodes[i] - s1.nodes[j]).norm() / diagonal;
      if (d <= options.max_distance) cand.emplace_back(d, i, j);
    }
  }
  std::sort(cand.begin(), cand.end());
  for (const auto& [d, i, j] : cand) {
    if (match0[i] >= 0 || match1[j] >= 0) continue;
    match0[i] = j;
    match1[j] = i;
    m.nodes.push_back({i, j, false, ""});
  }
  // The paper's cases 1-3: a branch with a terminal end goes with the target branch that holds the
  // terminal's match (a terminal lies on exactly one branch), whatever its other end.
  std::vector<char> used0(b0.size(), 0), used1(b1.size(), 0);
  for (int p = 0; p < static_cast<int>(b0.size()); ++p) {
    const Branch& br = b0[p];
    for (const int end : {br.a, br.b}) {
      if (used0[p] || d0[end] != 1 || match0[end] < 0 || d1[match0[end]] != 1) continue;
      const int t = match0[end];
      for (int q = 0; q < static_cast<int>(b1.size()); ++q) {
        if (used1[q] || (b1[q].a != t && b1[q].b != t)) continue;
        // Same direction when the terminal sits at the same end of both branches.
        const bool reversed = (end == br.a) != (b1[q].a == t);
        used0[p] = used1[q] = 1;
        m.branches.push_back({p, q, reversed});
        break;
      }
    }
  }
  // Case 6: branches whose two ends are matched to the ends of a target branch; the closest length
  // ratio wins.
  for (int p = 0; p < static_cast<int>(b0.size()); ++p) {
    if (used0[p]) continue;
    const Branch& br = b0[p];
    const int ta = match0[br.a], tb = match0[br.b];
    if (ta < 0 || tb < 0) continue;
    int best = -1;
    bool best_rev = false;
    double best_cost = std::numeric_limits<double>::infinity();
    for (int q = 0; q < static_cast<int>(b1.size()); ++q) {
      if (used1[q]) continue;
      const Branch& tq = b1[q];
      bool fwd = tq.a == ta && tq.b == tb, rev = tq.a == tb && tq.b == ta;
      if (!fwd && !rev) continue;
      if (fwd && rev) {  // a cycle through one node, or a loop between two: pick the better direction
        fwd = (tq.at(s1, 0.25) - br.at(s0, 0.25)).norm() <= (tq.at(s1, 0.75) - br.at(s0, 0.25)).norm();
        rev = !fwd;
      }
      const double cost = std::abs(std::log((tq.length + 1e-12) / (br.length + 1e-12))) +
                          (tq.at(s1, 0.5) - br.at(s0, 0.5)).norm() / diagonal;
      if (cost < best_cost) {
        best_cost = cost;
        best = q;
        best_rev = rev;
      }
    }
    if (best >= 0) {
      used1[best] = 1;
      m.branches.push_back({p, best, best_rev});
    }
  }
  std::sort(m.branches.begin(), m.branches.end(),
            [](const BranchPair& x, const BranchPair& y) { return x.source < y.source; });
  return m;
}

std::vector<AnchorPair> sample_anchors(const Skeleton& s0, const std::vector<Branch>& b0, const Skeleton& s1,
                                       const std::vector<Branch>& b1, const SkeletonMatching& m, int per_branch) {
  std::vector<AnchorPair> out;
  auto add = [&](const Vec3& a, const Vec3& b) {
    for (const AnchorPair& p : out)
      if ((p.source - a).norm() < 1e-12 && (p.target - b).norm() < 1e-12) return;
    out.push_back({a, b});
  };
  for (const NodePair& n : m.nodes) add(s0.nodes[n.source], s1.nodes[n.target]);
  for (const BranchPair& bp : m.branches)
    for (int k = 1; k <= per_branch; ++k) {
      const double f = static_cast<double>(k) / (per_branch + 1);
      add(b0[bp.source].at(s0, f), b1[bp.target].at(s1, bp.reversed ? 1 - f : f));
    }
  return out;
}

}  // namespace qs::dfi
