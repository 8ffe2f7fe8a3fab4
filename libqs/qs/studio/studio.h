#pragma once
// qs-studio's request handling, independent of the HTTP library: a Request in, a Response out.
// tools/qs-studio.cpp puts it behind cpp-httplib (qs/studio/server.h); tests call it directly.
//
// Routes (every path and name is checked by the rules of qs/studio/paths.h):
//   GET  /                          the page (web/studio/index.html); /app/* and /node_modules/three/*
//                                   are the page's scripts (served from the web folder)
//   GET  /api/meshes                the meshes of the folder with their validation in plain words
//   GET  /api/mesh?path=P           a mesh as JSON {positions, faces[, patch]}: faces as in the file
//                                   (ids that landmark files refer to); a .chart.ply adds its patches
//   GET  /api/landmarks?name=M      the landmarks beside mesh M (.landmarks.json or MeshLab .pp) as
//                                   exact {"face","bary"} references of the file as written
//   POST /api/landmarks?name=M      checks the landmark JSON in the body as qs-dissect would and
//                                   writes <stem>.landmarks.json atomically
//   POST /api/seed-loop?name=M      the seed loop qs-dissect would route for the body's seeds and
//                                   features: four polylines of 3D points
//   POST /api/upload?name=F         a new mesh file (must parse as its extension says; never
//                                   replaces a file)
//   POST /api/run                   starts a run (dissect, remesh, bake, morph) in the background
//   GET  /api/run                   the current or last run: stage, progress, log, error
//   GET  /api/runs                  the finished runs with their files
//   GET  /files/P                   any file of the folder (downloads, GLBs for the viewer)
// Errors are JSON {"error": message} with 400 (bad request), 404 (not found), 405, 409 (a run is
// going, a file exists), 413 (too large) or 500 (a bug).

#include <atomic>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace qs::studio {

struct StudioOptions {
  std::filesystem::path folder;    ///< the meshes; everything the studio writes goes here
  std::filesystem::path web_dir;   ///< the page (index.html, app/, node_modules/three)
  std::filesystem::path tools_dir; ///< qs-dissect, qs-remesh, qs-bake, qs-morph
  size_t max_upload_bytes = 256u << 20;   ///< a mesh upload (256 MiB)
  size_t max_json_bytes = 1u << 20;       ///< landmark, seed-loop and run requests (1 MiB)
  int max_meshes_per_run = 8;
};

struct Request {
  std::string method;  ///< "GET", "POST", ...
  std::string path;    ///< decoded URL path, e.g. "/api/mesh"
  std::map<std::string, std::string> query;
  std::string body;
};

struct Response {
  int status = 200;
  std::string content_type = "application/json; charset=utf-8";  ///< not compressed by the server
  std::string body;
  std::filesystem::path file;  ///< when set, the body is this file's contents (served by the server)
  bool attachment = false;     ///< Content-Disposition: attachment (download links)
};

/// What a run does; parsed from POST /api/run's JSON: {"meshes": [names...], "level": 3,
/// "bake_size": 128, "max_area": 0.15, "morph": true}.
struct RunRequest {
  std::vector<std::string> meshes;  ///< file names in the folder, in set order (seeds correspond by order)
  int level = 3;                    ///< qs-remesh --level (0..6)
  int bake_size = 128;              ///< qs-bake --size (16..2048)
  double max_area = 0.15;           ///< qs-dissect --max-area (0: off; 0.15 is its default)
  bool morph = true;                ///< qs-morph GLB when there are two meshes or more
};

/// One stage of a run: a tool and its arguments.
struct RunStage {
  std::string name;   ///< "dissect", "remesh", "bake", "morph"
  std::string tool;   ///< "qs-dissect" ...
  std::vector<std::string> args;
  std::string status = "waiting";  ///< waiting, running, done, failed
  int exit_code = -1;
  double fraction = 0;  ///< of the running stage, from the tool's "<tool>: <what> NN%" lines (qs-dissect)
};

struct RunState {
  std::string name;            ///< runs/<name> once it succeeded
  std::string status = "idle"; ///< idle, running, done, failed
  std::vector<RunStage> stages;
  std::string log;             ///< the tools' stdout and stderr, as they wrote them
  std::string error;           ///< the failing tool's error lines
  std::vector<std::string> meshes;
};

class Studio {
 public:
  /// \throws IoError when the folder does not exist; InvalidInput when it is not a folder.
  explicit Studio(StudioOptions options);
  ~Studio();  ///< waits for a run in progress
  Studio(const Studio&) = delete;
  Studio& operator=(const Studio&) = delete;

  Response handle(const Request& request);

  const std::filesystem::path& folder() const { return root_; }
  /// Blocks until the current run (if any) has finished. For tests and shutdown.
  void wait_for_run();
  RunState run_state() const;

 private:
  Response route(const Request& request);
  Response list_meshes();
  Response mesh_data(const Request& request);
  Response get_landmarks(const Request& request);
  Response save_landmarks(const Request& request);
  Response seed_loop(const Request& request);
  Response upload(const Request& request);
  Response start_run(const Request& request);
  Response runs();
  Response static_file(const std::string& path);
  Response folder_file(const std::string& rel, bool download);
  void run_thread(RunRequest request, std::string name, int lock_fd);

  StudioOptions opt_;
  std::filesystem::path root_, web_root_;
  mutable std::mutex mutex_;
  std::mutex write_mutex_;  ///< one landmark save or upload at a time (their temporary names are per process)
  RunState state_;
  std::thread worker_;
};

/// Parses and checks POST /api/run's body. \throws InvalidInput naming the field.
RunRequest parse_run_request(const std::string& json, int max_meshes);

/// The person-readable summary of a mesh's validation, e.g. "ready: a closed surface in one piece
/// without handles" or "rejected: the surface has holes (it is not closed)".
std::string plain_summary(const std::string& kind);

}  // namespace qs::studio
