#pragma once
// A small software renderer for looking at qs outputs: shaded meshes (optionally with per-face
// colours, a wireframe and highlighted edges such as patch boundaries) and uv layouts of charts.
// Orthographic, z-buffered, single-threaded and deterministic: the same input gives the same
// pixels. PNG output goes through qs::image (libpng).

#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "qs/core/mesh.h"

namespace qs::render {

using Rgb = std::array<std::uint8_t, 3>;

struct RenderOptions {
  int width = 800;   ///< pixels, 1..16384
  int height = 800;  ///< pixels, 1..16384
  /// Direction from the object towards the (orthographic) camera; need not be unit length.
  /// The default looks at the front (+z side) a little from the right and from above.
  Vec3 view_dir = Vec3(0.3, 0.4, 1.0).normalized();
  /// Up in the image. Only its part orthogonal to view_dir is used; if it is parallel to
  /// view_dir another axis is chosen.
  Vec3 up = Vec3(0, 1, 0);
  bool wireframe = false;  ///< draw every triangle edge, thin and dark
  bool smooth = false;     ///< interpolate area-weighted vertex normals instead of flat faces
  Rgb background = {255, 255, 255};
};

/// An 8-bit RGB image, rows top to bottom: pixel (x, y) is rgb[3 * (y * width + x) + c].
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  ///< 3 * width * height
};

/// Renders a mesh fitted (with a margin) into the image: orthographic projection along
/// options.view_dir, z-buffer, two-sided Lambert shading from a head light plus ambient light,
/// flat per face or smooth (options.smooth). Faces take face_colours[f] (#F entries), or light
/// grey when face_colours is null. highlight_edges are vertex pairs drawn as thick dark lines
/// (e.g. patch boundaries); they and the wireframe are depth-tested, so hidden ones don't show.
/// An empty mesh gives a background-only image. The picture depends only on the shape, not on
/// its position or size: any finite coordinates (up to the largest double) draw like the same
/// mesh scaled to unit size.
/// \throws InvalidInput for a size out of range, a zero view direction, a vertex id out of range
/// (naming the face or edge), a non-finite position, or a face_colours of the wrong size.
Image render_mesh(const TriMesh& mesh, const std::vector<Rgb>* face_colours, const RenderOptions& options,
                  const std::vector<std::array<int, 2>>* highlight_edges = nullptr);

/// The uv layout of a chart: patch p's triangles (face_patch[f] == p, corners face_uv[f]) drawn
/// in tile p of a grid atlas with ceil(sqrt(patches)) columns, tiles of tile_px x tile_px pixels,
/// row by row from the top left. In each tile the unit square (v up) is drawn inside a small gap
/// with a light frame; triangles are filled with patch_colours[p] (#patches entries; pass
/// dissect::patch_colour(p) to match the 3D view: render does not depend on dissect) and
/// outlined thin and dark (except triangles under 4 pixels across and in tiles whose unit square
/// is under 48 pixels, where outlines would paint the patch dark). To show where the map is not
/// bijective, triangles with negative uv area and pixels covered by more than one triangle are
/// drawn pure red (255, 0, 0).
/// \throws InvalidInput if sizes disagree, a patch index is outside [0, patches), a uv is not
/// finite, tile_px is outside 8..4096, or the atlas would exceed 16384 pixels in width or height.
Image render_uv_layout(const std::vector<std::array<Vec2, 3>>& face_uv, const std::vector<int>& face_patch,
                       int patches, int tile_px, const std::vector<Rgb>& patch_colours);

/// Concatenates images left to right; shorter ones are centred vertically on white.
/// \throws InvalidInput if an image's rgb size disagrees with its width and height.
Image side_by_side(const std::vector<Image>& images);

/// Writes an 8-bit RGB PNG atomically (to "<path>.tmp-<pid>.png", then renamed), whatever the
/// extension of `path`. \throws InvalidInput for an empty or inconsistent image; IoError if the
/// file cannot be written (no partial file is left behind).
void write_png(const std::filesystem::path& path, const Image& image);

}  // namespace qs::render
