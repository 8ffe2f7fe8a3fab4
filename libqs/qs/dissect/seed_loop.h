#pragma once
// The seed loop (paper 3.3): four seeds joined by shortest edge paths s0->s1->s2->s3->s0 that
// cut a closed genus-0 mesh into two quad patches.

#include <array>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"

namespace qs::dissect {

struct SeedLoop {
  std::array<int, 4> seeds{};
  /// paths[i] runs from seeds[i] to seeds[(i+1)%4], both included, along mesh edges (3D lengths).
  /// The four paths are simple and share no vertex except the seeds they meet at.
  std::array<std::vector<int>, 4> paths;
};

/// Traces the four paths. \pre mesh is a validated closed genus-0 mesh; seeds are 4 distinct
/// vertices. \throws InvalidInput naming the seeds when a path cannot be routed without
/// crossing or touching the others.
SeedLoop trace_seed_loop(const TriMesh& mesh, const std::array<int, 4>& seeds, const Context& context = {});

/// Four seeds chosen automatically (the documented rule is in the .cpp and the README):
/// the extreme vertices along the first two principal axes, in loop order.
std::array<int, 4> choose_seeds(const TriMesh& mesh);

}  // namespace qs::dissect
