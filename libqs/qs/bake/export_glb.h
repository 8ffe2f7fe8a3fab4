#pragma once
// The baked coarse mesh as a glTF mesh (qs::gltf): the split vertices (see split_mesh.h) with
// POSITION, NORMAL, TANGENT (the frame the bake used) and TEXCOORD_0 into the atlas
// (atlas.h: glTF's top-left origin, t down), and a material with the normal map.

#include <string>
#include <vector>

#include "qs/bake/bake.h"
#include "qs/gltf/glb.h"

namespace qs::bake {

/// `normal_png`: the 8-bit PNG of the atlas (encode_png8). A tangent-space bake becomes the
/// material's normalTexture; glTF has no object-space normal texture, so an object-space bake
/// gives a mesh with texture coordinates and a material without it (the map stays beside the GLB).
gltf::Mesh to_gltf_mesh(const BakeResult& result, const std::vector<unsigned char>& normal_png, const std::string& name);

}  // namespace qs::bake
