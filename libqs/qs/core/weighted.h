#pragma once
// Quantiles of weighted values (per-area errors and distances).

#include <utility>
#include <vector>

namespace qs {

/// Of (value, weight) pairs sorted by value: the first value at which the running sum of the
/// weights reaches `weight`, or the last value when it never does; 0 for none.
inline double value_at_weight(const std::vector<std::pair<double, double>>& sorted, double weight) {
  double below = 0;
  for (const auto& [value, w] : sorted)
    if ((below += w) >= weight) return value;
  return sorted.empty() ? 0.0 : sorted.back().first;
}

}  // namespace qs
