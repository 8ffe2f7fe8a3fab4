#include "qs/dfi/topology.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <queue>
#include <string>
#include <utility>
#include <vector>

#include "qs/core/error.h"

namespace qs::dfi {

namespace {

// Link edges: neighbours a and b of a sample are joined when b - a is one of the 14 offsets
// (the Kuhn triangulation is a flag complex: three pairwise joined samples span a triangle).
std::array<unsigned, 14> link_adjacency() {
  std::array<unsigned, 14> adj{};
  for (int a = 0; a < 14; ++a)
    for (int b = 0; b < 14; ++b) {
      if (a == b) continue;
      const int d[3] = {kNeighbours14[b][0] - kNeighbours14[a][0], kNeighbours14[b][1] - kNeighbours14[a][1],
                        kNeighbours14[b][2] - kNeighbours14[a][2]};
      for (const auto& o : kNeighbours14)
        if (o[0] == d[0] && o[1] == d[1] && o[2] == d[2]) adj[a] |= 1u << b;
    }
  return adj;
}

// Number of connected pieces of the neighbours in `set` along the link's edges.
int pieces(unsigned set, const std::array<unsigned, 14>& adj) {
  int count = 0;
  unsigned left = set;
  while (left) {
    ++count;
    unsigned front = left & (~left + 1u);  // lowest bit
    unsigned seen = front;
    while (front) {
      unsigned next = 0;
      for (int n = 0; n < 14; ++n)
        if (front & (1u << n)) next |= adj[n];
      next &= set & ~seen;
      seen |= next;
      front = next;
    }
    left &= ~seen;
  }
  return count;
}

const std::vector<char>& simple_table() {
  static const std::vector<char> table = [] {
    const auto adj = link_adjacency();
    std::vector<char> t(1u << 14);
    const unsigned all = (1u << 14) - 1;
    for (unsigned m = 0; m <= all; ++m) t[m] = pieces(m, adj) == 1 && pieces(all & ~m, adj) == 1;
    return t;
  }();
  return table;
}

}  // namespace

bool is_simple_14(unsigned mask) { return mask < (1u << 14) && simple_table()[mask]; }

BallReport make_ball(Grid& g, const BallOptions& options, const PolygonizeOptions& polygonize) {
  BallReport r;
  if (!(options.outside_value > polygonize.snap_tolerance))
    throw InvalidInput("topology control: outside value " + std::to_string(options.outside_value) +
                       " cells; expected more than the polygonizer's snap tolerance " +
                       std::to_string(polygonize.snap_tolerance));
  const int nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
  if (g.values.size() != g.size() || nx < 3 || ny < 3 || nz < 3) return r;
  const std::vector<char>& simple = simple_table();
  // What polygonize counts as inside: below zero after its snap of |v| < tol to +tol.
  const double tol = polygonize.snap_tolerance * g.spacing;
  const auto inside = [&](float v) { return !(std::abs(v) < tol) && v < 0; };
  // kQueued: inside, not in the ball, waiting in the queue (each sample is queued at most once at
  // a time: its key, the value, never changes).
  enum : char { kOut = 0, kIn = 1, kBall = 2, kQueued = 3 };
  std::vector<char> state(g.size(), kOut);
  std::ptrdiff_t step[14];
  for (int n = 0; n < 14; ++n)
    step[n] = (static_cast<std::ptrdiff_t>(kNeighbours14[n][2]) * ny + kNeighbours14[n][1]) * nx + kNeighbours14[n][0];
  size_t seed = g.size();
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const size_t s = g.index(i, j, k);
        if (!inside(g.values[s])) continue;
        ++r.inside;
        // A sample on the grid's boundary has neighbours off the grid: never added (and
        // polygonize would reject it).
        if (i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1) continue;
        state[s] = kIn;
        if (seed == g.size() || g.values[s] < g.values[seed]) seed = s;
      }
  if (seed == g.size()) {
    // Nothing can be grown: every inside sample (on the boundary, if any) goes outside.
    for (size_t s = 0; s < g.size(); ++s)
      if (inside(g.values[s])) g.values[s] = static_cast<float>(options.outside_value * g.spacing), ++r.removed;
    if (r.removed) r.components_removed = 1;
    return r;
  }
  using Item = std::pair<float, size_t>;  // (value, index): a total order, so the growth is deterministic
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  const auto add = [&](size_t s) {
    state[s] = kBall;
    for (int n = 0; n < 14; ++n) {
      const size_t t = static_cast<size_t>(static_cast<std::ptrdiff_t>(s) + step[n]);
      if (state[t] == kIn) state[t] = kQueued, queue.push({g.values[t], t});
    }
  };
  add(seed);
  while (!queue.empty()) {
    const size_t s = queue.top().second;
    queue.pop();
    unsigned mask = 0;
    for (int n = 0; n < 14; ++n)
      if (state[static_cast<size_t>(static_cast<std::ptrdiff_t>(s) + step[n])] == kBall) mask |= 1u << n;
    // Not simple now: it is queued again when one of its neighbours joins the ball.
    if (simple[mask]) add(s);
    else state[s] = kIn;
  }
  // Inside components the growth did not reach (14-connected among the inside samples left out).
  std::vector<size_t> stack;
  for (size_t s0 = 0; s0 < g.size(); ++s0) {
    if (state[s0] != kIn) continue;
    bool reached_ball = false;
    state[s0] = kOut;
    stack.push_back(s0);
    while (!stack.empty()) {
      const size_t s = stack.back();
      stack.pop_back();
      const int i = static_cast<int>(s % nx), j = static_cast<int>((s / nx) % ny),
                k = static_cast<int>(s / (static_cast<size_t>(nx) * ny));
      if (i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1) continue;
      for (int n = 0; n < 14; ++n) {
        const size_t t = static_cast<size_t>(static_cast<std::ptrdiff_t>(s) + step[n]);
        if (state[t] == kBall) reached_ball = true;
        if (state[t] == kIn) state[t] = kOut, stack.push_back(t);
      }
    }
    if (!reached_ball) ++r.components_removed;
  }
  const float outside = static_cast<float>(options.outside_value * g.spacing);
  for (size_t s = 0; s < g.size(); ++s)
    if (state[s] != kBall && inside(g.values[s])) g.values[s] = outside, ++r.removed;
  return r;
}

}  // namespace qs::dfi
