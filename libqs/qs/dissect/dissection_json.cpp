#include "qs/dissect/dissection_json.h"

#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>

#include "qs/core/error.h"
#include "qs/core/json_strict.h"
#include "qs/dissect/chart_io.h"

namespace qs::dissect {

using nlohmann::ordered_json;

namespace {

std::string document(const std::vector<DissectedMesh>& meshes, ordered_json options, bool include_times,
                     const std::string& maps) {
  ordered_json doc;
  doc["format"] = "qs-dissection";
  doc["version"] = kDissectionFormatVersion;
  if (!maps.empty()) doc["maps"] = maps;
  doc["options"] = std::move(options);
  if (meshes.empty()) return json_strict::dump(doc, 2);
  const Dissection& first = meshes.front().dissection;
  ordered_json tree = ordered_json::array();
  for (const auto& n : first.tree) {
    ordered_json j = {{"name", n.name}, {"depth", n.depth}, {"split", n.split}, {"stretch", n.stretch}};
    if (n.split) {
      j["peak_uv"] = {n.peak_uv.x(), n.peak_uv.y()};
      j["w"] = n.w;
      j["peak_mesh"] = n.split_mesh;
      if (n.posed) j["posed"] = true;
    }
    if (n.features > 0) {
      j["features"] = n.features;
      j["feature_groups"] = n.feature_groups;
      j["features_held"] = n.features_held;
      j["warp_events"] = n.warp_events;
      j["pinned_solves"] = n.pinned_solves;
    }
    if (!n.refined_faces.empty()) j["refined_faces"] = n.refined_faces;  // per mesh
    tree.push_back(j);
  }
  doc["tree"] = tree;
  ordered_json names = ordered_json::array(), quads = ordered_json::array();
  for (size_t i = 0; i < first.chart.patches.size(); ++i) {
    names.push_back(first.chart.patches[i].name);
    quads.push_back(first.base.quads[i]);
  }
  doc["base_domain"] = {{"vertices", first.base.vertices.size()},
                        {"edges", first.base.edges},
                        {"faces", first.base.quads.size()},
                        {"euler_characteristic", first.base.euler_characteristic},
                        {"closed_conforming", first.base.closed_conforming},
                        {"patches", names},
                        {"quads", quads}};
  ordered_json list = ordered_json::array();
  for (size_t mi = 0; mi < meshes.size(); ++mi) {
    const auto& m = meshes[mi];
    const Dissection& d = m.dissection;
    ordered_json patches = ordered_json::array();
    int over = 0;
    for (const auto& p : d.chart.patches) {
      ordered_json j = {{"name", p.name},
                        {"corners", p.corners},
                        {"faces", p.faces},
                        {"stretch", p.stretch},
                        {"flipped_faces", p.flipped_faces},
                        {"zero_area_faces", p.zero_area_faces},
                        {"uv_area_sum", p.uv_area_sum}};
      if (p.stop != StopReason::None) {
        j["stop_reason"] = stop_reason_name(p.stop);
        if (!p.stop_detail.empty()) j["stop_detail"] = p.stop_detail;
        ++over;
      }
      patches.push_back(j);
    }
    ordered_json node_stretch = ordered_json::object();
    for (const auto& n : d.tree)
      node_stretch[n.name] = mi < n.mesh_stretch.size() ? n.mesh_stretch[mi] : n.stretch;
    ordered_json features = ordered_json::array();
    for (const auto& f : d.features)
      features.push_back({{"name", f.name},
                          {"vertex", f.vertex},
                          {"patch", d.chart.patches[f.patch].name},
                          {"uv", {f.uv.x(), f.uv.y()}}});
    // Where each seed landed: a chart vertex, and the input surface point it was inserted at.
    ordered_json seed_places = ordered_json::array();
    for (const auto& sp : d.seed_placements) {
      ordered_json q = {{"vertex", sp.vertex}, {"inserted", sp.inserted}};
      if (sp.inserted) {
        q["face"] = sp.where.face;
        q["bary"] = sp.where.bary;
      }
      q["position"] = {sp.position.x(), sp.position.y(), sp.position.z()};
      seed_places.push_back(q);
    }
    ordered_json j = {{"file", m.file},
                      {"chart", m.chart_file},
                      {"input_vertices", m.input_vertices},
                      {"input_faces", m.input_faces},
                      {"chart_vertices", d.chart.mesh.positions.size()},
                      {"chart_faces", d.chart.mesh.faces.size()},
                      {"seed_source", m.seed_source},
                      {"seeds", d.seeds},
                      {"seed_placements", seed_places},
                      {"base_vertices", d.base.vertices},
                      {"max_stretch", d.max_stretch},
                      {"patches_over_tau", over},
                      {"node_stretch", node_stretch},
                      {"features", features},
                      {"patches", patches}};
    if (include_times) j["seconds"] = m.seconds;
    list.push_back(j);
  }
  doc["meshes"] = list;
  return json_strict::dump(doc, 2) + "\n";
}

}  // namespace

std::string dissection_to_json(const std::vector<DissectedMesh>& meshes, const DissectOptions& options,
                               bool include_times, const std::string& maps) {
  ordered_json o = {{"tau", options.tau},
                    {"max_depth", options.max_depth},
                    {"min_faces_to_split", options.min_faces_to_split},
                    {"w_bias", options.w_bias},
                    {"w_min", options.w_min},
                    {"w_max", options.w_max},
                    {"peak_margin", options.peak_margin},
                    {"feature_cut_margin", options.feature_cut_margin},
                    {"feature_group_distance", options.feature_group_distance},
                    {"geodesic_seed_curves", options.geodesic_seed_curves},
                    {"intrinsic_cotan", options.intrinsic_cotan},
                    {"fallback_maps", options.fallback_maps},
                    {"stretch_iterations", options.stretch_iterations},
                    {"max_patch_area", options.max_patch_area},
                    {"min_split_area", options.min_split_area},
                    {"force_split_area", options.force_split_area},
                    {"area_extra_depth", options.area_extra_depth},
                    {"protrusion_stretch", options.protrusion_stretch},
                    {"same_pose", options.same_pose},
                    {"same_pose_detect", options.same_pose_detect},
                    {"same_pose_maps", options.same_pose_maps}};
  return document(meshes, std::move(o), include_times, maps);
}

std::string dissection_to_json(const std::vector<DissectedMesh>& meshes, const std::string& options_json,
                               bool include_times, const std::string& maps) {
  ordered_json o = ordered_json::parse(options_json);
  if (!o.is_object()) throw InvalidInput("dissection_to_json: the options must be a JSON object");
  return document(meshes, std::move(o), include_times, maps);
}

}  // namespace qs::dissect

namespace qs::dissect {

namespace {

// Field access with messages that name the file and the field. Every value is checked for its
// type and range before it is converted (no wrapping of large integers, no NaN or infinity).
struct Reader {
  std::string file;
  const nlohmann::json& at(const nlohmann::json& j, const char* key, const std::string& where) const {
    if (!j.is_object() || !j.contains(key))
      throw InvalidInput(file + ": " + json_strict::printable(where, 80) + " lacks \"" + key + "\"");
    return j.at(key);
  }
  [[noreturn]] void wrong(const char* key, const std::string& where, const char* expected,
                          const nlohmann::json& found) const {
    throw InvalidInput(file + ": " + json_strict::printable(where, 80) + "." + key + " must be " + expected +
                       ", found " + json_strict::describe(found));
  }
  int integer(const nlohmann::json& v, const char* key, const std::string& where) const {
    long long x = 0;
    if (!json_strict::integer_in(v, -1, std::numeric_limits<int>::max(), x))
      wrong(key, where, "an integer in [-1, 2^31)", v);
    return static_cast<int>(x);
  }
  template <class T>
  T get(const nlohmann::json& j, const char* key, const std::string& where) const {
    const nlohmann::json& v = at(j, key, where);
    if constexpr (std::is_same_v<T, int>) {
      return integer(v, key, where);
    } else if constexpr (std::is_same_v<T, double>) {
      double x = 0;
      if (!json_strict::finite_number(v, x)) wrong(key, where, "a finite number", v);
      return x;
    } else if constexpr (std::is_same_v<T, bool>) {
      if (!v.is_boolean()) wrong(key, where, "true or false", v);
      return v.get<bool>();
    } else if constexpr (std::is_same_v<T, std::string>) {
      if (!v.is_string()) wrong(key, where, "a string", v);
      const auto& str = v.get_ref<const std::string&>();
      if (!json_strict::is_clean_text(str)) wrong(key, where, "UTF-8 text without control characters", v);
      return str;
    } else if constexpr (std::is_same_v<T, std::array<int, 4>>) {
      if (!v.is_array() || v.size() != 4) wrong(key, where, "an array of 4 integers", v);
      std::array<int, 4> a{};
      for (int i = 0; i < 4; ++i) a[i] = integer(v[i], key, where);
      return a;
    } else {
      static_assert(std::is_same_v<T, std::array<double, 2>>);
      if (!v.is_array() || v.size() != 2) wrong(key, where, "an array of 2 numbers", v);
      std::array<double, 2> a{};
      for (int i = 0; i < 2; ++i)
        if (!json_strict::finite_number(v[i], a[i])) wrong(key, where, "an array of 2 finite numbers", v);
      return a;
    }
  }
  const nlohmann::json& array(const nlohmann::json& j, const char* key, const std::string& where) const {
    const nlohmann::json& v = at(j, key, where);
    if (!v.is_array()) wrong(key, where, "an array", v);
    return v;
  }
};

}  // namespace

LoadedDissection read_dissection(const std::filesystem::path& folder) {
  const std::filesystem::path path = folder / "dissection.json";
  if (!std::filesystem::is_directory(folder))
    throw IoError(json_strict::printable(folder.string()) + ": no such folder (expected a qs-dissect output folder with dissection.json)");
  const nlohmann::json doc = json_strict::parse(
      json_strict::read_text_file(path, "dissection.json (is " + json_strict::printable(folder.string()) +
                                            " a qs-dissect output folder?)"),
      json_strict::printable(path.string()));
  const Reader r{json_strict::printable(path.string())};
  const auto format = doc.is_object() ? doc.find("format") : doc.end();
  if (!doc.is_object() || format == doc.end() || *format != "qs-dissection")
    throw InvalidInput(path.string() + ": not a qs-dissection file (\"format\" must be \"qs-dissection\")");
  const int version = r.get<int>(doc, "version", "the document");
  if (version != kDissectionFormatVersion)
    throw InvalidInput(path.string() + ": format version " + std::to_string(version) + ", this qs reads version " +
                       std::to_string(kDissectionFormatVersion) + "; run qs-dissect again");
  LoadedDissection out;
  const auto& o = r.at(doc, "options", "the document");
  out.options.tau = r.get<double>(o, "tau", "options");
  out.options.max_depth = r.get<int>(o, "max_depth", "options");
  out.options.min_faces_to_split = r.get<int>(o, "min_faces_to_split", "options");
  std::vector<TreeNode> tree;
  for (const auto& n : r.array(doc, "tree", "the document")) {
    TreeNode t;
    t.name = r.get<std::string>(n, "name", "a tree node");
    t.depth = r.get<int>(n, "depth", "tree node " + t.name);
    t.split = r.get<bool>(n, "split", "tree node " + t.name);
    tree.push_back(t);
  }
  const auto& meshes = r.at(doc, "meshes", "the document");
  if (!meshes.is_array() || meshes.empty()) throw InvalidInput(path.string() + ": \"meshes\" is empty");
  for (size_t mi = 0; mi < meshes.size(); ++mi) {
    const auto& m = meshes[mi];
    const std::string where = "meshes[" + std::to_string(mi) + "]";
    DissectedMesh dm;
    dm.file = r.get<std::string>(m, "file", where);
    dm.chart_file = r.get<std::string>(m, "chart", where);
    dm.seed_source = r.get<std::string>(m, "seed_source", where);
    dm.input_vertices = r.get<int>(m, "input_vertices", where);
    dm.input_faces = r.get<int>(m, "input_faces", where);
    if (dm.chart_file.empty() || dm.chart_file == "." || dm.chart_file == ".." ||
        dm.chart_file.find('/') != std::string::npos || dm.chart_file.find('\\') != std::string::npos)
      throw InvalidInput(path.string() + ": " + where + ".chart must be a file name in the folder");
    Dissection& d = dm.dissection;
    d.chart = read_chart_ply(folder / dm.chart_file);
    d.tree = tree;
    d.seeds = r.get<std::array<int, 4>>(m, "seeds", where);
    const auto& patches = r.array(m, "patches", where);
    if (patches.size() < d.chart.patches.size())
      throw InvalidInput(path.string() + ": " + where + " lists " + std::to_string(patches.size()) +
                         " patches but its chart uses " + std::to_string(d.chart.patches.size()));
    d.chart.patches.clear();
    const int nv = static_cast<int>(d.chart.mesh.positions.size());
    if (dm.input_vertices < 0 || dm.input_vertices > nv || dm.input_faces < 0)
      throw InvalidInput(r.file + ": " + where + ".input_vertices is " + std::to_string(dm.input_vertices) +
                         ", expected a count in [0, " + std::to_string(nv) + "] (the chart keeps the input's vertices)");
    for (const auto& pj : patches) {
      PatchInfo p;
      p.name = r.get<std::string>(pj, "name", where + ".patches");
      const std::string pw = where + " patch " + p.name;
      p.corners = r.get<std::array<int, 4>>(pj, "corners", pw);
      for (int c : p.corners)
        if (c < 0 || c >= nv)
          throw InvalidInput(path.string() + ": " + pw + " has corner vertex " + std::to_string(c) +
                             " outside its chart's " + std::to_string(nv) + " vertices");
      p.faces = r.get<int>(pj, "faces", pw);
      // A non-bijective map scores infinity, which JSON writes as null.
      p.stretch = r.at(pj, "stretch", pw).is_null() ? std::numeric_limits<double>::infinity()
                                                    : r.get<double>(pj, "stretch", pw);
      p.flipped_faces = r.get<int>(pj, "flipped_faces", pw);
      p.zero_area_faces = r.get<int>(pj, "zero_area_faces", pw);
      p.uv_area_sum = r.get<double>(pj, "uv_area_sum", pw);
      d.max_stretch = std::max(d.max_stretch, p.stretch);
      d.chart.patches.push_back(p);
    }
    std::vector<int> count(d.chart.patches.size(), 0);
    for (int p : d.chart.face_patch) ++count[p];
    for (size_t p = 0; p < count.size(); ++p)
      if (count[p] != d.chart.patches[p].faces)
        throw InvalidInput(path.string() + ": patch " + d.chart.patches[p].name + " of " + dm.chart_file + " has " +
                           std::to_string(count[p]) + " faces in the chart but " +
                           std::to_string(d.chart.patches[p].faces) + " in dissection.json");
    if (m.contains("features"))
      for (const auto& fj : r.array(m, "features", where)) {
        FeaturePlacement f;
        f.name = r.get<std::string>(fj, "name", where + ".features");
        f.vertex = r.get<int>(fj, "vertex", where + " feature " + f.name);
        const std::string pn = r.get<std::string>(fj, "patch", where + " feature " + f.name);
        const auto uv = r.get<std::array<double, 2>>(fj, "uv", where + " feature " + f.name);
        f.uv = Vec2(uv[0], uv[1]);
        for (size_t p = 0; p < d.chart.patches.size(); ++p)
          if (d.chart.patches[p].name == pn) f.patch = static_cast<int>(p);
        if (f.patch < 0 || f.vertex < 0 || f.vertex >= nv)
          throw InvalidInput(path.string() + ": " + where + " feature " + f.name + " names an unknown patch or vertex");
        d.features.push_back(f);
      }
    d.base = build_base_domain(d.chart.patches);
    if (!d.base.closed_conforming || d.base.euler_characteristic != 2)
      throw InvalidInput(path.string() + ": the patches of " + dm.chart_file +
                         " do not form a closed quad base domain of Euler characteristic 2");
    if (!out.meshes.empty()) {
      const Dissection& first = out.meshes.front().dissection;
      bool same = first.chart.patches.size() == d.chart.patches.size() && first.base.quads == d.base.quads;
      for (size_t p = 0; same && p < d.chart.patches.size(); ++p)
        same = first.chart.patches[p].name == d.chart.patches[p].name;
      if (!same)
        throw InvalidInput(path.string() + ": " + dm.chart_file + " does not have the same patches and base domain as " +
                           out.meshes.front().chart_file);
    }
    out.meshes.push_back(std::move(dm));
  }
  return out;
}

std::vector<std::filesystem::path> dissected_mesh_candidates(const std::string& file,
                                                             const std::filesystem::path& folder) {
  namespace fs = std::filesystem;
  std::vector<fs::path> out;
  const fs::path name = fs::path(file).filename();
  std::error_code ec;
  for (const fs::path& p : {fs::path(file), folder / file, folder.parent_path() / file, folder / name,
                            folder.parent_path() / name})
    if (!p.empty() && fs::exists(p, ec)) out.push_back(p);
  return out;
}

}  // namespace qs::dissect
