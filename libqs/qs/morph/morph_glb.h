#pragma once
// The glTF form of a morph: the base shape as the mesh, every other shape as a morph target,
// a weights animation along a path, and (optionally) the base shape's baked normal map.
//
// glTF cannot morph textures, so the paper's morphing with normal maps (its figure 22, where each
// frame is lit with a normal map of the in-between shape) is approximated: the material carries
// the base shape's tangent-space normal map on the base shape's atlas UVs and tangents for every
// weight; positions and normals morph, the map's detail stays that of the base shape.

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "qs/gltf/glb.h"
#include "qs/remesh/semi_regular.h"

namespace qs::morph {

/// What qs-morph takes from a qs-bake output folder for one shape. The bake may split vertices
/// along atlas seams; `vertex_source` says which remesh vertex each bake vertex stands for.
struct BakedShape {
  std::filesystem::path glb;                     ///< the file it was read from
  std::vector<int> vertex_source;                ///< #V': a remesh vertex id per bake vertex
  std::vector<Tri> faces;                        ///< #F, bake vertex ids; face f is remesh face f
  std::vector<Vec2> texcoords;                   ///< #V' atlas (u, v), glTF convention
  std::vector<std::array<double, 4>> tangents;   ///< #V' or empty
  std::vector<Vec3> normals;                     ///< #V' (the bake's NORMAL), or empty
  gltf::Image normal_map;
  double normal_scale = 1.0;
};

/// Reads `bake_dir`/bake.json (must exist and be a JSON object; refused: a "format" other than
/// "qs-bake", options.space other than "tangent", options.green "directx")
/// and `bake_dir`/<stem>.glb with read_glb: TEXCOORD_0 (required), TANGENT, NORMAL, and the
/// material's normalTexture image, else the file `bake_dir`/<stem>_normal.png. The GLB's faces
/// must be the remesh's faces in order (corner by corner, up to seam splits of vertices) and its
/// positions those of `positions` (within 1e-5 of the bounding-box diagonal).
/// \throws IoError (no bake.json, no <stem>.glb, unreadable files); InvalidInput (a bake that does
/// not belong to this remesh, no texcoords, no normal map), naming the file.
BakedShape read_baked_shape(const std::filesystem::path& bake_dir, const std::string& stem,
                            const std::vector<Tri>& faces, const std::vector<Vec3>& positions);

struct MorphGlbOptions {
  int base = 0;                  ///< the shape stored as the mesh; every other shape is a target
  std::vector<int> path;         ///< animation stops (shape ids); fewer than 2: no animation
  double seconds_per_leg = 1.0;  ///< time between two stops
  std::vector<double> weights;   ///< #shapes barycentric default pose, or empty for the base shape
  std::string name = "morph";    ///< mesh and node name
  std::string animation_name = "path";
};

/// The glTF mesh of a morph: base positions and area-weighted normals; targets in shape order
/// (skipping the base), named names[i], with POSITION and NORMAL deltas; mesh.weights = the
/// non-base entries of options.weights (or zeros); a LINEAR weights animation with one key per
/// path stop (stop k at k * seconds_per_leg: weight 1 on that stop's target, all 0 at the base).
/// With `baked`: the bake's vertex layout, texcoords, tangents, normals and its normal map as the
/// material's normalTexture; each target then also gets TANGENT deltas: the base tangent made
/// perpendicular to that shape's normal (Gram-Schmidt), so the tangent frame follows the morph. \throws InvalidInput (fewer than 2 shapes, names / weights / path not
/// matching the set, base out of range).
gltf::Mesh morph_glb_mesh(const remesh::SemiRegularSet& set, const std::vector<std::string>& names,
                          const MorphGlbOptions& options, const BakedShape* baked = nullptr);

/// qs-morph --glb: morph_glb_mesh written as a GLB at `path`, its folder created when missing.
/// Returns the mesh written. \throws as morph_glb_mesh; IoError when the folder or file cannot be
/// written.
gltf::Mesh write_morph_glb(const std::filesystem::path& path, const remesh::SemiRegularSet& set,
                           const std::vector<std::string>& names, const MorphGlbOptions& options,
                           const BakedShape* baked = nullptr);

}  // namespace qs::morph
