#pragma once
// Normal-map baking (paper 4.3, figures 18-19): the detail of the original surface, carried onto
// its coarse semi-regular remesh through the common parameterization. Each texel of a patch's
// tile is the patch point (patch, u, v) of atlas.h; its value is the ORIGINAL surface's smooth
// normal there (the chart's angle-weighted vertex normals, with the vertices inserted by the cuts
// interpolated along their input edge or face (OriginalNormals), interpolated barycentrically at
// the chart point of (patch, u, v)), expressed
//  - tangent space (default): in the coarse mesh's frame at the same (patch, u, v): the remesh
//    face of the patch whose (u, v) triangle holds the point, with its split vertices' normal,
//    tangent and bitangent B = w (N x T) interpolated barycentrically and each normalized, as a
//    glTF viewer does (Khronos sample viewer, three.js). The stored m solves
//    [T B N] m = n (the frame need not be orthogonal) and is normalized, so that the viewer's
//    normalize(T m.x + B m.y + N m.z) gives back n. OpenGL green (+Y = +v, up in the image) by
//    default; DirectX stores -Y.
//  - object space: n itself (x, y, z of the mesh's coordinates).

#include <cstdint>
#include <vector>

#include "qs/bake/atlas.h"
#include "qs/bake/split_mesh.h"
#include "qs/core/context.h"
#include "qs/remesh/chart_sampler.h"

namespace qs::bake {

enum class NormalSpace { Tangent, Object };
enum class GreenChannel { OpenGL, DirectX };
const char* to_string(NormalSpace s);   ///< "tangent", "object"
const char* to_string(GreenChannel g);  ///< "opengl", "directx"

struct BakeOptions {
  int tile_size = 256;     ///< S texels per tile side, >= 2 (with tile_sizes: only recorded)
  /// Per patch its tile side S_p (atlas.h's packed layout, e.g. tile_sizes_by_area); empty: every
  /// patch gets tile_size (the grid). Give the same sizes to every mesh of a set: one layout.
  std::vector<int> tile_sizes;
  int gutter = 4;          ///< texels around each tile, filled by extending the tile's edge texels
  NormalSpace space = NormalSpace::Tangent;
  GreenChannel green = GreenChannel::OpenGL;  ///< tangent space only
  int threads = 0;         ///< 0: Context::threads
  /// Chart vertices [0, original_vertices) are the input mesh's own, the others were inserted by
  /// the cuts (qs-dissect keeps the input's vertices first: DissectedMesh::input_vertices). See
  /// OriginalNormals. -1: every chart vertex keeps its angle-weighted normal.
  int original_vertices = -1;
};

/// The baked atlas as unit vectors, as they are to be stored (green convention applied), before
/// encoding (x * 0.5 + 0.5 per channel). Rows from the top of the image.
struct NormalAtlas {
  int width = 0, height = 0;
  std::vector<float> texels;  ///< width * height * 3
  Vec3 at(int x, int y) const {
    const float* t = &texels[3 * (static_cast<size_t>(y) * width + x)];
    return {t[0], t[1], t[2]};
  }
};

struct BakeResult {
  BakeOptions options;
  AtlasLayout layout;
  SplitMesh mesh;      ///< the coarse mesh split per patch, with the frames the bake used
  NormalAtlas atlas;
};

/// The original surface's smooth normal at chart locations: per chart vertex a normal,
/// interpolated barycentrically and normalized.
///
/// The input mesh's vertices get their angle-weighted normal. A vertex the cuts inserted lies on a
/// straight line between two chart neighbours (on an input edge, or on a cut segment inside an input
/// face); its angle-weighted normal would be that of the flat faces it splits (on the shared heads
/// 1.5-3 degrees off the input's interpolated normal there, median), so when `original_vertices`
/// is given it gets the input's own interpolated normal instead: the linear interpolation, along
/// its most nearly straight pair of neighbours (collinear to 1e-8), of their normals, solved for
/// chains of inserted vertices by Gauss-Seidel sweeps. Inserted vertices without such a pair keep
/// their angle-weighted normal. The result is exact for cuts along input edges and inside faces.
class OriginalNormals {
 public:
  /// \param original_vertices chart vertices below this id are the input's own; -1: all are.
  explicit OriginalNormals(const dissect::Chart& chart, int original_vertices = -1);
  Vec3 at(const remesh::ChartSampler::Location& where) const;
  /// Per chart vertex (unit for the input's vertices; the interpolated, not normalized, value for
  /// inserted ones).
  const std::vector<Vec3>& vertex_normals() const { return normals_; }

 private:
  const dissect::Chart* chart_;
  std::vector<Vec3> normals_;
};

/// Bakes the normal-map atlas of one mesh of a remeshed set.
/// \pre `sampler` is the chart of the same mesh, from the dissection the remesh was made from.
/// \throws InvalidInput for bad options (see make_atlas_layout) or a remesh that does not match
///         the chart (see split_by_patch); an Internal error "cancelled" when context's flag is set.
/// Reports progress as "bake" (from the calling thread).
BakeResult bake_normal_map(const remesh::ChartSampler& sampler, const remesh::SemiRegularConnectivity& connectivity,
                           const std::vector<Vec3>& positions, const BakeOptions& options = {},
                           const Context& context = {});

/// 8-bit RGB, rows from the top: the content of the baked PNG.
struct Rgb8Image {
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;  ///< width * height * 3
};
/// Encodes x * 0.5 + 0.5 per channel, rounded to 0..255.
Rgb8Image quantize8(const NormalAtlas& atlas);
/// The decoded vector (c / 255 * 2 - 1 per channel, not normalized) bilinearly interpolated at
/// glTF texture coordinates (s, t), texel centres at ((x + 0.5) / W, (y + 0.5) / H), clamped at
/// the image border.
Vec3 sample_bilinear(const Rgb8Image& image, const Vec2& st);

struct ShadingCheckOptions {
  int samples = 100000;     ///< surface points, uniform by area on the coarse mesh
  std::uint64_t seed = 1;   ///< deterministic
};

/// Angles in degrees between the original surface normal and the shaded normal at random points.
struct ShadingCheck {
  int samples = 0;
  double mean_with_map = 0, max_with_map = 0, p95_with_map = 0;
  double mean_without_map = 0, max_without_map = 0, p95_without_map = 0;
};

/// Measures what a viewer shows: at random points of the coarse mesh (face by area, uniform
/// barycentrics) the shaded normal, from the mesh's attributes rounded to float as in the GLB
/// (interpolated N, T, B = w (N x T) per vertex, each normalized) and the 8-bit map read bilinearly at
/// the point's texture coordinates and decoded with the bake's green convention, against the original
/// surface's normal at the same (patch, u, v); and the same with the interpolated normal alone.
/// \pre `result` was baked from `sampler`'s chart; `map` is quantize8(result.atlas).
ShadingCheck check_shading(const remesh::ChartSampler& sampler, const BakeResult& result, const Rgb8Image& map,
                           const ShadingCheckOptions& options = {});

}  // namespace qs::bake
