// Benchmark: set dissections of generated families (qs::family, 8000 faces a shape, 4 seeds and
// the limb tips as surface points) of 1, 2, 4, 8 and 16 shapes, dissected as qs-dissect does
// (qs::pipeline::dissect_meshes: the map hooks, same-pose detection, refine_maps after).
//   usage: qs-bench-family-sets [SEED ...]   (default seeds 1 2 3)
// Prints per family size: time (best of 3), time per mesh, the ratio t(N) / (N t(1)) (1: linear;
// below 1: the meshes' work runs in parallel), common patches, faces added by local refinement,
// and whether every leaf is bijective with every feature at one (patch, u, v).

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/dissect/dissection.h"
#include "qs/correspondence/correspondence.h"
#include "qs/family/family.h"
#include "qs/pipeline/pipeline.h"

using Clock = std::chrono::steady_clock;

int main(int argc, char** argv) {
  std::vector<std::uint64_t> seeds;
  for (int i = 1; i < argc; ++i) seeds.push_back(std::strtoull(argv[i], nullptr, 10));
  if (seeds.empty()) seeds = {1, 2, 3};
  std::printf("family sets: 8000-face shapes, seeds and limb tips as surface points, qs-dissect's defaults\n");
  std::printf("%6s %4s %10s %12s %10s %8s %9s %s\n", "seed", "N", "time s", "s per mesh", "t/(N t1)", "patches",
              "refined", "exact");
  for (const std::uint64_t seed : seeds) {
    qs::family::FamilyOptions fo;
    fo.shapes = 16;
    fo.seed = seed;
    const qs::family::Family fam = qs::family::generate_family(fo);
    std::vector<qs::dissect::MeshToDissect> all;
    for (const auto& s : fam.shapes) all.push_back(qs::correspondence::dissect_input(s));
    double t1 = 0;
    for (const int n : {1, 2, 4, 8, 16}) {
      const std::vector<qs::dissect::MeshToDissect> set(all.begin(), all.begin() + n);
      double best = 1e300;
      qs::dissect::DissectionSet result;
      try {
        for (int rep = 0; rep < 3; ++rep) {
          const auto t0 = Clock::now();
          result = qs::pipeline::dissect_meshes(set).set;
          best = std::min(best, std::chrono::duration<double>(Clock::now() - t0).count());
        }
      } catch (const qs::Error& e) {
        std::printf("%6llu %4d failed: %s\n", static_cast<unsigned long long>(seed), n, e.what());
        continue;
      }
      if (n == 1) t1 = best;
      int refined = 0;
      for (const auto& node : result.tree)
        for (int f : node.refined_faces) refined += f;
      bool exact = true;
      for (const auto& d : result.meshes) {
        for (const auto& p : d.chart.patches) exact = exact && p.flipped_faces + p.zero_area_faces == 0;
        for (size_t k = 0; k < d.features.size(); ++k)
          exact = exact && d.features[k].patch == result.meshes[0].features[k].patch &&
                  d.features[k].uv == result.meshes[0].features[k].uv;
      }
      std::printf("%6llu %4d %10.3f %12.3f %10.2f %8zu %9d %s\n", static_cast<unsigned long long>(seed), n, best,
                  best / n, t1 > 0 ? best / (n * t1) : 0.0, result.meshes[0].chart.patches.size(), refined,
                  exact ? "yes" : "NO");
    }
  }
  return 0;
}
