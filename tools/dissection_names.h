#pragma once
// Reading a qs-dissect folder from the tools that take one (qs-merge, qs-metro --correspondence),
// with a clear message for a folder whose file names JSON could not hold.

#include <exception>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/core/json_strict.h"
#include "qs/dissect/dissection_json.h"

namespace qs::tools {

/// qs::dissect::read_dissection, except that a chart that is missing because its name was not
/// UTF-8 when qs-dissect wrote it (dissection.json holds U+FFFD in place of those bytes, and no
/// file has that name) is an invalid-input error that says so, instead of "no such file".
inline dissect::LoadedDissection read_dissection_folder(const std::filesystem::path& folder) {
  namespace fs = std::filesystem;
  try {
    return dissect::read_dissection(folder);
  } catch (const IoError&) {
    static const std::string kReplacement = "\xEF\xBF\xBD";  // U+FFFD
    const std::exception_ptr original = std::current_exception();
    nlohmann::json doc;
    try {
      doc = json_strict::parse(json_strict::read_text_file(folder / "dissection.json", "dissection.json"),
                               "dissection.json");
    } catch (...) {
      std::rethrow_exception(original);  // dissection.json itself is the problem: its own message
    }
    const nlohmann::json* meshes = doc.is_object() && doc.contains("meshes") ? &doc["meshes"] : nullptr;
    if (meshes && meshes->is_array())
      for (const auto& m : *meshes) {
        if (!m.is_object() || !m.contains("chart") || !m["chart"].is_string()) continue;
        const std::string chart = m["chart"].get<std::string>();
        std::error_code ec;
        if (chart.find(kReplacement) != std::string::npos && !fs::exists(folder / chart, ec))
          throw InvalidInput(json_strict::printable((folder / "dissection.json").string()) + ": the chart '" +
                             json_strict::printable(chart) + "' of mesh '" +
                             json_strict::printable(m.value("file", std::string())) +
                             "' is not in the folder: its file name was not UTF-8, which dissection.json (JSON) "
                             "cannot hold, so qs-dissect wrote it with U+FFFD in place of those bytes; rename "
                             "the mesh to a UTF-8 name and dissect it again");
      }
    throw;
  }
}

}  // namespace qs::tools
