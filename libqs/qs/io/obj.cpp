// Wavefront OBJ reader: `v` and `f` lines; everything else is ignored.

#include <limits>
#include <map>

#include "qs/io/detail_parse.h"

namespace qs::io::detail {

namespace {

bool is_ignored_keyword(std::string_view k) {
  // Texture/normal data, grouping, materials, smoothing, lines, points, free-form geometry.
  static constexpr std::string_view kIgnored[] = {
      "vt", "vn", "vp", "s", "g", "o", "usemtl", "mtllib", "l", "p", "mg", "lod", "bevel",
      "c_interp", "d_interp", "usemap", "maplib", "shadow_obj", "trace_obj", "cstype", "deg",
      "bmat", "step", "curv", "curv2", "surf", "parm", "trim", "hole", "scrv", "sp", "end",
      "con", "call", "csh"};
  for (std::string_view i : kIgnored)
    if (k == i) return true;
  return false;
}

}  // namespace

ReadResult read_obj(std::string_view data, const std::string& name) {
  require_text(data, name, "OBJ");
  ReadResult result;
  result.report.variant = "ascii";
  auto& positions = result.mesh.positions;
  auto& faces = result.mesh.faces;

  std::vector<int> corners;
  long long max_index = 0;       // largest positive (1-based) index seen in a face
  long long max_index_line = 0;  // where it was first seen
  std::map<std::string, long long> unknown;  // unknown keyword -> number of lines

  LineReader lines(data);
  std::string_view line;
  while (lines.next(line)) {
    std::string_view rest = line;
    const std::string_view key = next_token(rest);
    if (key.empty() || key.front() == '#') continue;
    if (key == "v") {
      double xyz[3];
      for (int k = 0; k < 3; ++k) {
        const std::string_view tok = next_token(rest);
        if (tok.empty())
          fail_at_line(name, lines.line(),
                       "expected 3 vertex coordinates, found " + std::to_string(k));
        if (!parse_double(tok, xyz[k]))
          fail_at_line(name, lines.line(),
                       "vertex coordinate " + quote(tok) + " is not a number");
      }
      if (positions.size() >= static_cast<std::size_t>(std::numeric_limits<int>::max()))
        fail_at_line(name, lines.line(), "too many vertices");
      positions.emplace_back(xyz[0], xyz[1], xyz[2]);
    } else if (key == "f") {
      corners.clear();
      for (std::string_view tok = next_token(rest); !tok.empty(); tok = next_token(rest)) {
        const std::string_view vtok = tok.substr(0, tok.find('/'));
        long long index = 0;
        if (!parse_int(vtok, index))
          fail_at_line(name, lines.line(),
                       "face corner " + quote(tok) +
                           " does not start with a vertex index (expected v, v/vt, v//vn or "
                           "v/vt/vn)");
        if (index == 0)
          fail_at_line(name, lines.line(),
                       "vertex index 0 in face corner " + quote(tok) +
                           "; OBJ indices start at 1 (or are negative, relative to the end)");
        if (index < 0) {
          const long long resolved = static_cast<long long>(positions.size()) + index;
          if (resolved < 0)
            fail_at_line(name, lines.line(),
                         "relative vertex index " + std::to_string(index) + " points before the first vertex (only " +
                             std::to_string(positions.size()) + " vertices defined so far)");
          corners.push_back(static_cast<int>(resolved));
        } else {
          if (index > std::numeric_limits<int>::max())
            fail_at_line(name, lines.line(),
                         "vertex index " + std::to_string(index) + " is out of range");
          if (index > max_index) {
            max_index = index;
            max_index_line = lines.line();
          }
          corners.push_back(static_cast<int>(index - 1));
        }
      }
      add_polygon(faces, corners.data(), corners.size(), result.report);
    } else if (!is_ignored_keyword(key)) {
      ++unknown[std::string(key.substr(0, 32))];
    }
  }

  if (positions.empty())
    fail(name, "no vertex ('v') lines found; is this an OBJ file?");
  if (max_index > static_cast<long long>(positions.size()))
    fail_at_line(name, max_index_line,
                 "vertex index " + std::to_string(max_index) + " is out of range; the file has " +
                     std::to_string(positions.size()) + " vertices (valid: 1.." +
                     std::to_string(positions.size()) + " or negative)");
  if (unknown.size() <= 8) {
    for (const auto& [key, count] : unknown)
      result.report.notes.push_back("ignored " + std::to_string(count) +
                                    " line(s) starting with " + quote(key));
  } else {
    long long total = 0;
    for (const auto& entry : unknown) total += entry.second;
    result.report.notes.push_back("ignored " + std::to_string(total) + " lines with " +
                                  std::to_string(unknown.size()) + " different unknown keywords");
  }
  return result;
}

}  // namespace qs::io::detail
