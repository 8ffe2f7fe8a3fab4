// Benchmark: normal-map baking.
//  1. Bake time of all tiles of a ~30-patch mesh per tile size (64..512): max_planck_11k dissected
//     at tau 1.32 (34 patches), uniform level 3; best of 9 runs (3 at 512) of bake_normal_map (the chart
//     sampler is built once beforehand, as qs-bake does). Target: 30 patches at 256 x 256 under
//     0.2 s on the 2-core machine (the 34-patch time is scaled by 30/34 for the ratio).
//  2. Mean angle between the shaded normal (coarse level-3 mesh + 8-bit map, decoded as a viewer
//     does) and the original smooth normal, with and without the map, for the shared heads.
//     Targets: <= 3 degrees with the map, >= 10 without.
//   usage: qs-bench-bake [MESH_DIR] [HEAD_TAU] [HEAD_TILE]   (defaults ../shared/meshes, 3 = the default
//   dissection, 256)

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <ctime>

#include "qs/bake/bake.h"
#include "qs/dissect/dissection.h"
#include "qs/io/read_mesh.h"
#include "qs/mesh/validate.h"
#include "qs/remesh/chart_sampler.h"
#include "qs/remesh/uniform.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// CPU seconds of the process (all threads): with other jobs on the machine, wall time varies a
// lot; CPU time / threads is what an idle machine would show.
double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

// The dissection and the input's vertex count (the chart keeps the input's vertices first).
std::pair<qs::dissect::Dissection, int> dissect_file(const fs::path& path, double tau) {
  const auto r = qs::io::read_mesh(path);
  const auto v = qs::mesh::validate(r.mesh);
  qs::dissect::DissectOptions o;
  o.tau = tau;
  return {qs::dissect::dissect(v.mesh, std::nullopt, o), v.mesh.num_vertices()};
}

}  // namespace

int main(int argc, char** argv) {
  const fs::path dir = argc > 1 ? argv[1] : QS_SOURCE_DIR "/../shared/meshes";
  const double head_tau = argc > 2 ? std::stod(argv[2]) : 3.0;
  const int head_tile = argc > 3 ? std::stoi(argv[3]) : 256;
  if (!fs::is_directory(dir)) {
    std::fprintf(stderr, "qs-bench-bake: %s is not a folder of meshes\n", dir.string().c_str());
    return 2;
  }
  std::printf("threads: %u (hardware_concurrency); best of 9 runs (3 at 512); cpu_s = process CPU time of that run (all threads)\n\n",
              std::thread::hardware_concurrency());

  // 1. Bake time per tile size.
  {
    const double tau = 1.32;
    const auto [d, input_vertices] = dissect_file(dir / "max_planck_11k.obj", tau);
    const auto rm = qs::remesh::remesh_uniform(d.chart, 3);
    auto t0 = Clock::now();
    const qs::remesh::ChartSampler sampler(d.chart);
    sampler.locate(0, qs::Vec2(0.5, 0.5));  // builds the point-location grid
    const double sampler_s = since(t0);
    const int patches = static_cast<int>(d.chart.patches.size());
    std::printf("bake time: max_planck_11k, tau %.2f -> %d patches, level 3 (%d faces); chart sampler %.4f s (once)\n",
                tau, patches, rm.connectivity.num_faces(), sampler_s);
    std::printf("%6s %12s %10s %10s %10s %15s %10s\n", "tile", "atlas", "texels", "best_s", "cpu_s", "per_30_patch_s",
                "ns/texel");
    for (int size : {64, 128, 256, 512}) {
      qs::bake::BakeOptions o;
      o.tile_size = size;
      o.original_vertices = input_vertices;
      double best = 1e300, best_cpu = 1e300;
      qs::bake::BakeResult r;
      for (int k = 0; k < (size <= 256 ? 9 : 3); ++k) {
        t0 = Clock::now();
        const double c0 = cpu_seconds();
        r = qs::bake::bake_normal_map(sampler, rm.connectivity, rm.positions, o);
        best = std::min(best, since(t0));
        best_cpu = std::min(best_cpu, cpu_seconds() - c0);
      }
      const double texels = static_cast<double>(patches) * size * size;
      const std::string atlas = std::to_string(r.layout.width()) + "x" + std::to_string(r.layout.height());
      std::printf("%6d %12s %10.0f %10.4f %10.4f %15.4f %10.1f", size, atlas.c_str(), texels, best, best_cpu,
                  best * 30.0 / patches, 1e9 * best / texels);
      if (size == 256)
        std::printf("   target 0.2 s (30 patches): ratio %.2f, %s", best * 30.0 / patches / 0.2,
                    best * 30.0 / patches < 0.2 ? "met" : "MISSED");
      std::printf("\n");
    }
  }

  // 2. Shading angles for the heads.
  std::printf("\nshading check: heads dissected at tau %.2f, uniform level 3, %d x %d tiles, 8-bit map, 100000 points\n",
              head_tau, head_tile, head_tile);
  std::printf("%-24s %7s %8s %10s %12s %12s %12s  %s\n", "mesh", "patches", "faces", "bake_s", "with_map", "p95_with",
              "without", "targets (<=3, >=10)");
  for (const char* name : {"max_planck_11k.obj", "igea_17k.off", "mannequin_head_23k.off", "venus_100k.off"}) {
    if (!fs::exists(dir / name)) {
      std::printf("%-24s missing\n", name);
      continue;
    }
    const auto [d, input_vertices] = dissect_file(dir / name, head_tau);
    const auto rm = qs::remesh::remesh_uniform(d.chart, 3);
    const qs::remesh::ChartSampler sampler(d.chart);
    qs::bake::BakeOptions o;
    o.tile_size = head_tile;
    o.original_vertices = input_vertices;
    const auto t0 = Clock::now();
    const auto r = qs::bake::bake_normal_map(sampler, rm.connectivity, rm.positions, o);
    const double bake_s = since(t0);
    const auto c = qs::bake::check_shading(sampler, r, qs::bake::quantize8(r.atlas));
    std::printf("%-24s %7zu %8d %10.4f %12.3f %12.3f %12.3f  %s\n", name, d.chart.patches.size(),
                rm.connectivity.num_faces(), bake_s, c.mean_with_map, c.p95_with_map, c.mean_without_map,
                c.mean_with_map <= 3 && c.mean_without_map >= 10 ? "met" : (c.mean_with_map <= 3 ? "with: met, without: below 10" : "MISSED"));
  }
  return 0;
}
