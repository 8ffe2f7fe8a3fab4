// Benchmark: time to read and validate each mesh of a folder (default ../shared/meshes).
// Prints one row per mesh (best of 5 runs) and the target for venus_100k.
//   usage: qs-bench-io [MESH_DIR]

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/io/read_mesh.h"
#include "qs/mesh/validate.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

int main(int argc, char** argv) {
  const fs::path dir = argc > 1 ? argv[1] : QS_SOURCE_DIR "/../shared/meshes";
  if (!fs::is_directory(dir)) {
    std::fprintf(stderr, "qs-bench-io: %s is not a directory\n", dir.c_str());
    return 3;
  }
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string ext = e.path().extension().string();
    if (ext == ".obj" || ext == ".off" || ext == ".ply" || ext == ".stl") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  std::printf("%-24s %8s %8s %10s %10s %10s  %s\n", "mesh", "V", "F", "read_s", "valid_s", "total_s",
              "verdict");
  double venus = -1;
  for (const auto& f : files) {
    double best_read = 1e30, best_valid = 1e30;
    int v = 0, nf = 0;
    bool accepted = false;
    try {
      for (int run = 0; run < 5; ++run) {
        const auto t0 = Clock::now();
        const auto r = qs::io::read_mesh(f);
        const auto t1 = Clock::now();
        const auto val = qs::mesh::validate(r.mesh);
        const auto t2 = Clock::now();
        best_read = std::min(best_read, std::chrono::duration<double>(t1 - t0).count());
        best_valid = std::min(best_valid, std::chrono::duration<double>(t2 - t1).count());
        v = val.report.vertices;
        nf = val.report.faces;
        accepted = val.report.accepted;
      }
    } catch (const qs::Error& e) {
      std::printf("%-24s error: %s\n", f.filename().c_str(), e.what());
      continue;
    }
    std::printf("%-24s %8d %8d %10.4f %10.4f %10.4f  %s\n", f.filename().c_str(), v, nf, best_read,
                best_valid, best_read + best_valid, accepted ? "accepted" : "REJECTED");
    if (f.filename() == "venus_100k.off") venus = best_read + best_valid;
  }
  if (venus >= 0)
    std::printf("\ntarget: venus_100k read+validate < 0.300 s: %.4f s (%.2f of the budget)\n", venus,
                venus / 0.3);
  return 0;
}
