// qs-dissect: quinary-subdivision dissection of meshes into quad patches, each parameterized onto
// the unit square (qs::pipeline::dissect). Writes OUTDIR/dissection.json and OUTDIR/<stem>.chart.ply.
//
// Exit codes: 0 done (patches left over tau are listed with their reasons), 1 usage, 2 invalid
// mesh or landmarks, 3 i/o, 4 solver failure (the folder is still written), 70 internal error.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "qs/core/atomic_file.h"
#include "qs/core/json_strict.h"
#include "qs/core/output_folder.h"
#include "qs/pipeline/pipeline.h"
#include "tool_main.h"

namespace fs = std::filesystem;

namespace {

// The summary of --json: the output folder, per mesh its patches and quality, the set's figures.
std::string json_summary(const qs::pipeline::DissectResult& r, const std::string& outdir, double read_seconds,
                         double write_seconds) {
  nlohmann::ordered_json meshes = nlohmann::ordered_json::array();
  for (const auto& m : r.meshes) {
    int folded = 0, over_tau = 0;
    for (const auto& p : m.dissection.chart.patches) {
      folded += p.flipped_faces + p.zero_area_faces;
      over_tau += p.stop != qs::dissect::StopReason::None;
    }
    meshes.push_back({{"file", m.file},
                      {"chart", m.chart_file},
                      {"seed_source", m.seed_source},
                      {"patches", m.dissection.chart.patches.size()},
                      {"max_stretch", m.dissection.max_stretch},
                      {"patches_over_tau", over_tau},
                      {"folded_uv_faces", folded}});
  }
  nlohmann::ordered_json doc = {{"output", outdir},
                                {"dissection", (fs::path(outdir) / "dissection.json").generic_string()},
                                {"maps", r.maps},
                                {"bijective", r.folded_faces == 0},
                                {"meshes", meshes},
                                {"seconds",
                                 {{"read", read_seconds},
                                  {"dissect", r.dissect_seconds},
                                  {"refine_maps", r.refine_seconds},
                                  {"write", write_seconds}}}};
  return qs::json_strict::dump(doc, 2) + "\n";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Dissect closed genus-0 meshes into quad patches by quinary subdivision. Several meshes are\n"
               "dissected together: one union quinary tree, the same patches on every mesh, features aligned.\n"
               "Exit codes: 0 ok, 1 usage, 2 invalid input, 3 i/o, 4 solver, 70 internal.",
               "qs-dissect"};
  qs::pipeline::DissectConfig config;
  std::vector<std::string> meshes, landmark_files;
  std::string outdir, report_file, config_file, same_pose = "auto";
  bool quiet = false, json = false, no_refine = false;
  int threads = 0;
  app.set_help_all_flag("--help-all", "Print this help and every option of --config");
  app.add_option("meshes", meshes, "The meshes (.obj .off .ply .stl); seeds correspond by order, features by name")
      ->required();
  app.add_option("--landmarks", landmark_files,
                 "Landmark files (.json or MeshLab .pp), one per mesh in the same order; default "
                 "<stem>.landmarks.json or <stem>.pp beside each mesh, else seeds are chosen automatically")
      ->expected(1, -1);
  app.add_option("-o,--output", outdir, "Output folder (default: <stem>.dissection, or <stem1>_<stem2>....dissection)");
  app.add_option("--config", config_file,
                 "Options as JSON: a dissection.json (its \"options\", to replay a run) or such an object; "
                 "the options below override it")
      ->check(CLI::ExistingFile);
  auto* tau = app.add_option("--tau", config.dissect.tau, "Largest accepted patch L2 stretch (1 = isometric)")
                  ->capture_default_str()
                  ->check(CLI::Range(1.0, 1e6));
  auto* depth = app.add_option("--max-depth", config.dissect.max_depth, "Deepest quinary split")
                    ->capture_default_str()
                    ->check(CLI::Range(0, 12));
  auto* faces = app.add_option("--min-faces", config.dissect.min_faces_to_split, "Smallest patch (in faces) that may be split")
                    ->capture_default_str()
                    ->check(CLI::Range(10, 1 << 30));
  auto* area = app.add_option("--max-area", config.dissect.max_patch_area,
                              "Also split every patch larger than this fraction of its mesh's area (0: off)")
                   ->capture_default_str()
                   ->check(CLI::Range(0.0, 1.0));
  app.add_option("--same-pose", same_pose,
                 "Meshes in one pose (registered scans, re-tessellations of one surface): yes, no, or auto "
                 "(yes when the surfaces lie within 1% of the diagonal of each other after the landmarks' "
                 "similarity, 99% of them within 2%, or, for one surface in other poses, after registering the "
                 "first mesh onto the others)")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "yes", "no"}));
  app.add_flag("--no-refine-maps", no_refine,
               "Keep the dissection's own maps (by default, for two or more meshes, each mesh's chart is moved so "
               "that its map to the first mesh has low distortion)");
  app.add_option("--report", report_file, "Also write the text report (with timings and every patch) to this file");
  app.add_flag("--json", json, "Print a JSON summary on stdout instead of the text report");
  app.add_flag("-q,--quiet", quiet, "Print nothing but errors");
  app.add_option("--threads", threads, "Threads (0: all hardware threads; the output does not depend on it)")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
  app.footer([&]() -> std::string {
    // --help-all: every option of --config with its default.
    if (std::none_of(argv + 1, argv + argc, [](const char* a) { return std::string(a) == "--help-all"; })) return "";
    return "\nOptions of --config (JSON keys, defaults, what they do):\n" + qs::pipeline::describe_config();
  });

  return qs::tools::run_tool(app, argc, argv, [&] {
    if (!landmark_files.empty() && landmark_files.size() != meshes.size())
      throw qs::UsageError("--landmarks got " + std::to_string(landmark_files.size()) + " files for " +
                           std::to_string(meshes.size()) + " meshes; give one per mesh, in the same order");
    if (std::isnan(config.dissect.tau) || std::isnan(config.dissect.max_patch_area))
      throw qs::UsageError(std::string(std::isnan(config.dissect.tau) ? "--tau" : "--max-area") +
                           " must be a number, not nan");
    // The configuration file first, then the options given on the command line.
    if (!config_file.empty()) {
      const qs::pipeline::DissectConfig given = config;
      config = qs::pipeline::read_config(config_file);
      if (tau->count()) config.dissect.tau = given.dissect.tau;
      if (depth->count()) config.dissect.max_depth = given.dissect.max_depth;
      if (faces->count()) config.dissect.min_faces_to_split = given.dissect.min_faces_to_split;
      if (area->count()) config.dissect.max_patch_area = given.dissect.max_patch_area;
    }
    if (same_pose == "yes") config.dissect.same_pose = true;
    if (same_pose == "no") {
      config.dissect.same_pose = false;
      config.dissect.same_pose_detect = 0;
    }
    if (same_pose == "auto" && app.count("--same-pose") > 0) {
      config.dissect.same_pose = false;
      config.dissect.same_pose_detect = qs::dissect::kSamePoseDetect;
    }
    if (no_refine) config.refine_maps = false;
    qs::pipeline::validate_config(config);
    if (outdir.empty()) outdir = qs::pipeline::default_dissection_folder(meshes);
    // No output may replace an input: the report file, or the folder's files.
    std::vector<fs::path> input_paths(meshes.begin(), meshes.end());
    input_paths.insert(input_paths.end(), landmark_files.begin(), landmark_files.end());
    if (!config_file.empty()) input_paths.emplace_back(config_file);
    if (!report_file.empty()) qs::check_not_an_input(report_file, input_paths, "--report");
    // Checked (and staged) before the work, so that a bad -o fails at once; written on success only.
    qs::OutputFolder folder(outdir);

    const auto t0 = std::chrono::steady_clock::now();
    std::vector<qs::pipeline::Input> inputs;
    for (size_t i = 0; i < meshes.size(); ++i)
      inputs.push_back(qs::pipeline::load_input(
          meshes[i], landmark_files.empty() ? std::nullopt : std::optional(landmark_files[i])));
    const auto t1 = std::chrono::steady_clock::now();

    if (!quiet)
      for (const std::string& w : qs::pipeline::check_inputs(inputs)) std::cerr << "qs-dissect: warning: " << w << "\n";
    qs::Context ctx;
    ctx.threads = threads;
    // Wall time per stage, in the order the stages first ran (a stage that runs again, in a second
    // dissection, adds to its first entry); the time before the first stage is "setup" (the
    // landmarks and the pose test).
    std::vector<std::pair<std::string, double>> stage_seconds{{"setup", 0.0}};
    size_t stage_at = 0;
    auto stage_start = t1;
    auto close_stage = [&] {
      const auto now = std::chrono::steady_clock::now();
      stage_seconds[stage_at].second += std::chrono::duration<double>(now - stage_start).count();
      stage_start = now;
    };
    auto stage_to = [&](const std::string& stage) {
      close_stage();
      stage_at = std::find_if(stage_seconds.begin(), stage_seconds.end(),
                              [&](const auto& e) { return e.first == stage; }) - stage_seconds.begin();
      if (stage_at == stage_seconds.size()) stage_seconds.emplace_back(stage, 0.0);
    };
    // Each stage once at its start, then at every quarter it passes, never backwards or twice.
    std::string last_stage;
    int last_quarter = -1;
    ctx.progress = [&](const std::string& stage, double f) {
      if (stage != stage_seconds[stage_at].first) stage_to(stage);
      if (quiet || json) return;
      const int pct = static_cast<int>(std::floor(std::clamp(f, 0.0, 1.0) * 100));
      const int quarter = pct / 25;
      if (stage == last_stage && quarter <= last_quarter) return;
      if (stage != last_stage) last_quarter = -1;
      std::cerr << "qs-dissect: " << stage << " " << pct << "%\n";
      last_stage = stage;
      last_quarter = quarter;
    };
    const qs::pipeline::DissectResult result = qs::pipeline::dissect(inputs, config, ctx);
    close_stage();
    const auto t2 = std::chrono::steady_clock::now();
    qs::pipeline::write_dissection(result, folder);
    const auto t3 = std::chrono::steady_clock::now();

    std::ostringstream text;
    text << result.report << "  wrote " << (fs::path(outdir) / "dissection.json").string() << " and "
         << result.meshes.size() << " chart file" << (result.meshes.size() > 1 ? "s" : "") << "\n";
    const double read_s = std::chrono::duration<double>(t1 - t0).count();
    const double write_s = std::chrono::duration<double>(t3 - t2).count();
    std::ostringstream times;
    times << std::fixed << std::setprecision(3) << "  time: read+validate " << read_s << " s, dissect "
          << result.dissect_seconds << " s, ";
    if (config.refine_maps && result.meshes.size() > 1) times << "refine maps " << result.refine_seconds << " s, ";
    times << "write " << write_s << " s\n  stages:";
    for (size_t k = 0; k < stage_seconds.size(); ++k)
      times << (k ? ", " : " ") << stage_seconds[k].first << " " << std::setprecision(2) << stage_seconds[k].second << " s";
    times << "\n";
    if (json) std::cout << json_summary(result, outdir, read_s, write_s);
    else if (!quiet) std::cout << text.str() << times.str();
    if (!report_file.empty())
      qs::write_file_atomically(report_file, text.str() + times.str() + result.patch_report);
    // A result with folded leaves is written (the report refers to it), then exit 4.
    folder.commit();
    qs::pipeline::check_bijective(result);
    return 0;
  });
}
