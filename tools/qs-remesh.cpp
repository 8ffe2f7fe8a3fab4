// qs-remesh: even (the default for --level), uniform or adaptive semi-regular remeshes of a dissected
// set, all with one face list.
// Reads a qs-dissect output folder; writes OUTDIR/<stem>.obj|.ply per mesh and OUTDIR/remesh.json.
//
// Exit codes: 0 done, 1 usage, 2 invalid input (a folder that is not a consistent dissection),
// 3 i/o, 4 solver, 70 internal error.

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "qs/core/atomic_file.h"
#include "qs/core/json_strict.h"
#include "qs/core/output_folder.h"
#include "qs/dissect/dissection_json.h"
#include "qs/io/write_mesh.h"
#include "qs/metro/metro.h"
#include "qs/remesh/adaptive.h"
#include "qs/remesh/anisotropic.h"
#include "qs/remesh/quality.h"
#include "qs/remesh/uniform.h"
#include "resource_limits.h"
#include "tool_main.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

std::string stem_of_chart(const std::string& chart) {
  const std::string suffix = ".chart.ply";
  return chart.size() > suffix.size() && chart.compare(chart.size() - suffix.size(), suffix.size(), suffix) == 0
             ? chart.substr(0, chart.size() - suffix.size())
             : fs::path(chart).stem().string();
}

// OBJ with quad faces (the grid cells), written atomically.
void write_quad_obj(const fs::path& path, const std::vector<qs::Vec3>& positions,
                    const std::vector<std::array<int, 4>>& quads) {
  qs::AtomicFile file(path);
  std::ostream& out = file.stream();
  out << "# qs-remesh quads\n" << std::setprecision(17);
  for (const auto& p : positions) out << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  for (const auto& q : quads) out << "f " << q[0] + 1 << ' ' << q[1] + 1 << ' ' << q[2] + 1 << ' ' << q[3] + 1 << '\n';
  file.commit();
}

int patch_count(const std::vector<const qs::dissect::Chart*>& charts) {
  return static_cast<int>(charts.front()->patches.size());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Semi-regular remeshes of a dissected set with one common connectivity (uniform level or adaptive).\n"
               "Exit codes: 0 ok, 1 usage, 2 invalid input, 3 i/o, 4 solver, 70 internal.",
               "qs-remesh"};
  std::string folder, outdir, format = "obj";
  int level = -1;
  double eps = 0;
  bool quads = false, quiet = false, no_metro = false, with_error = false;
  long metro_samples = 20000;
  double max_memory = qs::tools::kDefaultMaxMemoryGiB;
  qs::remesh::AdaptiveOptions aopt;
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
  bool even = false, uniform = false;
  auto* even_flag = app.add_flag("--even", even,
                                 "With --level n (the default since issue 13): about the uniform level n's face count, "
                                 "spread over the surface by area (trees split while a cell covers more than "
                                 "2.3 s / (P 4^n) of the surface, the largest share over the set; s = the patches' "
                                 "largest shares summed)");
  even_flag->needs(lvl);
  auto* uniform_flag = app.add_flag("--uniform", uniform,
                                    "With --level n: the square grid, (2^n+1)^2 samples per patch whatever its size "
                                    "(the default before issue 13; --quads, --diagonals and --grid-relax select it)");
  uniform_flag->needs(lvl);
  uniform_flag->excludes(even_flag);
  std::string cells = "aniso";
  auto* cells_opt = app.add_option("--cells", cells,
                 "Even remesh: cells split in u or v alone where they are long on the surface, kept within 2:1 "
                 "(aniso), or square quadtree cells that keep their patch's aspect (square)")
      ->capture_default_str()
      ->check(CLI::IsMember({"aniso", "square"}));
  cells_opt->needs(lvl);
  cells_opt->excludes(uniform_flag);
  app.add_option("--max-level", aopt.max_level, "Adaptive: finest level")->capture_default_str()->check(CLI::Range(0, 10));
  app.add_option("--format", format, "Output format")->capture_default_str()->check(CLI::IsMember({"obj", "ply"}));
  app.add_flag("--quads", quads, "Uniform: write the grid cells as quads (OBJ only)");
  std::string diagonals = "angle";
  auto* diag_opt = app.add_option("--diagonals", diagonals,
                 "Uniform: cut each grid cell along the diagonal with the larger smallest angle over the set (angle) "
                 "or by the fixed symmetric pattern (pattern: the face list depends on the patches and level only)")
      ->capture_default_str()
      ->check(CLI::IsMember({"angle", "pattern"}));
  even_flag->excludes(diag_opt);
  cells_opt->excludes(diag_opt);
  double grid_relax = qs::remesh::UniformOptions{}.relax;
  auto* relax_opt = app.add_option("--grid-relax", grid_relax,
                 "Uniform: move the grid samples toward equal 3D spacing along every patch side (0 = the regular "
                 "grid u = i/2^n; same connectivity, (u,v) written to remesh.json)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, qs::remesh::kMaxGridRelax));
  even_flag->excludes(relax_opt);
  cells_opt->excludes(relax_opt);
  ad->excludes(relax_opt);
  // The error report is opt-in: its closest-point tree over the original costs more than the
  // whole remesh at the usual levels (venus_100k level 5: ~0.1 s of CPU for the remesh, ~0.3 s
  // for the report; see the README).
  auto* err_flag = app.add_flag("--error", with_error,
                                "Measure every output against its original (Metro two-sided mean, RMS, max; costs more "
                                "than the remesh itself)");
  auto* no_metro_flag =
      app.add_flag("--no-metro", no_metro, "No error measurement (the default; kept for scripts that pass it)");
  no_metro_flag->excludes(err_flag);
  auto* samples_opt = app.add_option("--metro-samples", metro_samples,
                                     "Error measurement: surface samples per direction (0: qs-metro's full count, "
                                     "max(100000, 2 x the larger face count)); implies --error")
                          ->capture_default_str()
                          ->check(CLI::Range(0L, 1000000000L));
  samples_opt->excludes(no_metro_flag);
  app.add_option("-o,--output", outdir, "Output folder (default: <dissection>/remesh-L<n>, remesh-L<n>-uniform, remesh-L<n>-square or "
                 "remesh-adaptive)");
  qs::tools::add_max_memory_option(app, max_memory);
  app.add_flag("-q,--quiet", quiet, "Print nothing but errors");

  return qs::tools::run_tool(app, argc, argv, [&] {
    if (level < 0 && eps <= 0) throw qs::UsageError("give --level N or --adaptive EPS");
    if (quads && (level < 0 || format != "obj")) throw qs::UsageError("--quads needs --level and --format obj");
    if (quads && (even || cells_opt->count() > 0)) throw qs::UsageError("--quads needs the uniform grid; drop --even and --cells");
    // --level n: the even remesh unless the uniform grid is asked for (--uniform, or one of its
    // own options).
    if (level >= 0 && !uniform && !quads && diag_opt->count() == 0 && relax_opt->count() == 0) even = true;
    no_metro = !(with_error || samples_opt->count() > 0);
    const auto t0 = Clock::now();
    const qs::dissect::LoadedDissection in = qs::dissect::read_dissection(folder);
    const auto t1 = Clock::now();
    std::vector<const qs::dissect::Chart*> charts;
    for (const auto& m : in.meshes) charts.push_back(&m.dissection.chart);
    if (level >= 0) {
      // Uniform level n: (2^n+1)^2 samples and 2 * 4^n triangles per patch. Per vertex: a position
      // per mesh (and its copy for writing), (patch, u, v), the JSON sites; per face: the face list,
      // its copy and, with --error, the error measurement's tree and samples. Measured on a
      // 42-patch level 8 (2.8M vertices): peak 1.69 GiB (0.59 GiB without --error), estimated 2.0
      // (1.0) GiB.
      const double patches = static_cast<double>(charts.front()->patches.size());
      const double side = std::ldexp(1.0, level) + 1;
      const double vertices = patches * side * side, faces = 2 * patches * std::ldexp(1.0, 2 * level);
      const double bytes =
          vertices * (48.0 * static_cast<double>(charts.size()) + 150) + faces * (no_metro ? 100 : 300);
      qs::tools::check_memory(bytes, max_memory,
                              "--level " + std::to_string(level) + " (" + std::to_string(static_cast<long long>(vertices)) +
                                  " vertices per mesh, " + std::to_string(charts.size()) + " meshes)");
    }
    if (even && cells == "aniso" && level > qs::remesh::kMaxAnisotropicLevel)
      throw qs::UsageError("--level " + std::to_string(level) + ": the even remesh goes to level " +
                           std::to_string(qs::remesh::kMaxAnisotropicLevel) + "; add --uniform for the square grid");
    if (outdir.empty())
      outdir = (fs::path(folder) / (level >= 0 ? "remesh-L" + std::to_string(level) +
                                                     (!even ? "-uniform" : cells == "square" ? "-square" : "")
                                               : std::string("remesh-adaptive"))).string();
    // Never write over the inputs (qs-remesh D -o D is fine: the names differ).
    std::vector<fs::path> input_paths = {fs::path(folder) / "dissection.json"};
    for (const auto& m : in.meshes) input_paths.push_back(fs::path(folder) / m.chart_file);
    for (const auto& m : in.meshes)
      qs::check_not_an_input(fs::path(outdir) / (stem_of_chart(m.chart_file) + "." + format), input_paths, "-o");
    qs::check_not_an_input(fs::path(outdir) / "remesh.json", input_paths, "-o");
    qs::OutputFolder out_folder(outdir);
    qs::Context ctx;
    qs::remesh::SemiRegularSet set;
    nlohmann::ordered_json adaptive_stats;
    if (even && cells == "aniso") {
      double share_sum = 0;
      for (double a : qs::remesh::patch_area_shares(charts)) share_sum += a;
      const qs::remesh::AnisotropicOptions ao =
          qs::remesh::anisotropic_options(level, patch_count(charts), std::max(share_sum, 1.0));
      const qs::remesh::AnisotropicRemesh ar = qs::remesh::remesh_anisotropic(charts, ao, ctx);
      set = ar.remesh;
      adaptive_stats = {{"level", level},
                        {"cells", cells},
                        {"max_area", ao.max_area},
                        {"max_aspect", ao.max_aspect},
                        {"max_level", ao.max_level},
                        {"finest_level", ar.stats.finest_level},
                        {"leaves", ar.leaves.size()},
                        {"fan_leaves", ar.stats.fan_leaves},
                        {"area_splits", ar.stats.area_splits},
                        {"aspect_splits", ar.stats.aspect_splits},
                        {"balance_splits", ar.stats.balance_splits},
                        {"unresolved_leaves", ar.stats.unresolved_leaves},
                        {"max_leaf_aspect", ar.stats.max_leaf_aspect},
                        {"smooth_iterations", ao.smooth_iterations},
                        {"smooth_below", ao.smooth_below},
                        {"smoothed_moves", ar.stats.smoothed_moves},
                        {"slid_moves", ar.stats.slid_moves},
                        {"flip_rounds", ao.flip_rounds},
                        {"flips", ar.stats.flips}};
    } else if (even) {
      double share_sum = 0;
      for (double a : qs::remesh::patch_area_shares(charts)) share_sum += a;
      const qs::remesh::AdaptiveOptions eo = qs::remesh::even_options(level, patch_count(charts), std::max(share_sum, 1.0));
      const qs::remesh::AdaptiveRemesh ar = qs::remesh::remesh_adaptive(charts, eo, ctx);
      set = ar.remesh;
      adaptive_stats = {{"level", level},
                        {"cells", cells},
                        {"max_area", eo.max_area},
                        {"max_level", eo.max_level},
                        {"finest_level", ar.forest.max_level},
                        {"area_splits", ar.stats.error_splits},
                        {"balance_splits", ar.stats.balance_splits},
                        {"unresolved_leaves", ar.stats.unresolved_leaves},
                        {"leaves_per_level", ar.stats.leaves_per_level}};
    } else if (level >= 0) {
      qs::remesh::UniformOptions uo;
      uo.quads = quads;
      uo.diagonals = diagonals == "angle" ? qs::remesh::DiagonalRule::BestAngle : qs::remesh::DiagonalRule::Pattern;
      uo.relax = grid_relax;
      set = qs::remesh::remesh_uniform(charts, level, uo, ctx);
    } else {
      aopt.epsilon = eps;
      const qs::remesh::AdaptiveRemesh ar = qs::remesh::remesh_adaptive(charts, aopt, ctx);
      set = ar.remesh;
      adaptive_stats = {{"epsilon", eps},
                        {"max_level", aopt.max_level},
                        {"finest_level", ar.forest.max_level},
                        {"error_splits", ar.stats.error_splits},
                        {"balance_splits", ar.stats.balance_splits},
                        {"unresolved_leaves", ar.stats.unresolved_leaves},
                        {"max_unresolved_error", ar.stats.max_unresolved_error},
                        {"leaves_per_level", ar.stats.leaves_per_level}};
    }
    const auto t2 = Clock::now();
    const auto& c = set.connectivity;
    std::ostringstream text;
    text << std::setprecision(4);
    text << "remesh "
         << (even ? "even level " + std::to_string(level) + (cells == "aniso" ? " (anisotropic cells)" : " (square cells)")
                  : level >= 0 ? "uniform level " + std::to_string(level) : "adaptive eps " + std::to_string(eps))
         << ": " << c.num_vertices() << " vertices, " << c.num_faces() << " faces, " << c.num_patches
         << " patches, the same for all " << in.meshes.size() << " meshes\n";
    nlohmann::ordered_json meshes = nlohmann::ordered_json::array();
    double metro_seconds = 0, quality_seconds = 0;
    for (size_t i = 0; i < in.meshes.size(); ++i) {
      const auto& dm = in.meshes[i];
      const std::string out_name = stem_of_chart(dm.chart_file) + "." + format;
      const qs::TriMesh mesh = set.mesh(static_cast<int>(i));
      if (quads) write_quad_obj(out_folder.staging() / out_name, set.positions[i], c.quads);
      else qs::io::write_mesh(out_folder.staging() / out_name, mesh);
      nlohmann::ordered_json j = {{"file", dm.file}, {"chart", dm.chart_file}, {"output", out_name}};
      text << "  " << out_name;
      if (!no_metro) {
        const auto tm = Clock::now();
        // A = the original (the chart: the input's surface with cut vertices added), B = the remesh;
        // percentages of A's bounding-box diagonal.
        qs::metro::MetroOptions mo;
        if (metro_samples > 0) mo.face_samples = metro_samples;
        mo.sample_vertices_b = false;  // the remesh's vertices are points of the chart: distance 0
        const qs::metro::MetroResult r = qs::metro::metro(dm.dissection.chart.mesh, mesh, mo);
        metro_seconds += std::chrono::duration<double>(Clock::now() - tm).count();
        const double diag = r.diagonal;
        auto pct = [&](double x) { return 100.0 * x / diag; };
        j["error"] = {{"diagonal", diag},
                      {"diagonal_of", "original"},
                      {"mean_percent", pct(r.mean)},
                      {"rms_percent", pct(r.rms)},
                      {"max_percent", pct(r.max)},
                      {"original_to_remesh_mean_percent", pct(r.a_to_b.mean)},
                      {"remesh_to_original_mean_percent", pct(r.b_to_a.mean)},
                      {"samples_per_direction", r.a_to_b.samples}};
        text << ": error mean " << pct(r.mean) << "%, rms " << pct(r.rms) << "%, max " << pct(r.max)
             << "% of the original's diagonal (" << r.a_to_b.samples << " samples per direction)";
      }
      const auto tq = Clock::now();
      const qs::remesh::AngleStats angles = qs::remesh::smallest_angle_stats(mesh);
      const qs::remesh::DensitySpread density = qs::remesh::vertex_density(mesh);
      quality_seconds += std::chrono::duration<double>(Clock::now() - tq).count();
      j["angles"] = {{"faces", angles.faces},
                     {"under_5_deg", angles.under_5},
                     {"under_10_deg", angles.under_10},
                     {"under_20_deg", angles.under_20},
                     {"median_deg", angles.median},
                     {"min_deg", angles.min}};
      j["vertex_density"] = {{"p5", density.p5},
                             {"p50", density.p50},
                             {"p95", density.p95},
                             {"spread", density.spread}};  // null when infinite (p5 = 0)
      text << "\n    triangles: smallest angle median " << angles.median << " deg, min " << angles.min
           << " deg; under 5 / 10 / 20 deg: " << 100 * angles.under_5 << "% / " << 100 * angles.under_10 << "% / "
           << 100 * angles.under_20 << "%\n    vertices per unit area, 5th-95th percentile over the surface: "
           << density.p5 << " .. " << density.p95 << " (spread " << density.spread << "x)";
      text << "\n";
      meshes.push_back(j);
    }
    // Where the dissection is, seen from the output folder (qs-bake reads the charts through it).
    const std::string dissection_path =
        fs::relative(fs::absolute(folder), fs::absolute(outdir)).lexically_normal().generic_string();
    nlohmann::ordered_json sites_patch = nlohmann::ordered_json::array(), sites_uv = nlohmann::ordered_json::array();
    for (int v = 0; v < c.num_vertices(); ++v) {
      sites_patch.push_back(c.vertex_patch[v]);
      sites_uv.push_back(c.vertex_uv[v].x());
      sites_uv.push_back(c.vertex_uv[v].y());
    }
    nlohmann::ordered_json doc = {{"format", "qs-remesh"},
                                  {"version", 1},
                                  {"dissection", fs::path(folder).filename().string()},
                                  {"dissection_path", dissection_path},
                                  {"mode", even ? "even" : level >= 0 ? "uniform" : "adaptive"},
                                  {"level", c.level},
                                  {"quads", quads},
                                  {"diagonals", level >= 0 && !even ? diagonals : std::string("templates")},
                                  {"grid_relax", level >= 0 && !even ? grid_relax : 0.0},
                                  {"vertices", c.num_vertices()},
                                  {"faces", c.num_faces()},
                                  {"base_vertices", c.num_base_vertices},
                                  {"base_edges", c.num_base_edges},
                                  {"patches", c.num_patches}};
    if (!adaptive_stats.is_null()) doc[even ? "even" : "adaptive"] = adaptive_stats;
    doc["meshes"] = meshes;
    doc["vertex_patch"] = sites_patch;
    doc["vertex_uv"] = sites_uv;
    qs::write_file_atomically(out_folder.staging() / "remesh.json", qs::json_strict::dump(doc, 1) + "\n");
    out_folder.commit();
    const auto t3 = Clock::now();
    if (!quiet) {
      std::cout << text.str() << "  wrote " << in.meshes.size() << " meshes and remesh.json to " << outdir << "\n"
                << std::fixed << std::setprecision(3) << "  time: load " << std::chrono::duration<double>(t1 - t0).count()
                << " s, remesh " << std::chrono::duration<double>(t2 - t1).count() << " s, metro " << metro_seconds
                << " s, quality " << quality_seconds << " s, write "
                << std::chrono::duration<double>(t3 - t2).count() - metro_seconds - quality_seconds << " s\n";
    }
    return 0;
  });
}
