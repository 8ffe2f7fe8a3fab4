#include "qs/dfi/transport.h"

#include <lemon/network_simplex.h>
#include <lemon/smart_graph.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "qs/core/error.h"

namespace qs::dfi {

TransportResult solve_transport(const Eigen::MatrixXd& cost) {
  const long long n0 = cost.rows(), n1 = cost.cols();
  if (n0 == 0 || n1 == 0) throw InvalidInput("transport: empty cost matrix");
  if (n0 * n1 > (1LL << 31)) throw InvalidInput("transport: " + std::to_string(n0 * n1) + " arcs; at most 2^31");
  if (!cost.allFinite() || cost.minCoeff() < 0) throw InvalidInput("transport: costs must be finite and >= 0");
  const double top = cost.maxCoeff();
  const double scale = top > 0 ? 1e9 / top : 1.0;
  lemon::SmartDigraph g;
  g.reserveNode(static_cast<int>(n0 + n1));
  g.reserveArc(static_cast<int>(n0 * n1));
  std::vector<lemon::SmartDigraph::Node> nodes(n0 + n1);
  for (auto& n : nodes) n = g.addNode();
  lemon::SmartDigraph::ArcMap<long long> arc_cost(g);
  lemon::SmartDigraph::NodeMap<long long> supply(g);
  for (long long i = 0; i < n0; ++i) supply[nodes[i]] = n1;
  for (long long j = 0; j < n1; ++j) supply[nodes[n0 + j]] = -n0;
  for (long long i = 0; i < n0; ++i)
    for (long long j = 0; j < n1; ++j) {
      const auto a = g.addArc(nodes[i], nodes[n0 + j]);
      arc_cost[a] = std::llround(cost(i, j) * scale);
    }
  lemon::NetworkSimplex<lemon::SmartDigraph, long long, long long> ns(g);
  ns.costMap(arc_cost).supplyMap(supply);
  if (ns.run() != lemon::NetworkSimplex<lemon::SmartDigraph, long long, long long>::OPTIMAL)
    throw SolverError("transport: the network simplex found no optimum");
  TransportResult r;
  const double total = static_cast<double>(n0) * static_cast<double>(n1);
  for (lemon::SmartDigraph::ArcIt a(g); a != lemon::INVALID; ++a) {
    const long long f = ns.flow(a);
    if (f == 0) continue;
    const int i = g.id(g.source(a)), j = g.id(g.target(a)) - static_cast<int>(n0);
    r.flows.push_back({i, j, f / total});
    r.cost += f / total * cost(i, j);
  }
  std::sort(r.flows.begin(), r.flows.end(), [](const Flow& a, const Flow& b) {
    return a.from != b.from ? a.from < b.from : a.to < b.to;
  });
  return r;
}

}  // namespace qs::dfi
