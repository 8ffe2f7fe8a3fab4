#pragma once
// Small helpers shared by the benchmark programs' command lines.

#include <sstream>
#include <string>
#include <vector>

namespace qs::bench {

/// The non-empty items of a comma-separated list ("a,,b" -> {"a", "b"}).
inline std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string x; std::getline(in, x, ',');)
    if (!x.empty()) out.push_back(x);
  return out;
}

}  // namespace qs::bench
