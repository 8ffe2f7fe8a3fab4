// qs-inspect: read and validate meshes (and their landmarks), print what qs thinks of them.
//
// Exit codes: 0 every mesh accepted; 1 usage; 2 some mesh rejected or unparsable (or its
// landmarks invalid); 3 some file could not be read. With several problems the highest wins.

#include <algorithm>
#include <iostream>
#include <optional>
#include <sstream>

#include "json_reports.h"
#include "qs/core/error.h"
#include "qs/io/read_mesh.h"
#include "qs/landmarks/landmarks.h"
#include "qs/mesh/validate.h"
#include "tool_main.h"

namespace {

struct Outcome {
  nlohmann::json json;
  std::string text;
  int exit = 0;
};

Outcome inspect(const std::string& file, const std::optional<std::string>& landmark_file) {
  Outcome out;
  out.json["file"] = file;
  std::ostringstream text;
  try {
    const qs::io::ReadResult read = qs::io::read_mesh(file);
    out.json["read"] = qs::tools::to_json(read.report);
    const qs::mesh::ValidationResult valid = qs::mesh::validate(read.mesh);
    out.json["validation"] = qs::tools::to_json(valid.report);
    text << qs::mesh::format_report(file, valid.report);
    if (read.report.polygons_triangulated > 0)
      text << "  note: " << read.report.polygons_triangulated << " polygons were triangulated\n";
    for (const auto& n : read.report.notes) text << "  note: " << n << "\n";
    if (!valid.report.accepted) out.exit = qs::exit_code(qs::ErrorCode::InvalidInput);

    std::optional<std::filesystem::path> lm_path;
    if (landmark_file) lm_path = *landmark_file;
    else lm_path = qs::landmarks::find_landmarks_beside(file);
    if (lm_path && valid.report.accepted) {
      try {
        const auto lm = qs::landmarks::read_landmarks(*lm_path, valid);
        out.json["landmarks"] = qs::tools::to_json(lm);
        text << "  landmarks: " << lm_path->string() << ": " << lm.seeds.size() << " seeds, "
             << lm.features.size() << " features";
        double worst = 0;
        for (const auto* group : {&lm.seeds, &lm.features})
          for (const auto& l : *group) worst = std::max(worst, l.snap_distance);
        if (worst > 0) text << ", largest snap distance " << worst;
        text << "\n";
      } catch (const qs::Error& e) {
        out.json["landmarks"] = {{"source", lm_path->string()}, {"error", e.what()}};
        text << "  landmarks: error: " << e.what() << "\n";
        out.exit = std::max(out.exit, qs::exit_code(e.code()));
      }
    }
  } catch (const qs::Error& e) {
    out.json["error"] = {{"kind", qs::error_name(e.code())}, {"message", e.what()}};
    text << file << ": " << qs::error_name(e.code()) << " error: " << e.what() << "\n";
    out.exit = qs::exit_code(e.code());
  }
  out.json["accepted"] = out.exit == 0;
  out.text = text.str();
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Read and validate meshes for qs: closed, manifold, one component, genus 0.\n"
               "Exit codes: 0 all accepted, 1 usage, 2 a mesh rejected, 3 a file unreadable.",
               "qs-inspect"};
  std::vector<std::string> meshes, landmark_files;
  bool as_json = false;
  app.add_option("meshes", meshes, "Mesh files (.obj .off .ply .stl)")->required();
  app.add_option("--landmarks", landmark_files,
                 "Landmark file per mesh, in mesh order (.json or .pp); default: <stem>.landmarks.json "
                 "or <stem>.pp beside each mesh");
  app.add_flag("--json", as_json, "Print one JSON document instead of text");

  return qs::tools::run_tool(app, argc, argv, [&] {
    if (!landmark_files.empty() && landmark_files.size() != meshes.size())
      throw qs::UsageError("--landmarks was given " + std::to_string(landmark_files.size()) +
                           " times for " + std::to_string(meshes.size()) + " meshes; give one per mesh");
    nlohmann::json all = nlohmann::json::array();
    int code = 0;
    for (size_t i = 0; i < meshes.size(); ++i) {
      std::optional<std::string> lm;
      if (!landmark_files.empty()) lm = landmark_files[i];
      Outcome o = inspect(meshes[i], lm);
      code = std::max(code, o.exit);
      if (as_json) all.push_back(std::move(o.json));
      else std::cout << o.text << (i + 1 < meshes.size() ? "\n" : "");
    }
    if (as_json) std::cout << all.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
    return code;
  });
}
