#pragma once
// A binary glTF 2.0 (GLB) writer for one triangle mesh: the export format of qs-bake (remesh +
// normal map + tangents) and qs-morph (morph targets + weights animation). tinygltf stays in the
// .cpp. Conventions (../shared/DESIGN.md): dense accessors, min/max on every POSITION accessor,
// mesh.extras.targetNames always present when there are targets, normal maps linear (never
// sRGB), y-up metres as glTF wants (positions are written as given).

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "qs/core/mesh.h"

namespace qs::gltf {

/// An encoded image embedded in the GLB's binary chunk.
struct Image {
  std::string name;
  std::string mime_type = "image/png";  ///< "image/png" or "image/jpeg" (glTF core)
  std::vector<unsigned char> bytes;     ///< the encoded file
};

/// A morph target: per-vertex deltas from the base mesh (dense, #V each).
struct MorphTarget {
  std::string name;                     ///< goes to mesh.extras.targetNames
  std::vector<Vec3> position_deltas;    ///< #V
  std::vector<Vec3> normal_deltas;      ///< #V, or empty when the mesh has no normals
  std::vector<Vec3> tangent_deltas;     ///< #V xyz deltas, or empty (needs mesh tangents)
};

/// A weights animation of the mesh's node: at times[k] the target weights are weights[k]
/// (#targets each); LINEAR interpolation.
struct WeightsAnimation {
  std::string name;
  std::vector<float> times;                  ///< seconds, strictly increasing
  std::vector<std::vector<float>> weights;   ///< times.size() x #targets
};

struct Material {
  std::string name = "qs";
  std::array<double, 4> base_color{0.8, 0.8, 0.8, 1.0};
  double metallic = 0.0;
  double roughness = 0.6;
  std::optional<Image> normal_texture;       ///< tangent-space normal map (uses TEXCOORD_0, TANGENT)
  double normal_scale = 1.0;
  std::optional<Image> base_color_texture;   ///< sRGB colour map (uses TEXCOORD_0)
  bool double_sided = false;
};

/// One mesh, one node, one scene.
struct Mesh {
  std::string name = "mesh";
  std::vector<Vec3> positions;               ///< #V
  std::vector<Tri> faces;                    ///< #F, counter-clockwise seen from outside
  std::vector<Vec3> normals;                 ///< #V unit vectors, or empty
  std::vector<Vec2> texcoords;               ///< #V (u, v) in glTF's convention (v down), or empty
  std::vector<std::array<double, 4>> tangents;  ///< #V (xyz unit, w = +-1 bitangent sign), or empty
  std::optional<Material> material;          ///< none: glTF's default material
  std::vector<MorphTarget> targets;
  std::vector<double> default_weights;       ///< #targets, or empty for all zero
  std::vector<WeightsAnimation> animations;
  std::string generator = "qs";
};

/// Checks `mesh` (array sizes, indices in range, finite values, unit normals and tangents within
/// 1e-3, tangent w = +-1, animation shapes). \throws InvalidInput naming the field.
void check_mesh(const Mesh& mesh);

/// The GLB file's bytes; deterministic (same mesh, same bytes). Floats are float32; normals and
/// tangent xyz are renormalized and tangent w written as exactly +-1; indices are uint16 when
/// #V <= 65535, else uint32; every buffer view starts on a 4-byte boundary; mesh.weights is
/// always written when there are targets (zeros when default_weights is empty).
/// \throws InvalidInput (check_mesh).
std::vector<unsigned char> glb_bytes(const Mesh& mesh);

/// Writes the GLB atomically (a temporary beside it, renamed on success).
/// \throws InvalidInput (check_mesh), IoError.
void write_glb(const std::filesystem::path& path, const Mesh& mesh);

/// Reads back the first triangle primitive of the first mesh of a GLB (or .gltf) file: positions,
/// faces, NORMAL, TEXCOORD_0, TANGENT, the material (images as their encoded bytes, never decoded),
/// morph targets (POSITION / NORMAL / TANGENT deltas, names from mesh.extras.targetNames) and
/// mesh.weights.
/// Animations are not read. Float attributes only (no normalized integers, no sparse accessors).
/// \throws IoError (missing or unreadable file); InvalidInput (not glTF, or a layout named above
/// as unsupported), naming the file and the element.
Mesh read_glb(const std::filesystem::path& path);

}  // namespace qs::gltf
