#pragma once
// Exact optimal transport (earth mover's distance) between two uniform discrete distributions,
// the dense-correspondence step of skeleton-guided DFI (the paper's equation 5), solved as a
// min-cost flow on the complete bipartite graph with LEMON's network simplex (as in the paper).

#include <Eigen/Core>
#include <vector>

namespace qs::dfi {

struct Flow {
  int from = 0, to = 0;  ///< source item, target item
  double mass = 0;       ///< in (0, 1]; the masses of one source item sum to 1 / n0
};

struct TransportResult {
  std::vector<Flow> flows;  ///< non-zero flows, sorted by (from, to)
  double cost = 0;          ///< sum of mass * cost
};

/// Minimizes sum_ij f_ij C_ij subject to f >= 0, sum_j f_ij = 1/n0, sum_i f_ij = 1/n1, for the
/// n0 x n1 cost matrix C (finite, >= 0). Costs are rounded to integers on a scale of 1e9 of the
/// largest cost, masses are exact (integers n1 and n0 per item, then divided by n0 n1).
/// \throws InvalidInput for an empty or non-finite matrix or more than 2^31 arcs; SolverError when
/// the solver reports no optimum (a bug).
TransportResult solve_transport(const Eigen::MatrixXd& cost);

}  // namespace qs::dfi
