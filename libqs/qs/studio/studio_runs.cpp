// qs-studio's runs: the tools run one after another in a staging folder under runs/, moved into
// place when all succeeded; the folder lock; the run list.
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstring>
#include <functional>
#include <cmath>
#include <map>
#include <thread>
#include <sstream>

#include "qs/core/atomic_file.h"
#include "qs/studio/studio.h"
#include "qs/studio/studio_detail.h"

extern char** environ;

namespace qs::studio {

using namespace detail;

namespace {

/// Runs argv[0] (a full path) in `cwd`, calling `out` with every chunk of its stdout and stderr.
/// `started` gets the child's pid once it runs, `ended` is called once it has exited and before its
/// pid is released (so that nobody signals a recycled pid). The child leads a process group of
/// its own (signalled as -pid). The child gets SIGTERM when the thread that started
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
    setpgid(0, 0);  // a process group of its own: a cancel stops the tool and anything it started
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
  if (pid > 0) setpgid(pid, pid);  // also here, so that the group exists whoever runs first
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

/// The phase name of qs-bake's stage once meshes are being baked (counted from its per-mesh lines).
constexpr const char* kMeshesBaked = "meshes baked";

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

json detail::state_json(const RunState& s) {
  json stages = json::array();
  for (const auto& st : s.stages) {
    json args = json::array();
    for (const auto& a : st.args) args.push_back(a);
    stages.push_back({{"name", st.name}, {"tool", st.tool}, {"args", args}, {"status", st.status},
                      {"exit_code", st.exit_code}, {"fraction", st.fraction}, {"phase", st.phase}});
  }
  std::string phase;  // what is going on, in words: "dissect: quinary subdivision"
  for (const auto& st : s.stages)
    if (st.status == "running") phase = st.name + (st.phase.empty() ? "" : ": " + st.phase);
  return json{{"name", s.name}, {"status", s.status}, {"meshes", s.meshes}, {"stages", stages},
              {"progress", s.progress}, {"phase", phase}, {"elapsed_s", s.elapsed_s},
              {"eta_s", s.eta_s}, {"verdict", s.verdict}, {"warnings", s.warnings},
              {"log", s.log}, {"error", s.error}};
}


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

void Studio::wait_for_run() {
  std::thread t;
  {
    std::lock_guard lock(mutex_);
    t = std::move(worker_);
  }
  if (t.joinable()) t.join();
}

void Studio::stop_run(bool cancel) {
  {
    std::lock_guard lock(mutex_);
    if (state_.status == "running") {
      if (!stop_requested_) stop_sent_ = std::chrono::steady_clock::now();
      stop_requested_ = true;
      cancelled_ = cancelled_ || cancel;
      if (child_ > 0) kill(-child_, SIGTERM);
    }
  }
  // The tools end at SIGTERM (the run's staging folder is removed whatever they leave); a group
  // still there after 1 s is killed.
  for (;;) {
    {
      std::lock_guard lock(mutex_);
      if (state_.status != "running") break;
      if (std::chrono::steady_clock::now() > stop_sent_ + std::chrono::seconds(1) && child_ > 0) kill(-child_, SIGKILL);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  wait_for_run();
}

Response Studio::cancel_run() {
  {
    std::lock_guard lock(mutex_);
    if (state_.status != "running") throw HttpError(409, "no run is going; there is nothing to cancel");
  }
  stop_run(true);
  return json_response(state_json(run_state()));
}

RunState Studio::run_state() const {
  std::lock_guard lock(mutex_);
  RunState s = state_;
  if (s.status == "running") {
    s.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - run_started_).count();
    // The time left at the pace so far, once there is a pace to go by.
    if (s.progress >= 0.02 && s.elapsed_s >= 0.5) s.eta_s = s.elapsed_s * (1 - s.progress) / s.progress;
  }
  return s;
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
  cancelled_ = false;
  run_started_ = std::chrono::steady_clock::now();
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
    // Shares of the overall progress, from the time each stage takes on the examples.
    const std::map<std::string, double> share = {{"dissect", 0.5}, {"remesh", 0.1}, {"bake", 0.25}, {"morph", 0.15}};
    double total = 0;
    for (const auto& st : stages) total += share.at(st.name);
    for (auto& st : stages) st.weight = share.at(st.name) / total;
  }
  // The overall progress: done stages count their weight, the running one its weight times an
  // estimate that only grows: each new phase of its tool takes a part of what is left (a tool
  // does not say how many phases it has). Never lowered.
  auto advance = [&](size_t i) {
    double base = 0;
    for (size_t k = 0; k < i; ++k) base += state_.stages[k].weight;
    const RunStage& st = state_.stages[i];
    double within = 0;
    if (st.status == "done") within = 1;
    else if (st.phase == kMeshesBaked) within = st.fraction;  // a count, not a phase
    else if (st.phases > 0) within = 1 - std::pow(0.7, st.phases - 1) * (1 - 0.3 * st.fraction);
    state_.progress = std::clamp(std::max(state_.progress, base + st.weight * within), 0.0, 1.0);
  };
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
          if (stages[i].name == "bake") {
            // qs-bake prints no percentages but a line per mesh as it is baked ("  spot_2k: bake 0.05 s"):
            // the share of meshes done (the maps are written after the last).
            for (const auto& m : req.meshes)
              if (line.rfind("  " + fs::path(m).stem().string() + ": bake ", 0) == 0) {
                std::lock_guard lock(mutex_);
                RunStage& st = state_.stages[i];
                st.phases = 1;
                st.phase = kMeshesBaked;
                st.fraction = std::min(1.0, st.fraction + 1.0 / static_cast<double>(req.meshes.size() + 1));
                advance(i);
                break;
              }
          }
          if (line.rfind(prefix, 0) != 0 || line.back() != '%' || k == line.size() - 1) {
            append(line + "\n");
            continue;
          }
          try {
            const double f = std::stod(line.substr(k, line.size() - 1 - k)) / 100;
            std::string phase = line.substr(prefix.size(), k - prefix.size());
            while (!phase.empty() && phase.back() == ' ') phase.pop_back();
            std::lock_guard lock(mutex_);
            RunStage& st = state_.stages[i];
            if (st.phases == 0 || phase != st.phase) ++st.phases;
            st.phase = phase;
            st.fraction = std::clamp(f, 0.0, 1.0);
            advance(i);
          } catch (const std::exception&) {
            append(line + "\n");
          }
        }
      }, [&](pid_t pid) {
        std::lock_guard lock(mutex_);
        child_ = pid;
        if (stop_requested_) kill(-pid, SIGTERM);
      }, [&] {
        std::lock_guard lock(mutex_);
        child_ = 0;
      });
      if (scanned < stage_out.size()) append(stage_out.substr(scanned) + "\n");  // a last line without '\n'
      std::lock_guard lock(mutex_);
      state_.stages[i].exit_code = code;
      state_.stages[i].status = code == 0 ? "done" : "failed";
      if (code == 0) {
        state_.stages[i].fraction = 1;
        state_.stages[i].phase.clear();
        advance(i);
      }
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
      std::string log;
      {
        std::lock_guard lock(mutex_);
        log = state_.log;
      }
      const std::vector<std::string> warnings = judge_run(staging, level_dir, log);
      const std::string verdict = warnings.empty() ? "done" : "done with warnings";
      json j = {{"format", "qs-studio-run"}, {"version", 1}, {"name", name}, {"meshes", req.meshes},
                {"level", req.level}, {"bake_size", req.bake_size}, {"max_area", req.max_area},
                {"verdict", verdict}, {"warnings", warnings}};
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
      state_.verdict = verdict;
      state_.warnings = warnings;
    }
  } catch (const std::exception& e) {
    ok = false;
    error = std::string("the run could not be carried out: ") + e.what();
  }
  {
    std::lock_guard lock(mutex_);
    if (!ok && stop_requested_)
      error = cancelled_ ? "cancelled: the run was stopped from the page (nothing was kept)"
                         : "stopped: the studio was shut down during the run (nothing was kept)";
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
  state_.status = ok ? "done" : cancelled_ && stop_requested_ ? "cancelled" : "failed";
  if (ok) state_.progress = 1;
  state_.error = error;
  state_.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - run_started_).count();
  state_.eta_s = ok ? 0 : -1;
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

namespace {

/// A tool's JSON report in a run, or null when it is missing or unreadable (judged as "not known").
nlohmann::json read_report(const fs::path& file) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) return nullptr;
  try {
    return nlohmann::json::parse(json_strict::read_text_file(file, "report"));
  } catch (const std::exception&) {
    return nullptr;
  }
}

double number_at(const nlohmann::json& j, const char* key, double otherwise) {
  return j.is_object() && j.contains(key) && j[key].is_number() ? j[key].get<double>() : otherwise;
}

std::string text_at(const nlohmann::json& j, const char* key) {
  return j.is_object() && j.contains(key) && j[key].is_string() ? j[key].get<std::string>() : std::string();
}

std::string figure(double x, int digits = 3) {
  std::ostringstream s;
  s.precision(digits);
  s << x;
  return s.str();
}

}  // namespace

std::vector<std::string> judge_run(const fs::path& run_dir, const std::string& remesh_dir, const std::string& log) {
  std::vector<std::string> out;
  auto add = [&](const std::string& w) {
    if (std::find(out.begin(), out.end(), w) == out.end()) out.push_back(w);
  };
  // The tools' own warnings ("qs-dissect: warning: no seeds given; ...").
  std::istringstream in(log);
  for (std::string line; std::getline(in, line);) {
    const size_t at = line.find(": warning: ");
    if (line.rfind("qs-", 0) == 0 && at != std::string::npos && at < 16)
      add(line.substr(0, at) + ": " + line.substr(at + 11));
  }
  const nlohmann::json d = read_report(run_dir / "dissection" / "dissection.json");
  if (d.is_object() && d.contains("meshes") && d["meshes"].is_array()) {
    const double tau = d.contains("options") ? number_at(d["options"], "tau", 3) : 3;
    for (const auto& m : d["meshes"]) {
      const std::string stem = fs::path(text_at(m, "file")).stem().string();
      const int over = static_cast<int>(number_at(m, "patches_over_tau", 0));
      const double stretch = number_at(m, "max_stretch", 0);
      double faces = 0, over_faces = 0;
      long folds = 0;
      if (m.contains("patches") && m["patches"].is_array())
        for (const auto& p : m["patches"]) {
          faces += number_at(p, "faces", 0);
          if (p.is_object() && p.contains("stop_reason")) over_faces += number_at(p, "faces", 0);
          folds += static_cast<long>(number_at(p, "flipped_faces", 0));
        }
      // A few small patches a little over tau are usual; a large share, or a stretch far over
      // tau, shows in the textures and remesh cells.
      const double share = faces > 0 ? over_faces / faces : 0;
      if (stretch > 3 * tau || share > 0.12)
        add(stem + ": " + std::to_string(over) + " patches left over the stretch limit tau " + figure(tau) + ", " +
            "holding " + figure(100 * share, 2) + "% of the triangles, largest stretch " + figure(stretch, 4) +
            ": textures and remesh cells are distorted there");
      if (folds > 0)
        add(stem + ": " + std::to_string(folds) + " folded triangles in the patch maps (the remesh crumples there)");
    }
    // Many patches: the dissection kept splitting to fit shapes that do not correspond well.
    const size_t patches = d.contains("base_domain") && d["base_domain"].is_object() &&
                                   d["base_domain"].contains("patches") && d["base_domain"]["patches"].is_array()
                               ? d["base_domain"]["patches"].size()
                               : 0;
    if (patches > 120)
      add(std::to_string(patches) + " patches (more than 120): the shapes were hard to map onto each other; "
          "seeds at corresponding places usually need far fewer");
  }
  const nlohmann::json r = read_report(run_dir / remesh_dir / "remesh.json");
  if (r.is_object() && r.contains("meshes") && r["meshes"].is_array())
    for (const auto& m : r["meshes"]) {
      const std::string stem = fs::path(text_at(m, "output")).stem().string();
      if (!m.contains("angles")) continue;
      const double min_deg = number_at(m["angles"], "min_deg", 90), under5 = number_at(m["angles"], "under_5_deg", 0);
      if (min_deg < 0.25 || under5 > 0.02)
        add(stem + ": thin triangles in the remesh (smallest angle " + figure(min_deg, 2) + " deg, " +
            figure(100 * under5, 2) + "% under 5 deg)");
    }
  const nlohmann::json b = read_report(run_dir / "bake" / "bake.json");
  if (b.is_object() && b.contains("meshes") && b["meshes"].is_array())
    for (const auto& m : b["meshes"]) {
      if (!m.contains("shading")) continue;
      const std::string stem = fs::path(text_at(m, "glb")).stem().string();
      const double with = number_at(m["shading"], "mean_deg_with_map", 0);
      if (with > 5)
        add(stem + ": the normal map misses the original's shading by " + figure(with, 3) +
            " deg on average (more than 5)");
    }
  return out;
}

/// runs/<name> as a plain folder of the studio's folder (never through a link); 404 when missing.
static fs::path run_folder(const fs::path& root, const std::string& name) {
  std::error_code ec;
  const fs::path runs = root / "runs", dir = runs / name;
  const auto rs = fs::symlink_status(runs, ec);
  const auto ds = fs::symlink_status(dir, ec);
  if (!fs::is_directory(rs) || fs::is_symlink(rs) || !fs::is_directory(ds) || fs::is_symlink(ds))
    throw HttpError(404, "there is no run " + quote(name) + " in runs/");
  return dir;
}

Response Studio::delete_run(const std::string& name) {
  const fs::path dir = run_folder(root_, name);
  // The run lock: no run of this or another studio moves a run into place meanwhile.
  const int fd = try_lock_folder(root_);
  if (fd < 0) throw HttpError(409, "a run is going in this folder; delete runs once it has ended");
  std::error_code ec;
  fs::remove_all(dir, ec);  // removes links inside, never what they point to
  flock(fd, LOCK_UN);
  close(fd);
  if (ec) throw IoError("cannot remove runs/" + name + ": " + ec.message());
  return json_response(json{{"removed", name}});
}

Response Studio::run_archive(const std::string& name) {
  const fs::path dir = run_folder(root_, name);
  Response res;
  for (const auto& f : list_files(root_, dir))
    res.archive.emplace_back(f["path"].get<std::string>().substr(5), root_ / f["path"].get<std::string>());  // "runs/" off
  if (res.archive.empty()) throw HttpError(404, "run " + quote(name) + " holds no files");
  res.download_name = name + ".tar";
  res.content_type = "application/x-tar";
  return res;
}

}  // namespace qs::studio
