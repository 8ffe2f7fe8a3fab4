// qs-studio's request checks (CheckedRequest) and POST /api/run's parser; run folder names.
#include <cctype>
#include <set>

#include "qs/studio/studio.h"
#include "qs/studio/studio_detail.h"

namespace qs::studio {

using namespace detail;

namespace {

std::string param(const Request& r, const std::string& key) {
  auto it = r.query.find(key);
  if (it == r.query.end() || it->second.empty()) throw HttpError(400, "missing query parameter '" + key + "'");
  return it->second;
}

/// The shape of a landmark body ({"seeds": [...], "features": ...}, nothing else); the references
/// themselves are checked against the mesh by qs-dissect's reader.
void check_landmark_body(const json& j, bool need_seeds) {
  if (!j.is_object())
    throw HttpError(400, "landmarks must be a JSON object {\"seeds\": [...], \"features\": {...}}, found " +
                             json_strict::describe(j));
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key() != "seeds" && it.key() != "features")
      throw HttpError(400, "unknown key \"" + printable(it.key(), 60) + "\" in the landmarks; expected seeds and features");
  if (need_seeds && !j.contains("seeds"))
    throw HttpError(400, "expected {\"seeds\": [4 references], \"features\": {...}}");
}

}  // namespace

RunRequest parse_run_request(const std::string& text, int max_meshes) {
  json j;
  try {
    j = json_strict::parse(text, "the run request");
  } catch (const InvalidInput& e) {
    throw HttpError(400, e.what());
  }
  if (!j.is_object()) throw InvalidInput("the run request must be a JSON object, found " + json_strict::describe(j));
  RunRequest r;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& k = it.key();
    const json& v = it.value();
    long long n = 0;
    double x = 0;
    if (k == "meshes") {
      if (!v.is_array() || v.empty())
        throw InvalidInput("\"meshes\" must be a non-empty array of mesh file names, found " + json_strict::describe(v));
      if (static_cast<long long>(v.size()) > max_meshes)
        throw InvalidInput("a run takes at most " + std::to_string(max_meshes) + " meshes, got " +
                           std::to_string(v.size()));
      for (const auto& m : v) {
        if (!m.is_string())
          throw InvalidInput("\"meshes\" holds a value that is not a file name: " + json_strict::describe(m));
        r.meshes.push_back(m.get<std::string>());
      }
    } else if (k == "level") {
      if (!json_strict::integer_in(v, 0, 6, n))
        throw InvalidInput("\"level\" must be an integer from 0 to 6, found " + json_strict::describe(v));
      r.level = static_cast<int>(n);
    } else if (k == "bake_size") {
      if (!json_strict::integer_in(v, 16, 2048, n))
        throw InvalidInput("\"bake_size\" must be an integer from 16 to 2048, found " + json_strict::describe(v));
      r.bake_size = static_cast<int>(n);
    } else if (k == "max_area") {
      if (!json_strict::finite_number(v, x) || !(x >= 0 && x <= 1))
        throw InvalidInput("\"max_area\" must be a number from 0 to 1 (0: off), found " + json_strict::describe(v));
      r.max_area = x;
    } else if (k == "morph") {
      if (!v.is_boolean()) throw InvalidInput("\"morph\" must be true or false, found " + json_strict::describe(v));
      r.morph = v.get<bool>();
    } else {
      throw InvalidInput("unknown key \"" + printable(k, 60) +
                         "\" in the run request; expected meshes, level, bake_size, max_area, morph");
    }
  }
  if (r.meshes.empty()) throw InvalidInput("the run request has no \"meshes\"");
  std::set<std::string> stems;
  for (const auto& m : r.meshes) {
    check_mesh_name(m);
    if (fs::path(m).stem().string().find(',') != std::string::npos)
      throw InvalidInput("mesh " + quote(m) + " has a ',' in its name, which qs-morph's --path cannot take; rename it");
    if (!stems.insert(fs::path(m).stem().string()).second)
      throw InvalidInput("two meshes of the run are named " + quote(fs::path(m).stem().string()) +
                         " (file stems name the shapes of a set); rename one");
  }
  return r;
}

std::string run_number(const std::string& name) {
  if (name.size() < 5 || name.compare(0, 4, "run-") != 0) return "";
  for (size_t i = 4; i < name.size(); ++i)
    if (!std::isdigit(static_cast<unsigned char>(name[i]))) return "";
  const size_t nz = name.find_first_not_of('0', 4);
  return nz == std::string::npos ? "0" : name.substr(nz);
}

std::string next_run_name(const std::vector<std::string>& existing) {
  std::string largest = "0";
  for (const auto& n : existing) {
    const std::string k = run_number(n);
    if (!k.empty() && number_less(largest, k)) largest = k;
  }
  // largest + 1 in decimal
  std::string next = largest;
  int i = static_cast<int>(next.size()) - 1;
  for (; i >= 0 && next[i] == '9'; --i) next[i] = '0';
  if (i < 0) next.insert(next.begin(), '1');
  else ++next[i];
  return "run-" + next;
}

CheckedRequest check_request(const Request& r, const StudioOptions& opt) {
  using Route = CheckedRequest::Route;
  CheckedRequest c;
  const std::string& p = r.path;
  if (!json_strict::is_clean_text(p))
    throw HttpError(400, "the URL path " + quote(p) + " is not valid UTF-8 or holds control characters");
  auto only = [&](const char* method) {
    if (r.method != method)
      throw HttpError(405, "method " + printable(r.method, 20) + " is not allowed on " + printable(p, 100) + "; use " +
                               method);
  };
  const bool has_body = !r.body.empty() || !r.body_file.empty();
  auto no_body = [&] {
    if (has_body) throw HttpError(413, "a " + printable(r.method, 20) + " request to " + printable(p, 100) + " takes no body");
  };
  // A run folder's name as the page sends it: run-<digits>, nothing else.
  auto run_name = [&] {
    c.name = param(r, "name");
    if (run_number(c.name).empty())
      throw HttpError(400, quote(c.name) + " is not a run name; expected run-N (a folder of runs/)");
  };
  if (p == "/api/meshes") {
    if (r.method == "DELETE") {
      no_body();
      c.route = Route::DeleteMesh;
      c.name = param(r, "name");
      check_mesh_name(c.name);
    } else {
      only("GET"), no_body();
      c.route = Route::Meshes;
    }
  } else if (p == "/api/mesh") {
    only("GET"), no_body();
    c.route = Route::Mesh;
    c.name = param(r, "path");
    if (!is_mesh_name(c.name)) throw HttpError(400, quote(c.name) + " is not a mesh file (.obj, .off, .ply, .stl)");
    check_relative_path(c.name);
  } else if (p == "/api/landmarks" || p == "/api/seed-loop") {
    const bool save = p == "/api/landmarks" && r.method != "GET";
    if (p == "/api/seed-loop" || save) only("POST");
    else no_body();
    c.name = param(r, "name");
    check_mesh_name(c.name);
    c.route = p == "/api/seed-loop" ? Route::SeedLoop : save ? Route::SaveLandmarks : Route::GetLandmarks;
    if (c.route != Route::GetLandmarks) check_landmark_body(parse_json_body(r, opt.max_json_bytes), c.route == Route::SeedLoop);
  } else if (p == "/api/upload") {
    only("POST");
    c.route = Route::Upload;
    auto it = r.query.find("name");
    c.name = it != r.query.end() && !it->second.empty() ? it->second : r.body_file_name;
    if (c.name.empty())
      throw HttpError(400, "missing query parameter 'name' (the new file's name, e.g. /api/upload?name=horse.obj)");
    check_mesh_name(c.name);
    if (r.body_file.empty()) {
      check_body_size(r.body.size(), opt.max_upload_bytes);
      if (r.body.empty()) throw HttpError(400, "the upload is empty; expected the contents of a mesh file");
    }
  } else if (p == "/api/run") {
    if (r.method == "GET") {
      no_body();
      c.route = Route::RunState;
    } else {
      only("POST");
      check_body_size(r.body.size(), opt.max_json_bytes);
      c.route = Route::StartRun;
      c.run = parse_run_request(r.body, opt.max_meshes_per_run);
    }
  } else if (p == "/api/run/cancel") {
    only("POST"), no_body();
    c.route = Route::CancelRun;
  } else if (p == "/api/runs") {
    if (r.method == "DELETE") {
      no_body();
      c.route = Route::DeleteRun;
      run_name();
    } else {
      only("GET"), no_body();
      c.route = Route::Runs;
    }
  } else if (p == "/api/run-archive") {
    only("GET"), no_body();
    c.route = Route::RunArchive;
    run_name();
  } else if (p.rfind("/files/", 0) == 0) {
    only("GET"), no_body();
    c.route = Route::File;
    c.name = p.substr(7);
    check_relative_path(c.name);
    auto it = r.query.find("download");
    c.download = it != r.query.end() && it->second == "1";
  } else if (p.rfind("/api/", 0) == 0) {
    throw HttpError(404, "no such API: " + printable(p, 100));
  } else {
    only("GET"), no_body();
    c.route = Route::Page;
    c.name = p;
    if (p == "/" || p == "/index.html" || p == "/favicon.ico") {
    } else if (p.rfind("/app/", 0) == 0 || p.rfind("/node_modules/three/", 0) == 0) {
      check_relative_path(p.substr(1));
    } else {
      throw HttpError(404, "not found: " + printable(p, 100));
    }
  }
  return c;
}

BodyLimit Studio::body_limit(const std::string& method, const std::string& path) const {
  if (method != "POST" && method != "PUT" && method != "PATCH" && method != "DELETE") return {0, false};
  if (path == "/api/upload") return {opt_.max_upload_bytes, true};
  return {opt_.max_json_bytes, false};  // JSON requests, and room for a 404/405 on anything else
}

}  // namespace qs::studio
