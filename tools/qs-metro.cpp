// qs-metro: Metro-style two-sided distance between two meshes (mean, RMS, max), in absolute
// units and as a percentage of the bounding-box diagonal of the first mesh (A).
//
// Exit codes: 0 measured; 1 usage; 2 a mesh that cannot be measured (unparsable, no faces,
// a face index out of range, a NaN or infinite coordinate, zero total area); 3 a file that
// cannot be read or written. Meshes that qs-inspect would reject for other reasons (open,
// non-manifold, several components, any genus) are measured anyway, with a note.
//
// --correspondence DIR: a qs-dissect folder measured against ground truth (map files, or identical
// face lists): qs::correspondence, docs/correspondence.md. Exit 2 also for meshes without a
// common domain or a map of another mesh.
//
// Outputs: -o is written under a temporary name and renamed; the --error-map folder is staged
// and moved into place only after every pair was measured and the report written. An output
// that is one of the run's inputs (a mesh, a map file, the dissection's charts or its
// dissection.json) is a usage error.

#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "qs/core/atomic_file.h"
#include "qs/correspondence/correspondence.h"
#include "qs/correspondence/dissection_measure.h"
#include "qs/dissect/dissection_json.h"
#include "qs/core/error.h"
#include "qs/core/json_strict.h"
#include "qs/core/output_folder.h"
#include "qs/io/read_mesh.h"
#include "qs/mesh/validate.h"
#include "qs/metro/metro.h"
#include "dissection_names.h"
#include "tool_main.h"

namespace {

struct Input {
  std::string file;
  qs::TriMesh mesh;
  std::vector<std::string> problems;  ///< kinds that make it no qs input, though measurable
};

/// Reads a mesh and rejects only what metro cannot measure; other problems become notes.
Input load(const std::string& file, const char* which) {
  Input in;
  in.file = file;
  in.mesh = qs::io::read_mesh(file).mesh;
  const qs::mesh::ValidationResult valid = qs::mesh::validate(in.mesh);
  std::string fatal;
  for (const auto& p : valid.report.problems) {
    if (p.severity != qs::mesh::Severity::Fatal) continue;
    if (p.kind == "empty" || p.kind == "invalid_vertex_index" || p.kind == "non_finite_coordinates")
      fatal += "\n  " + p.message;
    else
      in.problems.push_back(p.kind);
  }
  if (!fatal.empty())
    throw qs::InvalidInput(file + " (" + which + "): cannot measure distances on this mesh:" + fatal);
  return in;
}

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string pct(double v, double diagonal) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.4g%%", 100.0 * v / diagonal);
  return buf;
}

std::string describe(const Input& in) {
  return in.file + " (" + std::to_string(in.mesh.num_vertices()) + " vertices, " +
         std::to_string(in.mesh.num_faces()) + " faces)";
}

std::string text_report(const Input& a, const Input& b, const qs::metro::MetroResult& r) {
  std::ostringstream s;
  const double d = r.diagonal;
  s << "qs-metro: A = " << describe(a) << ", B = " << describe(b) << "\n";
  for (const auto* in : {&a, &b})
    if (!in->problems.empty()) {
      s << "note: " << (in == &a ? "A" : "B") << " is not a closed genus-0 mesh (";
      for (size_t i = 0; i < in->problems.size(); ++i) s << (i ? ", " : "") << in->problems[i];
      s << "); measured anyway\n";
    }
  s << "bounding box diagonal of A: " << num(d) << " (used for the percentages)\n";
  auto side = [&](const char* label, const qs::metro::OneSided& o) {
    s << label << ": mean " << num(o.mean) << " (" << pct(o.mean, d) << "), rms " << num(o.rms) << " ("
      << pct(o.rms, d) << "), max " << num(o.max) << " (" << pct(o.max, d) << ") (" << o.samples
      << " surface samples";
    if (o.vertex_samples > 0) s << " + " << o.vertex_samples << " vertices";
    s << ")\n";
  };
  side("A -> B", r.a_to_b);
  side("B -> A", r.b_to_a);
  s << "Hausdorff (two-sided): max " << num(r.max) << " (" << pct(r.max, d) << "), mean " << num(r.mean)
    << " (" << pct(r.mean, d) << "), rms " << num(r.rms) << " (" << pct(r.rms, d) << ")\n";
  return s.str();
}

nlohmann::json mesh_json(const Input& in, double area) {
  return {{"file", in.file},
          {"vertices", in.mesh.num_vertices()},
          {"faces", in.mesh.num_faces()},
          {"area", area},
          {"problems", in.problems}};
}

nlohmann::json side_json(const qs::metro::OneSided& o, double d) {
  return {{"mean", o.mean},
          {"rms", o.rms},
          {"max", o.max},
          {"mean_percent", 100 * o.mean / d},
          {"rms_percent", 100 * o.rms / d},
          {"max_percent", 100 * o.max / d},
          {"max_at", {o.max_at.x(), o.max_at.y(), o.max_at.z()}},
          {"samples", o.samples},
          {"vertex_samples", o.vertex_samples}};
}

nlohmann::json json_report(const Input& a, const Input& b, const qs::metro::MetroResult& r,
                           std::uint64_t seed) {
  const double d = r.diagonal;
  return {{"a", mesh_json(a, r.area_a)},
          {"b", mesh_json(b, r.area_b)},
          {"diagonal", d},
          {"diagonal_of", "A"},
          {"seed", seed},
          {"a_to_b", side_json(r.a_to_b, d)},
          {"b_to_a", side_json(r.b_to_a, d)},
          {"two_sided",
           {{"max", r.max},
            {"mean", r.mean},
            {"rms", r.rms},
            {"max_percent", 100 * r.max / d},
            {"mean_percent", 100 * r.mean / d},
            {"rms_percent", 100 * r.rms / d}}}};
}


// ---- --correspondence: a dissection measured against ground truth ----------------------------

/// The report file of -o, opened (under a temporary name) before any work so that an output that
/// cannot be written is found first; committed last.
void open_report(const std::optional<std::string>& output, std::optional<qs::AtomicFile>& file) {
  std::error_code ec;
  if (output && std::filesystem::is_directory(*output, ec))
    throw qs::IoError(*output + ": is a folder; -o names the report file");
  if (output) file.emplace(*output);
}

/// Writes the report into the file of open_report (flushed: a full disk shows here), or to stdout.
void write_report(std::optional<qs::AtomicFile>& file, const std::optional<std::string>& output,
                  const std::string& report) {
  if (!file) {
    std::cout << report;
    return;
  }
  if (!(file->stream() << report).flush()) throw qs::IoError(*output + ": cannot write the report");
}

nlohmann::json stats_json(const qs::correspondence::ErrorStats& s) {
  return {{"mean_percent", s.mean}, {"median_percent", s.median}, {"p95_percent", s.p95}, {"max_percent", s.max}};
}

std::string stats_text(const qs::correspondence::ErrorStats& s) {
  char buf[200];
  std::snprintf(buf, sizeof buf, "mean %.3f%%, median %.3f%%, p95 %.3f%%, max %.3f%%", s.mean, s.median, s.p95, s.max);
  return buf;
}

// Both maps' isometric distortion on A's faces (1: isometric up to the meshes' size).
std::string distortion_text(const qs::correspondence::PairMeasure& pm) {
  char buf[400];
  std::snprintf(buf, sizeof buf,
                "isometric distortion on %s's faces (symDirichlet / 4, 1 = isometric): dissection mean %.4f, "
                "median %.4f; ground truth mean %.4f, median %.4f (degenerate or turned faces left out: %d / %d)\n",
                pm.distortion_on_b ? "B" : "A", pm.distortion, pm.distortion_median, pm.truth_distortion,
                pm.truth_distortion_median, pm.distortion_folded, pm.truth_distortion_folded);
  return buf;
}

/// --error-map and --worst: what qs-metro does with the per-vertex errors (the map files, the list).
struct ErrorMapOptions {
  std::optional<std::string> folder;
  double scale = 0;  ///< % of the diagonal at red; 0: each pair's largest vertex error
  int worst = 0;     ///< --worst: list this many of A's vertices with the largest error per pair
};

int run_correspondence(const std::string& folder_name, const std::vector<std::string>& maps, long samples,
                       std::uint64_t seed, int level, int threads, bool as_json,
                       const std::optional<std::string>& output, const ErrorMapOptions& error_map) {
  namespace fs = std::filesystem;
  const fs::path folder(folder_name);
  const qs::dissect::LoadedDissection loaded = qs::tools::read_dissection_folder(folder);
  const int n = static_cast<int>(loaded.meshes.size());
  if (n < 2) throw qs::InvalidInput(folder_name + ": the dissection holds 1 mesh; a correspondence needs 2 or more");
  if (!maps.empty() && static_cast<int>(maps.size()) != n)
    throw qs::UsageError("--map: " + std::to_string(maps.size()) + " files given for " + std::to_string(n) +
                         " meshes (one per mesh in the dissection's order, '-' for a mesh without a map)");
  // Every input first (the dissection's files, the meshes and their maps), checked against the
  // outputs before anything is read further or written.
  const qs::correspondence::TruthFiles truth_files = qs::correspondence::find_truth_files(loaded, folder, maps);
  const std::vector<fs::path>& mesh_files = truth_files.meshes;
  const std::vector<std::optional<fs::path>>& map_files = truth_files.maps;
  std::vector<fs::path> input_paths = {folder / "dissection.json"};
  for (int i = 0; i < n; ++i) {
    input_paths.push_back(folder / loaded.meshes[i].chart_file);
    input_paths.push_back(mesh_files[i]);
    if (map_files[i]) input_paths.push_back(*map_files[i]);
  }
  if (output) qs::check_not_an_input(*output, input_paths, "-o");
  // Error maps: "<A stem>_to_<B stem>.error.ply" (mesh indices in front when two stems are equal).
  std::vector<std::string> stems(n);
  if (error_map.folder) {
    for (int i = 0; i < n; ++i) stems[i] = mesh_files[i].stem().string();
    bool unique = true;
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j) unique = unique && stems[i] != stems[j];
    if (!unique)
      for (int i = 0; i < n; ++i) stems[i] = std::to_string(i) + "_" + stems[i];
    std::vector<fs::path> taken = input_paths;
    if (output) taken.push_back(*output);
    for (int b = 1; b < n; ++b)
      qs::check_not_an_input(fs::path(*error_map.folder) / (stems[0] + "_to_" + stems[b] + ".error.ply"), taken,
                             "--error-map");
  }
  std::optional<qs::AtomicFile> report_file;
  open_report(output, report_file);
  const qs::correspondence::GroundTruth truth = qs::correspondence::load_ground_truth(truth_files);
  std::vector<std::string> map_used;
  for (int i = 0; i < n; ++i) {
    map_used.push_back(map_files[i] ? map_files[i]->string() : "");
    // A "surface" map's reference mesh (relative to the map file's folder) is an input too.
    const auto& map = truth.mesh(i).map;
    if (map && map->domain == qs::family::MapDomain::Surface) {
      fs::path ref(map->reference);
      if (ref.is_relative()) ref = map_files[i]->parent_path() / ref;
      if (output) qs::check_not_an_input(*output, {ref}, "-o");
      for (int b = 1; b < n && error_map.folder; ++b)
        qs::check_not_an_input(fs::path(*error_map.folder) / (stems[0] + "_to_" + stems[b] + ".error.ply"), {ref},
                               "--error-map");
    }
  }
  qs::correspondence::MeasureOptions mo;
  if (samples > 0) mo.samples = samples;
  mo.seed = seed;
  mo.level = level;
  mo.threads = threads;
  mo.vertex_errors = error_map.folder.has_value() || error_map.worst > 0;
  // The error maps are staged and moved into the folder only when every pair has been measured
  // and the report written.
  std::optional<qs::OutputFolder> map_folder;
  if (error_map.folder) map_folder.emplace(*error_map.folder);
  std::ostringstream text;
  nlohmann::json pairs = nlohmann::json::array();
  text << "qs-metro: correspondence of " << folder_name << " (" << n << " meshes, "
       << loaded.meshes[0].dissection.chart.patches.size() << " patches), " << mo.samples
       << " samples per pair, uniform per unit area on A, mapped "
       << (level == 0 ? std::string("by the charts") : "through B's level-" + std::to_string(level) + " remesh")
       << "; errors in % of B's bounding-box diagonal\n";
  for (int i = 0; i < n; ++i)
    text << "  mesh " << i << ": " << truth.mesh(i).name << " (ground truth: "
         << (map_used[i].empty() ? std::string("its own face list") : map_used[i]) << ")\n";
  const std::vector<qs::correspondence::PairMeasure> measured = qs::correspondence::measure_dissection(truth, loaded, mo);
  for (int b = 1; b < n; ++b) {
    const auto& pm = measured[b - 1];
    char share[64];
    std::snprintf(share, sizeof share, "%.1f%%", 100 * pm.same_patch_share);
    char corners[160];
    std::snprintf(corners, sizeof corners,
                  "B's corner to the exact image of A's corner (same patch and corner): mean %.3f%%, max %.3f%%\n",
                  pm.corner_mean, pm.corner_max);
    text << truth.mesh(0).name << " -> " << truth.mesh(b).name << ":\n"
         << "  dissection: " << stats_text(pm.dissection) << "; same patch: " << share << " of A's area\n"
         << "  patch corners: " << corners << "  " << distortion_text(pm)
         << "  baseline (similarity on " << pm.baseline_landmarks << " landmarks + nearest point): "
         << stats_text(pm.baseline) << "\n";
    if (level > 0)
      text << "  the remesh alone (each exact image through B's remesh at its own (u, v): an exact map's error): "
           << stats_text(pm.remesh) << "\n";
    if (pm.truth_tolerance > 0) {
      char tol[160];
      std::snprintf(tol, sizeof tol, "%.3f%% (mean %.4f%%)", pm.truth_tolerance, pm.truth_tolerance_mean);
      text << "  ground truth: exact at the vertices; between them within the re-tessellation's distance from its "
              "reference, at most " << tol << "\n";
    }
    nlohmann::json map_json;
    if (map_folder) {
      const std::string file = stems[0] + "_to_" + stems[b] + ".error.ply";
      double vmax = 0, vsum = 0;
      for (double e : pm.vertex_error) vmax = std::max(vmax, e), vsum += e;
      const double vmean = pm.vertex_error.empty() ? 0 : vsum / pm.vertex_error.size();
      const double scale = error_map.scale > 0 ? error_map.scale : vmax > 0 ? vmax : 1;
      qs::correspondence::write_error_map(map_folder->staging() / file, truth.mesh(0).mesh, pm, scale);
      const std::string where = (fs::path(*error_map.folder) / file).string();
      char line[400];
      std::snprintf(line, sizeof line,
                    "  error map: %s (A's %zu vertices: mean %.3f%%, max %.3f%%; red at %.3f%%)\n", where.c_str(),
                    pm.vertex_error.size(), vmean, vmax, scale);
      text << line;
      map_json = {{"file", where},
                  {"vertices", pm.vertex_error.size()},
                  {"vertex_mean_percent", vmean},
                  {"vertex_max_percent", vmax},
                  {"red_at_percent", scale}};
    }
    pairs.push_back({{"a", truth.mesh(0).name},
                     {"b", truth.mesh(b).name},
                     {"samples", pm.samples},
                     {"diagonal_of_b", pm.diagonal},
                     {"dissection", stats_json(pm.dissection)},
                     {"same_patch_share", pm.same_patch_share},
                     {"corner_distance_mean_percent", pm.corner_mean},
                     {"corner_distance_max_percent", pm.corner_max},
                     {"distortion", {{"on", pm.distortion_on_b ? "b" : "a"},
                                     {"dissection_mean", pm.distortion},
                                     {"dissection_median", pm.distortion_median},
                                     {"dissection_folded_faces", pm.distortion_folded},
                                     {"truth_mean", pm.truth_distortion},
                                     {"truth_median", pm.truth_distortion_median},
                                     {"truth_folded_faces", pm.truth_distortion_folded}}},
                     {"baseline", stats_json(pm.baseline)},
                     {"baseline_landmarks", pm.baseline_landmarks},
                     {"truth_tolerance_percent", pm.truth_tolerance},
                     {"truth_tolerance_mean_percent", pm.truth_tolerance_mean}});
    if (level > 0) pairs.back()["remesh_alone"] = stats_json(pm.remesh);
    if (map_folder) pairs.back()["error_map"] = map_json;
    if (error_map.worst > 0) {
      // Where the map is worst, and whether the patch layout put the point in another patch.
      const auto& patches = loaded.meshes[0].dissection.chart.patches;
      const auto& patches_b = loaded.meshes[b].dissection.chart.patches;
      const std::vector<int> worst = qs::correspondence::worst_vertices(pm, error_map.worst);
      const qs::TriMesh& ma = truth.mesh(0).mesh;
      text << "  worst " << worst.size() << " of A's vertices (error, baseline's error; A's patch -> the patch of "
              "the exact image on B):\n";
      nlohmann::json list = nlohmann::json::array();
      for (int v : worst) {
        const qs::Vec3& x = ma.positions[v];
        const std::string& pa = patches[pm.vertex_patch[v]].name;
        const std::string& pb = patches_b[pm.vertex_exact_patch[v]].name;
        char line[400];
        std::snprintf(line, sizeof line, "    vertex %d at (%.4g, %.4g, %.4g): %.3f%% (baseline %.3f%%), %s -> %s%s\n", v,
                      x.x(), x.y(), x.z(), pm.vertex_error[v], pm.vertex_baseline_error[v], pa.c_str(), pb.c_str(),
                      pa == pb ? "" : " (another patch)");
        text << line;
        list.push_back({{"vertex", v},
                        {"position", {x.x(), x.y(), x.z()}},
                        {"error_percent", pm.vertex_error[v]},
                        {"baseline_error_percent", pm.vertex_baseline_error[v]},
                        {"patch", pa},
                        {"exact_patch", pb}});
      }
      pairs.back()["worst_vertices"] = list;
    }
  }
  nlohmann::json doc = {{"dissection", folder_name},
                        {"meshes", n},
                        {"patches", loaded.meshes[0].dissection.chart.patches.size()},
                        {"seed", seed},
                        {"level", level},
                        {"pairs", pairs}};
  // Names that are not UTF-8 (the folder, a mesh, a map file) become U+FFFD in JSON.
  const std::string report = as_json ? qs::json_strict::dump(doc, 2) + "\n" : text.str();
  write_report(report_file, output, report);
  // Everything is measured and written: now the error maps, then the report, move into place.
  if (map_folder) map_folder->commit();
  if (report_file) report_file->commit();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Metro-style two-sided distance between two meshes: mean, RMS and max (Hausdorff) of\n"
               "the distances from points sampled on each to the surface of the other, absolute and\n"
               "as % of the bounding-box diagonal of A.\n"
               "With --correspondence DIR: how far a dissection's map A -> B is from the exact one.\n"
               "Exit codes: 0 measured, 1 usage, 2 a mesh that cannot be measured (or no common ground\n"
               "truth), 3 a file unreadable or unwritable.",
               "qs-metro"};
  std::string file_a, file_b;
  long samples = 0;
  std::uint64_t seed = 1;
  bool as_json = false, no_vertices = false;
  std::optional<std::string> output;
  std::optional<std::string> correspondence;
  std::vector<std::string> maps;
  int level = 0, threads = 0;
  ErrorMapOptions error_map;
  app.add_option("A", file_a, "First mesh (.obj .off .ply .stl); its bounding-box diagonal is the "
                              "reference for the percentages");
  app.add_option("B", file_b, "Second mesh");
  app.add_option("--correspondence", correspondence,
                 "Measure the correspondence of a qs-dissect folder against ground truth instead (no A, B): "
                 "the first mesh against every other (docs/correspondence.md)");
  app.add_option("--level", level, "With --correspondence: map through B's uniform level-N common remesh "
                                  "(1..12) instead of the charts' continuous map (0, the default)")
      ->check(CLI::Range(0, 12));
  app.add_option("--map", maps, "With --correspondence: a map file per mesh in the dissection's order, '-' for "
                                "none (default: <stem>.map.json beside each mesh when present)");
  app.add_option("--error-map", error_map.folder,
                 "With --correspondence: also write, per pair, A's mesh with each vertex's error (and the "
                 "baseline's) as a coloured PLY into this folder: <A>_to_<B>.error.ply");
  auto* error_scale = app.add_option("--error-scale", error_map.scale,
                 "With --error-map: the error (% of B's diagonal) drawn red (default: each pair's largest vertex "
                 "error)");
  app.add_option("--worst", error_map.worst,
                 "With --correspondence: also list, per pair, A's N vertices with the largest error (position, "
                 "error, the baseline's error, A's patch and the patch of the exact image on B), 0..1000")
      ->check(CLI::Range(0, 1000));
  app.add_option("--samples", samples,
                 "Surface samples per direction (default: max(100000, 2 x the larger face count)); with "
                 "--correspondence: points on A per pair (default 100000)")
      ->check(CLI::Range(1L, std::numeric_limits<long>::max()));
  app.add_option("--seed", seed, "Seed of the sampling, 0..18446744073709551615 (the same seed gives the same numbers)")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            // CLI11 reads "-1" into an unsigned as 2^64 - 1: only plain digits in range are seeds.
            std::uint64_t value = 0;
            const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
            if (text.empty() || ec != std::errc() || end != text.data() + text.size())
              return text + " is not a whole number in 0..18446744073709551615";
            return {};
          },
          "UINT64"));
  app.add_flag("--no-vertices", no_vertices, "Do not measure at the vertices (surface samples only)");
  app.add_flag("--json", as_json, "Print a JSON object instead of text");
  app.add_option("-o,--output", output, "Write the report to this file instead of stdout");
  app.add_option("--threads", threads, "Threads (0: all hardware threads; the output does not depend on it)")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
  long max_samples = 100000000;
  app.add_option("--max-samples", max_samples,
                 "Refuse a --samples count above this up front (the run time grows linearly with it)")
      ->capture_default_str()
      ->check(CLI::Range(1L, std::numeric_limits<long>::max()));

  return qs::tools::run_tool(app, argc, argv, [&] {
    if (error_scale->count() && !(std::isfinite(error_map.scale) && error_map.scale > 0))
      throw qs::UsageError("--error-scale " + error_scale->as<std::string>() +
                           " is not a finite positive number (the error in % of B's diagonal drawn red)");
    if (samples > max_samples)
      throw qs::UsageError("--samples " + std::to_string(samples) + " is more than --max-samples " +
                           std::to_string(max_samples) + " (the time grows linearly with the count); raise "
                           "--max-samples to allow it");
    if (correspondence) {
      if (!file_a.empty()) throw qs::UsageError("--correspondence takes a dissection folder, not meshes A and B");
      if (no_vertices) throw qs::UsageError("--no-vertices does not apply to --correspondence");
      if (error_scale->count() && !error_map.folder) throw qs::UsageError("--error-scale needs --error-map");
      return run_correspondence(*correspondence, maps, samples, seed, level, threads, as_json, output, error_map);
    }
    if (error_map.folder || error_scale->count() || error_map.worst > 0)
      throw qs::UsageError("--error-map, --error-scale and --worst need --correspondence");
    if (!maps.empty()) throw qs::UsageError("--map needs --correspondence");
    if (level != 0) throw qs::UsageError("--level needs --correspondence");
    if (file_a.empty() || file_b.empty()) throw qs::UsageError("two meshes A and B are needed (or --correspondence DIR)");
    if (output) qs::check_not_an_input(*output, {file_a, file_b}, "-o");
    std::optional<qs::AtomicFile> report_file;
  open_report(output, report_file);
    const Input a = load(file_a, "A");
    const Input b = load(file_b, "B");
    qs::metro::MetroOptions opt;
    opt.face_samples = samples;
    opt.seed = seed;
    opt.sample_vertices = !no_vertices;
    opt.threads = threads;
    qs::metro::MetroResult r;
    try {
      r = qs::metro::metro(a.mesh, b.mesh, opt);
    } catch (const qs::InvalidInput& e) {  // the library names the meshes "A" and "B"
      throw qs::InvalidInput(std::string(e.what()) + " (A = " + a.file + ", B = " + b.file + ")");
    }
    const std::string report = as_json ? qs::json_strict::dump(json_report(a, b, r, seed), 2) + "\n" : text_report(a, b, r);
    write_report(report_file, output, report);
    if (report_file) report_file->commit();
    return 0;
  });
}
