#include "qs/studio/studio.h"

#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cfloat>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/core/json_strict.h"
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

using json_strict::printable;

/// A name or text from a request, quoted for a message: printable, at most 200 bytes.
std::string quote(std::string_view s) { return "'" + printable(s, 200) + "'"; }

Response json_response(const json& j, int status = 200) {
  Response r;
  r.status = status;
  r.body = json_strict::dump(j, -1);  // never throws: bytes that are not UTF-8 become U+FFFD
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
    throw HttpError(400, "mesh name " + quote(name) + " has a '/'; meshes are files of the studio's folder itself");
  if (!is_mesh_name(name))
    throw HttpError(400, quote(name) + " is not a mesh file name; expected .obj, .off, .ply or .stl");
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

void check_body_size(size_t bytes, size_t limit) {
  if (bytes > limit)
    throw HttpError(413, "request body of " + std::to_string(bytes) + " bytes; at most " + std::to_string(limit) +
                             " are accepted here");
}

/// The body as strict JSON (nesting depth, duplicate keys, numbers that fit a double).
json parse_json_body(const Request& r, size_t limit) {
  check_body_size(r.body.size(), limit);
  try {
    return json_strict::parse(r.body, "the request body");
  } catch (const InvalidInput& e) {
    throw HttpError(400, e.what());
  }
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

/// Runs argv[0] (a full path) in `cwd`, calling `out` with every chunk of its stdout and stderr.
/// `started` gets the child's pid once it runs, `ended` is called once it has exited and before its
/// pid is released (so that nobody signals a recycled pid). The child gets SIGTERM when the thread that started
/// it ends (PR_SET_PDEATHSIG), so a killed studio leaves no tool running, and starts with no
/// signal blocked (the server blocks SIGINT/SIGTERM for its own threads).
/// Returns the exit status (128 + signal when killed). \throws IoError when it cannot start.
int spawn_and_wait(const std::vector<std::string>& argv, const fs::path& cwd,
                   const std::function<void(const std::string&)>& out, const std::function<void(pid_t)>& started,
                   const std::function<void()>& ended) {
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) throw IoError("cannot create a pipe for " + argv[0]);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  int err_pipe[2];  // the child writes errno here when exec fails
  if (pipe2(err_pipe, O_CLOEXEC) != 0) {
    close(fds[0]), close(fds[1]);
    throw IoError("cannot create a pipe for " + argv[0]);
  }
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid == 0) {
    // Only async-signal-safe calls from here to exec.
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(127);  // the studio died before prctl
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    signal(SIGPIPE, SIG_DFL);
    dup2(fds[1], 1);
    dup2(fds[1], 2);
    int e = 0;
    if (chdir(cwd.c_str()) != 0) e = errno;
    else {
      execve(argv[0].c_str(), args.data(), environ);
      e = errno;
    }
    ssize_t ignored = write(err_pipe[1], &e, sizeof e);
    (void)ignored;
    _exit(127);
  }
  close(fds[1]);
  close(err_pipe[1]);
  if (pid < 0) {
    const int e = errno;
    close(fds[0]), close(err_pipe[0]);
    throw IoError("cannot start " + argv[0] + ": " + std::strerror(e));
  }
  int exec_errno = 0;
  ssize_t got;
  while ((got = read(err_pipe[0], &exec_errno, sizeof exec_errno)) < 0 && errno == EINTR) {
  }
  close(err_pipe[0]);
  if (got == static_cast<ssize_t>(sizeof exec_errno)) {
    close(fds[0]);
    while (waitpid(pid, nullptr, 0) < 0 && errno == EINTR) {
    }
    throw IoError("cannot start " + argv[0] + ": " + std::strerror(exec_errno));
  }
  started(pid);
  char buf[4096];
  for (;;) {
    const ssize_t n = read(fds[0], buf, sizeof buf);
    if (n > 0) out(std::string(buf, static_cast<size_t>(n)));
    else if (n == 0 || errno != EINTR) break;
  }
  close(fds[0]);
  siginfo_t info{};
  while (waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOWAIT) < 0 && errno == EINTR) {
  }
  ended();
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return 70;
}

/// A coordinate for the page: the float it draws with when that is finite (shortest text that
/// reads back as that float), else the double itself (the page cannot draw it, but the value is
/// not lost); null only for NaN and infinities (which validation rejects).
void put_coordinate(std::string& out, double x) {
  char buf[40];
  std::to_chars_result r{};
  const float f = static_cast<float>(x);
  if (!std::isfinite(x)) {
    out += "null";
    return;
  }
  if (std::isfinite(f)) r = std::to_chars(buf, buf + sizeof buf, f);
  else r = std::to_chars(buf, buf + sizeof buf, x);
  out.append(buf, r.ptr);
}

void put_int(std::string& out, long long v) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, r.ptr);
}

/// {"positions": [...], "faces": [...]} members for a mesh, written without a JSON document (a
/// large mesh would need gigabytes as nlohmann values). Faces with an index out of range become
/// 0,0,0 (they keep the face ids and draw nothing).
void put_mesh(std::string& out, const TriMesh& m) {
  out += "\"positions\":[";
  bool first = true;
  for (const auto& p : m.positions)
    for (int k = 0; k < 3; ++k) {
      if (!first) out += ',';
      first = false;
      put_coordinate(out, p[k]);
    }
  out += "],\"faces\":[";
  const int n = m.num_vertices();
  first = true;
  for (const auto& t : m.faces) {
    const bool ok = t[0] >= 0 && t[1] >= 0 && t[2] >= 0 && t[0] < n && t[1] < n && t[2] < n;
    for (int k = 0; k < 3; ++k) {
      if (!first) out += ',';
      first = false;
      put_int(out, ok ? t[k] : 0);
    }
  }
  out += ']';
}

/// Every entry name in FOLDER/runs (none when it does not exist).
std::vector<std::string> run_folder_names(const fs::path& root) {
  std::vector<std::string> names;
  std::error_code ec;
  if (fs::is_directory(root / "runs", ec))
    for (const auto& e : fs::directory_iterator(root / "runs", ec)) names.push_back(e.path().filename().string());
  return names;
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

namespace {
/// Orders run numbers (decimal strings without leading zeros) by value.
bool number_less(const std::string& a, const std::string& b) {
  return a.size() != b.size() ? a.size() < b.size() : a < b;
}
}  // namespace

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
  if (p == "/api/meshes") {
    only("GET"), no_body();
    c.route = Route::Meshes;
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
  } else if (p == "/api/runs") {
    only("GET"), no_body();
    c.route = Route::Runs;
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

Studio::Studio(StudioOptions options) : opt_(std::move(options)) {
  std::error_code ec;
  if (!fs::exists(opt_.folder, ec)) throw IoError("folder " + quote(opt_.folder.string()) + " does not exist");
  if (!fs::is_directory(opt_.folder, ec)) throw InvalidInput(quote(opt_.folder.string()) + " is not a folder");
  root_ = fs::canonical(opt_.folder);
  web_root_ = fs::exists(opt_.web_dir, ec) ? fs::canonical(opt_.web_dir) : opt_.web_dir;
  clean_stale_staging();
}

Studio::~Studio() {
  // A studio going away (stopped server, failed start) leaves no tool running.
  stop_run();
}

namespace {

bool starts_with(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

/// Removes the run staging folders (.run-N.partial) under runs/. \pre the folder lock is held.
void remove_run_staging(const fs::path& root) {
  std::error_code ec;
  const fs::path runs = root / "runs";
  const auto st = fs::symlink_status(runs, ec);
  if (ec || !fs::is_directory(st)) return;
  for (const auto& e : fs::directory_iterator(runs, ec)) {
    const std::string n = e.path().filename().string();
    if (starts_with(n, ".run-") && n.size() > 8 && n.compare(n.size() - 8, 8, ".partial") == 0 && !e.is_symlink())
      fs::remove_all(e.path(), ec);
  }
}

/// The folder's run lock (one run per folder across processes), or -1 when another holds it.
int try_lock_folder(const fs::path& root) {
  const int fd = open(root.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) throw IoError("cannot open the folder " + quote(root.string()));
  if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
    close(fd);
    return -1;
  }
  return fd;
}

}  // namespace

void Studio::clean_stale_staging() {
  std::error_code ec;
  // Uploads in progress hold a lock on their file: only unlocked ones are left-overs.
  for (const auto& e : fs::directory_iterator(root_, ec)) {
    const std::string n = e.path().filename().string();
    if (!starts_with(n, ".upload-") || e.is_symlink() || !e.is_regular_file()) continue;
    const int fd = open(e.path().c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
    if (fd < 0) continue;
    if (flock(fd, LOCK_EX | LOCK_NB) == 0) fs::remove(e.path(), ec);
    close(fd);
  }
  // Run staging of a killed studio: only when no run is going in this folder.
  const int lock = try_lock_folder(root_);
  if (lock >= 0) {
    remove_run_staging(root_);
    close(lock);
  }
}

Studio::UploadFile::~UploadFile() {
  if (fd_ < 0) return;
  std::error_code ec;
  fs::remove(path_, ec);  // still here unless the upload was moved into place
  close(fd_);
}

Studio::UploadFile::UploadFile(UploadFile&& o) noexcept : path_(std::move(o.path_)), fd_(o.fd_), bytes_(o.bytes_) {
  o.fd_ = -1;
}

void Studio::UploadFile::write(const char* data, size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(fd_, data, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      throw IoError("cannot write the upload into the studio's folder: " + std::string(std::strerror(errno)));
    }
    data += w, n -= static_cast<size_t>(w), bytes_ += static_cast<size_t>(w);
  }
}

Studio::UploadFile Studio::new_upload_file(const std::string& extension) {
  static std::atomic<unsigned long> counter{0};
  std::string ext;
  for (char c : extension)
    if (std::isalnum(static_cast<unsigned char>(c)) || c == '.') ext += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  for (int attempt = 0; attempt < 100; ++attempt) {
    const fs::path path = root_ / (".upload-" + std::to_string(getpid()) + "-" + std::to_string(++counter) + ext.substr(0, 16));
    const int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0666);
    if (fd < 0) {
      if (errno == EEXIST) continue;
      throw IoError("cannot create a file for the upload in the studio's folder: " + std::string(std::strerror(errno)));
    }
    flock(fd, LOCK_EX);
    return UploadFile(path, fd);
  }
  throw IoError("cannot create a file for the upload in the studio's folder");
}

void Studio::check_upload_target(const std::string& name) const {
  check_mesh_name(name);
  std::error_code ec;
  if (fs::exists(fs::symlink_status(resolve_for_writing(root_, name), ec)))
    throw HttpError(409, quote(name) + " exists already; the studio never replaces a mesh (rename the upload)");
}

BodyLimit Studio::body_limit(const std::string& method, const std::string& path) const {
  if (method != "POST" && method != "PUT" && method != "PATCH" && method != "DELETE") return {0, false};
  if (path == "/api/upload") return {opt_.max_upload_bytes, true};
  return {opt_.max_json_bytes, false};  // JSON requests, and room for a 404/405 on anything else
}

void Studio::wait_for_run() {
  std::thread t;
  {
    std::lock_guard lock(mutex_);
    t = std::move(worker_);
  }
  if (t.joinable()) t.join();
}

void Studio::stop_run() {
  {
    std::lock_guard lock(mutex_);
    if (state_.status == "running") {
      stop_requested_ = true;
      if (child_ > 0) kill(child_, SIGTERM);
    }
  }
  // The tools clean up after SIGTERM; one that does not end within 2 s is killed.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  for (;;) {
    {
      std::lock_guard lock(mutex_);
      if (state_.status != "running") break;
      if (std::chrono::steady_clock::now() > deadline && child_ > 0) kill(child_, SIGKILL);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  wait_for_run();
}

RunState Studio::run_state() const {
  std::lock_guard lock(mutex_);
  return state_;
}

Response Studio::handle(const Request& request) {
  try {
    const CheckedRequest checked = check_request(request, opt_);
    return route(request, checked);
  } catch (const HttpError& e) {
    return error_response(e.status(), e.what());
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

Response Studio::route(const Request& r, const CheckedRequest& c) {
  using Route = CheckedRequest::Route;
  switch (c.route) {
    case Route::Meshes: return list_meshes();
    case Route::Mesh: return mesh_data(c.name);
    case Route::GetLandmarks: return get_landmarks(c.name);
    case Route::SaveLandmarks: return save_landmarks(c.name, r);
    case Route::SeedLoop: return seed_loop(c.name, r);
    case Route::Upload: return upload(c.name, r);
    case Route::RunState: return json_response(state_json(run_state()));
    case Route::StartRun: return start_run(c.run);
    case Route::Runs: return runs();
    case Route::File: return folder_file(c.name, c.download);
    case Route::Page: return static_file(c.name);
  }
  throw HttpError(404, "not found");
}

Response Studio::static_file(const std::string& p) {
  std::string rel;
  if (p == "/" || p == "/index.html") rel = "index.html";
  else if (p.rfind("/app/", 0) == 0) rel = p.substr(1);
  else if (p.rfind("/node_modules/three/", 0) == 0) rel = p.substr(1);
  else if (p == "/favicon.ico") return Response{204, "text/plain", "", {}, false};
  else throw HttpError(404, "not found: " + printable(p, 100));
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
    if (!json_strict::is_clean_text(name)) {
      // Put there by other means: listed (so that it is not a mystery) under a printable name,
      // but the page cannot name it back.
      list.push_back({{"name", printable(name)}, {"read", false}, {"accepted", false}, {"problems", json::array()},
                      {"summary", "cannot be used: the file name is not valid UTF-8 (rename the file)"}});
      continue;
    }
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
    if (rep.accepted) {
      double largest = 0;
      for (const auto& p : m->valid.mesh.positions) largest = std::max(largest, p.cwiseAbs().maxCoeff());
      if (largest > FLT_MAX) {
        const std::string words = "coordinates up to " + json_strict::describe(json(largest)) +
                                  " are beyond what the page can draw (3.4e38, single precision); the tools "
                                  "take them, the views stay empty (scale the mesh down to see it)";
        problems.push_back({{"kind", "viewer_range"}, {"severity", "note"}, {"plain", words}, {"message", words}});
      }
    }
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

Response Studio::mesh_data(const std::string& rel) {
  const fs::path file = existing(root_, rel);
  std::string out = "{\"path\":" + json_strict::dump(json(rel), -1) + ",";
  if (rel.size() > 10 && lower(rel.substr(rel.size() - 10)) == ".chart.ply") {
    const dissect::Chart chart = dissect::read_chart_ply(file);
    put_mesh(out, chart.mesh);
    out += ",\"patch\":[";
    for (size_t i = 0; i < chart.face_patch.size(); ++i) {
      if (i) out += ',';
      put_int(out, chart.face_patch[i]);
    }
    out += "],\"patches\":";
    put_int(out, static_cast<long long>(chart.patches.size()));
  } else {
    auto m = load_mesh(file);
    if (!m->read_ok) throw HttpError(400, m->read_error);
    put_mesh(out, m->read.mesh);
    out += std::string(",\"accepted\":") + (m->valid.report.accepted ? "true" : "false");
  }
  out += '}';
  Response res;
  res.body = std::move(out);
  return res;
}

Response Studio::get_landmarks(const std::string& name) {
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

Response Studio::save_landmarks(const std::string& name, const Request& r) {
  auto m = accepted_mesh(root_, name);
  const json j = parse_json_body(r, opt_.max_json_bytes);  // its shape was checked by check_request
  const std::string target = fs::path(name).stem().string() + ".landmarks.json";
  // The same reader qs-dissect uses: what it refuses is refused here, before anything is written.
  const auto lm = landmarks::parse_landmarks(r.body, landmarks::LandmarkFormat::Json, target, m->valid);
  std::lock_guard lock(write_mutex_);
  const fs::path out = resolve_for_writing(root_, target);
  write_file_atomically(out, json_strict::dump(j, 2) + "\n");
  return json_response(json{{"file", target}, {"seeds", lm.seeds.size()}, {"features", lm.features.size()}});
}

Response Studio::seed_loop(const std::string& name, const Request& r) {
  auto m = accepted_mesh(root_, name);
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

Response Studio::upload(const std::string& name, const Request& r) {
  const std::string ext = lower(fs::path(name).extension().string());
  std::optional<UploadFile> held;  // a body given in memory goes through a file too
  fs::path staged = r.body_file;
  if (staged.empty()) {
    held.emplace(new_upload_file(ext));
    held->write(r.body.data(), r.body.size());
    staged = held->path();
  }
  std::error_code ec;
  const uintmax_t bytes = fs::file_size(staged, ec);
  if (ec) throw IoError("the upload's file is gone from the studio's folder");
  if (bytes == 0) throw HttpError(400, "the upload is empty; expected the contents of a mesh file");
  if (bytes > opt_.max_upload_bytes)
    throw HttpError(413, "upload of " + std::to_string(bytes) + " bytes; at most " + std::to_string(opt_.max_upload_bytes) +
                             " are accepted");
  check_upload_target(name);
  const fs::path out = resolve_for_writing(root_, name);
  try {
    std::string bytes_read(static_cast<size_t>(bytes), '\0');
    {
      std::ifstream in(staged, std::ios::binary);
      if (!in.read(bytes_read.data(), static_cast<std::streamsize>(bytes)))
        throw IoError("cannot read the upload back from the studio's folder");
    }
    (void)io::read_mesh_from_memory(bytes_read, io::format_from_path(name), name);
  } catch (const InvalidInput& e) {
    throw HttpError(400, std::string("not a mesh file: ") + e.what());
  }
  std::lock_guard lock(write_mutex_);
  // Moved into place only if nothing has that name (never replaces, never follows a link).
  if (renameat2(AT_FDCWD, staged.c_str(), AT_FDCWD, out.c_str(), RENAME_NOREPLACE) != 0) {
    if (errno == EEXIST)
      throw HttpError(409, quote(name) + " exists already; the studio never replaces a mesh (rename the upload)");
    throw IoError("cannot move the upload into place as " + quote(name) + ": " + std::strerror(errno));
  }
  return json_response(json{{"file", name}, {"bytes", bytes}}, 201);
}

Response Studio::start_run(RunRequest req) {
  for (const auto& m : req.meshes) (void)existing(root_, m);
  for (const char* tool : {"qs-dissect", "qs-remesh", "qs-bake", "qs-morph"})
    if (access((opt_.tools_dir / tool).c_str(), X_OK) != 0)
      throw HttpError(500, std::string(tool) + " not found in " + printable(opt_.tools_dir.string()) +
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
  const int fd = try_lock_folder(root_);
  if (fd < 0) throw HttpError(409, "another qs-studio is running a job in this folder; wait until it ends");
  remove_run_staging(root_);  // left by a killed studio (nobody else can be running: we hold the lock)
  if (worker_.joinable()) worker_.join();  // the previous run's thread has finished (status is not running)
  state_ = RunState{};
  state_.name = next_run_name(run_folder_names(root_));
  state_.status = "running";
  state_.meshes = req.meshes;
  stop_requested_ = false;
  const std::string name = state_.name;
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
      {
        std::lock_guard lock(mutex_);
        if (stop_requested_) throw InvalidInput("stopped (the studio is shutting down)");
      }
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
      }, [&](pid_t pid) {
        std::lock_guard lock(mutex_);
        child_ = pid;
        if (stop_requested_) kill(pid, SIGTERM);
      }, [&] {
        std::lock_guard lock(mutex_);
        child_ = 0;
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
      // The final name: claimed with a rename that never replaces; a run-N made meanwhile (by hand)
      // moves this run to the next free number.
      std::string final_name = name;
      for (int attempt = 0;; ++attempt) {
        j["name"] = final_name;
        write_file_atomically(staging / "run.json", json_strict::dump(j, 2) + "\n");
        if (renameat2(AT_FDCWD, staging.c_str(), AT_FDCWD, (runs_dir / final_name).c_str(), RENAME_NOREPLACE) == 0) break;
        if ((errno != EEXIST && errno != ENOTEMPTY) || attempt >= 100)
          throw IoError("cannot move the run into place as runs/" + final_name + ": " + std::strerror(errno));
        final_name = next_run_name(run_folder_names(root_));
      }
      std::lock_guard lock(mutex_);
      state_.name = final_name;
    }
  } catch (const std::exception& e) {
    ok = false;
    error = std::string("the run could not be carried out: ") + e.what();
  }
  {
    std::lock_guard lock(mutex_);
    if (!ok && stop_requested_) error = "stopped: the studio was shut down during the run (nothing was kept)";
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
    std::vector<std::pair<std::string, std::string>> names;  // number, name
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      const std::string n = e.path().filename().string();
      const std::string k = run_number(n);
      if (!k.empty() && e.is_directory() && !e.is_symlink()) names.emplace_back(k, n);
    }
    std::sort(names.begin(), names.end(), [](const auto& a, const auto& b) {
      return number_less(a.first, b.first) || (a.first == b.first && a.second < b.second);
    });
    for (const auto& [k, n] : names) {
      json run = {{"name", n}, {"files", list_files(root_, dir / n)}};
      try {
        run["run"] = json_strict::parse(json_strict::read_text_file(dir / n / "run.json", "run file"), n + "/run.json");
      } catch (const Error&) {
        run["run"] = nullptr;
      }
      list.push_back(run);
    }
  }
  return json_response(json{{"runs", list}});
}

}  // namespace qs::studio
