// Benchmark: the exact merge of two charts (qs-merge) on dissections of pairs.
//   usage: qs-bench-merge DISSECTION_DIR...   (bench/merge_pairs.sh dissects the four pairs)
// Prints, per pair: chart faces, merged faces and their ratio to the inputs, crossings, slivers,
// the median wall and CPU time of the merge on 1 and 2 threads (5 runs each), CPU microseconds per
// merged face (near-constant = near-linear time), and whether 1 and 2 threads gave identical
// output. Wall time on a shared machine is only as good as its load: the CPU time is the figure
// to compare (target: pig_4k + cow2_9k under 0.5 s).

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/dissect/dissection_json.h"
#include "qs/merge/merge.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double cpu_seconds() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

bool same(const qs::merge::Merged& a, const qs::merge::Merged& b) {
  return a.faces == b.faces && a.positions_a == b.positions_a && a.positions_b == b.positions_b &&
         a.vertex_uv == b.vertex_uv && a.vertex_patch == b.vertex_patch;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: qs-bench-merge DISSECTION_DIR...  (dissections of two meshes)\n");
    return 1;
  }
  std::printf("%-34s %7s %7s %8s %5s %8s %8s %9s %9s %9s %9s %7s %5s\n", "pair", "faces A", "faces B", "merged",
              "ratio", "crossing", "slivers", "wall 1t", "cpu 1t", "wall 2t", "cpu 2t", "us/face", "same");
  for (int i = 1; i < argc; ++i) {
    try {
      const auto in = qs::dissect::read_dissection(argv[i]);
      if (in.meshes.size() != 2) {
        std::fprintf(stderr, "%s: %zu meshes, skipped\n", argv[i], in.meshes.size());
        continue;
      }
      const auto& a = in.meshes[0].dissection.chart;
      const auto& b = in.meshes[1].dissection.chart;
      qs::merge::Merged first[2];
      double wall[2], cpu[2];
      for (int t = 0; t < 2; ++t) {
        qs::merge::MergeOptions o;
        o.threads = t + 1;
        std::vector<double> w, c;
        for (int r = 0; r < 5; ++r) {
          const double c0 = cpu_seconds();
          const auto t0 = Clock::now();
          qs::merge::Merged m = qs::merge::merge_charts(a, b, o);
          w.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
          c.push_back(cpu_seconds() - c0);
          if (r == 0) first[t] = std::move(m);
        }
        wall[t] = median(w);
        cpu[t] = median(c);
      }
      const auto& m = first[0];
      const auto& st = m.stats;
      const std::string name = fs::path(in.meshes[0].file).stem().string() + " + " + fs::path(in.meshes[1].file).stem().string();
      std::printf("%-34s %7d %7d %8zu %5.2f %8d %8d %8.3fs %8.3fs %8.3fs %8.3fs %7.2f %5s\n", name.c_str(),
                  st.input_faces_a, st.input_faces_b, m.faces.size(),
                  static_cast<double>(m.faces.size()) / (st.input_faces_a + st.input_faces_b), st.crossings, st.slivers_uv,
                  wall[0], cpu[0], wall[1], cpu[1], 1e6 * cpu[0] / m.faces.size(), same(first[0], first[1]) ? "yes" : "NO");
    } catch (const qs::Error& e) {
      std::fprintf(stderr, "%s: %s\n", argv[i], e.what());
      return 2;
    }
  }
  return 0;
}
