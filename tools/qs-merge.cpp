// qs-merge: the exact-endpoint merge of two dissected meshes (SMCC, Lee & Huang 3.5-3.7).
// Reads a qs-dissect output folder of two meshes (or of more, with --pair A,B); writes OUTDIR/<stem>.obj|.ply per mesh (one face
// list, positions on A and on B) and OUTDIR/remesh.json with mode "merge", which qs-morph reads
// like a remesh.
//
// Exit codes: 0 done, 1 usage (also an output that would replace an input: a mesh of the
// dissection, its charts or dissection.json), 2 invalid input (not a dissection of two meshes, a
// flipped or degenerate uv triangle), 3 i/o, 4 solver (side points that cannot be ordered
// consistently), 70 internal error. Everything is written into a staging folder beside OUTDIR
// and moved into place only when the whole run succeeded (qs::OutputFolder).

#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/core/json_strict.h"
#include "qs/core/output_folder.h"
#include "qs/dissect/dissection_json.h"
#include "qs/dissect/chart_io.h"
#include "qs/io/write_mesh.h"
#include "qs/merge/merge.h"
#include "dissection_names.h"
#include "tool_main.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Merges the two meshes of a qs-dissect output into one mesh with one face list whose positions are "
               "exactly mesh A (t = 0) and exactly mesh B (t = 1): an exact-endpoint morph for qs-morph.\n"
               "Exit codes: 0 ok, 1 usage, 2 invalid input, 3 i/o, 4 solver, 70 internal.",
               "qs-merge"};
  std::string folder, outdir, format = "obj", pair;
  int threads = 0;
  double sliver = 1.0;
  bool quiet = false, fan = false;
  app.add_option("dissection", folder, "A qs-dissect output folder of two meshes (of more with --pair)")->required();
  app.add_option("--pair", pair, "For a dissection of more than two meshes: the two to merge, by chart stem, "
                                 "A,B (A is the shape at t = 0)");
  app.add_option("-o,--output", outdir, "Output folder (default: <dissection>/merge)");
  app.add_option("--format", format, "Output format: obj (text) or ply (ASCII)")
      ->capture_default_str()
      ->check(CLI::IsMember({"obj", "ply"}));
  app.add_option("--sliver-degrees", sliver, "Count merged faces with a smaller corner angle as slivers")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 60.0));
  app.add_flag("--fan", fan, "Cut every overlay polygon by a fan from its first vertex (default: the cut that "
                             "maximizes the smallest uv angle)");
  app.add_option("--threads", threads, "Threads (0: all hardware threads; the output does not depend on it)")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
  app.add_flag("-q,--quiet", quiet, "Print nothing but errors");

  return qs::tools::run_tool(app, argc, argv, [&] {
    const auto t0 = Clock::now();
    // CLI11's range check lets NaN through (every comparison with it is false).
    if (!(sliver >= 0 && sliver <= 60))
      throw qs::UsageError("--sliver-degrees " + std::to_string(sliver) + " is not a number of degrees in 0..60");
    if (!fs::is_directory(folder)) throw qs::IoError(folder + ": no such folder (expected a qs-dissect output folder)");
    const qs::dissect::LoadedDissection in = qs::tools::read_dissection_folder(folder);
    std::vector<std::string> stems;
    for (const auto& dm : in.meshes) stems.push_back(qs::dissect::chart_stem(dm.chart_file));
    auto known = [&] {
      std::string k;
      for (const auto& s : stems) k += (k.empty() ? "" : ", ") + s;
      return k;
    };
    int ia = 0, ib = 1;
    if (!pair.empty()) {
      const size_t comma = pair.find(',');
      if (comma == std::string::npos || pair.find(',', comma + 1) != std::string::npos)
        throw qs::UsageError("--pair takes two chart stems separated by a comma, A,B (not '" + pair + "')");
      auto index = [&](const std::string& s) {
        for (size_t i = 0; i < stems.size(); ++i)
          if (stems[i] == s) return static_cast<int>(i);
        throw qs::InvalidInput(folder + ": no mesh '" + s + "' in the dissection (its meshes: " + known() + ")");
      };
      ia = index(pair.substr(0, comma));
      ib = index(pair.substr(comma + 1));
      if (ia == ib) throw qs::UsageError("--pair names '" + stems[ia] + "' twice; merge two different meshes");
    } else if (in.meshes.size() != 2) {
      throw qs::InvalidInput(folder + ": a dissection of " + std::to_string(in.meshes.size()) +
                             " meshes (" + known() + "); qs-merge merges exactly two: name them with --pair A,B");
    }
    const auto& A = in.meshes[ia];
    const auto& B = in.meshes[ib];
    // The outputs may not replace an input: dissection.json, a chart, or a dissected mesh (where
    // it is found: as written, or in or beside the dissection folder).
    if (outdir.empty()) outdir = (fs::path(folder) / "merge").string();
    const std::string stem_a = stems[ia], stem_b = stems[ib];
    const std::string out_a = stem_a + "." + format, out_b = stem_b + "." + format;
    {
      std::vector<fs::path> inputs = {fs::path(folder) / "dissection.json"};
      for (const auto& dm : in.meshes) {
        inputs.push_back(fs::path(folder) / dm.chart_file);
        for (const fs::path& p : qs::dissect::dissected_mesh_candidates(dm.file, folder)) inputs.push_back(p);
      }
      for (const std::string& name : {out_a, out_b, std::string("remesh.json")})
        qs::check_not_an_input(fs::path(outdir) / name, inputs, "-o");
    }
    // Staged: nothing in OUTDIR changes unless everything was written. Created before the merge
    // so that an output folder that cannot be written is reported before any work.
    qs::OutputFolder out_folder(outdir);
    const auto t1 = Clock::now();
    qs::merge::MergeOptions options;
    options.threads = threads;
    options.sliver_degrees = sliver;
    options.improve_slivers = !fan;
    qs::merge::Merged m;
    try {
      m = qs::merge::merge_charts(A.dissection.chart, B.dissection.chart, options);
    } catch (const qs::InvalidInput& e) {
      std::string what = e.what();
      for (auto [tag, dm] : {std::pair{"mesh A", &A}, std::pair{"mesh B", &B}})
        if (what.rfind(tag, 0) == 0) what = (fs::path(folder) / dm->chart_file).string() + what.substr(6);
      throw qs::InvalidInput(what);
    }
    const auto t2 = Clock::now();

    qs::io::write_mesh(out_folder.staging() / out_a, m.mesh_a());
    qs::io::write_mesh(out_folder.staging() / out_b, m.mesh_b());

    const auto& st = m.stats;
    const int inputs = st.input_faces_a + st.input_faces_b;
    const double ratio = static_cast<double>(m.faces.size()) / inputs;
    nlohmann::ordered_json meshes = nlohmann::ordered_json::array();
    meshes.push_back({{"file", A.file}, {"chart", A.chart_file}, {"output", out_a}, {"t", 0}});
    meshes.push_back({{"file", B.file}, {"chart", B.chart_file}, {"output", out_b}, {"t", 1}});
    nlohmann::ordered_json patch = nlohmann::ordered_json::array(), uv = nlohmann::ordered_json::array();
    for (size_t v = 0; v < m.vertex_patch.size(); ++v) {
      patch.push_back(m.vertex_patch[v]);
      uv.push_back(m.vertex_uv[v].x());
      uv.push_back(m.vertex_uv[v].y());
    }
    const std::string dissection_path =
        fs::relative(fs::absolute(folder), fs::absolute(outdir)).lexically_normal().generic_string();
    const auto& base = A.dissection.base;
    nlohmann::ordered_json doc = {{"format", "qs-remesh"},
                                  {"version", 1},
                                  {"dissection", fs::path(folder).filename().string()},
                                  {"dissection_path", dissection_path},
                                  {"mode", "merge"},
                                  {"level", 0},
                                  {"quads", false},
                                  {"vertices", m.positions_a.size()},
                                  {"faces", m.faces.size()},
                                  {"base_vertices", base.vertices.size()},
                                  {"base_edges", base.edges},
                                  {"patches", st.patches}};
    doc["merge"] = {{"input_faces", {st.input_faces_a, st.input_faces_b}},
                    {"faces_over_inputs", ratio},
                    {"vertices_from_a", st.vertices_from_a},
                    {"vertices_from_b", st.vertices_from_b},
                    {"coincident_vertices", st.coincident_vertices},
                    {"crossings", st.crossings},
                    {"a_vertices_on_b_edges", st.a_on_b_edge},
                    {"b_vertices_on_a_edges", st.b_on_a_edge},
                    {"overlay_polygons", st.overlay_polygons},
                    {"side_points_moved", st.side_points_moved},
                    {"triangulation", fan ? "fan" : "max_min_uv_angle"},
                    {"sliver_degrees", sliver},
                    {"slivers", {{"uv", st.slivers_uv}, {"a", st.slivers_a}, {"b", st.slivers_b}}},
                    {"input_slivers", {{"a", st.input_slivers_a}, {"b", st.input_slivers_b}}},
                    {"min_angle_degrees", {{"uv", st.min_angle_uv}, {"a", st.min_angle_a}, {"b", st.min_angle_b}}},
                    {"thin_faces", {{"a", st.thin_faces_a}, {"b", st.thin_faces_b}}},
                    {"normal_disagreements", {{"a", st.normal_disagreements_a}, {"b", st.normal_disagreements_b}}}};
    doc["meshes"] = meshes;
    doc["vertex_patch"] = patch;
    doc["vertex_uv"] = uv;
    qs::write_file_atomically(out_folder.staging() / "remesh.json",
                              qs::json_strict::dump(doc, 1) + "\n");
    out_folder.commit();
    const auto t3 = Clock::now();
    if (!quiet) {
      std::cout << std::setprecision(4) << "merge of " << stem_a << " (" << st.input_faces_a << " chart faces) and "
                << stem_b << " (" << st.input_faces_b << "): " << m.positions_a.size() << " vertices, " << m.faces.size()
                << " faces (" << ratio << " x the inputs), " << st.patches << " patches\n"
                << "  vertices: " << st.vertices_from_a << " from A, " << st.vertices_from_b << " from B ("
                << st.coincident_vertices << " both), " << st.crossings << " edge crossings, " << st.a_on_b_edge
                << " A on a B edge, " << st.b_on_a_edge << " B on an A edge; " << st.side_points_moved
                << " B side points re-placed in their second patch\n"
                << "  slivers (< " << sliver << " deg): " << st.slivers_uv << " in uv, " << st.slivers_a << " at t=0, "
                << st.slivers_b << " at t=1 (inputs: " << st.input_slivers_a << ", " << st.input_slivers_b
                << "); too thin for a normal: " << st.thin_faces_a << ", " << st.thin_faces_b
                << "; normals off their parent's: " << st.normal_disagreements_a << ", " << st.normal_disagreements_b
                << "\n"
                << "  wrote " << out_a << ", " << out_b << " and remesh.json to " << outdir << "\n"
                << std::fixed << std::setprecision(3) << "  time: load " << seconds(t0, t1) << " s, merge "
                << seconds(t1, t2) << " s, write " << seconds(t2, t3) << " s\n";
    }
    return 0;
  });
}
