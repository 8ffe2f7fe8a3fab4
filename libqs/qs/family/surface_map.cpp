#include "qs/family/surface_map.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/core/json_strict.h"

namespace qs::family {

namespace {

std::string num(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

}  // namespace

std::string surface_map_to_json(const SurfaceMap& map) {
  std::ostringstream s;
  s << "{\"format\": \"qs-map\", \"version\": 1, ";
  if (map.domain == MapDomain::Sphere) {
    s << "\"domain\": \"sphere\", \"vertices\": " << map.sphere.size() << ",\n\"sphere\": [\n";
    for (std::size_t i = 0; i < map.sphere.size(); ++i)
      s << "[" << num(map.sphere[i].x()) << ", " << num(map.sphere[i].y()) << ", " << num(map.sphere[i].z()) << "]"
        << (i + 1 < map.sphere.size() ? ",\n" : "\n");
  } else {
    nlohmann::json ref = map.reference;  // escapes the path
    s << "\"domain\": \"surface\", \"vertices\": " << map.origins.size() << ", \"reference\": " << ref.dump()
      << ", \"reference_vertices\": " << map.reference_vertices << ", \"reference_faces\": " << map.reference_faces
      << ",\n\"origins\": [\n";
    for (std::size_t i = 0; i < map.origins.size(); ++i) {
      const auto& o = map.origins[i];
      s << "[" << o.face << ", " << num(o.bary[0]) << ", " << num(o.bary[1]) << ", " << num(o.bary[2]) << "]"
        << (i + 1 < map.origins.size() ? ",\n" : "\n");
    }
  }
  s << "]}\n";
  return s.str();
}

void write_surface_map(const std::filesystem::path& path, const SurfaceMap& map) {
  write_file_atomically(path, surface_map_to_json(map));
}

SurfaceMap parse_surface_map(const std::string& text, const std::string& file) {
  // Read as hostile text (json_strict): bounded nesting, no repeated keys, integers in range
  // without wrapping, finite numbers; messages name the file and the field.
  const std::string name = json_strict::printable(file);
  auto bad = [&](const std::string& m) { return InvalidInput(name + ": " + m); };
  const nlohmann::json j = json_strict::parse(text, name);
  const auto format = j.is_object() ? j.find("format") : j.end();
  if (!j.is_object() || format == j.end() || *format != "qs-map")
    throw bad("not a qs map file (expected \"format\": \"qs-map\")");
  auto field = [&](const char* key) -> const nlohmann::json& {
    const auto it = j.find(key);
    if (it == j.end()) throw bad(std::string("\"") + key + "\" is missing");
    return *it;
  };
  auto integer = [&](const nlohmann::json& v, long long lo, long long hi, const std::string& what) {
    long long out = 0;
    if (!json_strict::integer_in(v, lo, hi, out))
      throw bad(what + " is " + json_strict::describe(v) + "; expected an integer in [" + std::to_string(lo) + ", " +
                std::to_string(hi) + "]");
    return out;
  };
  auto number = [&](const nlohmann::json& v, const std::string& what) {
    double out = 0;
    if (!json_strict::finite_number(v, out)) throw bad(what + " is " + json_strict::describe(v) + "; expected a finite number");
    return out;
  };
  constexpr long long kMaxCount = std::numeric_limits<int>::max();
  long long version = 0;
  if (!json_strict::integer_in(field("version"), 1, 1, version))
    throw bad("unsupported version " + json_strict::describe(field("version")) + " (expected 1)");
  const nlohmann::json& domain = field("domain");
  const long long vertices = integer(field("vertices"), 0, kMaxCount, "\"vertices\"");
  SurfaceMap map;
  if (domain == "sphere") {
    map.domain = MapDomain::Sphere;
    const auto& a = field("sphere");
    if (!a.is_array() || static_cast<long long>(a.size()) != vertices)
      throw bad("\"sphere\" must hold \"vertices\" = " + std::to_string(vertices) + " vectors");
    map.sphere.reserve(a.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      const std::string at = "sphere[" + std::to_string(i) + "]";
      const auto& v = a[i];
      if (!v.is_array() || v.size() != 3) throw bad(at + " is not [x, y, z]");
      const Vec3 p(number(v[0], at), number(v[1], at), number(v[2], at));
      if (!(std::abs(p.norm() - 1) <= 1e-6)) throw bad(at + " is not a unit vector (length " + num(p.norm()) + ")");
      map.sphere.push_back(p);
    }
  } else if (domain == "surface") {
    map.domain = MapDomain::Surface;
    const auto& reference = field("reference");
    if (!reference.is_string()) throw bad("\"reference\" is " + json_strict::describe(reference) + "; expected a file name");
    map.reference = reference.get<std::string>();
    map.reference_vertices = static_cast<int>(integer(field("reference_vertices"), 0, kMaxCount, "\"reference_vertices\""));
    map.reference_faces = static_cast<int>(integer(field("reference_faces"), 0, kMaxCount, "\"reference_faces\""));
    const auto& a = field("origins");
    if (!a.is_array() || static_cast<long long>(a.size()) != vertices)
      throw bad("\"origins\" must hold \"vertices\" = " + std::to_string(vertices) + " entries");
    map.origins.reserve(a.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      const auto& v = a[i];
      const std::string at = "origins[" + std::to_string(i) + "]";
      if (!v.is_array() || v.size() != 4) throw bad(at + " is not [face, b0, b1, b2]");
      landmarks::SurfacePoint sp;
      long long face = 0;
      if (!json_strict::integer_in(v[0], std::numeric_limits<int>::min(), kMaxCount, face))
        throw bad(at + ": the face is " + json_strict::describe(v[0]) + "; expected an integer");
      if (face < 0 || face >= map.reference_faces)
        throw bad(at + ": face " + std::to_string(face) + " is outside [0, reference_faces = " +
                  std::to_string(map.reference_faces) + ")");
      sp.face = static_cast<int>(face);
      for (int k = 0; k < 3; ++k) sp.bary[k] = number(v[k + 1], at);
      const double sum = sp.bary[0] + sp.bary[1] + sp.bary[2];
      if (!(sp.bary[0] >= -1e-9 && sp.bary[1] >= -1e-9 && sp.bary[2] >= -1e-9 && std::abs(sum - 1) <= 1e-6))
        throw bad(at + ": barycentric weights must be >= 0 and sum to 1");
      map.origins.push_back(sp);
    }
  } else {
    throw bad("\"domain\" is " + json_strict::describe(domain) + "; expected \"sphere\" or \"surface\"");
  }
  return map;
}

SurfaceMap read_surface_map(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(json_strict::printable(path.string()) + ": cannot open the map file");
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw IoError(json_strict::printable(path.string()) + ": cannot read the map file");
  return parse_surface_map(s.str(), path.string());
}

}  // namespace qs::family
