#pragma once
// The normal-map atlas layout: patches are unit squares, so each gets one square tile. Two
// layouts, both deterministic (they depend on the patch count, the tile sizes and the gutter only):
//
//  - grid (every tile S x S): columns = ceil(sqrt(P)), rows = ceil(P / columns); patch p sits in
//    column p % columns, row p / columns (row 0 at the top of the image). Every tile is surrounded
//    by a gutter of G texels, so the cell pitch is S + 2G and the image is columns * (S + 2G) by
//    rows * (S + 2G).
//  - packed (a side S_p per patch, e.g. tile_sizes_by_area): cells of S_p + 2G texels placed on
//    shelves: tiles sorted by side (larger first, ties by patch index), left to right along a
//    shelf, a new shelf below when the next cell would pass the target width
//    max(largest cell, ceil(sqrt(sum of cell areas))); a shelf is as high as its first cell. The
//    image is as wide as the widest shelf and as high as the shelves together.
// Texels outside every cell hold the flat normal. Conventions, shared by the baker, the GLB
// texture coordinates and the checks (S_p the side of patch p's tile):
//  - texel centres: texel (i, j) of a tile (i = column from the left, j = row from the top,
//    0..S_p-1) holds the surface point (u, v) = (i / (S_p-1), 1 - j / (S_p-1)): the first and last
//    texel centres lie exactly on the patch sides, so the centres cover [0,1]^2 with the
//    corners included and u = 1 of one patch and u = 0 of its neighbour are baked from the same
//    surface points. v points up in the image (tangent-space green = +v direction).
//  - texture coordinates (glTF convention: origin at the image's top-left, t pointing down):
//    (s, t) = ((x0 + 0.5 + u (S_p-1)) / W, (y0 + 0.5 + (1 - v)(S_p-1)) / H), (x0, y0) the tile's
//    first texel; a bilinear read at (s, t) of a texel centre returns that texel exactly.

#include <vector>

#include "qs/core/mesh.h"

namespace qs::bake {

/// One patch's tile: its first (top-left) texel and its side in texels.
struct AtlasTile {
  int x = 0, y = 0, size = 0;
};

struct AtlasLayout {
  int num_patches = 0;
  int tile_size = 0;   ///< S: every tile's side (grid), the side of a tile of average area (packed)
  int gutter = 0;      ///< G, texels around each tile
  bool grid = true;    ///< the grid layout (columns, rows set) or shelves (columns = rows = 0)
  int columns = 0;
  int rows = 0;
  int atlas_width = 0, atlas_height = 0;
  std::vector<AtlasTile> tiles;  ///< per patch

  int width() const { return atlas_width; }
  int height() const { return atlas_height; }
  /// Image column of the tile's first texel (its gutter starts `gutter` texels further left).
  int tile_x(int patch) const { return tiles[static_cast<size_t>(patch)].x; }
  /// Image row of the tile's first (top) texel.
  int tile_y(int patch) const { return tiles[static_cast<size_t>(patch)].y; }
  /// S_p, the side of the patch's tile in texels.
  int tile_side(int patch) const { return tiles[static_cast<size_t>(patch)].size; }
  /// The patch point (u, v) of texel (i, j) of the patch's tile (see the top of this file).
  Vec2 texel_uv(int patch, int i, int j) const;
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

/// The packed layout above for one side per patch; `tile_size` is recorded as S.
/// \throws InvalidInput for no tiles, a side < 2, gutter < 0, or an atlas side beyond kMaxAtlasSide.
AtlasLayout make_atlas_layout(const std::vector<int>& tile_sides, int tile_size, int gutter);

/// Tile sides for an even texel density: patch p gets S_p - 1 = round((S - 1) sqrt(P a_p / sum a)),
/// at least min(S, 4) and at most 16384, so that (S_p - 1)^2 / a_p (texels per unit area) is about
/// the same for every patch and the atlas holds about the texels of P tiles of S x S.
/// `patch_area` is each patch's share of the surface (for a set: the largest over its meshes).
/// \throws InvalidInput for an empty list, S < 2, or an area that is negative, not finite, or all zero.
std::vector<int> tile_sizes_by_area(const std::vector<double>& patch_area, int tile_size);

}  // namespace qs::bake
