#include "qs/dfi/matching.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <tuple>
#include <utility>

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

namespace {

// Geodesic distances along the skeleton from `from` to every node, and per node the number of
// junctions (degree >= 3) strictly between it and `from` on the shortest path found.
void geodesics(const Skeleton& s, const std::vector<std::vector<std::pair<int, double>>>& adj,
               const std::vector<int>& degree, int from, std::vector<double>& dist, std::vector<int>& junctions) {
  const int n = static_cast<int>(s.nodes.size());
  dist.assign(n, std::numeric_limits<double>::infinity());
  junctions.assign(n, 0);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  dist[from] = 0;
  queue.push({0.0, from});
  while (!queue.empty()) {
    const auto [d, u] = queue.top();
    queue.pop();
    if (d > dist[u]) continue;
    for (const auto& [v, w] : adj[u]) {
      if (d + w < dist[v]) {
        dist[v] = d + w;
        junctions[v] = junctions[u] + (u != from && degree[u] >= 3 ? 1 : 0);
        queue.push({dist[v], v});
      }
    }
  }
}

std::vector<std::vector<std::pair<int, double>>> adjacency(const Skeleton& s) {
  std::vector<std::vector<std::pair<int, double>>> adj(s.nodes.size());
  for (const auto& e : s.edges) {
    const double w = (s.nodes[e[0]] - s.nodes[e[1]]).norm();
    adj[e[0]].push_back({e[1], w});
    adj[e[1]].push_back({e[0], w});
  }
  return adj;
}

// Length-weighted centroid of the skeleton's edges (its nodes' mean without edges).
Vec3 skeleton_centroid(const Skeleton& s) {
  Vec3 c = Vec3::Zero();
  double w = 0;
  for (const auto& e : s.edges) {
    const double l = (s.nodes[e[0]] - s.nodes[e[1]]).norm();
    c += l * 0.5 * (s.nodes[e[0]] + s.nodes[e[1]]);
    w += l;
  }
  if (w > 0) return c / w;
  for (const Vec3& p : s.nodes) c += p;
  return s.nodes.empty() ? c : Vec3(c / static_cast<double>(s.nodes.size()));
}

// What the voting needs of one skeleton's feature nodes.
struct Features {
  std::vector<int> nodes;                     // feature node indices
  std::vector<std::vector<double>> geodesic;  // [a][b] between feature nodes a, b (indices into nodes)
  std::vector<std::vector<int>> junctions;    // junctions strictly between them
};

Features features_of(const Skeleton& s, const std::vector<char>& feature, const std::vector<int>& degree) {
  Features f;
  for (int i = 0; i < static_cast<int>(s.nodes.size()); ++i)
    if (feature[i]) f.nodes.push_back(i);
  const auto adj = adjacency(s);
  const size_t n = f.nodes.size();
  f.geodesic.assign(n, std::vector<double>(n, 0));
  f.junctions.assign(n, std::vector<int>(n, 0));
  std::vector<double> dist;
  std::vector<int> junc;
  for (size_t a = 0; a < n; ++a) {
    geodesics(s, adj, degree, f.nodes[a], dist, junc);
    for (size_t b = 0; b < n; ++b) {
      f.geodesic[a][b] = dist[f.nodes[b]];
      f.junctions[a][b] = junc[f.nodes[b]];
    }
  }
  return f;
}

}  // namespace

std::vector<double> centricity(const Skeleton& s) {
  const int n = static_cast<int>(s.nodes.size());
  std::vector<double> c(n, 0);
  if (n == 0) return c;
  const auto adj = adjacency(s);
  const std::vector<int> degree = node_degrees(s);
  std::vector<double> dist;
  std::vector<int> junc;
  std::vector<double> length;
  double total = 0;
  for (const auto& e : s.edges) total += length.emplace_back((s.nodes[e[0]] - s.nodes[e[1]]).norm());
  for (int i = 0; i < n; ++i) {
    geodesics(s, adj, degree, i, dist, junc);
    double sum = 0;
    for (size_t k = 0; k < s.edges.size(); ++k) {
      const auto& e = s.edges[k];
      const double a = std::isfinite(dist[e[0]]) ? dist[e[0]] : 0, b = std::isfinite(dist[e[1]]) ? dist[e[1]] : 0;
      sum += length[k] * 0.5 * (a + b);
    }
    c[i] = total > 0 ? sum / total : 0;
  }
  const double most = *std::max_element(c.begin(), c.end());
  for (double& x : c) x = most > 0 ? x / most : 1;
  return c;
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
  // Forced nodes take part in the consistency checks as feature nodes.
  for (const NodePair& f : m.nodes) feat0[f.source] = feat1[f.target] = 1;
  const Features f0 = features_of(s0, feat0, d0), f1 = features_of(s1, feat1, d1);
  const std::vector<double> c0 = centricity(s0), c1 = centricity(s1);
  // The Euclidean term compares positions with the skeletons' centroids made to coincide.
  const Vec3 shift = skeleton_centroid(s0) - skeleton_centroid(s1);
  struct Candidate {
    int a = 0, b = 0;  // indices into f0.nodes, f1.nodes
    double distance = 0, score = 0, votes = 0;
  };
  std::vector<Candidate> cand;
  for (int a = 0; a < static_cast<int>(f0.nodes.size()); ++a) {
    const int i = f0.nodes[a];
    if (match0[i] >= 0) continue;
    for (int b = 0; b < static_cast<int>(f1.nodes.size()); ++b) {
      const int j = f1.nodes[b];
      if (match1[j] >= 0) continue;
      if ((d0[i] == 1) != (d1[j] == 1)) continue;  // terminal to terminal, junction to junction
      const double raw = (s0.nodes[i] - s1.nodes[j]).norm() / diagonal;
      if (!options.voting) {
        if (raw <= options.max_distance) cand.push_back({a, b, raw, 0, 0});
        continue;
      }
      const double d = (s0.nodes[i] - s1.nodes[j] - shift).norm() / diagonal;
      const double dc = std::abs(c0[i] - c1[j]);
      if (d > options.max_distance || dc > options.max_centricity_difference) continue;
      const double e = d / options.euclid_scale, g = dc / 0.1;
      cand.push_back({a, b, d, std::exp(-e * e - g * g), 0});
    }
  }
  const double cos_max = std::cos(options.max_angle_degrees * 3.14159265358979323846 / 180);
  // Whether source feature a <-> target b and source p <-> target q agree (path length, topology,
  // spatial configuration).
  auto consistent = [&](int a, int b, int p, int q) {
    if (a == p || b == q) return false;
    const double g0 = f0.geodesic[a][p], g1 = f1.geodesic[b][q];
    if (!std::isfinite(g0) || !std::isfinite(g1)) return std::isfinite(g0) == std::isfinite(g1);
    if (std::abs(g0 - g1) > std::max(options.max_path_difference * std::max(g0, g1), 0.05 * diagonal)) return false;
    if (std::abs(f0.junctions[a][p] - f1.junctions[b][q]) > 1) return false;
    const Vec3 u = s0.nodes[f0.nodes[p]] - s0.nodes[f0.nodes[a]], v = s1.nodes[f1.nodes[q]] - s1.nodes[f1.nodes[b]];
    const double lu = u.norm(), lv = v.norm();
    if (lu > 0.05 * diagonal && lv > 0.05 * diagonal && u.dot(v) < cos_max * lu * lv) return false;
    return true;
  };
  const int nc = static_cast<int>(cand.size());
  if (options.voting && nc >= 3) {
    // Consistency graph between candidates; the electors are its triangles.
    std::vector<std::vector<int>> next(nc);  // consistent candidates of higher index
    for (int x = 0; x < nc; ++x)
      for (int y = x + 1; y < nc; ++y)
        if (consistent(cand[x].a, cand[x].b, cand[y].a, cand[y].b)) next[x].push_back(y);
    long electors = 0;
    std::vector<char> near(nc, 0);
    for (int x = 0; x < nc && electors < options.max_electors; ++x) {
      for (int y : next[x]) near[y] = 1;
      for (int y : next[x]) {
        for (int z : next[y]) {
          if (!near[z]) continue;
          const double w = cand[x].score * cand[y].score * cand[z].score;
          cand[x].votes += w;
          cand[y].votes += w;
          cand[z].votes += w;
          if (++electors >= options.max_electors) break;
        }
        if (electors >= options.max_electors) break;
      }
      for (int y : next[x]) near[y] = 0;
    }
  }
  // Most votes first, then nearest; every pair taken must agree with those taken before.
  std::vector<int> order(nc);
  for (int x = 0; x < nc; ++x) order[x] = x;
  std::sort(order.begin(), order.end(), [&](int x, int y) {
    if (cand[x].votes != cand[y].votes) return cand[x].votes > cand[y].votes;
    if (cand[x].distance != cand[y].distance) return cand[x].distance < cand[y].distance;
    return std::tie(cand[x].a, cand[x].b) < std::tie(cand[y].a, cand[y].b);
  });
  std::vector<std::pair<int, int>> taken;  // (feature index source, target)
  auto feature_index = [](const Features& f, int node) {
    return static_cast<int>(std::lower_bound(f.nodes.begin(), f.nodes.end(), node) - f.nodes.begin());
  };
  for (const NodePair& f : m.nodes) taken.push_back({feature_index(f0, f.source), feature_index(f1, f.target)});
  for (int x : order) {
    const Candidate& c = cand[x];
    const int i = f0.nodes[c.a], j = f1.nodes[c.b];
    if (match0[i] >= 0 || match1[j] >= 0) continue;
    if (options.voting) {
      bool ok = true;
      for (const auto& [p, q] : taken) ok = ok && consistent(c.a, c.b, p, q);
      if (!ok) continue;
    }
    match0[i] = j;
    match1[j] = i;
    taken.push_back({c.a, c.b});
    m.nodes.push_back({i, j, false, "", c.votes});
  }
  // The fallback: feature nodes the votes left unmatched, nearest-first in the aligned space.
  if (options.voting) {
    std::vector<std::tuple<double, int, int>> rest;
    for (const int i : f0.nodes) {
      if (match0[i] >= 0) continue;
      for (const int j : f1.nodes) {
        if (match1[j] >= 0 || (d0[i] == 1) != (d1[j] == 1)) continue;
        const double d = (s0.nodes[i] - s1.nodes[j]).norm() / diagonal;
        if (d <= options.max_distance) rest.emplace_back(d, i, j);
      }
    }
    std::sort(rest.begin(), rest.end());
    for (const auto& [d, i, j] : rest) {
      if (match0[i] >= 0 || match1[j] >= 0) continue;
      match0[i] = j;
      match1[j] = i;
      m.nodes.push_back({i, j, false, "", 0.0});
    }
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
