// qs-dissect: quinary-subdivision dissection of a mesh into quad patches, each parameterized onto
// the unit square. Writes OUTDIR/dissection.json and OUTDIR/<stem>.chart.ply.
//
// Exit codes: 0 done (patches left over tau are listed with their reasons), 1 usage, 2 invalid
// mesh or landmarks, 3 i/o, 4 solver failure, 70 internal error.

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "mesh_input.h"
#include "qs/core/atomic_file.h"
#include "qs/dissect/chart_io.h"
#include "qs/dissect/dissection.h"
#include "qs/dissect/dissection_json.h"
#include "tool_main.h"

namespace fs = std::filesystem;

namespace {

std::array<int, 4> seeds_from_landmarks(const qs::landmarks::Landmarks& lm, const qs::TriMesh& mesh,
                                        std::ostream& notes) {
  std::array<int, 4> seeds{};
  for (int i = 0; i < 4; ++i) {
    const auto& l = lm.seeds[i];
    if (l.vertex >= 0) {
      seeds[i] = l.vertex;
      continue;
    }
    // Seeds must be vertices: the nearest corner of the face the point lies on.
    const qs::Tri& t = mesh.faces[l.where.face];
    int best = 0;
    for (int k = 1; k < 3; ++k)
      if ((mesh.positions[t[k]] - l.position).norm() < (mesh.positions[t[best]] - l.position).norm()) best = k;
    seeds[i] = t[best];
    notes << "  note: " << l.name << " moved to the nearest vertex " << seeds[i] << " ("
          << (mesh.positions[t[best]] - l.position).norm() << " away)\n";
  }
  return seeds;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Dissect a closed genus-0 mesh into quad patches by quinary subdivision.\n"
               "Exit codes: 0 ok, 1 usage, 2 invalid input, 3 i/o, 4 solver, 70 internal.",
               "qs-dissect"};
  std::vector<std::string> meshes;
  std::string landmark_file, outdir, report_file;
  bool quiet = false;
  qs::dissect::DissectOptions opt;
  app.add_option("meshes", meshes, "The mesh (.obj .off .ply .stl)")->required();
  app.add_option("--landmarks", landmark_file,
                 "Landmarks (.json or MeshLab .pp) with 4 seeds; default <stem>.landmarks.json or <stem>.pp "
                 "beside the mesh, else seeds are chosen automatically");
  app.add_option("--tau", opt.tau, "Largest accepted patch L2 stretch (1 = isometric)")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1e6));
  app.add_option("--max-depth", opt.max_depth, "Deepest quinary split")->capture_default_str()->check(CLI::Range(0, 12));
  app.add_option("--min-faces", opt.min_faces_to_split, "Smallest patch (in faces) that may be split")
      ->capture_default_str()
      ->check(CLI::Range(10, 1 << 30));
  app.add_option("-o,--output", outdir, "Output folder (default: <stem>.dissection)");
  app.add_option("--report", report_file, "Also write the text report (with timings) to this file");
  app.add_flag("-q,--quiet", quiet, "Print nothing but errors");

  return qs::tools::run_tool(app, argc, argv, [&] {
    if (meshes.size() != 1)
      throw qs::UsageError("dissecting several meshes together (the union quinary tree) is not available yet; "
                           "give one mesh");
    const std::string file = meshes.front();
    const std::string stem = fs::path(file).stem().string();
    if (outdir.empty()) outdir = stem + ".dissection";
    const auto t0 = std::chrono::steady_clock::now();
    std::ostringstream text;
    const qs::tools::MeshInput in =
        qs::tools::load_mesh_input(file, landmark_file.empty() ? std::nullopt : std::optional(landmark_file));

    std::optional<std::array<int, 4>> seeds;
    std::string seed_source = "automatic";
    if (in.landmarks && in.landmarks->seeds.size() == 4) {
      seeds = seeds_from_landmarks(*in.landmarks, in.valid.mesh, text);
      seed_source = in.landmark_file;
    }
    qs::Context ctx;
    int last_pct = -1;
    if (!quiet)
      ctx.progress = [&](const std::string& stage, double f) {
        const int pct = static_cast<int>(f * 100);
        if (pct / 25 != last_pct / 25 || pct == 100) {
          std::cerr << "qs-dissect: " << stage << " " << pct << "%\n";
          last_pct = pct;
        }
      };
    const auto t1 = std::chrono::steady_clock::now();
    qs::dissect::DissectedMesh dm;
    dm.dissection = qs::dissect::dissect(in.valid.mesh, seeds, opt, ctx);
    const auto t2 = std::chrono::steady_clock::now();
    dm.file = file;
    dm.chart_file = stem + ".chart.ply";
    dm.seed_source = seed_source;
    dm.input_vertices = in.valid.report.vertices;
    dm.input_faces = in.valid.report.faces;
    dm.seconds = std::chrono::duration<double>(t2 - t1).count();
    const auto& d = dm.dissection;
    if (!d.base.closed_conforming || d.base.euler_characteristic != 2)
      throw qs::InternalError("the base domain is not a closed conforming quad mesh of Euler characteristic 2 (" +
                              std::to_string(d.base.euler_characteristic) + ")");

    fs::create_directories(outdir);
    qs::dissect::write_chart_ply(fs::path(outdir) / dm.chart_file, d.chart);
    qs::write_file_atomically(fs::path(outdir) / "dissection.json",
                              qs::dissect::dissection_to_json({dm}, opt, false));
    const auto t3 = std::chrono::steady_clock::now();

    text << file << ": " << d.chart.patches.size() << " patches (base domain V=" << d.base.vertices.size()
         << " E=" << d.base.edges << " F=" << d.base.quads.size() << "), max stretch " << std::setprecision(4)
         << d.max_stretch << " (tau " << opt.tau << "), seeds " << seed_source << " [" << d.seeds[0] << " "
         << d.seeds[1] << " " << d.seeds[2] << " " << d.seeds[3] << "]\n";
    int flipped = 0;
    for (const auto& p : d.chart.patches) {
      flipped += p.flipped_faces + p.zero_area_faces;
      if (p.stop != qs::dissect::StopReason::None)
        text << "  patch " << p.name << ": stretch " << p.stretch << " over tau, left as is: "
             << qs::dissect::stop_reason_name(p.stop) << (p.stop_detail.empty() ? "" : " (" + p.stop_detail + ")")
             << ", " << p.faces << " faces\n";
    }
    text << "  bijective: " << (flipped == 0 ? "yes" : "NO") << " (" << flipped << " flipped or zero-area uv faces)\n";
    text << "  wrote " << (fs::path(outdir) / "dissection.json").string() << " and "
         << (fs::path(outdir) / dm.chart_file).string() << "\n";
    std::ostringstream times;
    times << std::fixed << std::setprecision(3) << "  time: read+validate "
          << std::chrono::duration<double>(t1 - t0).count() << " s, dissect " << dm.seconds << " s, write "
          << std::chrono::duration<double>(t3 - t2).count() << " s\n";
    if (!quiet) std::cout << text.str() << times.str();
    if (flipped > 0) {
      if (!report_file.empty()) qs::write_file_atomically(report_file, text.str() + times.str());
      throw qs::SolverError(std::to_string(flipped) +
                            " uv faces are flipped or of zero area in patches that could not be split further "
                            "(see the report above); try a larger --max-depth or a smaller --min-faces");
    }
    if (!report_file.empty()) {
      std::ostringstream full;
      full << text.str() << times.str();
      for (const auto& p : d.chart.patches)
        full << "  " << p.name << ": " << p.faces << " faces, stretch " << p.stretch << ", flipped "
             << p.flipped_faces << "\n";
      qs::write_file_atomically(report_file, full.str());
    }
    return 0;
  });
}
