#pragma once
// Output files are written to a temporary name beside the target and renamed into place
// only when complete, so that a failure never leaves a half-written file behind. A killed
// process leaves its "<path>.tmp-<pid>" file; the next AtomicFile for the same path removes it
// once that process is gone (remove_stale_staging in output_folder.h).

#include <filesystem>
#include <fstream>
#include <string>

namespace qs {

class AtomicFile {
 public:
  /// Removes the temporary files of killed runs for `path`, then opens "<path>.tmp-<pid>" for
  /// binary writing. \throws IoError if it cannot.
  explicit AtomicFile(std::filesystem::path path);
  /// Removes the temporary file if commit() was not reached.
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  std::ostream& stream() { return out_; }
  /// Flushes, closes and renames onto the target. \throws IoError on any failure.
  void commit();

 private:
  std::filesystem::path path_, tmp_;
  std::ofstream out_;
  bool committed_ = false;
};

/// Writes a whole string through an AtomicFile.
void write_file_atomically(const std::filesystem::path& path, const std::string& contents);

}  // namespace qs
