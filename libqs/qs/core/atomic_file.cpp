#include "qs/core/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "qs/core/error.h"
#include "qs/core/output_folder.h"

namespace qs {

AtomicFile::AtomicFile(std::filesystem::path path) : path_(std::move(path)) {
  tmp_ = path_;
  tmp_ += ".tmp-" + std::to_string(::getpid());
  remove_stale_staging(path_, false);
  out_.open(tmp_, std::ios::binary | std::ios::trunc);
  if (!out_)
    throw IoError(path_.string() + ": cannot open for writing (" + std::strerror(errno) + ")");
}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    out_.close();
    std::error_code ec;
    std::filesystem::remove(tmp_, ec);
  }
}

void AtomicFile::commit() {
  out_.flush();
  const bool ok = static_cast<bool>(out_);
  out_.close();
  if (!ok || out_.fail())
    throw IoError(path_.string() + ": write failed (disk full or file system error)");
  std::error_code ec;
  std::filesystem::rename(tmp_, path_, ec);
  if (ec) throw IoError(path_.string() + ": cannot move the finished file into place (" + ec.message() + ")");
  committed_ = true;
}

void write_file_atomically(const std::filesystem::path& path, const std::string& contents) {
  AtomicFile file(path);
  file.stream().write(contents.data(), static_cast<std::streamsize>(contents.size()));
  file.commit();
}

}  // namespace qs
