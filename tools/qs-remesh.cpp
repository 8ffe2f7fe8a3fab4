// qs-remesh: even (the default for --level), uniform or adaptive semi-regular remeshes of a dissected
// set, all with one face list (qs::pipeline::remesh).
// Reads a qs-dissect output folder; writes OUTDIR/<stem>.obj|.ply per mesh and OUTDIR/remesh.json.
//
// Exit codes: 0 done, 1 usage, 2 invalid input (a folder that is not a consistent dissection),
// 3 i/o, 4 solver, 70 internal error.

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>

#include "qs/core/output_folder.h"
#include "qs/pipeline/pipeline.h"
#include "qs/remesh/adaptive.h"
#include "qs/remesh/uniform.h"
#include "resource_limits.h"
#include "tool_main.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

int main(int argc, char** argv) {
  CLI::App app{"Semi-regular remeshes of a dissected set with one common connectivity (even, uniform or adaptive).\n"
               "Exit codes: 0 ok, 1 usage, 2 invalid input, 3 i/o, 4 solver, 70 internal.",
               "qs-remesh"};
  qs::pipeline::RemeshConfig config;
  std::string folder, outdir, cells = "aniso", diagonals = "angle";
  int level = -1, threads = 0;
  double eps = 0;
  bool quiet = false, uniform = false;
  double max_memory = qs::tools::kDefaultMaxMemoryGiB;
  app.add_option("dissection", folder, "A qs-dissect output folder (dissection.json + charts)")->required();
  auto* lvl = app.add_option("--level", level,
                             "Level n: about 2 P 4^n faces (P patches), spread over the surface by area, cells kept "
                             "near square on the surface (the even remesh); with --uniform (2^n+1)^2 samples per patch")
                  ->check(CLI::Range(0, qs::remesh::kMaxUniformLevel));
  auto* ad = app.add_option("--adaptive", eps,
                            "Adaptive: refine each patch's quadtree while the error (fraction of the bounding-box "
                            "diagonal, max over the set) exceeds EPS")
                 ->check(CLI::PositiveNumber);
  lvl->excludes(ad);
  auto* uniform_flag = app.add_flag("--uniform", uniform,
                                    "With --level n: the square grid, (2^n+1)^2 samples per patch whatever its size "
                                    "(--quads, --diagonals and --grid-relax select it too)");
  uniform_flag->needs(lvl);
  auto* cells_opt = app.add_option("--cells", cells,
                                   "Even remesh: cells split in u or v alone where they are long on the surface, kept "
                                   "within 2:1 (aniso), or square quadtree cells that keep their patch's aspect (square)")
                        ->capture_default_str()
                        ->check(CLI::IsMember({"aniso", "square"}));
  cells_opt->needs(lvl);
  cells_opt->excludes(uniform_flag);
  app.add_option("--max-level", config.max_level, "Adaptive: finest level")->capture_default_str()->check(CLI::Range(0, 10));
  app.add_option("--format", config.format, "Output format")->capture_default_str()->check(CLI::IsMember({"obj", "ply"}));
  auto* quads_flag = app.add_flag("--quads", config.quads, "Uniform: write the grid cells as quads (OBJ only)");
  auto* diag_opt = app.add_option("--diagonals", diagonals,
                                  "Uniform: cut each grid cell along the diagonal with the larger smallest angle over "
                                  "the set (angle) or by the fixed symmetric pattern (pattern: the face list depends "
                                  "on the patches and level only)")
                       ->capture_default_str()
                       ->check(CLI::IsMember({"angle", "pattern"}));
  cells_opt->excludes(diag_opt);
  auto* relax_opt = app.add_option("--grid-relax", config.grid_relax,
                                   "Uniform: move the grid samples toward equal 3D spacing along every patch side (0 = "
                                   "the regular grid u = i/2^n; same connectivity, (u,v) written to remesh.json)")
                        ->capture_default_str()
                        ->check(CLI::Range(0.0, qs::remesh::kMaxGridRelax));
  cells_opt->excludes(relax_opt);
  ad->excludes(relax_opt);
  app.add_flag("--error", config.error,
               "Measure every output against its original (Metro two-sided mean, RMS, max; costs more than the "
               "remesh itself)");
  auto* samples_opt = app.add_option("--metro-samples", config.metro_samples,
                                     "Error measurement: surface samples per direction (0: qs-metro's full count, "
                                     "max(100000, 2 x the larger face count)); implies --error")
                          ->capture_default_str()
                          ->check(CLI::Range(0L, 1000000000L));
  app.add_option("-o,--output", outdir,
                 "Output folder (default: <dissection>/remesh-L<n>, remesh-L<n>-uniform, remesh-L<n>-square or "
                 "remesh-adaptive)");
  qs::tools::add_max_memory_option(app, max_memory);
  app.add_option("--threads", threads, "Threads (0: all hardware threads; the output does not depend on it)")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
  app.add_flag("-q,--quiet", quiet, "Print nothing but errors");

  return qs::tools::run_tool(app, argc, argv, [&] {
    if (level < 0 && eps <= 0) throw qs::UsageError("give --level N or --adaptive EPS");
    if (config.quads && (level < 0 || config.format != "obj")) throw qs::UsageError("--quads needs --level and --format obj");
    if (config.quads && cells_opt->count() > 0) throw qs::UsageError("--quads needs the uniform grid; drop --cells");
    // --level n: the even remesh unless the uniform grid is asked for (--uniform, or one of its own options).
    using Mode = qs::pipeline::RemeshConfig::Mode;
    if (level < 0) config.mode = Mode::Adaptive;
    else if (uniform || quads_flag->count() > 0 || diag_opt->count() > 0 || relax_opt->count() > 0)
      config.mode = Mode::Uniform;
    else config.mode = Mode::Even;
    config.level = level;
    config.adaptive = eps;
    config.square_cells = cells == "square";
    config.pattern_diagonals = diagonals == "pattern";
    config.error = config.error || samples_opt->count() > 0;
    qs::pipeline::validate_config(config);
    const auto t0 = Clock::now();
    const qs::dissect::LoadedDissection in = qs::pipeline::read_dissection(folder);
    const auto t1 = Clock::now();
    if (level >= 0) {
      // Uniform level n: (2^n+1)^2 samples and 2 * 4^n triangles per patch. Per vertex: a position
      // per mesh (and its copy for writing), (patch, u, v), the JSON sites; per face: the face list,
      // its copy and, with --error, the error measurement's tree and samples. Measured on a
      // 42-patch level 8 (2.8M vertices): peak 1.69 GiB (0.59 GiB without --error), estimated 2.0
      // (1.0) GiB.
      const double patches = static_cast<double>(in.meshes.front().dissection.chart.patches.size());
      const double side = std::ldexp(1.0, level) + 1;
      const double vertices = patches * side * side, faces = 2 * patches * std::ldexp(1.0, 2 * level);
      const double meshes = static_cast<double>(in.meshes.size());
      const double bytes = vertices * (48.0 * meshes + 150) + faces * (config.error ? 300 : 100);
      qs::tools::check_memory(bytes, max_memory,
                              "--level " + std::to_string(level) + " (" +
                                  std::to_string(static_cast<long long>(vertices)) + " vertices per mesh, " +
                                  std::to_string(in.meshes.size()) + " meshes)");
    }
    if (outdir.empty()) outdir = qs::pipeline::default_remesh_folder(folder, config).string();
    qs::OutputFolder out_folder(outdir);
    qs::Context ctx;
    ctx.threads = threads;
    const qs::pipeline::RemeshResult result = qs::pipeline::remesh(in, folder, config, ctx);
    const auto t2 = Clock::now();
    qs::pipeline::write_remesh(result, out_folder);
    out_folder.commit();
    const auto t3 = Clock::now();
    if (!quiet) {
      std::cout << result.report << "  wrote " << in.meshes.size() << " meshes and remesh.json to " << outdir << "\n"
                << std::fixed << std::setprecision(3)
                << "  time: load " << std::chrono::duration<double>(t1 - t0).count() << " s, remesh "
                << std::chrono::duration<double>(t2 - t1).count() - result.metro_seconds - result.quality_seconds
                << " s, metro " << result.metro_seconds << " s, quality " << result.quality_seconds << " s, write "
                << std::chrono::duration<double>(t3 - t2).count() << " s\n";
    }
    return 0;
  });
}
