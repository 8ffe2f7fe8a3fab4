#pragma once
// Output folders written all-or-nothing. A tool writes every file into a staging folder beside
// the target ("<target>.tmp-<pid>") and calls commit() when everything succeeded:
//   - a target that does not exist is created by renaming the staging folder onto it (atomic);
//   - an existing target folder gets each staged file renamed into it (each rename atomic), so
//     files of the folder that this run does not write (the inputs of qs-remesh -o <dissection>,
//     the user's own files) are kept.
// Until commit() nothing in the target changes; a run that fails or throws removes its staging
// folder (and any parent folders it created), leaving the target exactly as it was.
//
// A killed run cannot clean up: its staging folder stays. The next OutputFolder for the same
// target removes every "<target>.tmp-<pid>" folder of the same user whose process is gone (or
// whose process id now belongs to a process started after the folder was last changed); a
// staging folder of a running process is never touched.

#include <sys/types.h>

#include <filesystem>
#include <string>
#include <vector>

namespace qs {

class OutputFolder {
 public:
  /// Checks the target up front, removes staging folders that killed runs left for it, and
  /// creates the staging folder. \throws IoError when the target is an existing file, lies
  /// under a file, or its folder cannot be created or written.
  explicit OutputFolder(std::filesystem::path target);
  /// A group of files written all-or-nothing into `folder`, beside files it already holds (a
  /// mesh and the files that go with it). The staging folder is "<folder>/<name>.tmp-<pid>"
  /// (`name`: the main file's name); `folder` is created when missing (and removed again on
  /// failure); commit() renames each staged file into `folder`. \throws IoError as above.
  OutputFolder(std::filesystem::path folder, const std::string& name);
  /// Removes the staging folder (and parents this object created) unless commit() was reached.
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

  /// Where to write the files now.
  const std::filesystem::path& staging() const { return staging_; }
  /// Where they will be after commit().
  const std::filesystem::path& target() const { return target_; }
  /// Moves the staged files into place. \throws IoError on failure.
  void commit();

 private:
  void prepare(const std::filesystem::path& folder_to_create);
  std::filesystem::path target_, staging_;
  std::vector<std::filesystem::path> created_parents_;  ///< deepest first
  bool inside_ = false;                                 ///< staging inside the target folder
  bool committed_ = false;
};

/// \throws UsageError when `output` (a file a tool is about to write) is one of `inputs`, or the
/// same file through another path (links, "./a" vs "a"): no tool writes over its own input.
/// `option` names the option that gave the output ("-o", "--report", ...).
void check_not_an_input(const std::filesystem::path& output, const std::vector<std::filesystem::path>& inputs,
                        const std::string& option);

/// True when `pid` may still be writing a staging entry last modified at `modified`: the
/// process exists (or cannot be signalled for lack of permission) and did not start after the
/// entry was last changed (60 s of slack for clocks). Our own process id counts as running.
bool staging_owner_running(pid_t pid, std::filesystem::file_time_type modified);

/// Removes the staging entries that killed runs left for `target`: "<target>.tmp-<pid>" beside
/// it, folders when `folders` (OutputFolder) else regular files (AtomicFile), owned by this
/// user, whose owner is not running (staging_owner_running). Errors are ignored (an entry that
/// cannot be removed stays). Returns how many were removed.
int remove_stale_staging(const std::filesystem::path& target, bool folders);

}  // namespace qs
