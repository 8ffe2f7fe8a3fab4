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
//   POST /api/upload?name=F         a new mesh file: the raw body, or one file of a multipart form
//                                   (F defaults to its file name); must parse as its extension says;
//                                   never replaces a file
//   DELETE /api/meshes?name=M       removes mesh M from the folder (not while a run uses it)
//   POST /api/run                   starts a run (dissect, remesh, bake, morph) in the background
//   GET  /api/run                   the current or last run: stages, overall progress (never
//                                   decreasing), phase, elapsed and estimated time left, log, error,
//                                   and once done its verdict and warnings
//   POST /api/run/cancel            stops the run in progress: its tools' process group gets SIGTERM
//                                   (SIGKILL after 1 s), its staging folder is removed; answers
//                                   once the run has ended
//   GET  /api/runs                  the finished runs with their files (and run.json: verdict, warnings)
//   DELETE /api/runs?name=run-N     removes runs/run-N
//   GET  /api/run-archive?name=run-N  runs/run-N as one uncompressed tar file (a download)
//   GET  /files/P                   any file of the folder (downloads, GLBs for the viewer)
// Errors are JSON {"error": message} with 400 (bad request), 403 (a path rule), 404 (not found),
// 405, 409 (a run is going, a file exists), 413 (too large) or 500 (a bug, or a missing tool;
// never for a malformed request). Messages quote request text only as short, printable excerpts.

#include <atomic>
#include <chrono>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <sys/types.h>

#include "qs/core/error.h"

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
  /// An upload streamed to disk by the server (a file from Studio::new_upload_file()) instead of
  /// `body`; handle() moves it into place when it is accepted, its UploadFile removes it otherwise.
  std::filesystem::path body_file{};
  std::string body_file_name{};  ///< the file name a multipart form gave for it (used when ?name= is absent)
};

/// A refusal with its HTTP status (4xx: the request; 5xx: the server's own state).
class HttpError : public Error {
 public:
  HttpError(int status, const std::string& message)
      : Error(status < 500 ? ErrorCode::InvalidInput : ErrorCode::Internal, message), status_(status) {}
  int status() const { return status_; }

 private:
  int status_;
};

/// The request bodies a route accepts, from its method and path alone (checked from the headers
/// before any byte of the body is read).
struct BodyLimit {
  size_t bytes = 0;     ///< the largest body accepted (413 beyond)
  bool upload = false;  ///< a mesh upload: streamed to a file, raw or multipart/form-data
};

struct Response {
  int status = 200;
  std::string content_type = "application/json; charset=utf-8";  ///< not compressed by the server
  std::string body;
  std::filesystem::path file;  ///< when set, the body is this file's contents (served by the server)
  bool attachment = false;     ///< Content-Disposition: attachment (download links)
  /// When not empty, the body is a tar file of these files (name in the archive, file), streamed
  /// by the server from the disk (TarLayout); `download_name` names it.
  std::vector<std::pair<std::string, std::filesystem::path>> archive{};
  std::string download_name{};
};

/// The byte layout of an uncompressed POSIX tar (ustar, with GNU long-name records for names over
/// 100 bytes) of regular files, sized up front so that it can be streamed in pieces.
class TarLayout {
 public:
  /// Reads each file's size and modification time. \throws IoError when one cannot be read.
  explicit TarLayout(const std::vector<std::pair<std::string, std::filesystem::path>>& files);
  size_t size() const { return size_; }
  /// Writes up to `n` bytes of the archive from `offset` into `out`; returns how many (0 at the
  /// end, or when a file has shrunk since it was measured).
  size_t read(size_t offset, char* out, size_t n) const;

 private:
  struct Segment {
    size_t begin = 0, size = 0;
    std::string bytes;           ///< a header (or long-name record), padding or the end marker
    std::filesystem::path file;  ///< else: a file's contents
  };
  std::vector<Segment> segments_;
  size_t size_ = 0;
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

/// A request checked without touching the file system: the route, its names (path syntax, mesh
/// names, UTF-8), the body's size and, for JSON bodies, strict JSON (depth, duplicate keys, finite
/// numbers, integer ranges, known keys). Studio::handle checks every request this way first.
struct CheckedRequest {
  enum class Route {
    Page, Meshes, Mesh, GetLandmarks, SaveLandmarks, SeedLoop, Upload, DeleteMesh,
    RunState, StartRun, CancelRun, Runs, DeleteRun, RunArchive, File
  };
  Route route = Route::Page;
  std::string name;       ///< mesh name (landmarks, seed loop, upload, delete), run name (delete,
                          ///< archive), relative path (mesh, file), URL path (page)
  bool download = false;  ///< GET /files/P?download=1
  RunRequest run;         ///< POST /api/run
};

/// One stage of a run: a tool and its arguments.
struct RunStage {
  std::string name;   ///< "dissect", "remesh", "bake", "morph"
  std::string tool;   ///< "qs-dissect" ...
  std::vector<std::string> args;
  std::string status = "waiting";  ///< waiting, running, done, failed
  int exit_code = -1;
  double fraction = 0;  ///< of the running stage, from the tool's "<tool>: <what> NN%" lines (qs-dissect)
  double weight = 0;    ///< the stage's share of the run's overall progress
  int phases = 0;       ///< the tool's phases seen so far (a new "<what>" in its progress lines)
  std::string phase{};  ///< the tool's current phase ("quinary subdivision")
};

struct RunState {
  std::string name;            ///< runs/<name> once it succeeded
  std::string status = "idle"; ///< idle, running, done, failed, cancelled
  /// The overall fraction done, 0..1: done stages count their weight, the running one its weight
  /// times an estimate from its tool's phases; never decreases during a run.
  double progress = 0;
  double elapsed_s = 0;        ///< since the run started (to its end once it ended)
  double eta_s = -1;           ///< estimated seconds left (-1: not known yet)
  std::string verdict;         ///< once done: "done" or "done with warnings"
  std::vector<std::string> warnings;  ///< why "done with warnings", in plain words
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

  /// A new, empty, exclusively locked file in the folder to stream an upload into (hidden, never
  /// listed or served; `extension` keeps the format); removed by its destructor unless handle()
  /// took it. Left-over ones of a killed studio are removed when the next one starts.
  class UploadFile {
   public:
    ~UploadFile();
    UploadFile(UploadFile&&) noexcept;
    UploadFile& operator=(UploadFile&&) = delete;
    /// Appends bytes. \throws IoError (disk full ...).
    void write(const char* data, size_t n);
    size_t bytes() const { return bytes_; }
    const std::filesystem::path& path() const { return path_; }

   private:
    friend class Studio;
    UploadFile(std::filesystem::path path, int fd) : path_(std::move(path)), fd_(fd) {}
    std::filesystem::path path_;
    int fd_ = -1;
    size_t bytes_ = 0;
  };
  UploadFile new_upload_file(const std::string& extension);

  /// Refuses (HttpError 409, PathRefused) an upload name that is taken or cannot be written, so
  /// that the server can say so before it reads the body. The upload checks again when it ends.
  void check_upload_target(const std::string& name) const;

  /// The body limit of a route (for the server, before it reads a body).
  BodyLimit body_limit(const std::string& method, const std::string& path) const;

  /// Stops the run in progress: its tool's process group gets SIGTERM (SIGKILL after 1 s), the
  /// run ends "failed" (a shutdown) or "cancelled" with nothing left in runs/; returns once it
  /// has ended.
  void stop_run(bool cancel = false);

  const std::filesystem::path& folder() const { return root_; }
  const StudioOptions& options() const { return opt_; }
  /// Blocks until the current run (if any) has finished. For tests and shutdown.
  void wait_for_run();
  RunState run_state() const;

 private:
  Response route(const Request& request, const CheckedRequest& checked);
  Response list_meshes();
  Response mesh_data(const std::string& rel);
  Response get_landmarks(const std::string& name);
  Response save_landmarks(const std::string& name, const Request& request);
  Response seed_loop(const std::string& name, const Request& request);
  Response upload(const std::string& name, const Request& request);
  Response delete_mesh(const std::string& name);
  Response start_run(RunRequest request);
  Response cancel_run();
  Response delete_run(const std::string& name);
  Response run_archive(const std::string& name);
  void clean_stale_staging();
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
  pid_t child_ = 0;           ///< the running tool, leader of its own process group (guarded by mutex_)
  bool stop_requested_ = false;
  bool cancelled_ = false;    ///< stopped from the page (not by a shutdown)
  std::chrono::steady_clock::time_point run_started_{}, stop_sent_{};
};

/// Parses and checks POST /api/run's body. \throws InvalidInput naming the field.
RunRequest parse_run_request(const std::string& json, int max_meshes);

/// The checks of CheckedRequest. Pure (no file system, no state). \throws HttpError (4xx),
/// PathRefused (403) or InvalidInput (400) with a printable message; never anything else.
CheckedRequest check_request(const Request& request, const StudioOptions& options);

/// The run folder name after the given ones: "run-" + (largest number + 1), for numbers of any
/// length (decimal strings, never overflowing); names that are not run-<digits> are ignored.
std::string next_run_name(const std::vector<std::string>& existing);
/// The number of a run folder name as a decimal string without leading zeros, or "" when the name
/// is not run-<digits>. Runs sort by (length, string) of this.
std::string run_number(const std::string& name);

/// The warnings of a finished run, in plain words, from its tools' reports in `run_dir`
/// (dissection/dissection.json, <remesh>/remesh.json, bake/bake.json) and the "<tool>: warning:"
/// lines of `log`: patches left over tau, high stretch, folds, thin triangles, a poor shading
/// match, automatic seeds. Empty for a result without known faults.
std::vector<std::string> judge_run(const std::filesystem::path& run_dir, const std::string& remesh_dir,
                                   const std::string& log);

/// The person-readable summary of a mesh's validation, e.g. "ready: a closed surface in one piece
/// without handles" or "rejected: the surface has holes (it is not closed)".
std::string plain_summary(const std::string& kind);

}  // namespace qs::studio
