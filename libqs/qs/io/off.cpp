// Object File Format reader: OFF and its [ST][C][N]OFF variants (texture coordinates, colours
// and normals after the coordinates are ignored), ASCII only.

#include "qs/io/detail_parse.h"

namespace qs::io::detail {

namespace {

/// The next line with content: comments ('#' to the end of the line) and blank lines skipped.
bool next_content_line(LineReader& lines, std::string_view& line) {
  while (lines.next(line)) {
    const std::size_t hash = line.find('#');
    if (hash != std::string_view::npos) line = line.substr(0, hash);
    line = trim(line);
    if (!line.empty()) return true;
  }
  return false;
}

/// True for OFF header keywords: [ST][C][N][4][n]OFF.
bool is_off_keyword(std::string_view key) {
  if (key.size() < 3 || key.substr(key.size() - 3) != "OFF") return false;
  for (char c : key.substr(0, key.size() - 3))
    if (c != 'S' && c != 'T' && c != 'C' && c != 'N' && c != '4' && c != 'n') return false;
  return true;
}

long long read_count(std::string_view token, const std::string& name, long long line,
                     const char* what) {
  long long value = 0;
  if (!parse_int(token, value))
    fail_at_line(name, line, std::string("expected the number of ") + what + ", found " + quote(token));
  if (value < 0)
    fail_at_line(name, line, std::string("negative number of ") + what + " (" + std::to_string(value) + ")");
  return value;
}

}  // namespace

ReadResult read_off(std::string_view data, const std::string& name) {
  require_text(data, name, "OFF");
  ReadResult result;
  auto& positions = result.mesh.positions;
  auto& faces = result.mesh.faces;

  LineReader lines(data);
  std::string_view line;
  if (!next_content_line(lines, line)) fail(name, "no OFF header (the file has only comments)");

  // Header: "OFF", optionally followed by the counts on the same line; the keyword is optional.
  std::string_view rest = line;
  std::string_view first = rest;
  const std::string_view key = next_token(first);
  std::string variant = "OFF";
  if (is_off_keyword(key)) {
    variant = std::string(key);
    if (key.find('4') != std::string_view::npos || key.find('n') != std::string_view::npos)
      fail_at_line(name, lines.line(),
                   quote(key) + " (4D or n-dimensional OFF) is not supported; qs reads 3D OFF");
    rest = first;
    std::string_view peek = rest;
    const std::string_view next = next_token(peek);
    if (next == "BINARY")
      fail_at_line(name, lines.line(), "binary OFF is not supported; convert it to ASCII OFF");
    if (trim(rest).empty() && !next_content_line(lines, rest))
      fail_at_line(name, lines.line(), "file ends after the header; expected the vertex and face counts");
  } else {
    long long dummy = 0;
    if (!parse_int(key, dummy))
      fail_at_line(name, lines.line(),
                   "expected an OFF header (OFF, COFF, NOFF, STOFF, ...), found " + quote(key));
    result.report.notes.push_back("the OFF keyword is missing; read the file as OFF anyway");
  }
  result.report.variant = variant;

  const long long count_line = lines.line();
  const std::string_view counts_text = trim(rest);
  const std::string_view vtok = next_token(rest);
  const std::string_view ftok = next_token(rest);
  if (ftok.empty())
    fail_at_line(name, count_line,
                 "expected the counts 'vertices faces [edges]', found " + quote(counts_text));
  const long long nv = read_count(vtok, name, count_line, "vertices");
  const long long nf = read_count(ftok, name, count_line, "faces");
  const std::string_view etok = next_token(rest);
  if (!etok.empty()) read_count(etok, name, count_line, "edges");  // checked, otherwise unused

  // Every vertex line has at least "x y z\n" (6 bytes), every face line at least "0\n".
  const std::string where = name + ":" + std::to_string(count_line);
  check_count_fits(where, nv, "vertices", 6, lines.bytes_left());
  check_count_fits(where, nf, "faces", 2, lines.bytes_left() - std::min<std::size_t>(lines.bytes_left(), static_cast<std::size_t>(nv) * 6));
  positions.reserve(static_cast<std::size_t>(nv));
  faces.reserve(static_cast<std::size_t>(nf));

  for (long long i = 0; i < nv; ++i) {
    if (!next_content_line(lines, line))
      fail_at_line(name, lines.line(),
                   "file ends after " + std::to_string(i) + " of " + std::to_string(nv) +
                       " vertices (truncated, or the header counts are wrong)");
    rest = line;
    double xyz[3];
    for (int k = 0; k < 3; ++k) {
      const std::string_view tok = next_token(rest);
      if (tok.empty())
        fail_at_line(name, lines.line(), "expected 3 vertex coordinates, found " + std::to_string(k));
      if (!parse_double(tok, xyz[k]))
        fail_at_line(name, lines.line(), "vertex coordinate " + quote(tok) + " is not a number");
    }
    positions.emplace_back(xyz[0], xyz[1], xyz[2]);
  }

  std::vector<int> corners;
  for (long long f = 0; f < nf; ++f) {
    if (!next_content_line(lines, line))
      fail_at_line(name, lines.line(),
                   "file ends after " + std::to_string(f) + " of " + std::to_string(nf) +
                       " faces (truncated, or the header counts are wrong)");
    rest = line;
    const std::string_view ntok = next_token(rest);
    long long n = 0;
    if (!parse_int(ntok, n) || n < 0)
      fail_at_line(name, lines.line(),
                   "expected the number of corners of face " + std::to_string(f) + ", found " + quote(ntok));
    if (static_cast<unsigned long long>(n) > line.size())
      fail_at_line(name, lines.line(),
                   "face " + std::to_string(f) + " claims " + std::to_string(n) +
                       " corners but its line is too short to hold them");
    corners.clear();
    for (long long k = 0; k < n; ++k) {
      const std::string_view tok = next_token(rest);
      if (tok.empty())
        fail_at_line(name, lines.line(),
                     "expected " + std::to_string(n) + " vertex indices, found " + std::to_string(k));
      long long index = 0;
      if (!parse_int(tok, index))
        fail_at_line(name, lines.line(), "vertex index " + quote(tok) + " is not an integer");
      if (index < 0 || index >= nv)
        fail_at_line(name, lines.line(),
                     "face " + std::to_string(f) + " references vertex " + std::to_string(index) +
                         " but the file has " + std::to_string(nv) + " vertices (0-based ids 0.." +
                         std::to_string(nv - 1) + ")");
      corners.push_back(static_cast<int>(index));
    }
    // Anything after the indices (a face colour) is ignored.
    add_polygon(faces, corners.data(), corners.size(), result.report);
  }

  if (next_content_line(lines, line))
    fail_at_line(name, lines.line(),
                 "unexpected data after the last of " + std::to_string(nf) +
                     " faces; the header counts (" + std::to_string(nv) + " vertices, " +
                     std::to_string(nf) + " faces) do not match the data");
  return result;
}

}  // namespace qs::io::detail
