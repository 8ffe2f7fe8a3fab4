#include "qs/studio/studio.h"

#include <fcntl.h>
#include <stdio.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cfloat>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <optional>

#include "qs/core/atomic_file.h"
#include "qs/dissect/chart_io.h"
#include "qs/dissect/seed_loop.h"
#include "qs/io/read_mesh.h"
#include "qs/landmarks/landmarks.h"
#include "qs/mesh/validate.h"
#include "qs/studio/studio_detail.h"

namespace qs::studio {

using namespace detail;

namespace {

Response error_response(int status, const std::string& message) {
  return json_response(json{{"error", message}}, status);
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

}  // namespace

std::string plain_summary(const std::string& kind) {
  auto it = plain_words().find(kind);
  return it == plain_words().end() ? kind : it->second;
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
    case Route::DeleteMesh: return delete_mesh(c.name);
    case Route::RunState: return json_response(state_json(run_state()));
    case Route::StartRun: return start_run(c.run);
    case Route::CancelRun: return cancel_run();
    case Route::Runs: return runs();
    case Route::DeleteRun: return delete_run(c.name);
    case Route::RunArchive: return run_archive(c.name);
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
          json names = json::array();
          for (const auto& f : l.features) names.push_back(f.name);
          lm["feature_names"] = names;
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

Response Studio::delete_mesh(const std::string& name) {
  {
    std::lock_guard lock(mutex_);
    if (state_.status == "running" && std::find(state_.meshes.begin(), state_.meshes.end(), name) != state_.meshes.end())
      throw HttpError(409, quote(name) + " is used by the run in progress; cancel it or wait until it ends");
  }
  // The name itself is removed (a link is removed, never what it points to); its landmark files stay.
  const fs::path file = root_ / name;
  (void)existing(root_, name);
  std::lock_guard lock(write_mutex_);
  std::error_code ec;
  if (!fs::remove(file, ec) || ec)
    throw IoError("cannot remove " + quote(name) + (ec ? ": " + ec.message() : std::string()));
  return json_response(json{{"removed", name}});
}

}  // namespace qs::studio
