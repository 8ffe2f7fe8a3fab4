// qs-bake: normal-map atlases for the meshes of a qs-remesh output, and a GLB per mesh (the coarse
// remesh with texture coordinates, normals, tangents and the map). Reads REMESH_DIR/remesh.json,
// its meshes and the dissection they were made from; writes into OUTDIR per mesh
// <stem>_normal.png (+ <stem>_normal16.png / <stem>_normal.exr on request) and <stem>.glb, and
// bake.json (options, atlas layout, files, measured shading angles).
//
// Exit codes: 0 done, 1 usage, 2 invalid input (a folder that is not a consistent remesh +
// dissection), 3 i/o (missing folder or file, unwritable output), 70 internal error.

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "qs/bake/bake.h"
#include "qs/bake/bake_folder.h"
#include "qs/bake/export_glb.h"
#include "qs/bake/image_io.h"
#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/core/json_strict.h"
#include "qs/core/output_folder.h"
#include "qs/dissect/dissection_json.h"
#include "qs/gltf/glb.h"
#include "qs/remesh/chart_sampler.h"
#include "qs/remesh/quality.h"
#include "qs/remesh/remesh_io.h"
#include "resource_limits.h"
#include "tool_main.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

void check_positions(const qs::remesh::ChartSampler& sampler, const qs::remesh::SemiRegularConnectivity& c,
                     const std::vector<qs::Vec3>& positions, const std::string& file) {
  const std::vector<qs::Vec3> expected = qs::remesh::sample_positions(sampler, c);
  const double tol = 1e-6 * sampler.bbox_diagonal();
  for (size_t v = 0; v < expected.size(); ++v)
    if (!((expected[v] - positions[v]).norm() <= tol)) {
      std::ostringstream m;
      m << file << ": vertex " << v << " is " << (expected[v] - positions[v]).norm()
        << " away from its (patch, u, v) point on the chart: the remesh was not made from this dissection (or its "
           "file was edited)";
      throw qs::InvalidInput(m.str());
    }
}

/// The smallest and largest tile side.
std::pair<int, int> tile_range(const qs::bake::AtlasLayout& layout) {
  int lo = layout.tile_side(0), hi = lo;
  for (int p = 1; p < layout.num_patches; ++p) lo = std::min(lo, layout.tile_side(p)), hi = std::max(hi, layout.tile_side(p));
  return {lo, hi};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Bake tangent-space (or object-space) normal maps of the original meshes onto their semi-regular remeshes:\n"
               "one atlas per mesh (a tile per patch), and a GLB with the coarse mesh, its tangents and the map.\n"
               "Exit codes: 0 ok, 1 usage, 2 invalid input, 3 i/o, 70 internal.",
               "qs-bake"};
  std::string folder, outdir, dissection, space = "tangent", green = "opengl", tiles = "area";
  std::vector<std::string> formats;
  int size = 256, gutter = 4, samples = 100000, threads = 0;
  bool quiet = false;
  double max_memory = qs::tools::kDefaultMaxMemoryGiB;
  app.add_option("remesh", folder, "A qs-remesh output folder (remesh.json + meshes)")->required();
  app.add_option("--size", size,
                 "Tile size S: texels per patch side (--tiles area: of a patch of average area; the atlas holds "
                 "about the texels of P tiles of S x S)")
      ->capture_default_str()
      ->check(CLI::Range(2, 16384));
  app.add_option("--tiles", tiles,
                 "Tile sizes: area (each patch's side grows with the square root of its surface area, the largest "
                 "over the set: even texel density; shelf-packed atlas) or uniform (every tile S x S in a grid)")
      ->capture_default_str()
      ->check(CLI::IsMember({"area", "uniform"}));
  app.add_option("--space", space, "Normal space")->capture_default_str()->check(CLI::IsMember({"tangent", "object"}));
  app.add_option("--green", green, "Green channel convention of tangent-space maps: opengl (+Y up) or directx (-Y)")
      ->capture_default_str()
      ->check(CLI::IsMember({"opengl", "directx"}));
  app.add_option("--gutter", gutter, "Texels around each tile, filled from the tile's edge texels")
      ->capture_default_str()
      ->check(CLI::Range(0, 1024));
  app.add_option("--format", formats, "Extra map files: png16, exr (png8 is always written)")
      ->check(CLI::IsMember({"png8", "png16", "exr"}));
  app.add_option("--dissection", dissection,
                 "The dissection folder the remesh was made from (default: remesh.json's dissection_path)");
  app.add_option("--samples", samples, "Surface points for the shading check (0: skip it)")
      ->capture_default_str()
      ->check(CLI::Range(0, 100000000));
  app.add_option("-o,--output", outdir, "Output folder (default: <remesh>/bake-<size>)");
  qs::tools::add_max_memory_option(app, max_memory);
  app.add_option("--threads", threads, "Threads (0: all hardware threads; the output does not depend on it)")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
  app.add_flag("-q,--quiet", quiet, "Print nothing but errors");

  return qs::tools::run_tool(app, argc, argv, [&] {
    const qs::bake::BakeSetOptions so =
        qs::bake::bake_set_options(size, tiles, gutter, space, green, samples, formats);

    const auto t0 = Clock::now();
    if (!fs::exists(folder)) throw qs::IoError(folder + ": no such folder (expected a qs-remesh output folder)");
    if (!fs::is_directory(folder)) throw qs::IoError(folder + ": not a folder (expected a qs-remesh output folder)");
    const qs::remesh::LoadedRemesh rm = qs::remesh::read_remesh(folder);
    const fs::path dfolder = dissection.empty() ? rm.dissection_folder : fs::path(dissection);
    if (!fs::exists(dfolder / "dissection.json"))
      throw qs::IoError((fs::path(folder) / "remesh.json").string() + " was made from the dissection " + dfolder.lexically_normal().string() +
                        ", which has no dissection.json (moved or deleted?); qs-bake needs the dissection's charts: "
                        "pass --dissection DIR");
    const qs::dissect::LoadedDissection ds = qs::dissect::read_dissection(dfolder);
    if (ds.meshes.size() != rm.outputs.size())
      throw qs::InvalidInput(dfolder.string() + ": " + std::to_string(ds.meshes.size()) + " meshes, the remesh " +
                             std::to_string(rm.outputs.size()) + ": not the dissection it was made from");
    const auto& c = rm.set.connectivity;
    std::vector<std::unique_ptr<qs::remesh::ChartSampler>> samplers;
    for (size_t i = 0; i < ds.meshes.size(); ++i) {
      const auto& dm = ds.meshes[i];
      if (!rm.sources[i].empty() && rm.sources[i] != dm.file)
        throw qs::InvalidInput((fs::path(folder) / "remesh.json").string() + ": mesh " + std::to_string(i) + " is " +
                               rm.sources[i] + ", the dissection's is " + dm.file + ": not the dissection it was made from");
      if (static_cast<int>(dm.dissection.chart.patches.size()) != c.num_patches)
        throw qs::InvalidInput(dfolder.string() + ": " + std::to_string(dm.dissection.chart.patches.size()) +
                               " patches, the remesh " + std::to_string(c.num_patches) +
                               ": not the dissection it was made from");
      samplers.push_back(std::make_unique<qs::remesh::ChartSampler>(dm.dissection.chart));
      check_positions(*samplers.back(), c, rm.set.positions[i], (fs::path(folder) / rm.outputs[i]).string());
    }
    // One layout for the whole set (qs-morph blends the maps texel by texel): with --tiles area each
    // patch's tile side follows the square root of the surface it covers at its median face's
    // density (patch_texel_shares: its area share for an evenly mapped patch), the largest over the set.
    qs::bake::BakeSetInput input;
    input.set = &rm.set;
    input.outputs = rm.outputs;
    input.stems = rm.stems;
    input.dissection = &ds;
    input.remesh_folder = folder;
    input.dissection_folder = dfolder;
    const qs::bake::BakePlan plan = qs::bake::plan_bake(input, so);
    const qs::bake::AtlasLayout& layout = plan.layout;
    {
      const double texels = static_cast<double>(layout.width()) * layout.height();
      qs::tools::check_memory(texels * 48, max_memory,
                              "--size " + std::to_string(size) + " (an atlas of about " +
                                  std::to_string(static_cast<long long>(texels / 1e6)) + " M texels for " +
                                  std::to_string(c.num_patches) + " patches)");
    }
    const double load_seconds = seconds_since(t0);

    if (outdir.empty()) outdir = (fs::path(folder) / ("bake-" + std::to_string(size))).string();
    qs::bake::check_bake_outputs(outdir, input);
    qs::OutputFolder out_folder(outdir);
    const fs::path staging = out_folder.staging();

    if (!quiet)
      std::cout << "bake " << rm.outputs.size() << " meshes, " << c.num_patches << " patches, "
                << (layout.grid ? std::to_string(size) + " x " + std::to_string(size) + " tiles"
                                : "tiles sized by area (" + std::to_string(tile_range(layout).first) + ".." +
                                      std::to_string(tile_range(layout).second) + " texels, S = " + std::to_string(size) + ")")
                << ", gutter " << gutter << ": atlas " << layout.width() << " x " << layout.height()
                << (layout.grid ? " (" + std::to_string(layout.columns) + " x " + std::to_string(layout.rows) + " tiles)"
                                : std::string(" (shelves)"))
                << ", " << space << " space"
                << (so.space == qs::bake::NormalSpace::Tangent ? ", " + green + " green" : std::string()) << "\n"
                << std::fixed << std::setprecision(3);
    double bake_seconds = 0, write_seconds = 0, check_seconds = 0;
    qs::Context ctx;
    ctx.threads = threads;  // progress on a terminal only
    if (!quiet && ::isatty(2))
      ctx.progress = [&](const std::string& stem, double f) {
        std::cerr << "\r  " << stem << ": baking " << static_cast<int>(100 * f) << "%" << (f >= 1 ? "\r\033[K" : "")
                  << std::flush;
      };
    std::vector<const qs::remesh::ChartSampler*> sampler_list;
    for (const auto& s : samplers) sampler_list.push_back(s.get());
    qs::bake::write_bake_folder(staging, outdir, input, sampler_list, plan, so, ctx,
                                [&](size_t i, const qs::bake::BakedMeshInfo& info) {
      bake_seconds += info.bake_seconds;
      write_seconds += info.write_seconds;
      check_seconds += info.check_seconds;
      const qs::remesh::DensitySpread& td = info.texel_density;
      std::ostringstream line;
      line << std::fixed << std::setprecision(3) << "  " << rm.stems[i] << ": bake " << info.bake_seconds << " s, GLB "
           << info.glb_vertices << " vertices (" << c.num_vertices() << " before the per-patch split)";
      line << std::setprecision(3) << std::defaultfloat << "; texels per unit area, 5th-95th percentile: " << td.p5
           << " .. " << td.p95 << " (spread " << td.spread << "x)" << std::fixed;
      if (info.shading)
        line << std::setprecision(2) << "; shaded vs original normal: mean " << info.shading->mean_with_map
             << " deg with the map, " << info.shading->mean_without_map << " deg without";
      if (!quiet) std::cout << line.str() << "\n" << std::flush;
    });
    out_folder.commit();
    if (!quiet)
      std::cout << "  wrote " << rm.outputs.size() << " maps + GLBs and bake.json to " << outdir << "\n  time: load "
                << load_seconds << " s, bake " << bake_seconds << " s, encode + write " << write_seconds << " s, check "
                << check_seconds << " s\n";
    return 0;
  });
}
