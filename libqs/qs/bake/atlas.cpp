#include "qs/bake/atlas.h"

#include <cmath>
#include <string>

#include "qs/core/error.h"

namespace qs::bake {

Vec2 AtlasLayout::texel_uv(int i, int j) const {
  const double d = tile_size - 1;
  return {i / d, 1.0 - j / d};
}

Vec2 AtlasLayout::pixel(int patch, const Vec2& uv) const {
  const double d = tile_size - 1;
  return {tile_x(patch) + 0.5 + uv.x() * d, tile_y(patch) + 0.5 + (1.0 - uv.y()) * d};
}

Vec2 AtlasLayout::texcoord(int patch, const Vec2& uv) const {
  const Vec2 p = pixel(patch, uv);
  return {p.x() / width(), p.y() / height()};
}

AtlasLayout make_atlas_layout(int num_patches, int tile_size, int gutter) {
  if (num_patches < 1) throw InvalidInput("atlas: " + std::to_string(num_patches) + " patches, need at least 1");
  if (tile_size < 2)
    throw InvalidInput("atlas: tile size " + std::to_string(tile_size) + ", need at least 2 texels per side");
  if (gutter < 0) throw InvalidInput("atlas: gutter " + std::to_string(gutter) + ", need 0 or more texels");
  AtlasLayout a;
  a.num_patches = num_patches;
  a.tile_size = tile_size;
  a.gutter = gutter;
  a.columns = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(num_patches)) - 1e-9));
  while (a.columns * a.columns < num_patches) ++a.columns;
  a.rows = (num_patches + a.columns - 1) / a.columns;
  const long long w = static_cast<long long>(a.columns) * (tile_size + 2LL * gutter);
  const long long h = static_cast<long long>(a.rows) * (tile_size + 2LL * gutter);
  if (w > kMaxAtlasSide || h > kMaxAtlasSide)
    throw InvalidInput("atlas: " + std::to_string(num_patches) + " tiles of " + std::to_string(tile_size) +
                       " texels with a gutter of " + std::to_string(gutter) + " make a " + std::to_string(w) + " x " +
                       std::to_string(h) + " image, more than " + std::to_string(kMaxAtlasSide) +
                       " per side; use a smaller tile size");
  return a;
}

}  // namespace qs::bake
