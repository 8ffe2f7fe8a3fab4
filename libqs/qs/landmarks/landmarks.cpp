#include "qs/landmarks/landmarks.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "qs/core/error.h"
#include "qs/core/finite.h"
#include "qs/core/json_strict.h"

namespace qs::landmarks {

std::array<double, 3> closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0)) return {1, 0, 0};  // degenerate triangle: its first corner
  const double v = vb / denom, w = vc / denom;
  return {1 - v - w, v, w};
}

namespace {

using nlohmann::json;

// Resolves references in the file's numbering against the validated mesh.
class Resolver {
 public:
  Resolver(const std::string& source, const mesh::ValidationResult& m, const LandmarkOptions& o)
      : source_(source), m_(m), opt_(o) {
    // First face (lowest id) around each output vertex, for vertex references.
    first_face_.assign(m.mesh.positions.size(), -1);
    for (int f = m.mesh.num_faces() - 1; f >= 0; --f)
      for (int k = 0; k < 3; ++k) first_face_[m.mesh.faces[f][k]] = f;
  }

  [[noreturn]] void fail(const std::string& what, const std::string& msg) const {
    throw InvalidInput(source_ + ": landmark '" + json_strict::printable(what, 80) + "': " + msg);
  }

  /// Names are matched across meshes and written into dissection.json: they must be text.
  void check_name(const std::string& name) const {
    if (name.empty()) fail(name, "the name is empty");
    if (name.size() > 256) fail(name, "the name is longer than 256 bytes");
    if (!json_strict::is_clean_text(name))
      fail(name, "the name is not UTF-8 text (or holds control characters); save the file as UTF-8");
  }

  Landmark vertex(const std::string& name, long long input_id) const {
    const long long n = static_cast<long long>(m_.vertex_map.size());
    if (input_id < 0 || input_id >= n)
      fail(name, "vertex " + std::to_string(input_id) + " is out of range (the mesh has " +
                     std::to_string(n) + " vertices, ids 0.." + std::to_string(n - 1) + ")");
    const int v = m_.vertex_map[input_id];
    if (v < 0) fail(name, "vertex " + std::to_string(input_id) + " is used by no face");
    Landmark lm;
    lm.name = name;
    lm.vertex = v;
    lm.where.face = first_face_[v];
    const Tri& t = m_.mesh.faces[lm.where.face];
    lm.where.bary = {t[0] == v ? 1.0 : 0.0, t[1] == v ? 1.0 : 0.0, t[2] == v ? 1.0 : 0.0};
    lm.position = m_.mesh.positions[v];
    return lm;
  }

  Landmark face(const std::string& name, long long f, std::array<double, 3> bary) const {
    const long long n = m_.mesh.num_faces();
    if (f < 0 || f >= n)
      fail(name, "face " + std::to_string(f) + " is out of range (the mesh has " + std::to_string(n) +
                     " faces)");
    for (double b : bary)
      if (!std::isfinite(b) || b < -1e-9)
        fail(name, "barycentric coordinates must be finite and non-negative");
    const double sum = bary[0] + bary[1] + bary[2];
    if (std::abs(sum - 1.0) > 1e-6)
      fail(name, "barycentric coordinates sum to " + std::to_string(sum) + ", expected 1");
    for (double& b : bary) b = std::max(0.0, b) / sum;
    if (m_.report.orientation_flipped) std::swap(bary[1], bary[2]);  // corners 1 and 2 swapped
    Landmark lm;
    lm.name = name;
    lm.where = {static_cast<int>(f), bary};
    lm.position = position_of(m_.mesh, lm.where);
    for (int k = 0; k < 3; ++k)
      if (bary[k] == 1.0) lm.vertex = m_.mesh.faces[f][k];
    return lm;
  }

  Landmark point(const std::string& name, const Vec3& p) const {
    if (!usable_position(p))
      fail(name, "point coordinates must be finite numbers of magnitude at most 1e100");
    double d = 0;
    Landmark lm;
    lm.name = name;
    lm.where = closest_surface_point(m_.mesh, p, &d);
    lm.position = position_of(m_.mesh, lm.where);
    lm.snap_distance = d;
    const double limit = opt_.max_snap_fraction * m_.report.bbox_diagonal;
    if (d > limit) {
      std::ostringstream s;
      s << "point (" << p.x() << ", " << p.y() << ", " << p.z() << ") is " << d
        << " from the surface, more than " << opt_.max_snap_fraction * 100
        << "% of the bounding-box diagonal (" << limit
        << "); was it picked on another mesh or in other units?";
      fail(name, s.str());
    }
    // A point within 1e-6 of the diagonal of a vertex is that vertex (picked points are rounded).
    const Tri& t = m_.mesh.faces[lm.where.face];
    for (int k = 0; k < 3; ++k)
      if ((m_.mesh.positions[t[k]] - lm.position).norm() <= 1e-6 * m_.report.bbox_diagonal) {
        lm.vertex = t[k];
        lm.where.bary = {k == 0 ? 1.0 : 0.0, k == 1 ? 1.0 : 0.0, k == 2 ? 1.0 : 0.0};
        lm.position = m_.mesh.positions[t[k]];
        break;
      }
    return lm;
  }

 private:
  std::string source_;
  const mesh::ValidationResult& m_;
  LandmarkOptions opt_;
  std::vector<int> first_face_;
};

// A vertex or face id: an integer (a huge unsigned one is out of range, never wrapped to -1).
long long json_id(const Resolver& r, const std::string& name, const json& j, const char* what) {
  long long id = 0;
  if (json_strict::integer_in(j, std::numeric_limits<long long>::min(), std::numeric_limits<long long>::max(), id))
    return id;
  if (j.is_number_integer())  // an unsigned value past the signed range
    r.fail(name, std::string(what) + " " + json_strict::describe(j) + " is out of range");
  r.fail(name, std::string("\"") + what + "\" must be an integer, found " + json_strict::describe(j));
}

Landmark parse_json_ref(const Resolver& r, const std::string& name, const json& j) {
  r.check_name(name);
  if (j.is_number_integer()) return r.vertex(name, json_id(r, name, j, "vertex"));
  if (!j.is_object())
    r.fail(name, "expected a vertex index, {\"vertex\": i}, {\"point\": [x, y, z]} or "
                 "{\"face\": f, \"bary\": [a, b, c]}, found " + json_strict::describe(j));
  auto number_array = [&](const json& a, size_t n, const char* key) {
    if (!a.is_array() || a.size() != n)
      r.fail(name, std::string("\"") + key + "\" must be an array of " + std::to_string(n) + " numbers");
    std::array<double, 3> out{};
    for (size_t i = 0; i < n; ++i) {
      if (!a[i].is_number()) r.fail(name, std::string("\"") + key + "\" must hold numbers");
      out[i] = a[i].get<double>();
    }
    return out;
  };
  if (j.contains("vertex") && j.size() == 1) return r.vertex(name, json_id(r, name, j["vertex"], "vertex"));
  if (j.contains("point") && j.size() == 1) {
    const auto p = number_array(j["point"], 3, "point");
    return r.point(name, Vec3(p[0], p[1], p[2]));
  }
  if (j.contains("face") && j.contains("bary") && j.size() == 2) {
    return r.face(name, json_id(r, name, j["face"], "face"), number_array(j["bary"], 3, "bary"));
  }
  r.fail(name, "unknown reference (" + json_strict::describe(j) + ")" +
                   "; expected {\"vertex\": i}, {\"point\": [x, y, z]} or {\"face\": f, \"bary\": [a, b, c]}");
}

Landmarks parse_json(std::string_view text, const std::string& name, const Resolver& r) {
  const json doc = json_strict::parse(text, name);
  if (!doc.is_object()) throw InvalidInput(name + ": expected a JSON object with \"seeds\" and/or \"features\"");
  for (const auto& [key, value] : doc.items())
    if (key != "seeds" && key != "features")
      throw InvalidInput(name + ": unknown key \"" + json_strict::printable(key, 80) +
                         "\"; expected \"seeds\" and/or \"features\"");
  Landmarks out;
  out.source = name;
  if (doc.contains("seeds")) {
    const json& s = doc["seeds"];
    if (!s.is_array() || s.size() != 4)
      throw InvalidInput(name + ": \"seeds\" must be an array of exactly 4 references, found " +
                         (s.is_array() ? std::to_string(s.size()) + " entries" : json_strict::describe(s)));
    for (int i = 0; i < 4; ++i) out.seeds.push_back(parse_json_ref(r, "seed" + std::to_string(i), s[i]));
  }
  if (doc.contains("features")) {
    const json& f = doc["features"];
    if (!f.is_object()) throw InvalidInput(name + ": \"features\" must be an object {\"name\": reference, ...}");
    for (const auto& [key, value] : f.items()) out.features.push_back(parse_json_ref(r, key, value));
  }
  return out;
}

// Reads attribute `key="value"` of one XML tag; nullopt when absent.
std::optional<std::string> attribute(std::string_view tag, std::string_view key) {
  size_t pos = 0;
  while ((pos = tag.find(key, pos)) != std::string_view::npos) {
    const bool starts = pos > 0 && std::isspace(static_cast<unsigned char>(tag[pos - 1]));
    size_t eq = pos + key.size();
    while (eq < tag.size() && std::isspace(static_cast<unsigned char>(tag[eq]))) ++eq;
    if (starts && eq < tag.size() && tag[eq] == '=') {
      size_t q = eq + 1;
      while (q < tag.size() && std::isspace(static_cast<unsigned char>(tag[q]))) ++q;
      if (q < tag.size() && (tag[q] == '"' || tag[q] == '\'')) {
        const size_t end = tag.find(tag[q], q + 1);
        if (end == std::string_view::npos) return std::nullopt;
        return std::string(tag.substr(q + 1, end - q - 1));
      }
    }
    pos += key.size();
  }
  return std::nullopt;
}

Landmarks parse_pp(std::string_view text, const std::string& name, const Resolver& r) {
  if (text.find("<PickedPoints") == std::string_view::npos)
    throw InvalidInput(name + ": not a MeshLab PickedPoints file (no <PickedPoints> element)");
  Landmarks out;
  out.source = name;
  std::map<int, Landmark> seeds;
  size_t pos = 0;
  while ((pos = text.find("<point", pos)) != std::string_view::npos) {
    const size_t end = text.find('>', pos);
    const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + pos, '\n'));
    const std::string where = name + ":" + std::to_string(line);
    if (end == std::string_view::npos) throw InvalidInput(where + ": unterminated <point> element");
    const std::string_view tag = text.substr(pos, end - pos);
    pos = end;
    if (auto active = attribute(tag, "active"); active && *active == "0") continue;
    const auto label = attribute(tag, "name");
    if (!label || label->empty()) throw InvalidInput(where + ": <point> without a name");
    r.check_name(*label);
    Vec3 p;
    const char* axes[3] = {"x", "y", "z"};
    for (int k = 0; k < 3; ++k) {
      const auto v = attribute(tag, axes[k]);
      char* stop = nullptr;
      if (!v) throw InvalidInput(where + ": point '" + *label + "' has no " + axes[k] + " attribute");
      p[k] = std::strtod(v->c_str(), &stop);
      if (stop == v->c_str() || *stop != '\0')
        throw InvalidInput(where + ": point '" + *label + "': " + axes[k] + "=\"" + json_strict::printable(*v, 40) +
                           "\" is not a number");
    }
    if (label->size() == 5 && label->rfind("seed", 0) == 0 && (*label)[4] >= '0' && (*label)[4] <= '3') {
      const int i = (*label)[4] - '0';
      if (seeds.count(i)) throw InvalidInput(where + ": seed" + std::to_string(i) + " is given twice");
      seeds[i] = r.point(*label, p);
    } else {
      out.features.push_back(r.point(*label, p));
    }
  }
  if (!seeds.empty()) {
    if (seeds.size() != 4) {
      std::string missing;
      for (int i = 0; i < 4; ++i)
        if (!seeds.count(i)) missing += (missing.empty() ? "seed" : ", seed") + std::to_string(i);
      throw InvalidInput(name + ": " + std::to_string(seeds.size()) +
                         " of the 4 seed points are given; missing " + missing);
    }
    for (auto& [i, lm] : seeds) out.seeds.push_back(lm);
  }
  return out;
}

void check(Landmarks& lm) {
  // Duplicate seeds: the same vertex, or the same point.
  for (size_t i = 0; i < lm.seeds.size(); ++i)
    for (size_t j = i + 1; j < lm.seeds.size(); ++j) {
      const Landmark &a = lm.seeds[i], &b = lm.seeds[j];
      const bool same_vertex = a.vertex >= 0 && a.vertex == b.vertex;
      if (same_vertex || (a.position - b.position).norm() == 0.0)
        throw InvalidInput(lm.source + ": " + a.name + " and " + b.name + " are the same point" +
                           (same_vertex ? " (vertex " + std::to_string(a.vertex) + ")" : "") +
                           "; the 4 seeds must be distinct");
    }
  std::sort(lm.features.begin(), lm.features.end(),
            [](const Landmark& a, const Landmark& b) { return a.name < b.name; });
  for (size_t i = 1; i < lm.features.size(); ++i)
    if (lm.features[i].name == lm.features[i - 1].name)
      throw InvalidInput(lm.source + ": feature '" + lm.features[i].name + "' is given twice");
}

}  // namespace

SurfacePoint closest_surface_point(const TriMesh& mesh, const Vec3& p, double* distance) {
  SurfacePoint best;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Tri& t = mesh.faces[f];
    const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    // Cheap reject by the distance to the triangle's bounding sphere around a.
    const double r2 = std::max((b - a).squaredNorm(), (c - a).squaredNorm());
    const double da = (p - a).norm() - std::sqrt(r2);
    if (da > 0 && da * da > best_d2) continue;
    const auto bc = closest_on_triangle(p, a, b, c);
    const double d2 = (bc[0] * a + bc[1] * b + bc[2] * c - p).squaredNorm();
    if (d2 < best_d2) {
      best_d2 = d2;
      best = {f, bc};
    }
  }
  if (distance) *distance = std::sqrt(best_d2);
  return best;
}

Vec3 position_of(const TriMesh& mesh, const SurfacePoint& sp) {
  const Tri& t = mesh.faces.at(sp.face);
  return sp.bary[0] * mesh.positions[t[0]] + sp.bary[1] * mesh.positions[t[1]] +
         sp.bary[2] * mesh.positions[t[2]];
}

Landmarks parse_landmarks(std::string_view text, LandmarkFormat format, const std::string& name,
                          const mesh::ValidationResult& mesh, const LandmarkOptions& options) {
  if (!mesh.report.accepted)
    throw InvalidInput(name + ": landmarks need a valid mesh, and this one was rejected");
  const Resolver resolver(name, mesh, options);
  Landmarks out = format == LandmarkFormat::Json ? parse_json(text, name, resolver)
                                                 : parse_pp(text, name, resolver);
  check(out);
  return out;
}

Landmarks read_landmarks(const std::filesystem::path& path, const mesh::ValidationResult& mesh,
                         const LandmarkOptions& options) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  LandmarkFormat format;
  if (ext == ".json") format = LandmarkFormat::Json;
  else if (ext == ".pp") format = LandmarkFormat::PickedPoints;
  else
    throw InvalidInput(path.string() + ": unknown landmark file type '" + ext +
                       "'; expected .json or MeshLab's .pp");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string() + ": cannot open landmark file");
  std::ostringstream buf;
  buf << in.rdbuf();
  if (in.bad()) throw IoError(path.string() + ": read error");
  return parse_landmarks(buf.str(), format, path.string(), mesh, options);
}

std::optional<std::filesystem::path> find_landmarks_beside(const std::filesystem::path& mesh_path) {
  for (const char* suffix : {".landmarks.json", ".pp"}) {
    std::filesystem::path p = mesh_path.parent_path() / (mesh_path.stem().string() + suffix);
    if (std::filesystem::is_regular_file(p)) return p;
  }
  return std::nullopt;
}

}  // namespace qs::landmarks
