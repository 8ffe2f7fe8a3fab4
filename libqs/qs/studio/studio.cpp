#include "qs/studio/studio.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <nlohmann/json.hpp>
#include <cstring>
#include <functional>
#include <set>
#include <sstream>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/dissect/chart_io.h"
#include "qs/dissect/seed_loop.h"
#include "qs/io/read_mesh.h"
#include "qs/landmarks/landmarks.h"
#include "qs/mesh/validate.h"
#include "qs/studio/paths.h"

extern char** environ;

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

namespace qs::studio {

namespace {

/// An error with its HTTP status, thrown inside the handlers.
struct HttpError : std::runtime_error {
  int status;
  HttpError(int s, const std::string& m) : std::runtime_error(m), status(s) {}
};

Response json_response(const json& j, int status = 200) {
  Response r;
  r.status = status;
  r.body = j.dump();
  return r;
}

Response error_response(int status, const std::string& message) {
  return json_response(json{{"error", message}}, status);
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool is_mesh_name(const std::string& name) {
  const std::string ext = lower(fs::path(name).extension().string());
  return ext == ".obj" || ext == ".off" || ext == ".ply" || ext == ".stl";
}

std::string param(const Request& r, const std::string& key) {
  auto it = r.query.find(key);
  if (it == r.query.end() || it->second.empty()) throw HttpError(400, "missing query parameter '" + key + "'");
  return it->second;
}

/// A mesh name as the page sends it: a file of the folder itself (no sub-folder), with a mesh extension.
void check_mesh_name(const std::string& name) {
  check_relative_path(name);
  if (name.find('/') != std::string::npos)
    throw HttpError(400, "mesh name '" + name + "' has a '/'; meshes are files of the studio's folder itself");
  if (!is_mesh_name(name))
    throw HttpError(400, "'" + name + "' is not a mesh file name; expected .obj, .off, .ply or .stl");
}

fs::path existing(const fs::path& root, const std::string& rel, bool allow_directory = false) {
  try {
    return resolve_existing(root, rel, allow_directory);
  } catch (const PathRefused&) {
    throw;
  } catch (const IoError& e) {
    throw HttpError(404, e.what());
  }
}

json parse_json_body(const Request& r, size_t limit) {
  if (r.body.size() > limit)
    throw HttpError(413, "request body of " + std::to_string(r.body.size()) + " bytes; at most " +
                             std::to_string(limit) + " are accepted here");
  try {
    return json::parse(r.body);
  } catch (const json::parse_error& e) {
    throw HttpError(400, std::string("the request body is not valid JSON: ") + e.what());
  }
}

// cpp-httplib (Debian's build) compresses text/*, application/javascript and application/json
// bodies with brotli at its highest quality when the browser accepts it: ~10 s for three.js's
// 1.5 MB. The types below are equivalent ones that it leaves alone (application/x-javascript is
// one of the JavaScript MIME types browsers accept for modules); only small pages stay text/*.
std::string content_type_of(const fs::path& p) {
  static const std::map<std::string, std::string> types = {
      {".html", "text/html; charset=utf-8"}, {".js", "application/x-javascript"}, {".mjs", "application/x-javascript"},
      {".css", "text/css"}, {".json", "application/json; charset=utf-8"}, {".png", "image/png"},
      {".glb", "model/gltf-binary"}, {".gltf", "model/gltf+json"}, {".obj", "application/octet-stream"},
      {".mtl", "application/octet-stream"}, {".off", "application/octet-stream"},
      {".txt", "text/plain; charset=utf-8"}, {".pp", "application/xml; charset=utf-8"}, {".exr", "image/x-exr"}};
  auto it = types.find(lower(p.extension().string()));
  return it == types.end() ? "application/octet-stream" : it->second;
}

// What a person should understand from each problem kind of qs::mesh::validate.
const std::map<std::string, std::string>& plain_words() {
  static const std::map<std::string, std::string> words = {
      {"empty", "the file holds no triangles"},
      {"invalid_vertex_index", "some faces refer to vertices that the file does not have"},
      {"non_finite_coordinates", "some vertices have coordinates that are not numbers (NaN or infinite)"},
      {"repeated_index_faces", "some faces use the same vertex twice"},
      {"duplicate_faces", "some faces are there twice"},
      {"non_manifold_edges", "some edges are shared by more than two faces"},
      {"non_manifold_vertices", "some vertices join two surfaces that only touch at a point"},
      {"inconsistent_orientation", "neighbouring faces point in opposite directions"},
      {"boundary_edges", "the surface has holes (it is not closed)"},
      {"multiple_components", "the file holds several separate pieces; qs needs one"},
      {"genus", "the surface has handles (tunnels through it, like a ring); qs needs a sphere-like shape"},
      {"unreferenced_vertices", "unused vertices were left out (harmless)"},
      {"orientation_flipped", "the faces pointed inwards and were turned outwards (harmless)"},
      {"zero_area_faces", "some triangles have no area (accepted)"},
      {"tiny_angles", "some triangles are very thin (accepted)"},
  };
  return words;
}

const char* severity_name(mesh::Severity s) {
  switch (s) {
    case mesh::Severity::Note: return "note";
    case mesh::Severity::Warning: return "warning";
    case mesh::Severity::Fatal: return "fatal";
  }
  return "fatal";
}

json reference_json(int face, std::array<double, 3> bary) {
  return json{{"face", face}, {"bary", {bary[0], bary[1], bary[2]}}};
}

/// The landmark's exact reference in the file as written (undoing validate()'s corner swap).
json file_reference(const landmarks::Landmark& l, const mesh::ValidationResult& v) {
  std::array<double, 3> b = l.where.bary;
  if (v.report.orientation_flipped) std::swap(b[1], b[2]);
  return reference_json(l.where.face, b);
}

/// Inserts surface points into a copy of the mesh (a point inside a face splits it in three),
/// as qs-dissect makes features vertices; returns the vertex of each point.
class PointInserter {
 public:
  explicit PointInserter(const TriMesh& m) : original_(m), mesh_(m), children_(m.faces.size()) {
    for (int f = 0; f < m.num_faces(); ++f) children_[f] = {f};
  }
  int insert(const landmarks::SurfacePoint& sp) {
    const Tri& t = original_.faces.at(sp.face);
    for (int k = 0; k < 3; ++k)
      if (sp.bary[k] > 1 - 1e-9) return t[k];
    const Vec3 p = landmarks::position_of(original_, sp);
    // The current face (a piece of the original one) that holds the point best.
    int best = -1;
    double best_min = -1e300;
    for (int f : children_[sp.face]) {
      const auto b = barycentric(mesh_.faces[f], p);
      const double mn = std::min({b[0], b[1], b[2]});
      if (mn > best_min) best_min = mn, best = f;
    }
    const auto b = barycentric(mesh_.faces[best], p);
    for (int k = 0; k < 3; ++k)
      if (b[k] > 1 - 1e-9) return mesh_.faces[best][k];
    const int v = mesh_.num_vertices();
    mesh_.positions.push_back(p);
    const Tri old = mesh_.faces[best];
    mesh_.faces[best] = {old[0], old[1], v};
    mesh_.faces.push_back({old[1], old[2], v});
    mesh_.faces.push_back({old[2], old[0], v});
    children_[sp.face].push_back(mesh_.num_faces() - 2);
    children_[sp.face].push_back(mesh_.num_faces() - 1);
    return v;
  }
  const TriMesh& mesh() const { return mesh_; }

 private:
  std::array<double, 3> barycentric(const Tri& t, const Vec3& p) const {
    const Vec3 a = mesh_.positions[t[0]], e1 = mesh_.positions[t[1]] - a, e2 = mesh_.positions[t[2]] - a;
    const Vec3 d = p - a;
    const double d11 = e1.dot(e1), d12 = e1.dot(e2), d22 = e2.dot(e2), dp1 = d.dot(e1), dp2 = d.dot(e2);
    const double den = d11 * d22 - d12 * d12;
    if (!(std::abs(den) > 0)) return {1.0 / 3, 1.0 / 3, 1.0 / 3};
    const double v = (d22 * dp1 - d12 * dp2) / den, w = (d11 * dp2 - d12 * dp1) / den;
    return {1 - v - w, v, w};
  }
  const TriMesh& original_;
  TriMesh mesh_;
  std::vector<std::vector<int>> children_;
};

/// One mesh of the folder, read and validated (cached while the file does not change).
struct LoadedMesh {
  fs::file_time_type mtime;
  uintmax_t size = 0;
  bool read_ok = false;
  std::string read_error;
  io::ReadResult read;
  mesh::ValidationResult valid;
};

std::mutex g_cache_mutex;
std::map<fs::path, std::shared_ptr<const LoadedMesh>> g_cache;

std::shared_ptr<const LoadedMesh> load_mesh(const fs::path& file) {
  std::lock_guard lock(g_cache_mutex);
  const auto mtime = fs::last_write_time(file);
  const auto size = fs::file_size(file);
  auto it = g_cache.find(file);
  if (it != g_cache.end() && it->second->mtime == mtime && it->second->size == size) return it->second;
  auto m = std::make_shared<LoadedMesh>();
  m->mtime = mtime;
  m->size = size;
  try {
    m->read = io::read_mesh(file);
    m->valid = mesh::validate(m->read.mesh);
    m->read_ok = true;
  } catch (const Error& e) {
    m->read_error = e.what();
  }
  g_cache[file] = m;
  return m;
}

std::shared_ptr<const LoadedMesh> accepted_mesh(const fs::path& root, const std::string& name) {
  check_mesh_name(name);
  auto m = load_mesh(existing(root, name));
  if (!m->read_ok) throw HttpError(400, m->read_error);
  if (!m->valid.report.accepted)
    throw HttpError(400, name + " is rejected (" + mesh::format_report(name, m->valid.report) +
                             "); landmarks need a closed genus-0 mesh");
  return m;
}

json landmarks_json(const landmarks::Landmarks& lm, const mesh::ValidationResult& v) {
  json seeds = json::array(), features = json::array();
  for (const auto& l : lm.seeds) seeds.push_back(file_reference(l, v));
  for (const auto& l : lm.features) {
    json f = file_reference(l, v);
    f["name"] = l.name;
    features.push_back(f);
  }
  return json{{"seeds", seeds}, {"features", features}};
}

// Run helpers ----------------------------------------------------------------------------------

int run_number(const std::string& name) {
  if (name.rfind("run-", 0) != 0 || name.size() < 5 || name.size() > 12) return -1;
  for (size_t i = 4; i < name.size(); ++i)
    if (!std::isdigit(static_cast<unsigned char>(name[i]))) return -1;
  return std::stoi(name.substr(4));
}

/// Runs argv[0] (a full path) in `cwd`, calling `out` with every chunk of its stdout and stderr.
/// Returns the exit status (128 + signal when killed). \throws IoError when it cannot start.
int spawn_and_wait(const std::vector<std::string>& argv, const fs::path& cwd,
                   const std::function<void(const std::string&)>& out) {
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) throw IoError("cannot create a pipe for " + argv[0]);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 2);
  posix_spawn_file_actions_addchdir_np(&actions, cwd.c_str());
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, argv[0].c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[1]);
  if (rc != 0) {
    close(fds[0]);
    throw IoError("cannot start " + argv[0] + ": " + std::strerror(rc));
  }
  char buf[4096];
  for (;;) {
    const ssize_t n = read(fds[0], buf, sizeof buf);
    if (n > 0) out(std::string(buf, static_cast<size_t>(n)));
    else if (n == 0 || errno != EINTR) break;
  }
  close(fds[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return 70;
}

json list_files(const fs::path& root, const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file() && !e.is_symlink()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  json out = json::array();
  for (const auto& f : files)
    out.push_back({{"path", fs::relative(f, root).generic_string()}, {"bytes", fs::file_size(f)}});
  return out;
}

json state_json(const RunState& s) {
  json stages = json::array();
  for (const auto& st : s.stages) {
    json args = json::array();
    for (const auto& a : st.args) args.push_back(a);
    stages.push_back({{"name", st.name}, {"tool", st.tool}, {"args", args}, {"status", st.status},
                      {"exit_code", st.exit_code}, {"fraction", st.fraction}});
  }
  return json{{"name", s.name}, {"status", s.status}, {"meshes", s.meshes}, {"stages", stages},
              {"log", s.log}, {"error", s.error}};
}

}  // namespace

std::string plain_summary(const std::string& kind) {
  auto it = plain_words().find(kind);
  return it == plain_words().end() ? kind : it->second;
}

RunRequest parse_run_request(const std::string& text, int max_meshes) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    throw InvalidInput(std::string("the run request is not valid JSON: ") + e.what());
  }
  if (!j.is_object()) throw InvalidInput("the run request must be a JSON object");
  RunRequest r;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& k = it.key();
    const json& v = it.value();
    if (k == "meshes") {
      if (!v.is_array() || v.empty())
        throw InvalidInput("\"meshes\" must be a non-empty array of mesh file names");
      for (const auto& m : v) {
        if (!m.is_string()) throw InvalidInput("\"meshes\" holds a value that is not a file name: " + m.dump());
        r.meshes.push_back(m.get<std::string>());
      }
    } else if (k == "level") {
      if (!v.is_number_integer() || v.get<int>() < 0 || v.get<int>() > 6)
        throw InvalidInput("\"level\" must be an integer from 0 to 6, found " + v.dump());
      r.level = v.get<int>();
    } else if (k == "bake_size") {
      if (!v.is_number_integer() || v.get<int>() < 16 || v.get<int>() > 2048)
        throw InvalidInput("\"bake_size\" must be an integer from 16 to 2048, found " + v.dump());
      r.bake_size = v.get<int>();
    } else if (k == "max_area") {
      if (!v.is_number() || !(v.get<double>() >= 0 && v.get<double>() <= 1))
        throw InvalidInput("\"max_area\" must be a number from 0 to 1 (0: off), found " + v.dump());
      r.max_area = v.get<double>();
    } else if (k == "morph") {
      if (!v.is_boolean()) throw InvalidInput("\"morph\" must be true or false, found " + v.dump());
      r.morph = v.get<bool>();
    } else {
      throw InvalidInput("unknown key \"" + k + "\" in the run request; expected meshes, level, bake_size, "
                         "max_area, morph");
    }
  }
  if (r.meshes.empty()) throw InvalidInput("the run request has no \"meshes\"");
  if (static_cast<int>(r.meshes.size()) > max_meshes)
    throw InvalidInput("a run takes at most " + std::to_string(max_meshes) + " meshes, got " +
                       std::to_string(r.meshes.size()));
  std::set<std::string> stems;
  for (const auto& m : r.meshes) {
    check_mesh_name(m);
    if (fs::path(m).stem().string().find(',') != std::string::npos)
      throw InvalidInput("mesh '" + m + "' has a ',' in its name, which qs-morph's --path cannot take; rename it");
    if (!stems.insert(fs::path(m).stem().string()).second)
      throw InvalidInput("two meshes of the run are named '" + fs::path(m).stem().string() +
                         "' (file stems name the shapes of a set); rename one");
  }
  return r;
}

Studio::Studio(StudioOptions options) : opt_(std::move(options)) {
  std::error_code ec;
  if (!fs::exists(opt_.folder, ec)) throw IoError("folder '" + opt_.folder.string() + "' does not exist");
  if (!fs::is_directory(opt_.folder, ec)) throw InvalidInput("'" + opt_.folder.string() + "' is not a folder");
  root_ = fs::canonical(opt_.folder);
  web_root_ = fs::exists(opt_.web_dir, ec) ? fs::canonical(opt_.web_dir) : opt_.web_dir;
}

Studio::~Studio() { wait_for_run(); }

void Studio::wait_for_run() {
  std::thread t;
  {
    std::lock_guard lock(mutex_);
    t = std::move(worker_);
  }
  if (t.joinable()) t.join();
}

RunState Studio::run_state() const {
  std::lock_guard lock(mutex_);
  return state_;
}

Response Studio::handle(const Request& request) {
  try {
    return route(request);
  } catch (const HttpError& e) {
    return error_response(e.status, e.what());
  } catch (const PathRefused& e) {
    return error_response(403, e.what());
  } catch (const InvalidInput& e) {
    return error_response(400, e.what());
  } catch (const Error& e) {
    return error_response(500, std::string(error_name(e.code())) + " error: " + e.what());
  } catch (const std::exception& e) {
    return error_response(500, std::string("internal error: ") + e.what() + " (please report this)");
  }
}

Response Studio::route(const Request& r) {
  const std::string& p = r.path;
  auto only = [&](const char* method) {
    if (r.method != method)
      throw HttpError(405, "method " + r.method + " is not allowed on " + p + "; use " + method);
  };
  if (p == "/api/meshes") return only("GET"), list_meshes();
  if (p == "/api/mesh") return only("GET"), mesh_data(r);
  if (p == "/api/landmarks") {
    if (r.method == "GET") return get_landmarks(r);
    return only("POST"), save_landmarks(r);
  }
  if (p == "/api/seed-loop") return only("POST"), seed_loop(r);
  if (p == "/api/upload") return only("POST"), upload(r);
  if (p == "/api/run") {
    if (r.method == "GET") return json_response(state_json(run_state()));
    return only("POST"), start_run(r);
  }
  if (p == "/api/runs") return only("GET"), runs();
  if (p.rfind("/files/", 0) == 0) {
    only("GET");
    auto it = r.query.find("download");
    return folder_file(p.substr(7), it != r.query.end() && it->second == "1");
  }
  if (p.rfind("/api/", 0) == 0) throw HttpError(404, "no such API: " + p);
  only("GET");
  return static_file(p);
}

Response Studio::static_file(const std::string& p) {
  std::string rel;
  if (p == "/" || p == "/index.html") rel = "index.html";
  else if (p.rfind("/app/", 0) == 0) rel = p.substr(1);
  else if (p.rfind("/node_modules/three/", 0) == 0) rel = p.substr(1);
  else if (p == "/favicon.ico") return Response{204, "text/plain", "", {}, false};
  else throw HttpError(404, "not found: " + p);
  if (rel == "index.html" && !fs::exists(web_root_ / "node_modules/three/build/three.module.js")) {
    // The page cannot work without three.js: say so instead of a blank page.
    Response res;
    res.status = 200;
    res.content_type = "text/html; charset=utf-8";
    res.body = "<!DOCTYPE html><html><body><h1>qs-studio</h1><p>three.js is not installed in " +
               web_root_.string() +
               "/node_modules: run <code>scripts/setup.sh</code> (or <code>npm ci</code> in that folder).</p></body></html>";
    return res;
  }
  Response res;
  res.file = existing(web_root_, rel);
  res.content_type = content_type_of(res.file);
  return res;
}

Response Studio::folder_file(const std::string& rel, bool download) {
  Response res;
  res.file = existing(root_, rel);
  res.content_type = content_type_of(res.file);
  res.attachment = download;
  return res;
}

Response Studio::list_meshes() {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(root_)) {
    const std::string name = e.path().filename().string();
    if (name.empty() || name[0] == '.' || !is_mesh_name(name)) continue;
    names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  json list = json::array();
  for (const auto& name : names) {
    fs::path file;
    try {
      file = resolve_existing(root_, name);
    } catch (const Error&) {
      continue;  // a link out of the folder, a folder named like a mesh: not listed
    }
    auto m = load_mesh(file);
    json j = {{"name", name}, {"bytes", m->size}, {"read", m->read_ok}};
    if (!m->read_ok) {
      j["accepted"] = false;
      j["summary"] = "cannot be read: " + m->read_error;
      j["problems"] = json::array();
      list.push_back(j);
      continue;
    }
    const auto& rep = m->valid.report;
    j["vertices"] = rep.input_vertices;
    j["faces"] = rep.input_faces;
    j["accepted"] = rep.accepted;
    json problems = json::array();
    std::string fatal;
    for (const auto& pr : rep.problems) {
      problems.push_back({{"kind", pr.kind}, {"severity", severity_name(pr.severity)},
                          {"plain", plain_summary(pr.kind)}, {"message", pr.message}});
      if (pr.severity == mesh::Severity::Fatal) fatal += (fatal.empty() ? "" : "; ") + plain_summary(pr.kind);
    }
    for (const auto& note : m->read.report.notes)
      problems.push_back({{"kind", "read_note"}, {"severity", "note"}, {"plain", note}, {"message", note}});
    j["problems"] = problems;
    j["summary"] = rep.accepted ? "ready: a closed surface in one piece without handles (" +
                                      std::to_string(rep.vertices) + " vertices, " + std::to_string(rep.faces) +
                                      " triangles)"
                                : "rejected: " + fatal;
    json lm = nullptr;
    if (auto beside = landmarks::find_landmarks_beside(file)) {
      lm = {{"file", beside->filename().string()}};
      if (rep.accepted) {
        try {
          const auto l = landmarks::read_landmarks(*beside, m->valid);
          lm["seeds"] = l.seeds.size();
          lm["features"] = l.features.size();
        } catch (const Error& e) {
          lm["error"] = e.what();
        }
      }
    }
    j["landmarks"] = lm;
    list.push_back(j);
  }
  return json_response(json{{"folder", root_.filename().string()}, {"meshes", list}});
}

Response Studio::mesh_data(const Request& r) {
  const std::string rel = param(r, "path");
  if (!is_mesh_name(rel)) throw HttpError(400, "'" + rel + "' is not a mesh file (.obj, .off, .ply, .stl)");
  const fs::path file = existing(root_, rel);
  json positions = json::array(), faces = json::array();
  auto put = [&](const TriMesh& m) {
    for (const auto& p : m.positions)
      for (int k = 0; k < 3; ++k) positions.push_back(static_cast<float>(p[k]));
    const int n = m.num_vertices();
    for (const auto& t : m.faces) {
      if (t[0] < 0 || t[1] < 0 || t[2] < 0 || t[0] >= n || t[1] >= n || t[2] >= n) {
        faces.push_back(0), faces.push_back(0), faces.push_back(0);  // keeps face ids; draws nothing
        continue;
      }
      for (int k = 0; k < 3; ++k) faces.push_back(t[k]);
    }
  };
  json out;
  if (rel.size() > 10 && lower(rel.substr(rel.size() - 10)) == ".chart.ply") {
    const dissect::Chart chart = dissect::read_chart_ply(file);
    put(chart.mesh);
    out = {{"path", rel}, {"positions", positions}, {"faces", faces}, {"patch", chart.face_patch},
           {"patches", chart.patches.size()}};
  } else {
    auto m = load_mesh(file);
    if (!m->read_ok) throw HttpError(400, m->read_error);
    put(m->read.mesh);
    out = {{"path", rel}, {"positions", positions}, {"faces", faces}, {"accepted", m->valid.report.accepted}};
  }
  return json_response(out);
}

Response Studio::get_landmarks(const Request& r) {
  const std::string name = param(r, "name");
  auto m = accepted_mesh(root_, name);
  const fs::path file = existing(root_, name);
  json out = {{"file", nullptr}, {"seeds", json::array()}, {"features", json::array()}};
  if (auto beside = landmarks::find_landmarks_beside(file)) {
    const auto lm = landmarks::read_landmarks(*beside, m->valid);  // InvalidInput -> 400 with qs's words
    out = landmarks_json(lm, m->valid);
    out["file"] = beside->filename().string();
  }
  return json_response(out);
}

Response Studio::save_landmarks(const Request& r) {
  const std::string name = param(r, "name");
  auto m = accepted_mesh(root_, name);
  const json j = parse_json_body(r, opt_.max_json_bytes);
  if (!j.is_object()) throw HttpError(400, "landmarks must be a JSON object {\"seeds\": [...], \"features\": {...}}");
  for (auto it = j.begin(); it != j.end(); ++it)
    if (it.key() != "seeds" && it.key() != "features")
      throw HttpError(400, "unknown key \"" + it.key() + "\" in the landmarks; expected seeds and features");
  const std::string target = fs::path(name).stem().string() + ".landmarks.json";
  // The same reader qs-dissect uses: what it refuses is refused here, before anything is written.
  const auto lm = landmarks::parse_landmarks(r.body, landmarks::LandmarkFormat::Json, target, m->valid);
  std::lock_guard lock(write_mutex_);
  const fs::path out = resolve_for_writing(root_, target);
  write_file_atomically(out, j.dump(2) + "\n");
  return json_response(json{{"file", target}, {"seeds", lm.seeds.size()}, {"features", lm.features.size()}});
}

Response Studio::seed_loop(const Request& r) {
  const std::string name = param(r, "name");
  auto m = accepted_mesh(root_, name);
  const json j = parse_json_body(r, opt_.max_json_bytes);
  if (!j.is_object() || !j.contains("seeds"))
    throw HttpError(400, "expected {\"seeds\": [4 references], \"features\": {...}}");
  const auto lm = landmarks::parse_landmarks(r.body, landmarks::LandmarkFormat::Json, name + " (seed loop)", m->valid);
  if (lm.seeds.size() != 4) throw HttpError(400, "the seed loop needs 4 seeds");
  PointInserter ins(m->valid.mesh);
  std::array<int, 4> seeds{};
  std::vector<int> avoid;
  for (int i = 0; i < 4; ++i) seeds[i] = ins.insert(lm.seeds[i].where);
  for (const auto& f : lm.features) avoid.push_back(ins.insert(f.where));
  for (int i = 0; i < 4; ++i)
    for (int k = i + 1; k < 4; ++k)
      if (seeds[i] == seeds[k]) throw HttpError(400, "seed" + std::to_string(i) + " and seed" + std::to_string(k) +
                                                         " are the same point; give 4 distinct seeds");
  dissect::SeedLoop loop;
  try {
    loop = dissect::trace_seed_loop(ins.mesh(), seeds, avoid);
  } catch (const InvalidInput& e) {
    throw HttpError(400, std::string("the seed loop cannot be routed: ") + e.what());
  }
  json paths = json::array();
  double length = 0;
  for (const auto& path : loop.paths) {
    json pts = json::array();
    for (size_t k = 0; k < path.size(); ++k) {
      const Vec3& p = ins.mesh().positions[path[k]];
      pts.push_back(p.x()), pts.push_back(p.y()), pts.push_back(p.z());
      if (k) length += (p - ins.mesh().positions[path[k - 1]]).norm();
    }
    paths.push_back(pts);
  }
  return json_response(json{{"paths", paths}, {"length", length}});
}

Response Studio::upload(const Request& r) {
  const std::string name = param(r, "name");
  check_mesh_name(name);
  if (r.body.size() > opt_.max_upload_bytes)
    throw HttpError(413, "upload of " + std::to_string(r.body.size()) + " bytes; at most " +
                             std::to_string(opt_.max_upload_bytes) + " are accepted");
  if (r.body.empty()) throw HttpError(400, "the upload is empty; expected the contents of a mesh file");
  std::lock_guard lock(write_mutex_);
  const fs::path out = resolve_for_writing(root_, name);
  if (fs::exists(fs::symlink_status(out)))
    throw HttpError(409, "'" + name + "' exists already; the studio never replaces a mesh (rename the upload)");
  try {
    (void)io::read_mesh_from_memory(r.body, io::format_from_path(name), name);
  } catch (const InvalidInput& e) {
    throw HttpError(400, std::string("not a mesh file: ") + e.what());
  }
  write_file_atomically(out, r.body);
  return json_response(json{{"file", name}, {"bytes", r.body.size()}}, 201);
}

Response Studio::start_run(const Request& r) {
  if (r.body.size() > opt_.max_json_bytes)
    throw HttpError(413, "request body of " + std::to_string(r.body.size()) + " bytes; at most " +
                             std::to_string(opt_.max_json_bytes) + " are accepted here");
  RunRequest req = parse_run_request(r.body, opt_.max_meshes_per_run);
  for (const auto& m : req.meshes) (void)existing(root_, m);
  for (const char* tool : {"qs-dissect", "qs-remesh", "qs-bake", "qs-morph"})
    if (access((opt_.tools_dir / tool).c_str(), X_OK) != 0)
      throw HttpError(500, std::string(tool) + " not found in " + opt_.tools_dir.string() +
                               " (build it, or start qs-studio with --tools DIR)");
  {
    // Runs are written under FOLDER/runs: never through a link (it could point out of the folder).
    std::error_code ec;
    const fs::file_status st = fs::symlink_status(root_ / "runs", ec);
    if (!ec && fs::exists(st) && (fs::is_symlink(st) || !fs::is_directory(st)))
      throw HttpError(409, "'runs' in the studio's folder is a symbolic link or not a folder; the studio writes its "
                           "runs only into a plain 'runs' folder (rename or remove it)");
  }
  std::unique_lock lock(mutex_);
  if (state_.status == "running")
    throw HttpError(409, "a run (" + state_.name + ") is already going in this folder; wait until it ends");
  // One run per folder across processes too: an exclusive lock on the folder itself.
  const int fd = open(root_.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) throw IoError("cannot open the folder " + root_.string());
  if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
    close(fd);
    throw HttpError(409, "another qs-studio is running a job in this folder; wait until it ends");
  }
  int next = 1;
  std::error_code ec;
  if (fs::is_directory(root_ / "runs", ec))
    for (const auto& e : fs::directory_iterator(root_ / "runs"))
      next = std::max(next, run_number(e.path().filename().string()) + 1);
  const std::string name = "run-" + std::to_string(next);
  if (worker_.joinable()) worker_.join();  // the previous run's thread has finished (status is not running)
  state_ = RunState{};
  state_.name = name;
  state_.status = "running";
  state_.meshes = req.meshes;
  worker_ = std::thread(&Studio::run_thread, this, std::move(req), name, fd);
  return json_response(json{{"name", name}, {"status", "running"}}, 202);
}

void Studio::run_thread(RunRequest req, std::string name, int lock_fd) {
  const fs::path runs_dir = root_ / "runs";
  const fs::path staging = runs_dir / ("." + name + ".partial");
  bool created_runs = false;
  auto append = [&](const std::string& s) {
    std::lock_guard lock(mutex_);
    state_.log += s;
    if (state_.log.size() > (4u << 20)) state_.log.erase(0, state_.log.size() - (4u << 20));
  };
  const std::string level_dir = "remesh-L" + std::to_string(req.level);
  std::vector<RunStage> stages;
  {
    RunStage d{"dissect", "qs-dissect", {}};
    for (const auto& m : req.meshes) d.args.push_back("../../" + m);
    d.args.insert(d.args.end(), {"-o", "dissection"});
    {
      std::ostringstream s;
      s.precision(12);  // the page's steps are 0.05: "0.15", not 0.14999999999999999
      s << req.max_area;
      d.args.insert(d.args.end(), {"--max-area", s.str()});
    }
    stages.push_back(d);
    stages.push_back({"remesh", "qs-remesh", {"dissection", "--level", std::to_string(req.level), "-o", level_dir}});
    stages.push_back({"bake", "qs-bake", {level_dir, "--size", std::to_string(req.bake_size), "-o", "bake"}});
    if (req.morph && req.meshes.size() >= 2) {
      std::string path;
      for (const auto& m : req.meshes) path += fs::path(m).stem().string() + ",";
      path += fs::path(req.meshes[0]).stem().string();
      stages.push_back({"morph", "qs-morph",
                        {level_dir, "--path", path, "--align", "similarity", "--bake", "bake", "--glb", "morph.glb",
                         "-o", "morph"}});
    }
  }
  {
    std::lock_guard lock(mutex_);
    state_.stages = stages;
  }
  bool ok = true;
  std::string error;
  try {
    if (!fs::exists(runs_dir)) {
      fs::create_directory(runs_dir);
      created_runs = true;
    }
    fs::remove_all(staging);
    fs::create_directory(staging);
    for (size_t i = 0; i < stages.size() && ok; ++i) {
      {
        std::lock_guard lock(mutex_);
        state_.stages[i].status = "running";
      }
      std::vector<std::string> argv = {(opt_.tools_dir / stages[i].tool).string()};
      argv.insert(argv.end(), stages[i].args.begin(), stages[i].args.end());
      std::string cmd = "$ " + stages[i].tool;
      for (const auto& a : stages[i].args) cmd += " " + a;
      append(cmd + "\n");
      std::string stage_out;
      size_t scanned = 0;
      const std::string prefix = stages[i].tool + ": ";
      const int code = spawn_and_wait(argv, staging, [&](const std::string& s) {
        stage_out += s;
        // Whole lines go to the log, except progress lines ("qs-dissect: quinary subdivision
        // 53%"), which set the stage's fraction instead.
        for (size_t nl; (nl = stage_out.find('\n', scanned)) != std::string::npos; scanned = nl + 1) {
          const std::string line = stage_out.substr(scanned, nl - scanned);
          size_t k = line.empty() ? 0 : line.size() - 1;
          while (k > 0 && (std::isdigit(static_cast<unsigned char>(line[k - 1])) || line[k - 1] == '.')) --k;
          if (line.rfind(prefix, 0) != 0 || line.back() != '%' || k == line.size() - 1) {
            append(line + "\n");
            continue;
          }
          try {
            const double f = std::stod(line.substr(k, line.size() - 1 - k)) / 100;
            std::lock_guard lock(mutex_);
            state_.stages[i].fraction = std::clamp(f, 0.0, 1.0);
          } catch (const std::exception&) {
            append(line + "\n");
          }
        }
      });
      if (scanned < stage_out.size()) append(stage_out.substr(scanned) + "\n");  // a last line without '\n'
      std::lock_guard lock(mutex_);
      state_.stages[i].exit_code = code;
      state_.stages[i].status = code == 0 ? "done" : "failed";
      if (code == 0) state_.stages[i].fraction = 1;
      if (code != 0) {
        ok = false;
        // The tool's own error lines ("qs-dissect: invalid input error: ..."), else its last output.
        std::istringstream in(stage_out);
        std::string line, mine, tail;
        bool in_error = false;
        while (std::getline(in, line)) {
          if (line.rfind(stages[i].tool + ":", 0) == 0 && line.find("error") != std::string::npos) in_error = true;
          if (in_error) mine += line + "\n";
          tail += line + "\n";
          if (tail.size() > 4000) tail.erase(0, tail.size() - 4000);
        }
        error = stages[i].tool + " failed (exit " + std::to_string(code) + "):\n" + (mine.empty() ? tail : mine);
      }
    }
    if (ok) {
      json j = {{"format", "qs-studio-run"}, {"version", 1}, {"name", name}, {"meshes", req.meshes},
                {"level", req.level}, {"bake_size", req.bake_size}, {"max_area", req.max_area}};
      json st = json::array();
      for (const auto& s : stages) st.push_back({{"tool", s.tool}, {"args", s.args}});
      j["stages"] = st;
      write_file_atomically(staging / "run.json", j.dump(2) + "\n");
      fs::rename(staging, runs_dir / name);
    }
  } catch (const std::exception& e) {
    ok = false;
    error = std::string("the run could not be carried out: ") + e.what();
  }
  if (!ok) {
    // A failed run leaves the folder as it was.
    std::error_code ec;
    fs::remove_all(staging, ec);
    if (created_runs && fs::is_empty(runs_dir, ec)) fs::remove(runs_dir, ec);
  }
  flock(lock_fd, LOCK_UN);
  close(lock_fd);
  std::lock_guard lock(mutex_);
  state_.status = ok ? "done" : "failed";
  state_.error = error;
}

Response Studio::runs() {
  json list = json::array();
  std::error_code ec;
  const fs::path dir = root_ / "runs";
  if (fs::is_directory(dir, ec) && !fs::is_symlink(dir, ec)) {
    std::vector<std::pair<int, std::string>> names;
    for (const auto& e : fs::directory_iterator(dir)) {
      const std::string n = e.path().filename().string();
      const int k = run_number(n);
      if (k >= 0 && e.is_directory() && !e.is_symlink()) names.emplace_back(k, n);
    }
    std::sort(names.begin(), names.end());
    for (const auto& [k, n] : names) {
      json run = {{"name", n}, {"files", list_files(root_, dir / n)}};
      std::ifstream in(dir / n / "run.json");
      if (in) {
        try {
          run["run"] = json::parse(in);
        } catch (const json::parse_error&) {
          run["run"] = nullptr;
        }
      }
      list.push_back(run);
    }
  }
  return json_response(json{{"runs", list}});
}

}  // namespace qs::studio
