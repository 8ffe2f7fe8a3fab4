#include "qs/core/output_folder.h"

#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <fstream>
#include <sstream>
#include <system_error>

#include "qs/core/error.h"

namespace qs {

namespace fs = std::filesystem;

namespace {

std::string why(const std::error_code& ec) { return ec ? " (" + ec.message() + ")" : std::string(); }

std::string staging_suffix() { return ".tmp-" + std::to_string(::getpid()); }

// When process `pid` started, in seconds since the epoch; false when /proc cannot tell (the
// process is then taken to be the entry's owner). Also false for a zombie, reported in `zombie`.
bool process_start(pid_t pid, double& seconds, bool& zombie) {
  zombie = false;
  std::ifstream stat_file("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!std::getline(stat_file, line)) return false;
  const auto close = line.rfind(')');  // the command name may hold spaces and parentheses
  if (close == std::string::npos) return false;
  std::istringstream fields(line.substr(close + 1));
  std::string state;
  fields >> state;  // field 3
  if (state == "Z" || state == "X") {
    zombie = true;
    return false;
  }
  std::string skip;
  for (int field = 4; field < 22; ++field) fields >> skip;
  unsigned long long ticks = 0;
  if (!(fields >> ticks)) return false;  // field 22: start time in clock ticks after boot
  std::ifstream proc_stat("/proc/stat");
  long long boot = -1;
  for (std::string key; proc_stat >> key;) {
    if (key == "btime") {
      proc_stat >> boot;
      break;
    }
    std::getline(proc_stat, key);
  }
  const long hz = ::sysconf(_SC_CLK_TCK);
  if (boot < 0 || hz <= 0) return false;
  seconds = static_cast<double>(boot) + static_cast<double>(ticks) / static_cast<double>(hz);
  return true;
}

// The process id of a staging name "<prefix><digits>", or 0 when `name` is not one.
pid_t staging_pid(const std::string& name, const std::string& prefix) {
  if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) return 0;
  const std::string digits = name.substr(prefix.size());
  if (digits.size() > 9 || digits[0] == '0') return 0;
  for (char c : digits)
    if (c < '0' || c > '9') return 0;
  return static_cast<pid_t>(std::stol(digits));
}

}  // namespace

bool staging_owner_running(pid_t pid, fs::file_time_type modified) {
  if (pid == ::getpid()) return true;
  if (pid <= 0) return true;  // not a process id: never ours to remove
  if (::kill(pid, 0) != 0 && errno == ESRCH) return false;
  // The id is in use (EPERM: by another user). It may have been reused by a process that
  // started after the entry was last changed: that one cannot be writing it.
  double started = 0;
  bool zombie = false;
  if (!process_start(pid, started, zombie)) return !zombie;
  const auto changed = std::chrono::duration<double>(
      std::chrono::file_clock::to_sys(modified).time_since_epoch()).count();
  return !(started > changed + 60.0);
}

int remove_stale_staging(const fs::path& target, bool folders) {
  fs::path t = target;
  if (!t.has_filename()) t = t.parent_path();
  if (t.empty()) return 0;
  fs::path dir = t.parent_path();
  if (dir.empty()) dir = ".";
  const std::string prefix = t.filename().string() + ".tmp-";
  std::error_code ec;
  std::vector<fs::path> stale;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const pid_t pid = staging_pid(it->path().filename().string(), prefix);
    if (pid <= 0) continue;
    struct stat st;
    if (::lstat(it->path().c_str(), &st) != 0 || st.st_uid != ::geteuid()) continue;
    if (folders ? !S_ISDIR(st.st_mode) : !S_ISREG(st.st_mode)) continue;
    std::error_code tec;
    const auto modified = fs::last_write_time(it->path(), tec);
    if (tec || staging_owner_running(pid, modified)) continue;
    stale.push_back(it->path());
  }
  int removed = 0;
  for (const auto& p : stale) {
    std::error_code rec;
    if (folders)
      fs::remove_all(p, rec);
    else
      fs::remove(p, rec);
    if (!rec) ++removed;
  }
  return removed;
}

OutputFolder::OutputFolder(fs::path target) : target_(std::move(target)) {
  if (target_.empty()) throw IoError("the output folder name is empty");
  // "out/" names the folder "out": drop a trailing separator so that the staging name is a sibling.
  if (!target_.has_filename()) target_ = target_.parent_path();
  fs::path parent = target_.parent_path();
  if (parent.empty()) parent = ".";
  prepare(parent);
  staging_ = parent / (target_.filename().string() + staging_suffix());
  remove_stale_staging(target_, true);
  std::error_code ec;
  fs::remove_all(staging_, ec);  // a leftover of an earlier run with the same process id
  if (!fs::create_directory(staging_, ec) || ec) {
    const std::string reason = why(ec);
    for (const auto& made : created_parents_) fs::remove(made, ec);
    throw IoError(target_.string() + ": cannot create a folder beside it" + reason);
  }
}

OutputFolder::OutputFolder(fs::path folder, const std::string& name) : target_(std::move(folder)), inside_(true) {
  if (name.empty() || name == "." || name == ".." || fs::path(name).has_parent_path())
    throw IoError("the output file name \"" + name + "\" is not a file name");
  if (target_.empty()) target_ = ".";
  if (!target_.has_filename()) target_ = target_.parent_path();
  prepare(target_);
  staging_ = target_ / (name + staging_suffix());
  remove_stale_staging(target_ / name, true);
  std::error_code ec;
  fs::remove_all(staging_, ec);
  if (!fs::create_directory(staging_, ec) || ec) {
    const std::string reason = why(ec);
    for (const auto& made : created_parents_) fs::remove(made, ec);
    throw IoError((target_ / name).string() + ": cannot create a folder beside it" + reason);
  }
}

// Checks the target and creates `folder_to_create` with its missing parents, remembering them
// for the clean-up after a failure.
void OutputFolder::prepare(const fs::path& folder_to_create) {
  std::error_code ec;
  const auto st = fs::status(target_, ec);
  if (fs::exists(st) && !fs::is_directory(st))
    throw IoError(target_.string() + ": exists and is not a folder; -o needs a folder (or a new name)");
  std::vector<fs::path> missing;
  for (fs::path p = folder_to_create; !p.empty() && !fs::exists(fs::symlink_status(p, ec)); p = p.parent_path()) {
    missing.push_back(p);
    if (p == p.parent_path()) break;
  }
  for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
    if (!fs::create_directory(*it, ec) || ec) {
      for (const auto& made : created_parents_) fs::remove(made, ec);
      throw IoError(target_.string() + ": cannot create the folder " + it->string() + why(ec));
    }
    created_parents_.insert(created_parents_.begin(), *it);
  }
  if (!fs::is_directory(folder_to_create, ec)) {
    for (const auto& made : created_parents_) fs::remove(made, ec);
    throw IoError(target_.string() + ": cannot create the folder: " + folder_to_create.string() + " is not a folder");
  }
  if (fs::exists(fs::status(target_, ec)) && ::access(target_.c_str(), W_OK | X_OK) != 0) {
    for (const auto& made : created_parents_) fs::remove(made, ec);
    throw IoError(target_.string() + ": the output folder is not writable");
  }
}

OutputFolder::~OutputFolder() {
  if (committed_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);
  for (const auto& p : created_parents_) fs::remove(p, ec);  // only if empty: deepest first
}

void OutputFolder::commit() {
  std::error_code ec;
  if (!inside_ && !fs::exists(fs::symlink_status(target_, ec))) {
    fs::rename(staging_, target_, ec);
    if (ec) throw IoError(target_.string() + ": cannot move the finished folder into place" + why(ec));
    committed_ = true;
    return;
  }
  if (!fs::is_directory(target_, ec))
    throw IoError(target_.string() + ": exists and is not a folder");
  // Every staged name must be placeable before any is moved: a folder in the way stops the run.
  std::vector<fs::path> names;
  for (const auto& e : fs::directory_iterator(staging_, ec)) names.push_back(e.path().filename());
  if (ec) throw IoError(staging_.string() + ": cannot list the staged files" + why(ec));
  for (const auto& n : names) {
    const auto st = fs::symlink_status(target_ / n, ec);
    if (fs::is_directory(st) && !fs::is_directory(staging_ / n))
      throw IoError((target_ / n).string() + ": is a folder; cannot replace it with a file");
  }
  for (const auto& n : names) {
    fs::rename(staging_ / n, target_ / n, ec);
    if (ec) throw IoError((target_ / n).string() + ": cannot move the finished file into place" + why(ec));
  }
  fs::remove_all(staging_, ec);
  committed_ = true;
}

void check_not_an_input(const fs::path& output, const std::vector<fs::path>& inputs, const std::string& option) {
  std::error_code ec;
  for (const auto& in : inputs) {
    bool same = fs::exists(output, ec) && fs::exists(in, ec) && fs::equivalent(output, in, ec);
    if (!same) same = fs::weakly_canonical(output, ec) == fs::weakly_canonical(in, ec) && !ec;
    if (same)
      throw UsageError(option + " " + output.string() + " is an input of this run (" + in.string() +
                       "); write the output somewhere else");
  }
}

}  // namespace qs
