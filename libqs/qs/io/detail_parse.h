#pragma once
// Private helpers shared by the mesh readers: locations in error messages, a line reader and a
// tokenizer over a string_view, number parsing with std::from_chars, and fan triangulation.
// Not installed, not part of the API.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "qs/core/error.h"
#include "qs/core/mesh.h"
#include "qs/io/read_mesh.h"

namespace qs::io::detail {

// ---- error messages --------------------------------------------------------------------------

/// Throws InvalidInput("name: message").
[[noreturn]] void fail(const std::string& name, const std::string& message);
/// Throws InvalidInput("name:line: message").
[[noreturn]] void fail_at_line(const std::string& name, long long line, const std::string& message);
/// Throws InvalidInput("name: byte offset N: message").
[[noreturn]] void fail_at_offset(const std::string& name, std::size_t offset,
                                 const std::string& message);

/// A token as it may appear in a message: quoted, non-printable bytes escaped, long ones cut.
std::string quote(std::string_view token);

/// Throws (naming the line) if the text contains a NUL byte: binary data in a text format.
void require_text(std::string_view data, const std::string& name, const char* format);

/// 1-based line number of a byte offset.
long long line_of_offset(std::string_view data, std::size_t offset);

// ---- tokenizing ------------------------------------------------------------------------------

inline bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}

/// Removes leading and trailing white space.
inline std::string_view trim(std::string_view s) {
  std::size_t b = 0, e = s.size();
  while (b < e && is_space(s[b])) ++b;
  while (e > b && is_space(s[e - 1])) --e;
  return s.substr(b, e - b);
}

/// The next white-space separated token of `rest` (empty when none); `rest` moves past it.
inline std::string_view next_token(std::string_view& rest) {
  std::size_t i = 0;
  const std::size_t n = rest.size();
  while (i < n && is_space(rest[i])) ++i;
  std::size_t j = i;
  while (j < n && !is_space(rest[j])) ++j;
  std::string_view tok = rest.substr(i, j - i);
  rest.remove_prefix(j);
  return tok;
}

/// Splits a text into lines ('\n', '\r\n' or a lone '\r' at the very end), counting them.
class LineReader {
 public:
  explicit LineReader(std::string_view data, std::size_t start = 0, long long first_line = 1)
      : data_(data), pos_(start), next_line_(first_line) {}

  /// The next line without its terminator; false at the end of the data.
  bool next(std::string_view& line) {
    if (pos_ >= data_.size()) return false;
    const char* begin = data_.data() + pos_;
    const std::size_t left = data_.size() - pos_;
    const void* nl = std::memchr(begin, '\n', left);
    std::size_t len = nl ? static_cast<std::size_t>(static_cast<const char*>(nl) - begin) : left;
    pos_ += nl ? len + 1 : len;
    if (len > 0 && begin[len - 1] == '\r') --len;
    line = std::string_view(begin, len);
    line_ = next_line_++;
    return true;
  }
  /// 1-based number of the line last returned.
  long long line() const { return line_; }
  /// Byte offset just past the line last returned (its terminator included).
  std::size_t offset() const { return pos_; }
  std::size_t bytes_left() const { return data_.size() - pos_; }

 private:
  std::string_view data_;
  std::size_t pos_;
  long long next_line_;
  long long line_ = 0;
};

// ---- numbers ---------------------------------------------------------------------------------

/// Parses the whole token as a double (from_chars; a leading '+' is allowed; "nan" and "inf"
/// are read as such; out-of-range values become +-inf or 0 as strtod would give). False if
/// the token is not a number.
bool parse_double(std::string_view token, double& value);
/// Parses the whole token as a decimal integer (a leading '+' is allowed).
bool parse_int(std::string_view token, long long& value);

// ---- faces -----------------------------------------------------------------------------------

/// Appends a polygon (corner ids already validated) fan-triangulated, counting polygons with
/// more than 3 corners in report.polygons_triangulated and dropping (and counting) those with
/// fewer than 3.
inline void add_polygon(std::vector<Tri>& faces, const int* ids, std::size_t n, ReadReport& report) {
  if (n < 3) {
    ++report.degenerate_polygons_dropped;
    return;
  }
  if (n > 3) ++report.polygons_triangulated;
  for (std::size_t k = 1; k + 1 < n; ++k) faces.push_back({ids[0], ids[k], ids[k + 1]});
}

/// Throws "header claims N <what> but the file has only M bytes left" when `count` records of
/// at least `min_bytes` each cannot fit in `bytes_left` (before anything is reserved).
/// `where` is a ready location prefix such as "bunny.off:2".
void check_count_fits(const std::string& where, long long count, const char* what,
                      std::size_t min_bytes, std::size_t bytes_left);

// ---- the readers -----------------------------------------------------------------------------

ReadResult read_obj(std::string_view data, const std::string& name);
ReadResult read_off(std::string_view data, const std::string& name);
ReadResult read_ply(std::string_view data, const std::string& name);
ReadResult read_stl(std::string_view data, const std::string& name);

}  // namespace qs::io::detail
