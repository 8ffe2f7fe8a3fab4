#include "qs/core/output_folder.h"

#include <unistd.h>

#include <system_error>

#include "qs/core/error.h"

namespace qs {

namespace fs = std::filesystem;

namespace {

std::string why(const std::error_code& ec) { return ec ? " (" + ec.message() + ")" : std::string(); }

}  // namespace

OutputFolder::OutputFolder(fs::path target) : target_(std::move(target)) {
  if (target_.empty()) throw IoError("the output folder name is empty");
  // "out/" names the folder "out": drop a trailing separator so that the staging name is a sibling.
  if (!target_.has_filename()) target_ = target_.parent_path();
  std::error_code ec;
  const auto st = fs::status(target_, ec);
  if (fs::exists(st) && !fs::is_directory(st))
    throw IoError(target_.string() + ": exists and is not a folder; -o needs a folder (or a new name)");
  fs::path parent = target_.parent_path();
  if (parent.empty()) parent = ".";
  // Create the missing parents one by one, remembering them for the clean-up after a failure.
  std::vector<fs::path> missing;
  for (fs::path p = parent; !p.empty() && !fs::exists(fs::symlink_status(p, ec)); p = p.parent_path()) {
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
  if (!fs::is_directory(parent, ec))
    throw IoError(target_.string() + ": cannot create the folder: " + parent.string() + " is not a folder");
  if (fs::exists(st) && ::access(target_.c_str(), W_OK | X_OK) != 0)
    throw IoError(target_.string() + ": the output folder is not writable");
  staging_ = parent / (target_.filename().string() + ".tmp-" + std::to_string(::getpid()));
  fs::remove_all(staging_, ec);  // a leftover of an earlier run with the same process id
  if (!fs::create_directory(staging_, ec) || ec) {
    const std::string reason = why(ec);
    for (const auto& made : created_parents_) fs::remove(made, ec);
    throw IoError(target_.string() + ": cannot create a folder beside it" + reason);
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
  if (!fs::exists(fs::symlink_status(target_, ec))) {
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
