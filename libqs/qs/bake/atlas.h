#pragma once
// The normal-map atlas layout: patches are unit squares, so each gets one S x S tile in a grid
// (no packing). Conventions, shared by the baker, the GLB texture coordinates and the checks:
//
//  - grid: columns = ceil(sqrt(P)), rows = ceil(P / columns); patch p sits in column p % columns,
//    row p / columns (row 0 at the top of the image). Every tile is surrounded by a gutter of G
//    texels, so the cell pitch is S + 2G and the image is columns * (S + 2G) by rows * (S + 2G).
//  - texel centres: texel (i, j) of a tile (i = column from the left, j = row from the top,
//    0..S-1) holds the surface point (u, v) = (i / (S-1), 1 - j / (S-1)): the first and last
//    texel centres lie exactly on the patch sides, so the S x S centres cover [0,1]^2 with the
//    corners included and u = 1 of one patch and u = 0 of its neighbour are baked from the same
//    surface points. v points up in the image (tangent-space green = +v direction).
//  - texture coordinates (glTF convention: origin at the image's top-left, t pointing down):
//    (s, t) = ((x0 + 0.5 + u (S-1)) / W, (y0 + 0.5 + (1 - v)(S-1)) / H), (x0, y0) the tile's
//    first texel; a bilinear read at (s, t) of a texel centre returns that texel exactly.

#include <vector>

#include "qs/core/mesh.h"

namespace qs::bake {

struct AtlasLayout {
  int num_patches = 0;
  int tile_size = 0;   ///< S, texels per tile side (>= 2)
  int gutter = 0;      ///< G, texels around each tile
  int columns = 0;
  int rows = 0;

  int pitch() const { return tile_size + 2 * gutter; }
  int width() const { return columns * pitch(); }
  int height() const { return rows * pitch(); }
  /// Image column of the tile's first texel (its gutter starts `gutter` texels further left).
  int tile_x(int patch) const { return (patch % columns) * pitch() + gutter; }
  /// Image row of the tile's first (top) texel.
  int tile_y(int patch) const { return (patch / columns) * pitch() + gutter; }
  /// The patch point (u, v) of texel (i, j) of a tile (see the top of this file).
  Vec2 texel_uv(int i, int j) const;
  /// Image coordinates of (patch, u, v) in texel units, texel (x, y)'s centre at (x + 0.5, y + 0.5).
  Vec2 pixel(int patch, const Vec2& uv) const;
  /// glTF texture coordinates (s, t) of (patch, u, v): pixel() divided by the image size.
  Vec2 texcoord(int patch, const Vec2& uv) const;
};

/// Largest atlas side accepted (texels); GPUs commonly stop at 16384.
inline constexpr int kMaxAtlasSide = 32768;

/// The grid layout above. \throws InvalidInput for num_patches < 1, tile_size < 2, gutter < 0,
/// or an atlas side beyond kMaxAtlasSide (naming the sizes).
AtlasLayout make_atlas_layout(int num_patches, int tile_size, int gutter);

}  // namespace qs::bake
