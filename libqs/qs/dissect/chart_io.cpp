#include "qs/dissect/chart_io.h"

#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/core/finite.h"
#include "qs/core/json_strict.h"

namespace qs::dissect {
namespace {

/// Binary records gathered in memory and written to the stream in large blocks.
class BlockWriter {
 public:
  explicit BlockWriter(std::ostream& out) : out_(out) { buf_.reserve(kBlock + 256); }
  ~BlockWriter() { flush(); }
  template <class T>
  void put(T value) {
    static_assert(std::is_arithmetic_v<T>);
    const char* b = reinterpret_cast<const char*>(&value);  // x86-64 and aarch64: little endian
    buf_.insert(buf_.end(), b, b + sizeof(T));
  }
  /// Writes the block once it is full (call between records).
  void maybe_flush() {
    if (buf_.size() >= kBlock) flush();
  }
  void flush() {
    out_.write(buf_.data(), static_cast<std::streamsize>(buf_.size()));
    buf_.clear();
  }

 private:
  static constexpr size_t kBlock = 1 << 20;
  std::ostream& out_;
  std::vector<char> buf_;
};

// Version 2 (written): texcoords as float64. Version 1 (still read): float32.
const char* kHeaderTail =
    "property list uchar int vertex_indices\n"
    "property list uchar double texcoord\n"
    "property int patch\n"
    "property uchar red\n"
    "property uchar green\n"
    "property uchar blue\n"
    "end_header\n";
const char* kFloatTexcoord = "property list uchar float texcoord\n";
const char* kDoubleTexcoord = "property list uchar double texcoord\n";

}  // namespace

std::array<unsigned char, 3> patch_colour(int patch) {
  const double h = std::fmod(0.13 + patch * 0.618033988749895, 1.0) * 6.0;
  const double s = patch % 2 ? 0.55 : 0.75, v = patch % 3 == 2 ? 0.8 : 0.95;
  const int i = static_cast<int>(h);
  const double f = h - i, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  double r, g, b;
  switch (i % 6) {
    case 0: r = v, g = t, b = p; break;
    case 1: r = q, g = v, b = p; break;
    case 2: r = p, g = v, b = t; break;
    case 3: r = p, g = q, b = v; break;
    case 4: r = t, g = p, b = v; break;
    default: r = v, g = p, b = q; break;
  }
  auto c = [](double x) { return static_cast<unsigned char>(std::lround(255 * x)); };
  return {c(r), c(g), c(b)};
}

void write_chart_ply(const std::filesystem::path& path, const Chart& chart) {
  AtomicFile file(path);
  std::ostream& out = file.stream();
  out << "ply\nformat binary_little_endian 1.0\ncomment qs chart: cut mesh, per-face patch and wedge uv\n"
      << "comment qs chart version " << kChartFormatVersion << "\n"
      << "element vertex " << chart.mesh.positions.size()
      << "\nproperty double x\nproperty double y\nproperty double z\n"
      << "element face " << chart.mesh.faces.size() << "\n"
      << kHeaderTail;
  std::vector<std::array<unsigned char, 3>> colour(chart.patches.size());
  for (size_t q = 0; q < colour.size(); ++q) colour[q] = patch_colour(static_cast<int>(q));
  {
    BlockWriter w(out);
    for (const Vec3& p : chart.mesh.positions) {
      for (int k = 0; k < 3; ++k) w.put<double>(p[k]);
      w.maybe_flush();
    }
    for (size_t f = 0; f < chart.mesh.faces.size(); ++f) {
      w.put<std::uint8_t>(3);
      for (int k = 0; k < 3; ++k) w.put<std::int32_t>(chart.mesh.faces[f][k]);
      w.put<std::uint8_t>(6);
      for (int k = 0; k < 3; ++k)
        for (int d = 0; d < 2; ++d) w.put<double>(chart.face_uv[f][k][d]);
      const int patch = chart.face_patch[f];
      w.put<std::int32_t>(patch);
      const auto c = patch >= 0 && patch < static_cast<int>(colour.size()) ? colour[patch] : patch_colour(patch);
      for (unsigned char x : c) w.put<std::uint8_t>(x);
      w.maybe_flush();
    }
  }
  file.commit();
}

Chart read_chart_ply(const std::filesystem::path& path) {
  return parse_chart_ply(json_strict::read_text_file(path, "chart file"), json_strict::printable(path.string()));
}

Chart parse_chart_ply(std::string_view data, const std::string& name) {
  const size_t end = data.find("end_header\n");
  if (data.rfind("ply\nformat binary_little_endian 1.0\n", 0) != 0 || end == std::string::npos)
    throw InvalidInput(name + ": not a qs chart file (expected a binary little-endian PLY header)");
  const std::string header(data.substr(0, end));
  long long nv = -1, nf = -1;
  std::istringstream hs(header);
  auto count = [&](const std::string& line, size_t from, const char* element) {
    long long n = -1;
    const char* first = line.data() + from;
    const char* last = line.data() + line.size();
    const auto [ptr, ec] = std::from_chars(first, last, n);
    if (ec != std::errc() || ptr != last || n < 0)
      throw InvalidInput(name + ": header line \"" + json_strict::printable(line, 60) + "\": the " + element +
                         " count must be a non-negative integer");
    return n;
  };
  for (std::string line; std::getline(hs, line);) {
    if (line.rfind("element vertex ", 0) == 0) nv = count(line, 15, "vertex");
    if (line.rfind("element face ", 0) == 0) nf = count(line, 13, "face");
  }
  if (header.find("property int patch") == std::string::npos ||
      (header.find(kDoubleTexcoord) == std::string::npos && header.find(kFloatTexcoord) == std::string::npos))
    throw InvalidInput(name + ": PLY file lacks the chart's per-face patch and texcoord properties");
  const bool double_uv = header.find(kDoubleTexcoord) != std::string::npos;
  const size_t face_bytes = 1 + 12 + 1 + (double_uv ? 48 : 24) + 4 + 3;
  const size_t body = end + std::strlen("end_header\n");
  const size_t bytes = data.size() - body;
  // Counts are checked against the bytes present before anything is multiplied or allocated.
  if (nv < 0 || nf < 0 || static_cast<unsigned long long>(nv) > bytes / 24 ||
      static_cast<unsigned long long>(nf) > bytes / face_bytes ||
      bytes != static_cast<size_t>(nv) * 24 + static_cast<size_t>(nf) * face_bytes)
    throw InvalidInput(name + ": chart file size does not match its header (truncated?)");
  if (nv > std::numeric_limits<int>::max() || nf > std::numeric_limits<int>::max())
    throw InvalidInput(name + ": more than 2^31 vertices or faces");
  Chart chart;
  const char* p = data.data() + body;
  auto get = [&p](auto& v) {
    std::memcpy(&v, p, sizeof(v));
    p += sizeof(v);
  };
  chart.mesh.positions.resize(nv);
  for (long long v = 0; v < nv; ++v) {
    for (int k = 0; k < 3; ++k) get(chart.mesh.positions[v][k]);
    if (!usable_position(chart.mesh.positions[v]))
      throw InvalidInput(name + ": vertex " + std::to_string(v) +
                         " has a NaN, infinite or too large coordinate (expected finite, |x| <= 1e100)");
  }
  chart.mesh.faces.resize(nf);
  chart.face_uv.resize(nf);
  chart.face_patch.resize(nf);
  int max_patch = -1;
  for (long long f = 0; f < nf; ++f) {
    std::uint8_t n3, n6, rgb[3];
    get(n3);
    std::int32_t idx[3];
    for (auto& i : idx) get(i);
    get(n6);
    if (n3 != 3 || n6 != 6) throw InvalidInput(name + ": face " + std::to_string(f) + " is not a chart triangle");
    for (int k = 0; k < 3; ++k) {
      if (idx[k] < 0 || idx[k] >= nv)
        throw InvalidInput(name + ": face " + std::to_string(f) + " has vertex index " +
                           std::to_string(idx[k]) + " out of range");
      chart.mesh.faces[f][k] = idx[k];
      double u, v;
      if (double_uv) {
        get(u);
        get(v);
      } else {
        float uf, vf;
        get(uf);
        get(vf);
        u = uf;
        v = vf;
      }
      // Patch parameters lie in the unit square (float rounding aside); NaN fails the test too.
      constexpr double lo = -1e-4, hi = 1 + 1e-4;
      if (!(u >= lo && u <= hi && v >= lo && v <= hi))
        throw InvalidInput(name + ": face " + std::to_string(f) + " has texcoord (" + std::to_string(u) + ", " +
                           std::to_string(v) + "), expected a point of the unit square");
      chart.face_uv[f][k] = Vec2(u, v);
    }
    std::int32_t patch;
    get(patch);
    for (auto& c : rgb) get(c);
    // Every patch has at least one face, so an id past the face count cannot be right (and would
    // make readers allocate per-patch tables of that size).
    if (patch < 0 || patch >= nf)
      throw InvalidInput(name + ": face " + std::to_string(f) + " has patch " + std::to_string(patch) +
                         ", expected an id in [0, " + std::to_string(nf) + ") (at most one patch per face)");
    chart.face_patch[f] = patch;
    max_patch = std::max(max_patch, static_cast<int>(patch));
  }
  chart.patches.resize(max_patch + 1);
  return chart;
}

std::string chart_stem(const std::string& chart_file) {
  const std::string suffix = ".chart.ply";
  return chart_file.size() > suffix.size() &&
                 chart_file.compare(chart_file.size() - suffix.size(), suffix.size(), suffix) == 0
             ? chart_file.substr(0, chart_file.size() - suffix.size())
             : std::filesystem::path(chart_file).stem().string();
}

}  // namespace qs::dissect
