#include "qs/family/surface_map.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"

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

SurfaceMap parse_surface_map(const std::string& text, const std::string& name) {
  auto bad = [&](const std::string& m) { return InvalidInput(name + ": " + m); };
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw bad(std::string("not valid JSON (") + e.what() + ")");
  }
  try {
    if (!j.is_object() || j.value("format", "") != "qs-map")
      throw bad("not a qs map file (expected \"format\": \"qs-map\")");
    if (j.value("version", 0) != 1) throw bad("unsupported version (expected 1)");
    const std::string domain = j.value("domain", "");
    const long vertices = j.at("vertices").get<long>();
    SurfaceMap map;
    if (domain == "sphere") {
      map.domain = MapDomain::Sphere;
      const auto& a = j.at("sphere");
      if (!a.is_array() || static_cast<long>(a.size()) != vertices)
        throw bad("\"sphere\" must hold \"vertices\" = " + std::to_string(vertices) + " vectors");
      map.sphere.reserve(a.size());
      for (std::size_t i = 0; i < a.size(); ++i) {
        const auto& v = a[i];
        if (!v.is_array() || v.size() != 3) throw bad("sphere[" + std::to_string(i) + "] is not [x, y, z]");
        const Vec3 p(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
        if (!(std::abs(p.norm() - 1) <= 1e-6))
          throw bad("sphere[" + std::to_string(i) + "] is not a unit vector (length " + num(p.norm()) + ")");
        map.sphere.push_back(p);
      }
    } else if (domain == "surface") {
      map.domain = MapDomain::Surface;
      map.reference = j.at("reference").get<std::string>();
      map.reference_vertices = j.at("reference_vertices").get<int>();
      map.reference_faces = j.at("reference_faces").get<int>();
      const auto& a = j.at("origins");
      if (!a.is_array() || static_cast<long>(a.size()) != vertices)
        throw bad("\"origins\" must hold \"vertices\" = " + std::to_string(vertices) + " entries");
      map.origins.reserve(a.size());
      for (std::size_t i = 0; i < a.size(); ++i) {
        const auto& v = a[i];
        const std::string at = "origins[" + std::to_string(i) + "]";
        if (!v.is_array() || v.size() != 4) throw bad(at + " is not [face, b0, b1, b2]");
        landmarks::SurfacePoint sp;
        sp.face = v[0].get<int>();
        if (sp.face < 0 || sp.face >= map.reference_faces)
          throw bad(at + ": face " + std::to_string(sp.face) + " is outside [0, reference_faces = " +
                    std::to_string(map.reference_faces) + ")");
        for (int k = 0; k < 3; ++k) sp.bary[k] = v[k + 1].get<double>();
        const double sum = sp.bary[0] + sp.bary[1] + sp.bary[2];
        if (!(sp.bary[0] >= -1e-9 && sp.bary[1] >= -1e-9 && sp.bary[2] >= -1e-9 && std::abs(sum - 1) <= 1e-6))
          throw bad(at + ": barycentric weights must be >= 0 and sum to 1");
        map.origins.push_back(sp);
      }
    } else {
      throw bad("\"domain\" must be \"sphere\" or \"surface\"");
    }
    return map;
  } catch (const nlohmann::json::exception& e) {
    throw bad(std::string("malformed map file (") + e.what() + ")");
  }
}

SurfaceMap read_surface_map(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string() + ": cannot open the map file");
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw IoError(path.string() + ": cannot read the map file");
  return parse_surface_map(s.str(), path.string());
}

}  // namespace qs::family
