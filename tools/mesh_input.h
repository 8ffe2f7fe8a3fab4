#pragma once
// Reading a mesh for a tool: read, validate (rejecting with the full report), find landmarks.

#include <optional>
#include <string>

#include "qs/core/error.h"
#include "qs/io/read_mesh.h"
#include "qs/landmarks/landmarks.h"
#include "qs/mesh/validate.h"

namespace qs::tools {

struct MeshInput {
  std::string file;
  io::ReadResult read;
  mesh::ValidationResult valid;
  std::optional<landmarks::Landmarks> landmarks;
  std::string landmark_file;  ///< empty when none
};

/// \throws InvalidInput with the validation report when the mesh is rejected.
inline MeshInput load_mesh_input(const std::string& file, const std::optional<std::string>& landmark_file) {
  MeshInput in;
  in.file = file;
  in.read = io::read_mesh(file);
  in.valid = mesh::validate(in.read.mesh);
  if (!in.valid.report.accepted)
    throw InvalidInput("mesh rejected:\n" + mesh::format_report(file, in.valid.report));
  std::optional<std::filesystem::path> lm = landmark_file ? std::optional<std::filesystem::path>(*landmark_file)
                                                          : landmarks::find_landmarks_beside(file);
  if (lm) {
    in.landmarks = landmarks::read_landmarks(*lm, in.valid);
    in.landmark_file = lm->string();
  }
  return in;
}

}  // namespace qs::tools
