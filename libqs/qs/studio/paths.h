#pragma once
// qs-studio's path rules: every file the studio serves or writes lies inside one folder.
//
// A request names a file by a relative path with '/' separators. It is refused when it is empty,
// longer than 1024 bytes, holds a NUL, a backslash or a control character, is not valid UTF-8 (it
// could not be named in JSON or on the page), is absolute, has an empty, "." or ".." component, a
// component longer than 255 bytes, or a component starting with '.' (hidden files and the
// studio's own staging files are never served). The resolved file must then stay inside the folder
// after every symbolic link is followed: a link that points out of the folder is refused like
// "..", and a link is never written through.

#include <filesystem>
#include <string>
#include <string_view>

#include "qs/core/error.h"

namespace qs::studio {

/// A path that breaks the rules above; the message says which rule.
class PathRefused : public InvalidInput {
 public:
  explicit PathRefused(const std::string& m) : InvalidInput(m) {}
};

/// Checks the syntax of a relative path (the rules above that need no file system).
/// \throws PathRefused naming the rule that is broken (the path quoted printable, at most 200 bytes).
void check_relative_path(std::string_view relative);

/// An existing regular file (or, with allow_directory, a folder) inside `root`.
/// \pre root is canonical (std::filesystem::canonical). \throws PathRefused when the path breaks
/// a rule or leaves the root through a symbolic link; IoError("... not found") when it does not
/// exist or is not a regular file.
std::filesystem::path resolve_existing(const std::filesystem::path& root, std::string_view relative,
                                       bool allow_directory = false);

/// A file that may be created or replaced inside `root`: its folder must exist inside the root
/// (after links), and the file itself must not be a symbolic link or a folder.
/// \pre root is canonical. \throws PathRefused, IoError.
std::filesystem::path resolve_for_writing(const std::filesystem::path& root, std::string_view relative);

/// True when `path` (canonical) is `root` or lies under it.
bool is_inside(const std::filesystem::path& root, const std::filesystem::path& path);

}  // namespace qs::studio
