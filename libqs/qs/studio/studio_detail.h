#pragma once
// Internal helpers shared by the studio's source files (studio.cpp, studio_requests.cpp,
// studio_runs.cpp). Not installed.

#include <cctype>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "qs/core/error.h"
#include "qs/core/json_strict.h"
#include "qs/studio/paths.h"
#include "qs/studio/studio.h"

namespace qs::studio::detail {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;
using json_strict::printable;

/// A name or text from a request, quoted for a message: printable, at most 200 bytes.
inline std::string quote(std::string_view s) {
  std::string q = "'";  // appended: GCC 12 warns falsely (-Wrestrict) on "'" + a string, inlined
  q += printable(s, 200);
  q += '\'';
  return q;
}

inline Response json_response(const json& j, int status = 200) {
  Response r;
  r.status = status;
  r.body = json_strict::dump(j, -1);  // never throws: bytes that are not UTF-8 become U+FFFD
  return r;
}

inline std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

inline bool is_mesh_name(const std::string& name) {
  const std::string ext = lower(fs::path(name).extension().string());
  return ext == ".obj" || ext == ".off" || ext == ".ply" || ext == ".stl";
}

/// A mesh name as the page sends it: a file of the folder itself (no sub-folder), with a mesh extension.
inline void check_mesh_name(const std::string& name) {
  check_relative_path(name);
  if (name.find('/') != std::string::npos)
    throw HttpError(400, "mesh name " + quote(name) + " has a '/'; meshes are files of the studio's folder itself");
  if (!is_mesh_name(name))
    throw HttpError(400, quote(name) + " is not a mesh file name; expected .obj, .off, .ply or .stl");
}

/// An existing file of `root` (resolve_existing); a missing one is HttpError 404.
inline fs::path existing(const fs::path& root, const std::string& rel, bool allow_directory = false) {
  try {
    return resolve_existing(root, rel, allow_directory);
  } catch (const PathRefused&) {
    throw;
  } catch (const IoError& e) {
    throw HttpError(404, e.what());
  }
}

inline void check_body_size(size_t bytes, size_t limit) {
  if (bytes > limit)
    throw HttpError(413, "request body of " + std::to_string(bytes) + " bytes; at most " + std::to_string(limit) +
                             " are accepted here");
}

/// The body as strict JSON (nesting depth, duplicate keys, numbers that fit a double).
inline json parse_json_body(const Request& r, size_t limit) {
  check_body_size(r.body.size(), limit);
  try {
    return json_strict::parse(r.body, "the request body");
  } catch (const InvalidInput& e) {
    throw HttpError(400, e.what());
  }
}

/// Orders run numbers (decimal strings without leading zeros) by value.
inline bool number_less(const std::string& a, const std::string& b) {
  return a.size() != b.size() ? a.size() < b.size() : a < b;
}

/// GET /api/run's answer: the run's name, status, meshes, stages, log and error (studio_runs.cpp).
json state_json(const RunState& s);

}  // namespace qs::studio::detail
