#pragma once
// The cyclic order of the four seeds: seeds correspond by index across a set, but the seed loop
// s0-s1-s2-s3-s0 may be taken in any of the three cyclic orders without changing what
// corresponds. The order whose loop is shortest over the set is the one that cuts each mesh
// along a belt instead of winding around it.

#include <array>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"

namespace qs::dissect {

struct MeshToDissect;

/// The unobstructed loop length of the three cyclic orders (0,1,2,3), (0,1,3,2), (0,2,1,3),
/// summed over the meshes, each mesh's shortest edge-path distances between its seeds divided by
/// the square root of its surface area (so that every mesh weighs alike).
struct SeedOrderChoice {
  std::array<int, 4> order{0, 1, 2, 3};  ///< seeds[order[k]] becomes seed k
  std::array<double, 3> lengths{};       ///< per cyclic order, in the order above
  bool changed() const { return order != std::array<int, 4>{0, 1, 2, 3}; }
};

/// shortest_seed_order's margin: a given order within 5% of the shortest loop stays.
inline constexpr double kSeedOrderMargin = 0.05;

/// The set's shortest cyclic order. The given order is kept unless its loop is longer than the
/// shortest by more than `margin` (a fraction: 0.05 = 5%), so that near ties never flip.
/// Meshes without seeds (automatic seeds) leave the order as given.
/// \pre every mesh validated (closed, manifold); seeds in range.
SeedOrderChoice shortest_seed_order(const std::vector<MeshToDissect>& meshes, double margin = kSeedOrderMargin,
                                    const Context& context = {});

}  // namespace qs::dissect
