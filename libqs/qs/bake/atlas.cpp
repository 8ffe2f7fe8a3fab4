#include "qs/bake/atlas.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "qs/core/error.h"

namespace qs::bake {

Vec2 AtlasLayout::texel_uv(int patch, int i, int j) const {
  const double d = tile_side(patch) - 1;
  return {i / d, 1.0 - j / d};
}

Vec2 AtlasLayout::pixel(int patch, const Vec2& uv) const {
  const double d = tile_side(patch) - 1;
  return {tile_x(patch) + 0.5 + uv.x() * d, tile_y(patch) + 0.5 + (1.0 - uv.y()) * d};
}

Vec2 AtlasLayout::texcoord(int patch, const Vec2& uv) const {
  const Vec2 p = pixel(patch, uv);
  return {p.x() / width(), p.y() / height()};
}

namespace {

void check_side(long long w, long long h, const std::string& what) {
  if (w > kMaxAtlasSide || h > kMaxAtlasSide)
    throw InvalidInput("atlas: " + what + " make a " + std::to_string(w) + " x " + std::to_string(h) +
                       " image, more than " + std::to_string(kMaxAtlasSide) + " per side; use a smaller tile size");
}

}  // namespace

AtlasLayout make_atlas_layout(int num_patches, int tile_size, int gutter) {
  if (num_patches < 1) throw InvalidInput("atlas: " + std::to_string(num_patches) + " patches, need at least 1");
  if (tile_size < 2)
    throw InvalidInput("atlas: tile size " + std::to_string(tile_size) + ", need at least 2 texels per side");
  if (gutter < 0) throw InvalidInput("atlas: gutter " + std::to_string(gutter) + ", need 0 or more texels");
  AtlasLayout a;
  a.num_patches = num_patches;
  a.tile_size = tile_size;
  a.gutter = gutter;
  a.grid = true;
  a.columns = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(num_patches)) - 1e-9));
  while (a.columns * a.columns < num_patches) ++a.columns;
  a.rows = (num_patches + a.columns - 1) / a.columns;
  const long long w = static_cast<long long>(a.columns) * (tile_size + 2LL * gutter);
  const long long h = static_cast<long long>(a.rows) * (tile_size + 2LL * gutter);
  check_side(w, h, std::to_string(num_patches) + " tiles of " + std::to_string(tile_size) +
                       " texels with a gutter of " + std::to_string(gutter));
  a.atlas_width = static_cast<int>(w);
  a.atlas_height = static_cast<int>(h);
  const int pitch = tile_size + 2 * gutter;
  a.tiles.resize(static_cast<size_t>(num_patches));
  for (int p = 0; p < num_patches; ++p)
    a.tiles[static_cast<size_t>(p)] = {(p % a.columns) * pitch + gutter, (p / a.columns) * pitch + gutter, tile_size};
  return a;
}

AtlasLayout make_atlas_layout(const std::vector<int>& tile_sides, int tile_size, int gutter) {
  const int np = static_cast<int>(tile_sides.size());
  if (np < 1) throw InvalidInput("atlas: no tiles, need at least 1");
  if (gutter < 0) throw InvalidInput("atlas: gutter " + std::to_string(gutter) + ", need 0 or more texels");
  long long total = 0, largest = 0;
  for (int p = 0; p < np; ++p) {
    const int s = tile_sides[static_cast<size_t>(p)];
    if (s < 2)
      throw InvalidInput("atlas: tile of patch " + std::to_string(p) + " is " + std::to_string(s) +
                         " texels, need at least 2 per side");
    if (s > kMaxAtlasSide) check_side(s, s, "a tile of " + std::to_string(s) + " texels");
    const long long cell = s + 2LL * gutter;
    total += cell * cell;
    largest = std::max(largest, cell);
  }
  std::vector<int> order(static_cast<size_t>(np));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return tile_sides[static_cast<size_t>(a)] > tile_sides[static_cast<size_t>(b)]; });
  const long long target = std::max(largest, static_cast<long long>(std::ceil(std::sqrt(static_cast<double>(total)))));
  AtlasLayout a;
  a.num_patches = np;
  a.tile_size = tile_size;
  a.gutter = gutter;
  a.grid = false;
  a.tiles.resize(static_cast<size_t>(np));
  long long x = 0, y = 0, shelf = 0, width = 0;
  for (int p : order) {
    const long long cell = tile_sides[static_cast<size_t>(p)] + 2LL * gutter;
    if (x > 0 && x + cell > target) y += shelf, x = 0, shelf = 0;
    if (x == 0) shelf = cell;
    check_side(x + cell, y + shelf, std::to_string(np) + " tiles (largest " + std::to_string(largest - 2LL * gutter) +
                                        " texels) with a gutter of " + std::to_string(gutter));
    a.tiles[static_cast<size_t>(p)] = {static_cast<int>(x + gutter), static_cast<int>(y + gutter),
                                       tile_sides[static_cast<size_t>(p)]};
    x += cell;
    width = std::max(width, x);
  }
  a.atlas_width = static_cast<int>(width);
  a.atlas_height = static_cast<int>(y + shelf);
  return a;
}

std::vector<int> tile_sizes_by_area(const std::vector<double>& patch_area, int tile_size) {
  if (patch_area.empty()) throw InvalidInput("atlas: no patch areas");
  if (tile_size < 2)
    throw InvalidInput("atlas: tile size " + std::to_string(tile_size) + ", need at least 2 texels per side");
  double sum = 0;
  for (size_t p = 0; p < patch_area.size(); ++p) {
    const double a = patch_area[p];
    if (!std::isfinite(a) || a < 0)
      throw InvalidInput("atlas: patch " + std::to_string(p) + " has area " + std::to_string(a) +
                         "; expected a finite number >= 0");
    sum += a;
  }
  if (!(sum > 0)) throw InvalidInput("atlas: every patch has zero area; cannot size tiles by area");
  const double np = static_cast<double>(patch_area.size());
  const int lo = std::min(tile_size, 4);
  std::vector<int> out(patch_area.size());
  for (size_t p = 0; p < patch_area.size(); ++p) {
    const double side = 1.0 + (tile_size - 1) * std::sqrt(np * patch_area[p] / sum);
    out[p] = static_cast<int>(std::clamp(std::lround(side), static_cast<long>(lo), 16384L));
  }
  return out;
}

}  // namespace qs::bake
