#pragma once
// qs-bake's output folder for a remeshed set: per mesh <stem>_normal.png (and the extra formats),
// <stem>.glb, and bake.json. The tool and the Python module both write it with these calls.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "qs/bake/atlas.h"
#include "qs/bake/bake.h"
#include "qs/bake/image_io.h"
#include "qs/core/context.h"
#include "qs/dissect/dissection_json.h"
#include "qs/remesh/chart_sampler.h"
#include "qs/remesh/quality.h"
#include "qs/remesh/semi_regular.h"

namespace qs::bake {

/// qs-bake's options, by its option names and with its defaults.
struct BakeSetOptions {
  int size = 256;              ///< --size S. \pre 2..16384
  bool area_tiles = true;      ///< --tiles area (else uniform: an S x S grid)
  int gutter = 4;              ///< \pre 0..1024
  NormalSpace space = NormalSpace::Tangent;
  GreenChannel green = GreenChannel::OpenGL;   ///< tangent space only
  std::vector<ImageFormat> extra;              ///< exr / png16, each once, in this order (qs-bake: by name)
  int samples = 100000;                        ///< shading check points per mesh; 0: none
  bool keep_atlases = false;                   ///< BakedSet::atlases filled (else empty)
};

/// BakeSetOptions from qs-bake's option words: `tiles` area|uniform, `space` tangent|object,
/// `green` opengl|directx, `formats` any of png8 (always written), png16, exr.
/// \throws UsageError for an unknown word or `green` directx with `space` object.
BakeSetOptions bake_set_options(int size, const std::string& tiles, int gutter, const std::string& space,
                                const std::string& green, int samples, const std::vector<std::string>& formats);

/// A remeshed set and the dissection it was made from, as qs-bake reads them.
struct BakeSetInput {
  const remesh::SemiRegularSet* set = nullptr;
  std::vector<std::string> outputs;  ///< per mesh the remesh file name (bake.json's "remesh")
  std::vector<std::string> stems;    ///< per mesh the output stem
  const dissect::LoadedDissection* dissection = nullptr;
  std::filesystem::path remesh_folder;      ///< bake.json names it relative to the output folder
  std::filesystem::path dissection_folder;  ///< likewise
};

/// The atlas of a set: one layout for every mesh.
struct BakePlan {
  BakeOptions options;                 ///< tile sizes filled with area tiles
  AtlasLayout layout;
  std::vector<double> side_minus_one;  ///< per patch S_p - 1 (texel density)
};

/// \throws InvalidInput for charts whose patch counts differ from the set's.
BakePlan plan_bake(const BakeSetInput& input, const BakeSetOptions& options);

/// What was baked for one mesh (the tool's per-mesh line and timings).
struct BakedMeshInfo {
  int glb_vertices = 0;
  remesh::DensitySpread texel_density;
  std::optional<ShadingCheck> shading;
  double bake_seconds = 0, write_seconds = 0, check_seconds = 0;
};

struct BakedSet {
  std::vector<BakedMeshInfo> meshes;
  std::vector<NormalAtlas> atlases;  ///< with keep_atlases
};

/// Every output file name qs-bake may write into `outdir` (per stem the maps and the GLB, and
/// bake.json), each checked with check_not_an_input against the set's inputs (remesh.json, the
/// remesh files, dissection.json, the charts). \throws UsageError naming the one that is an input.
void check_bake_outputs(const std::filesystem::path& outdir, const BakeSetInput& input);

/// Bakes every mesh (`samplers`: one per mesh, its chart) and writes the files into `staging`;
/// bake.json's relative paths are taken from `outdir` (where the files will be). `on_mesh(i, info)`
/// after each mesh, when given. Progress: context.progress(stem, fraction) per mesh.
/// \throws InvalidInput (a remesh that does not match its chart), IoError, Error(Internal "cancelled").
BakedSet write_bake_folder(const std::filesystem::path& staging, const std::filesystem::path& outdir,
                           const BakeSetInput& input, const std::vector<const remesh::ChartSampler*>& samplers,
                           const BakePlan& plan, const BakeSetOptions& options, const Context& context = {},
                           const std::function<void(size_t, const BakedMeshInfo&)>& on_mesh = {});

}  // namespace qs::bake
