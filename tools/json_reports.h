#pragma once
// JSON forms of the library's reports, shared by the tools' --json outputs.

#include <nlohmann/json.hpp>

#include "qs/io/read_mesh.h"
#include "qs/landmarks/landmarks.h"
#include "qs/mesh/validate.h"

namespace qs::tools {

inline const char* severity_name(mesh::Severity s) {
  switch (s) {
    case mesh::Severity::Note: return "note";
    case mesh::Severity::Warning: return "warning";
    case mesh::Severity::Fatal: return "fatal";
  }
  return "fatal";
}

inline nlohmann::json to_json(const io::ReadReport& r) {
  return {{"format", io::format_name(r.format)},
          {"variant", r.variant},
          {"polygons_triangulated", r.polygons_triangulated},
          {"degenerate_polygons_dropped", r.degenerate_polygons_dropped},
          {"notes", r.notes}};
}

inline nlohmann::json to_json(const mesh::ValidationReport& r) {
  nlohmann::json problems = nlohmann::json::array();
  for (const auto& p : r.problems)
    problems.push_back({{"kind", p.kind},
                        {"severity", severity_name(p.severity)},
                        {"count", p.count},
                        {"first_ids", p.first_ids},
                        {"message", p.message}});
  return {{"input_vertices", r.input_vertices},
          {"input_faces", r.input_faces},
          {"vertices", r.vertices},
          {"faces", r.faces},
          {"edges", r.edges},
          {"components", r.components},
          {"boundary_loop_sizes", r.boundary_loop_sizes},
          {"euler_characteristic", r.euler_characteristic},
          {"genus", r.genus},
          {"orientation_flipped", r.orientation_flipped},
          {"min_angle_degrees", r.min_angle_degrees},
          {"bbox_diagonal", r.bbox_diagonal},
          {"problems", problems},
          {"accepted", r.accepted}};
}

inline nlohmann::json to_json(const landmarks::Landmark& l) {
  nlohmann::json j = {{"name", l.name},
                      {"face", l.where.face},
                      {"bary", l.where.bary},
                      {"position", {l.position.x(), l.position.y(), l.position.z()}}};
  if (l.vertex >= 0) j["vertex"] = l.vertex;
  if (l.snap_distance > 0) j["snap_distance"] = l.snap_distance;
  return j;
}

inline nlohmann::json to_json(const landmarks::Landmarks& lm) {
  nlohmann::json seeds = nlohmann::json::array(), features = nlohmann::json::array();
  for (const auto& l : lm.seeds) seeds.push_back(to_json(l));
  for (const auto& l : lm.features) features.push_back(to_json(l));
  return {{"source", lm.source}, {"seeds", seeds}, {"features", features}};
}

}  // namespace qs::tools
