#include "qs/studio/paths.h"

#include <system_error>

#include "qs/core/json_strict.h"

namespace fs = std::filesystem;

namespace qs::studio {

namespace {

std::string quoted(std::string_view s) { return "'" + json_strict::printable(s, 200) + "'"; }

}  // namespace

void check_relative_path(std::string_view rel) {
  if (rel.empty()) throw PathRefused("empty path; expected a file name inside the studio's folder");
  if (rel.size() > 1024)
    throw PathRefused("path of " + std::to_string(rel.size()) + " bytes; at most 1024 are accepted");
  for (char c : rel) {
    if (c == '\0' || c == '\\' || static_cast<unsigned char>(c) < 0x20)
      throw PathRefused("path " + quoted(rel) + " holds a NUL, a backslash or a control character");
  }
  if (!json_strict::is_clean_text(rel))
    throw PathRefused("path " + quoted(rel) + " is not valid UTF-8; the studio names files in UTF-8 only");
  if (rel.front() == '/')
    throw PathRefused("absolute path " + quoted(rel) + " refused; paths are relative to the studio's folder");
  size_t start = 0;
  while (start <= rel.size()) {
    size_t end = rel.find('/', start);
    if (end == std::string_view::npos) end = rel.size();
    const std::string_view part = rel.substr(start, end - start);
    if (part.empty())
      throw PathRefused("path " + quoted(rel) + " has an empty component ('//' or a trailing '/')");
    if (part == "..")
      throw PathRefused("path " + quoted(rel) + " has a '..' component; the studio serves only inside its folder");
    if (part.front() == '.')
      throw PathRefused("path " + quoted(rel) + " names a hidden file or folder (a component starting with '.')");
    if (part.size() > 255)
      throw PathRefused("path " + quoted(rel) + " has a component of " + std::to_string(part.size()) +
                        " bytes; file names have at most 255");
    start = end + 1;
  }
}

bool is_inside(const fs::path& root, const fs::path& path) {
  auto r = root.begin(), p = path.begin();
  for (; r != root.end(); ++r, ++p) {
    if (r->empty()) continue;  // a trailing separator of the root
    if (p == path.end() || *r != *p) return false;
  }
  return true;
}

fs::path resolve_existing(const fs::path& root, std::string_view rel, bool allow_directory) {
  check_relative_path(rel);
  const fs::path joined = root / fs::path(std::string(rel));
  std::error_code ec;
  const fs::file_status st = fs::status(joined, ec);
  if (ec || !fs::exists(st)) throw IoError(quoted(rel) + " not found in the studio's folder");
  const fs::path real = fs::canonical(joined, ec);
  if (ec) throw IoError(quoted(rel) + " cannot be resolved: " + ec.message());
  if (!is_inside(root, real))
    throw PathRefused("path " + quoted(rel) + " leads out of the studio's folder through a symbolic link");
  if (!fs::is_regular_file(st) && !(allow_directory && fs::is_directory(st)))
    throw IoError(quoted(rel) + " is not a regular file");
  return real;
}

fs::path resolve_for_writing(const fs::path& root, std::string_view rel) {
  check_relative_path(rel);
  const fs::path joined = root / fs::path(std::string(rel));
  std::error_code ec;
  const fs::path parent = fs::canonical(joined.parent_path(), ec);
  if (ec) throw IoError("the folder of " + quoted(rel) + " does not exist in the studio's folder");
  if (!is_inside(root, parent))
    throw PathRefused("path " + quoted(rel) + " leads out of the studio's folder through a symbolic link");
  if (!fs::is_directory(parent)) throw IoError("the folder of " + quoted(rel) + " is not a folder");
  const fs::file_status st = fs::symlink_status(joined, ec);
  if (!ec && fs::is_symlink(st))
    throw PathRefused(quoted(rel) + " is a symbolic link; the studio never writes through links");
  if (!ec && fs::exists(st) && !fs::is_regular_file(st))
    throw PathRefused(quoted(rel) + " exists and is not a regular file");
  return parent / joined.filename();
}

}  // namespace qs::studio
