// The remesh pipeline: a dissection folder -> even, uniform or adaptive semi-regular remeshes
// with one face list -> measured -> the remesh folder.

#include <chrono>
#include <cmath>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/core/json_strict.h"
#include "qs/dissect/chart_io.h"
#include "qs/io/write_mesh.h"
#include "qs/metro/metro.h"
#include "qs/pipeline/pipeline.h"
#include "qs/remesh/adaptive.h"
#include "qs/remesh/anisotropic.h"
#include "qs/remesh/quality.h"
#include "qs/remesh/uniform.h"

namespace qs::pipeline {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using nlohmann::ordered_json;

namespace {

// OBJ with quad faces (the grid cells), written atomically.
void write_quad_obj(const fs::path& path, const std::vector<Vec3>& positions, const std::vector<std::array<int, 4>>& quads) {
  AtomicFile file(path);
  std::ostream& out = file.stream();
  out << "# qs-remesh quads\n" << std::setprecision(17);
  for (const auto& p : positions) out << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  for (const auto& q : quads) out << "f " << q[0] + 1 << ' ' << q[1] + 1 << ' ' << q[2] + 1 << ' ' << q[3] + 1 << '\n';
  file.commit();
}

bool even(const RemeshConfig& c) { return c.mode == RemeshConfig::Mode::Even; }
bool uniform(const RemeshConfig& c) { return c.mode == RemeshConfig::Mode::Uniform; }
bool adaptive(const RemeshConfig& c) { return c.mode == RemeshConfig::Mode::Adaptive; }

}  // namespace

void validate_config(const RemeshConfig& c) {
  if (adaptive(c)) {
    if (!(c.adaptive > 0) || !std::isfinite(c.adaptive))
      throw UsageError("the adaptive remesh needs an error bound > 0 (--adaptive EPS)");
    if (c.max_level < 0 || c.max_level > remesh::kMaxAdaptiveLevel)
      throw UsageError("--max-level " + std::to_string(c.max_level) + ": expected 0 to " +
                       std::to_string(remesh::kMaxAdaptiveLevel));
  } else if (c.level < 0 || c.level > remesh::kMaxUniformLevel) {
    throw UsageError("--level " + std::to_string(c.level) + ": expected 0 to " + std::to_string(remesh::kMaxUniformLevel));
  }
  if (c.format != "obj" && c.format != "ply") throw UsageError("--format " + c.format + ": expected obj or ply");
  if (c.quads && (!uniform(c) || c.format != "obj")) throw UsageError("--quads needs --uniform and --format obj");
  if (!uniform(c) && (c.pattern_diagonals || c.grid_relax != 0))
    throw UsageError("--diagonals and --grid-relax are options of the uniform grid (--uniform)");
  if (!even(c) && c.square_cells) throw UsageError("--cells is an option of the even remesh (--level without --uniform)");
  if (!(c.grid_relax >= 0 && c.grid_relax <= remesh::kMaxGridRelax))
    throw UsageError("--grid-relax must be in [0, " + std::to_string(remesh::kMaxGridRelax) + "]");
  if (c.metro_samples < 0) throw UsageError("--metro-samples must be at least 0");
}

fs::path default_remesh_folder(const fs::path& dissection_folder, const RemeshConfig& c) {
  return dissection_folder / (!adaptive(c) ? "remesh-L" + std::to_string(c.level) +
                                                 (uniform(c) ? "-uniform" : c.square_cells ? "-square" : "")
                                           : std::string("remesh-adaptive"));
}

RemeshResult remesh(const dissect::LoadedDissection& in, const fs::path& dissection_folder, const RemeshConfig& config,
                    const Context& ctx) {
  validate_config(config);
  if (even(config) && !config.square_cells && config.level > remesh::kMaxAnisotropicLevel)
    throw UsageError("--level " + std::to_string(config.level) + ": the even remesh goes to level " +
                     std::to_string(remesh::kMaxAnisotropicLevel) + "; add --uniform for the square grid");
  if (in.meshes.empty()) throw InvalidInput("the dissection has no meshes");
  RemeshResult result;
  result.config = config;
  result.dissection_folder = dissection_folder;
  result.inputs.push_back(dissection_folder / "dissection.json");
  for (const auto& m : in.meshes) result.inputs.push_back(dissection_folder / m.chart_file);
  std::vector<const dissect::Chart*> charts;
  for (const auto& m : in.meshes) charts.push_back(&m.dissection.chart);
  const int level = config.level;
  const int patches = static_cast<int>(charts.front()->patches.size());
  const std::string cells = config.square_cells ? "square" : "aniso";
  const std::string diagonals = config.pattern_diagonals ? "pattern" : "angle";
  remesh::SemiRegularSet& set = result.set;
  ordered_json stats;
  double share_sum = 0;
  if (even(config))
    for (double a : remesh::patch_area_shares(charts)) share_sum += a;
  if (even(config) && !config.square_cells) {
    const remesh::AnisotropicOptions ao = remesh::anisotropic_options(level, patches, std::max(share_sum, 1.0));
    const remesh::AnisotropicRemesh ar = remesh::remesh_anisotropic(charts, ao, ctx);
    set = ar.remesh;
    stats = {{"level", level},
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
  } else if (even(config)) {
    const remesh::AdaptiveOptions eo = remesh::even_options(level, patches, std::max(share_sum, 1.0));
    const remesh::AdaptiveRemesh ar = remesh::remesh_adaptive(charts, eo, ctx);
    set = ar.remesh;
    stats = {{"level", level},
             {"cells", cells},
             {"max_area", eo.max_area},
             {"max_level", eo.max_level},
             {"finest_level", ar.forest.max_level},
             {"area_splits", ar.stats.error_splits},
             {"balance_splits", ar.stats.balance_splits},
             {"unresolved_leaves", ar.stats.unresolved_leaves},
             {"leaves_per_level", ar.stats.leaves_per_level}};
  } else if (uniform(config)) {
    remesh::UniformOptions uo;
    uo.quads = config.quads;
    uo.diagonals = config.pattern_diagonals ? remesh::DiagonalRule::Pattern : remesh::DiagonalRule::BestAngle;
    uo.relax = config.grid_relax;
    set = remesh::remesh_uniform(charts, level, uo, ctx);
  } else {
    remesh::AdaptiveOptions aopt;
    aopt.max_level = config.max_level;
    aopt.epsilon = config.adaptive;
    const remesh::AdaptiveRemesh ar = remesh::remesh_adaptive(charts, aopt, ctx);
    set = ar.remesh;
    stats = {{"epsilon", config.adaptive},
             {"max_level", aopt.max_level},
             {"finest_level", ar.forest.max_level},
             {"error_splits", ar.stats.error_splits},
             {"balance_splits", ar.stats.balance_splits},
             {"unresolved_leaves", ar.stats.unresolved_leaves},
             {"max_unresolved_error", ar.stats.max_unresolved_error},
             {"leaves_per_level", ar.stats.leaves_per_level}};
  }
  if (!stats.is_null()) result.mode_json = json_strict::dump(stats, -1);

  const auto& c = set.connectivity;
  std::ostringstream text;
  text << std::setprecision(4);
  text << "remesh "
       << (even(config) ? "even level " + std::to_string(level) +
                              (!config.square_cells ? " (anisotropic cells)" : " (square cells)")
           : uniform(config) ? "uniform level " + std::to_string(level)
                             : "adaptive eps " + std::to_string(config.adaptive))
       << ": " << c.num_vertices() << " vertices, " << c.num_faces() << " faces, " << c.num_patches
       << " patches, the same for all " << in.meshes.size() << " meshes\n";
  for (size_t i = 0; i < in.meshes.size(); ++i) {
    const auto& dm = in.meshes[i];
    const std::string out_name = dissect::chart_stem(dm.chart_file) + "." + config.format;
    result.outputs.push_back(out_name);
    const TriMesh mesh = set.mesh(static_cast<int>(i));
    ordered_json j = {{"file", dm.file}, {"chart", dm.chart_file}, {"output", out_name}};
    text << "  " << out_name;
    if (config.error) {
      const auto tm = Clock::now();
      // A = the original (the chart: the input's surface with cut vertices added), B = the remesh;
      // percentages of A's bounding-box diagonal.
      metro::MetroOptions mo;
      if (config.metro_samples > 0) mo.face_samples = config.metro_samples;
      mo.sample_vertices_b = false;  // the remesh's vertices are points of the chart: distance 0
      const metro::MetroResult r = metro::metro(dm.dissection.chart.mesh, mesh, mo);
      result.metro_seconds += std::chrono::duration<double>(Clock::now() - tm).count();
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
    const remesh::AngleStats angles = remesh::smallest_angle_stats(mesh);
    const remesh::DensitySpread density = remesh::vertex_density(mesh);
    result.quality_seconds += std::chrono::duration<double>(Clock::now() - tq).count();
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
    result.mesh_json.push_back(json_strict::dump(j, -1));
  }
  result.report = text.str();
  return result;
}

void write_remesh(const RemeshResult& result, OutputFolder& folder) {
  const RemeshConfig& config = result.config;
  const auto& c = result.set.connectivity;
  for (const auto& name : result.outputs) check_not_an_input(folder.target() / name, result.inputs, "output");
  check_not_an_input(folder.target() / "remesh.json", result.inputs, "output");
  for (size_t i = 0; i < result.outputs.size(); ++i) {
    const fs::path path = folder.staging() / result.outputs[i];
    if (config.quads) write_quad_obj(path, result.set.positions[i], c.quads);
    else io::write_mesh(path, result.set.mesh(static_cast<int>(i)));
  }
  // Where the dissection is, seen from the output folder (qs-bake reads the charts through it).
  const std::string dissection_path =
      fs::relative(fs::absolute(result.dissection_folder), fs::absolute(folder.target())).lexically_normal().generic_string();
  ordered_json sites_patch = ordered_json::array(), sites_uv = ordered_json::array();
  for (int v = 0; v < c.num_vertices(); ++v) {
    sites_patch.push_back(c.vertex_patch[v]);
    sites_uv.push_back(c.vertex_uv[v].x());
    sites_uv.push_back(c.vertex_uv[v].y());
  }
  const bool even = config.mode == RemeshConfig::Mode::Even;
  const bool grid = config.mode == RemeshConfig::Mode::Uniform;
  ordered_json doc = {{"format", "qs-remesh"},
                      {"version", 1},
                      {"dissection", result.dissection_folder.filename().string()},
                      {"dissection_path", dissection_path},
                      {"mode", even ? "even" : grid ? "uniform" : "adaptive"},
                      {"level", c.level},
                      {"quads", config.quads},
                      {"diagonals", grid ? (config.pattern_diagonals ? "pattern" : "angle") : "templates"},
                      {"grid_relax", grid ? config.grid_relax : 0.0},
                      {"vertices", c.num_vertices()},
                      {"faces", c.num_faces()},
                      {"base_vertices", c.num_base_vertices},
                      {"base_edges", c.num_base_edges},
                      {"patches", c.num_patches}};
  if (!result.mode_json.empty()) doc[even ? "even" : "adaptive"] = ordered_json::parse(result.mode_json);
  ordered_json meshes = ordered_json::array();
  for (const auto& m : result.mesh_json) meshes.push_back(ordered_json::parse(m));
  doc["meshes"] = meshes;
  doc["vertex_patch"] = sites_patch;
  doc["vertex_uv"] = sites_uv;
  write_file_atomically(folder.staging() / "remesh.json", json_strict::dump(doc, 1) + "\n");
}

void write_remesh(const RemeshResult& result, const fs::path& folder) {
  OutputFolder out(folder);
  write_remesh(result, out);
  out.commit();
}

}  // namespace qs::pipeline
