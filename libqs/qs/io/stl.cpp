// STL reader, ASCII and binary. STL stores every triangle with its own three corners, so every
// triangle gets three fresh vertices: nothing is welded (that would be guessing), and validation
// will report such a mesh as open / non-manifold unless it is welded explicitly afterwards.

#include <cstring>
#include <limits>

#include "qs/io/detail_parse.h"

namespace qs::io::detail {

namespace {

constexpr std::size_t kHeaderBytes = 84;  // 80-byte header + uint32 triangle count
constexpr std::size_t kTriangleBytes = 50;

const char kUnsharedNote[] =
    "STL stores unshared vertices: each triangle got 3 vertices of its own (not welded), so "
    "validation will report the mesh as open and non-manifold";

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    char c = a[i];
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    if (c != b[i]) return false;
  }
  return true;
}

std::uint32_t le_u32(const char* p) {
  unsigned char b[4];
  std::memcpy(b, p, 4);
  return static_cast<std::uint32_t>(b[0]) | static_cast<std::uint32_t>(b[1]) << 8 |
         static_cast<std::uint32_t>(b[2]) << 16 | static_cast<std::uint32_t>(b[3]) << 24;
}

float le_f32(const char* p) {
  const std::uint32_t bits = le_u32(p);
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}

ReadResult read_binary(std::string_view data, const std::string& name) {
  ReadResult result;
  result.report.variant = "binary";
  const std::uint64_t n = le_u32(data.data() + 80);
  const std::uint64_t expected = kHeaderBytes + kTriangleBytes * n;
  if (expected > data.size()) {
    const std::uint64_t complete = (data.size() - kHeaderBytes) / kTriangleBytes;
    fail_at_offset(name, kHeaderBytes + complete * kTriangleBytes,
                   "binary STL header claims " + std::to_string(n) + " triangles (" +
                       std::to_string(expected) + " bytes) but the file has only " +
                       std::to_string(data.size()) + " bytes; it ends inside triangle " +
                       std::to_string(complete) + " (truncated file?)");
  }
  if (n * 3 > static_cast<std::uint64_t>(std::numeric_limits<int>::max()))
    fail(name, "binary STL with " + std::to_string(n) + " triangles is too large for qs");
  if (expected < data.size())
    result.report.notes.push_back("ignored " + std::to_string(data.size() - expected) +
                                  " bytes after the last triangle");
  auto& positions = result.mesh.positions;
  auto& faces = result.mesh.faces;
  positions.reserve(static_cast<std::size_t>(n * 3));
  faces.reserve(static_cast<std::size_t>(n));
  const char* p = data.data() + kHeaderBytes;
  for (std::uint64_t t = 0; t < n; ++t, p += kTriangleBytes) {
    const int base = static_cast<int>(positions.size());
    for (int k = 0; k < 3; ++k) {
      const char* v = p + 12 + 12 * k;  // after the normal
      positions.emplace_back(le_f32(v), le_f32(v + 4), le_f32(v + 8));
    }
    faces.push_back({base, base + 1, base + 2});
  }
  return result;
}

ReadResult read_ascii(std::string_view data, const std::string& name) {
  ReadResult result;
  result.report.variant = "ascii";
  auto& positions = result.mesh.positions;
  auto& faces = result.mesh.faces;

  enum class State { OutsideSolid, InSolid, InFacet };
  State state = State::OutsideSolid;
  long long solids = 0;
  long long facet_line = 0;
  std::vector<int> corners;

  LineReader lines(data);
  std::string_view line;
  while (lines.next(line)) {
    std::string_view rest = line;
    const std::string_view key = next_token(rest);
    if (key.empty()) continue;
    if (iequals(key, "solid")) {
      if (state != State::OutsideSolid)
        fail_at_line(name, lines.line(), "'solid' inside another solid; expected 'endsolid' first");
      state = State::InSolid;
      ++solids;
    } else if (iequals(key, "endsolid")) {
      if (state != State::InSolid)
        fail_at_line(name, lines.line(),
                     state == State::InFacet ? "'endsolid' inside a facet; expected 'endfacet' first"
                                             : "'endsolid' without 'solid'");
      state = State::OutsideSolid;
    } else if (iequals(key, "facet")) {
      if (state != State::InSolid)
        fail_at_line(name, lines.line(),
                     state == State::InFacet ? "'facet' inside a facet; expected 'endfacet' first"
                                             : "'facet' outside a solid; expected 'solid <name>' first");
      state = State::InFacet;
      facet_line = lines.line();
      corners.clear();
    } else if (iequals(key, "outer") || iequals(key, "endloop")) {
      if (state != State::InFacet)
        fail_at_line(name, lines.line(), quote(key) + " outside a facet");
    } else if (iequals(key, "vertex")) {
      if (state != State::InFacet)
        fail_at_line(name, lines.line(), "'vertex' outside a facet");
      double xyz[3];
      for (int k = 0; k < 3; ++k) {
        const std::string_view tok = next_token(rest);
        if (tok.empty())
          fail_at_line(name, lines.line(), "expected 3 vertex coordinates, found " + std::to_string(k));
        if (!parse_double(tok, xyz[k]))
          fail_at_line(name, lines.line(), "vertex coordinate " + quote(tok) + " is not a number");
      }
      if (positions.size() >= static_cast<std::size_t>(std::numeric_limits<int>::max()))
        fail_at_line(name, lines.line(), "too many vertices");
      corners.push_back(static_cast<int>(positions.size()));
      positions.emplace_back(xyz[0], xyz[1], xyz[2]);
    } else if (iequals(key, "endfacet")) {
      if (state != State::InFacet) fail_at_line(name, lines.line(), "'endfacet' without 'facet'");
      add_polygon(faces, corners.data(), corners.size(), result.report);
      state = State::InSolid;
    } else {
      fail_at_line(name, lines.line(),
                   "unexpected " + quote(key) +
                       "; expected solid, facet, outer loop, vertex, endloop, endfacet or endsolid");
    }
  }
  if (state == State::InFacet)
    fail_at_line(name, lines.line(),
                 "file ends inside the facet that starts on line " + std::to_string(facet_line) +
                     " (truncated file?)");
  if (state == State::InSolid)
    fail_at_line(name, lines.line(), "file ends without 'endsolid' (truncated file?)");
  if (solids == 0) fail(name, "no 'solid' found; expected an ASCII or binary STL file");
  return result;
}

}  // namespace

ReadResult read_stl(std::string_view data, const std::string& name) {
  const std::string_view start = trim(data.substr(0, 512));
  const bool says_solid = start.size() >= 5 && iequals(start.substr(0, 5), "solid") &&
                          (start.size() == 5 || is_space(start[5]));
  const bool binary_size_matches =
      data.size() >= kHeaderBytes &&
      kHeaderBytes + kTriangleBytes * static_cast<std::uint64_t>(le_u32(data.data() + 80)) == data.size();

  ReadResult result;
  if (binary_size_matches) {
    // Many binary writers start the 80-byte header with "solid": the size decides.
    result = read_binary(data, name);
  } else if (says_solid) {
    const void* nul = std::memchr(data.data(), '\0', data.size());
    if (nul) {
      const auto offset = static_cast<std::size_t>(static_cast<const char*>(nul) - data.data());
      std::string binary_hint;
      if (data.size() >= kHeaderBytes) {
        const std::uint64_t n = le_u32(data.data() + 80);
        binary_hint = ", and its size (" + std::to_string(data.size()) +
                      " bytes) does not match a binary STL with the " + std::to_string(n) +
                      " triangles its header claims (" +
                      std::to_string(kHeaderBytes + kTriangleBytes * n) + " bytes)";
      }
      fail_at_offset(name, offset,
                     "the file starts with 'solid' like an ASCII STL but contains binary data" +
                         binary_hint + "; it is corrupt or truncated");
    }
    result = read_ascii(data, name);
  } else if (data.size() < kHeaderBytes) {
    fail(name, "file of " + std::to_string(data.size()) +
                   " bytes is neither an ASCII STL (no 'solid' at the start) nor a binary STL "
                   "(needs at least 84 bytes)");
  } else {
    result = read_binary(data, name);
  }
  result.report.notes.push_back(kUnsharedNote);
  return result;
}

}  // namespace qs::io::detail
