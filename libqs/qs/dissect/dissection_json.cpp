#include "qs/dissect/dissection_json.h"

#include <nlohmann/json.hpp>

namespace qs::dissect {

using nlohmann::ordered_json;

std::string dissection_to_json(const std::vector<DissectedMesh>& meshes, const DissectOptions& options,
                               bool include_times) {
  ordered_json doc;
  doc["format"] = "qs-dissection";
  doc["version"] = kDissectionFormatVersion;
  doc["options"] = {{"tau", options.tau},
                    {"max_depth", options.max_depth},
                    {"min_faces_to_split", options.min_faces_to_split},
                    {"w_bias", options.w_bias},
                    {"w_min", options.w_min},
                    {"w_max", options.w_max},
                    {"peak_margin", options.peak_margin}};
  if (meshes.empty()) return doc.dump(2);
  const Dissection& first = meshes.front().dissection;
  ordered_json tree = ordered_json::array();
  for (const auto& n : first.tree) {
    ordered_json j = {{"name", n.name}, {"depth", n.depth}, {"split", n.split}};
    if (n.split) {
      j["peak_uv"] = {n.peak_uv.x(), n.peak_uv.y()};
      j["w"] = n.w;
    }
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
  for (const auto& m : meshes) {
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
    for (const auto& n : d.tree) node_stretch[n.name] = n.stretch;
    ordered_json j = {{"file", m.file},
                      {"chart", m.chart_file},
                      {"input_vertices", m.input_vertices},
                      {"input_faces", m.input_faces},
                      {"chart_vertices", d.chart.mesh.positions.size()},
                      {"chart_faces", d.chart.mesh.faces.size()},
                      {"seed_source", m.seed_source},
                      {"seeds", d.seeds},
                      {"base_vertices", d.base.vertices},
                      {"max_stretch", d.max_stretch},
                      {"patches_over_tau", over},
                      {"node_stretch", node_stretch},
                      {"patches", patches}};
    if (include_times) j["seconds"] = m.seconds;
    list.push_back(j);
  }
  doc["meshes"] = list;
  return doc.dump(2) + "\n";
}

}  // namespace qs::dissect
