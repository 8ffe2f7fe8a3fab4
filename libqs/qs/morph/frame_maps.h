#pragma once
// Normal maps that morph with the shape, for frame files (the paper's figure 22: a coarse remesh
// lit with normal maps while it morphs). Every shape's bake uses one atlas layout (a tile per
// patch, the same patches for all shapes), so the map of an in-between shape is approximated
// texel by texel: n = normalize(sum_i w_i n_i), n_i the decoded tangent-space normal of shape i.
// A frame is then an OBJ with the bake's atlas UVs, an MTL and its own blended PNG.

#include <filesystem>
#include <string>
#include <vector>

#include "qs/core/mesh.h"
#include "qs/core/context.h"
#include "qs/morph/blend.h"
#include "qs/morph/morph_glb.h"

namespace qs::morph {

/// The 8-bit RGB normal-map atlases of every shape of a bake, decoded once.
struct NormalAtlases {
  int width = 0, height = 0;
  std::vector<std::vector<unsigned char>> rgb;  ///< per shape: width * height * 3 bytes, rows top down
  std::vector<std::vector<unsigned char>> png;  ///< per shape: the file's bytes (or empty)
};

/// Reads `bake_dir`/<stem>_normal.png for every stem (RGB PNGs; 16-bit ones rounded to 8 bits).
/// \throws IoError (missing or unreadable file); InvalidInput (damaged, truncated, not an RGB PNG,
/// sizes that differ: the message names the file and what was expected).
NormalAtlases read_normal_atlases(const std::filesystem::path& bake_dir, const std::vector<std::string>& stems);

/// The blended map for barycentric `weights` (check_weights): per texel the normalized weighted
/// sum of the decoded normals (c / 255 * 2 - 1), encoded back as round((n * 0.5 + 0.5) * 255);
/// a texel whose sum vanishes becomes (0, 0, 1). A weight vector (0, .., 1, .., 0) gives that
/// shape's bytes unchanged. \throws InvalidInput.
std::vector<unsigned char> blend_normal_maps(const NormalAtlases& atlases, const std::vector<double>& weights);

/// PNG bytes of an 8-bit RGB image (qs::image::encode_png, zlib level 3). \throws IoError when encoding fails.
std::vector<unsigned char> encode_png_rgb8(int width, int height, const std::vector<unsigned char>& rgb);

/// Frame files with texture coordinates: OBJ text "mtllib <mtl>", the blended positions as v, the
/// bake's atlas UVs as vt (v flipped to OBJ's bottom-up convention), faces "f v/vt ..." (remesh
/// vertex / bake vertex); and the MTL naming the frame's normal map (map_Bump and norm).
class TexturedObjWriter {
 public:
  /// \pre baked was read for this remesh (read_baked_shape); faces are the remesh faces.
  TexturedObjWriter(const std::vector<Tri>& faces, const BakedShape& baked);
  std::string obj(const std::vector<Vec3>& positions, const std::string& mtl_file) const;
  static std::string mtl(const std::string& normal_png);

 private:
  size_t num_vertices_ = 0;
  std::string uv_and_faces_;
};

/// Writes frame f as folder/<names[f]>.obj, <names[f]>.mtl and <names[f]>_normal.png for every f
/// (positions blend(shapes, w), map blend_normal_maps(atlases, w) encoded with encode_png_rgb8, or
/// shape i's PNG bytes when w is 1 on shape i; w = frames[f].weights), each file
/// atomically, on `threads` threads (the files do not depend on the count). \throws IoError,
/// InvalidInput.
void write_textured_frames(const std::filesystem::path& folder, const std::vector<std::string>& names,
                           const std::vector<std::vector<Vec3>>& shapes, const std::vector<Tri>& faces,
                           const BakedShape& baked, const NormalAtlases& atlases, const std::vector<PathFrame>& frames,
                           int threads = 0, const Context& context = {});

}  // namespace qs::morph
