#include "qs/bake/bake_folder.h"

#include <chrono>
#include <nlohmann/json.hpp>
#include <set>

#include "qs/bake/export_glb.h"
#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/core/json_strict.h"
#include "qs/core/output_folder.h"
#include "qs/gltf/glb.h"

namespace qs::bake {

BakeSetOptions bake_set_options(int size, const std::string& tiles, int gutter, const std::string& space,
                                const std::string& green, int samples, const std::vector<std::string>& formats) {
  if (tiles != "area" && tiles != "uniform") throw UsageError("tiles '" + tiles + "': expected area or uniform");
  if (space != "tangent" && space != "object") throw UsageError("space '" + space + "': expected tangent or object");
  if (green != "opengl" && green != "directx") throw UsageError("green '" + green + "': expected opengl or directx");
  if (space == "object" && green == "directx")
    throw UsageError("--green applies to tangent-space maps only; drop it with --space object");
  BakeSetOptions so;
  so.size = size;
  so.area_tiles = tiles == "area";
  so.gutter = gutter;
  so.space = space == "tangent" ? NormalSpace::Tangent : NormalSpace::Object;
  so.green = green == "opengl" ? GreenChannel::OpenGL : GreenChannel::DirectX;
  so.samples = samples;
  // Each extra format once, by name (exr before png16), as bake.json lists them.
  for (const auto& f : std::set<std::string>(formats.begin(), formats.end())) {
    if (f == "exr") so.extra.push_back(ImageFormat::Exr);
    else if (f == "png16") so.extra.push_back(ImageFormat::Png16);
    else if (f != "png8") throw UsageError("format '" + f + "': expected png8, png16 or exr");
  }
  return so;
}

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

void write_bytes(const fs::path& path, const std::vector<unsigned char>& bytes) {
  AtomicFile file(path);
  file.stream().write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  file.commit();
}

}  // namespace

BakePlan plan_bake(const BakeSetInput& input, const BakeSetOptions& options) {
  const auto& c = input.set->connectivity;
  BakePlan plan;
  plan.options.tile_size = options.size;
  plan.options.gutter = options.gutter;
  plan.options.space = options.space;
  plan.options.green = options.green;
  plan.side_minus_one.assign(static_cast<size_t>(c.num_patches), options.size - 1.0);
  if (options.area_tiles) {
    std::vector<const dissect::Chart*> charts;
    for (const auto& dm : input.dissection->meshes) charts.push_back(&dm.dissection.chart);
    plan.options.tile_sizes = tile_sizes_by_area(remesh::patch_texel_shares(charts), options.size);
    plan.layout = make_atlas_layout(plan.options.tile_sizes, options.size, options.gutter);
    for (int p = 0; p < c.num_patches; ++p) plan.side_minus_one[static_cast<size_t>(p)] = plan.layout.tile_side(p) - 1.0;
  } else {
    plan.layout = make_atlas_layout(c.num_patches, options.size, options.gutter);
  }
  return plan;
}

void check_bake_outputs(const fs::path& outdir, const BakeSetInput& input) {
  std::vector<fs::path> input_paths = {input.remesh_folder / "remesh.json", input.dissection_folder / "dissection.json"};
  for (const auto& o : input.outputs) input_paths.push_back(input.remesh_folder / o);
  for (const auto& m : input.dissection->meshes) input_paths.push_back(input.dissection_folder / m.chart_file);
  for (const auto& stem : input.stems)
    for (const std::string suffix : {"_normal.png", "_normal16.png", "_normal.exr", ".glb"})
      check_not_an_input(outdir / (stem + suffix), input_paths, "-o");
  check_not_an_input(outdir / "bake.json", input_paths, "-o");
}

BakedSet write_bake_folder(const fs::path& staging, const fs::path& outdir, const BakeSetInput& input,
                           const std::vector<const remesh::ChartSampler*>& samplers, const BakePlan& plan,
                           const BakeSetOptions& options, const Context& context,
                           const std::function<void(size_t, const BakedMeshInfo&)>& on_mesh) {
  const auto& c = input.set->connectivity;
  const auto& ds = *input.dissection;
  const std::string space = to_string(options.space), green = to_string(options.green);
  BakedSet out;
  nlohmann::ordered_json meshes = nlohmann::ordered_json::array();
  for (size_t i = 0; i < input.outputs.size(); ++i) {
    const std::string& stem = input.stems[i];
    BakedMeshInfo info;
    auto t = Clock::now();
    BakeOptions mesh_opt = plan.options;
    mesh_opt.original_vertices = ds.meshes[i].input_vertices;  // the chart keeps the input's vertices first
    Context ctx = context;
    if (context.progress) ctx.progress = [&](const std::string&, double f) { context.progress(stem, f); };
    BakeResult r = bake_normal_map(*samplers[i], c, input.set->positions[i], mesh_opt, ctx);
    info.bake_seconds = seconds_since(t);
    t = Clock::now();
    const Rgb8Image img8 = quantize8(r.atlas);
    const std::vector<unsigned char> png8 = encode_png8(img8);
    nlohmann::ordered_json files = {{"png8", stem + file_suffix(ImageFormat::Png8)}};
    write_bytes(staging / files["png8"].get<std::string>(), png8);
    for (auto f : options.extra) {
      const std::string name = stem + file_suffix(f);
      write_bytes(staging / name, encode_image(r.atlas, f));
      files[to_string(f)] = name;
    }
    const gltf::Mesh g = to_gltf_mesh(r, png8, stem);
    gltf::write_glb(staging / (stem + ".glb"), g);
    info.write_seconds = seconds_since(t);
    t = Clock::now();
    info.glb_vertices = r.mesh.num_vertices();
    nlohmann::ordered_json j = {{"remesh", input.outputs[i]},
                                {"source", ds.meshes[i].file},
                                {"chart", ds.meshes[i].chart_file},
                                {"maps", files},
                                {"glb", stem + ".glb"},
                                {"glb_vertices", r.mesh.num_vertices()},
                                {"glb_faces", r.mesh.num_faces()},
                                {"glb_normal_texture", options.space == NormalSpace::Tangent}};
    info.texel_density = remesh::chart_density(ds.meshes[i].dissection.chart, plan.side_minus_one);
    const remesh::DensitySpread& td = info.texel_density;
    j["texel_density"] = {{"p5", td.p5}, {"p50", td.p50}, {"p95", td.p95}, {"spread", td.spread}};
    if (options.samples > 0) {
      ShadingCheckOptions co;
      co.samples = options.samples;
      const ShadingCheck s = check_shading(*samplers[i], r, img8, co);
      info.shading = s;
      j["shading"] = {{"samples", s.samples},
                      {"seed", co.seed},
                      {"mean_deg_with_map", s.mean_with_map},
                      {"p95_deg_with_map", s.p95_with_map},
                      {"max_deg_with_map", s.max_with_map},
                      {"mean_deg_without_map", s.mean_without_map},
                      {"p95_deg_without_map", s.p95_without_map},
                      {"max_deg_without_map", s.max_without_map}};
    }
    info.check_seconds = seconds_since(t);
    meshes.push_back(j);
    if (options.keep_atlases) out.atlases.push_back(std::move(r.atlas));
    out.meshes.push_back(info);
    if (on_mesh) on_mesh(i, info);
  }

  const AtlasLayout& layout = plan.layout;
  nlohmann::ordered_json patches = nlohmann::ordered_json::array();
  const auto& names = ds.meshes[0].dissection.chart.patches;
  for (int p = 0; p < layout.num_patches; ++p)
    patches.push_back({{"patch", p},
                       {"name", names[p].name},
                       {"x", layout.tile_x(p)},
                       {"y", layout.tile_y(p)},
                       {"width", layout.tile_side(p)},
                       {"height", layout.tile_side(p)}});
  nlohmann::ordered_json doc = {
      {"format", "qs-bake"},
      {"version", 1},
      {"remesh", fs::relative(fs::absolute(input.remesh_folder), fs::absolute(outdir)).lexically_normal().generic_string()},
      {"dissection",
       fs::relative(fs::absolute(input.dissection_folder), fs::absolute(outdir)).lexically_normal().generic_string()},
      {"options",
       {{"size", options.size},
        {"gutter", options.gutter},
        {"space", space},
        {"green", options.space == NormalSpace::Tangent ? green : std::string("none")},
        {"formats", [&] {
           nlohmann::ordered_json f = {"png8"};
           for (auto e : options.extra) f.push_back(to_string(e));
           return f;
         }()},
        {"tiles", options.area_tiles ? "area" : "uniform"},
        {"samples", options.samples},
        {"original_normals", "angle-weighted at the input's vertices, interpolated along the input's edges and "
                             "faces at vertices inserted by the cuts"}}},
      {"atlas",
       {{"layout", layout.grid ? "grid" : "shelves"},
        {"columns", layout.columns},
        {"rows", layout.rows},
        {"tile_size", options.size},
        {"gutter", options.gutter},
        {"width", layout.width()},
        {"height", layout.height()},
        {"encoding", "x*0.5+0.5 per channel, linear"},
        {"texel_centres", "texel (i,j) of a patch's tile, j from the top, is (u,v) = (i/(S-1), 1-j/(S-1)), S its width"},
        {"texcoord", "s = (x + 0.5 + u*(S-1)) / width, t = (y + 0.5 + (1-v)*(S-1)) / height, S the tile's width"},
        {"patches", patches}}},
      {"meshes", meshes}};
  write_file_atomically(staging / "bake.json", json_strict::dump(doc, 1) + "\n");
  return out;
}

}  // namespace qs::bake
