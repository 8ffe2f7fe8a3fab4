// The dissection's own helpers (dissection.h), apart from the dissector: its readers use them too.
#include "qs/dissect/dissection.h"

#include <algorithm>
#include <array>
#include <unordered_map>
#include <utility>
#include <vector>

namespace qs::dissect {

const char* stop_reason_name(StopReason r) {
  switch (r) {
    case StopReason::None: return "none";
    case StopReason::MaxDepth: return "max_depth";
    case StopReason::TooFewFaces: return "too_few_faces";
    case StopReason::SplitFailed: return "split_failed";
    case StopReason::NoProgress: return "no_progress";
    case StopReason::SmallArea: return "small_area";
  }
  return "none";
}

BaseDomain build_base_domain(const std::vector<PatchInfo>& patches) {
  BaseDomain bd;
  std::unordered_map<int, int> base_of;  // chart vertex -> base vertex, by first appearance
  for (const auto& p : patches)
    for (int c : p.corners)
      if (base_of.emplace(c, static_cast<int>(bd.vertices.size())).second) bd.vertices.push_back(c);
  std::vector<std::pair<int, int>> sides;
  for (const auto& p : patches) {
    std::array<int, 4> q;
    for (int k = 0; k < 4; ++k) q[k] = base_of.at(p.corners[k]);
    bd.quads.push_back(q);
    for (int k = 0; k < 4; ++k) sides.emplace_back(q[k], q[(k + 1) % 4]);
  }
  std::sort(sides.begin(), sides.end());
  bool ok = std::adjacent_find(sides.begin(), sides.end()) == sides.end();  // no side twice one way
  for (const auto& [a, b] : sides) ok = ok && std::binary_search(sides.begin(), sides.end(), std::make_pair(b, a));
  bd.closed_conforming = ok;
  bd.edges = static_cast<int>(sides.size()) / 2;
  bd.euler_characteristic = static_cast<int>(bd.vertices.size()) - bd.edges + static_cast<int>(bd.quads.size());
  return bd;
}

}  // namespace qs::dissect
