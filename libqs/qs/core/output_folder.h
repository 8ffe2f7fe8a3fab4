#pragma once
// Output folders written all-or-nothing. A tool writes every file into a staging folder beside
// the target ("<target>.tmp-<pid>") and calls commit() when everything succeeded:
//   - a target that does not exist is created by renaming the staging folder onto it (atomic);
//   - an existing target folder gets each staged file renamed into it (each rename atomic), so
//     files of the folder that this run does not write (the inputs of qs-remesh -o <dissection>,
//     the user's own files) are kept.
// Until commit() nothing in the target changes; a run that fails or throws removes its staging
// folder (and any parent folders it created), leaving the target exactly as it was.

#include <filesystem>
#include <string>
#include <vector>

namespace qs {

class OutputFolder {
 public:
  /// Checks the target up front and creates the staging folder. \throws IoError when the target
  /// is an existing file, lies under a file, or its folder cannot be created or written.
  explicit OutputFolder(std::filesystem::path target);
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
  std::filesystem::path target_, staging_;
  std::vector<std::filesystem::path> created_parents_;  ///< deepest first
  bool committed_ = false;
};

/// \throws UsageError when `output` (a file a tool is about to write) is one of `inputs`, or the
/// same file through another path (links, "./a" vs "a"): no tool writes over its own input.
/// `option` names the option that gave the output ("-o", "--report", ...).
void check_not_an_input(const std::filesystem::path& output, const std::vector<std::filesystem::path>& inputs,
                        const std::string& option);

}  // namespace qs
