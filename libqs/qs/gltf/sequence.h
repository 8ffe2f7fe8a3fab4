#pragma once
// A GLB that plays a sequence of meshes with different connectivity (glTF cannot morph between
// different vertex counts): one mesh and one node per frame, all under one root node, and one
// animation whose STEP-interpolated scale channels show exactly one frame at a time (scale 1 while
// it is the current frame, 0 otherwise). Plays in three.js and Blender; checked with the Khronos
// validator in the tests.

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "qs/core/mesh.h"

namespace qs::gltf {

struct SequenceFrame {
  std::string name;            ///< node and mesh name
  std::vector<Vec3> positions; ///< #V
  std::vector<Tri> faces;      ///< #F, counter-clockwise seen from outside
};

struct SequenceOptions {
  double seconds_per_frame = 1.0 / 12;  ///< frame k is shown during [k, k+1) * seconds_per_frame
  std::string name = "sequence";        ///< root node and animation name
  std::array<double, 4> base_color{0.8, 0.8, 0.8, 1.0};
  std::string generator = "qs";
};

/// The GLB's bytes (deterministic). Vertex normals are area-weighted face normals.
/// \throws InvalidInput for no frames, a frame with no faces, an index out of range, a non-finite
/// position or seconds_per_frame <= 0, naming the frame.
std::vector<unsigned char> sequence_glb_bytes(const std::vector<SequenceFrame>& frames, const SequenceOptions& options = {});

/// Writes it atomically. \throws as sequence_glb_bytes, IoError.
void write_sequence_glb(const std::filesystem::path& path, const std::vector<SequenceFrame>& frames,
                        const SequenceOptions& options = {});

}  // namespace qs::gltf
