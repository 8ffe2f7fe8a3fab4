// qs-morph: morphs between the shapes of a qs-remesh output by plain linear blending.
// Writes frames along a path (OUTDIR/frame_NNNN.<fmt> + OUTDIR/morph.json), one blend for given
// barycentric weights (OUTDIR/blend.<fmt>), and/or a GLB with one morph target per shape and a
// weights animation along the path (optionally with the base shape's baked normal map); with
// --frame-maps the frames carry the bake's atlas UVs and their own blended normal map.
//
// Exit codes: 0 done, 1 usage, 2 invalid input (unknown shape, bad weights, meshes that do not
// share one connectivity, a bake of another remesh), 3 i/o (missing files, bake.json missing),
// 70 internal error.

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <unistd.h>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/core/json_strict.h"
#include "qs/core/output_folder.h"
#include "qs/gltf/glb.h"
#include "qs/morph/blend.h"
#include "qs/morph/frame_maps.h"
#include "qs/morph/frames.h"
#include "qs/morph/morph_glb.h"
#include "qs/remesh/remesh_io.h"
#include "tool_main.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

std::vector<std::string> split_names(const std::string& list) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : list) {
    if (c == ',') {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

// frame_0000, frame_0001, ... (more digits from 10000 frames on).
std::string frame_stem(int f, int frames) {
  int width = 4;
  for (int n = frames - 1; n >= 10000; n /= 10) ++width;
  std::ostringstream s;
  s << "frame_" << std::setw(width) << std::setfill('0') << f;
  return s.str();
}

std::string path_list_string(const nlohmann::ordered_json& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : " -> ") + n.get<std::string>();
  return s;
}

// Creates `dir` (and its parents); a failure is an i/o error, not an internal one.
double seconds(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Morphs between the shapes of a qs-remesh output folder by plain linear blending: frames along a "
               "path, one blend of given weights, and/or a GLB with morph targets and a weights animation.\n"
               "Exit codes: 0 ok, 1 usage, 2 invalid input, 3 i/o, 70 internal.",
               "qs-morph"};
  std::string folder, outdir, format = "obj", path_list, glb, bake, align = "none";
  int frames = 0;
  std::vector<double> weights;
  bool quiet = false, frame_maps = false;
  int threads = 0;
  app.add_option("remesh", folder, "A qs-remesh output folder (remesh.json + one mesh per shape)")->required();
  app.add_option("--frames", frames,
                 "Write K frames along the path, uniform in the path parameter (default when neither --weights nor "
                 "--glb is given: 10 per leg + 1, so every stop is a frame)")
      ->check(CLI::Range(2, 1000000));
  app.add_option("--path", path_list, "Shapes to pass through, by file stem, comma-separated; may repeat (a,b,a). "
                                      "Default: all shapes in remesh.json's order");
  app.add_option("--weights", weights, "Write OUTDIR/blend.<fmt>: barycentric weights w1,...,wN, one per shape in "
                                       "remesh.json's order, each >= 0, summing to 1")
      ->delimiter(',');
  app.add_option("--format", format, "Frame and blend format: obj (text) or ply (binary little-endian, float64)")
      ->capture_default_str()
      ->check(CLI::IsMember({"obj", "ply"}));
  app.add_option("--glb", glb, "Write a GLB: the path's first shape as the mesh, one morph target per other shape, "
                               "default weights from --weights (else 0), an animation along the path (1 s per leg)");
  app.add_option("--bake", bake, "A qs-bake output folder (bake.json, <stem>.glb, <stem>_normal.png): put the base "
                                 "shape's normal map, atlas UVs and tangents into the GLB (and see --frame-maps)");
  app.add_flag("--frame-maps", frame_maps,
               "With --bake: frames (and the blend) as OBJ with the bake's atlas UVs, an MTL and their own normal map "
               "(<name>_normal.png: the shapes' maps blended texel by texel with the frame's weights)");
  app.add_option("-o,--output", outdir, "Output folder for frames, blend and morph.json (default: <remesh>/morph)");
  app.add_option("--threads", threads, "Threads (0: all hardware threads; the output does not depend on it)")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
  app.add_option("--align", align,
                 "Place every shape on the path's first by the least-squares rotation (rigid) or rotation and "
                 "uniform scale (similarity) over corresponding vertices, before blending")
      ->capture_default_str()
      ->check(CLI::IsMember({"none", "rigid", "similarity"}));
  app.add_flag("-q,--quiet", quiet, "Print nothing but errors");

  return qs::tools::run_tool(app, argc, argv, [&] {
    if (!bake.empty() && glb.empty() && !frame_maps)
      throw qs::UsageError("--bake needs --glb FILE or --frame-maps (the normal maps go into the GLB or the frames)");
    if (frame_maps && bake.empty()) throw qs::UsageError("--frame-maps needs --bake DIR (the normal maps to blend)");
    if (frame_maps && format != "obj") throw qs::UsageError("--frame-maps writes OBJ + MTL frames; drop --format " + format);
    qs::Context context;
    context.threads = threads;
    if (!quiet && ::isatty(2))  // progress on a terminal only
      context.progress = [](const std::string& stage, double done) {
        std::cerr << "\r  " << stage << " " << static_cast<int>(100 * done) << "%" << (done >= 1 ? "\n" : "") << std::flush;
      };
    const auto t0 = Clock::now();
    qs::remesh::LoadedRemesh in = qs::remesh::read_remesh(folder);
    const auto& set = in.set;
    const int n = static_cast<int>(set.positions.size());
    if (n < 2) throw qs::InvalidInput(folder + ": holds " + std::to_string(n) + " shape; a morph needs at least 2");
    const std::vector<std::string>& names = in.stems;

    std::vector<int> stops;
    if (path_list.empty()) {
      for (int i = 0; i < n; ++i) stops.push_back(i);
    } else {
      for (const std::string& name : split_names(path_list)) stops.push_back(qs::morph::shape_index(names, name));
      if (stops.size() < 2) throw qs::InvalidInput("--path needs at least 2 shapes (got '" + path_list + "')");
    }
    const bool have_weights = app.count("--weights") > 0;
    if (have_weights) {
      try {
        qs::morph::check_weights(weights, n);
      } catch (const qs::InvalidInput& e) {
        std::string known;
        for (const auto& s : names) known += (known.empty() ? "" : ", ") + s;
        throw qs::InvalidInput(std::string(e.what()) + " (--weights gives one weight per shape, in order: " + known + ")");
      }
    }
    // Alignment onto the path's first shape (the GLB's base, left as it is).
    const qs::morph::Align how = qs::morph::align_from_name(align);
    for (int i = 0; i < n; ++i)
      if (i != stops[0]) in.set.positions[i] = qs::morph::align_to(in.set.positions[i], in.set.positions[stops[0]], how);
    if (frames == 0 && !have_weights && glb.empty()) frames = 10 * (static_cast<int>(stops.size()) - 1) + 1;
    const qs::morph::FrameFormat ff = qs::morph::frame_format(format);
    const char* ext = qs::morph::extension(ff);
    if (outdir.empty()) outdir = (fs::path(folder) / "morph").string();
    // Every input is read and checked before anything is written.
    std::optional<qs::morph::BakedShape> baked;
    qs::morph::NormalAtlases atlases;
    if (!bake.empty()) {
      baked = qs::morph::read_baked_shape(bake, names[stops[0]], set.connectivity.faces, set.positions[stops[0]]);
      if (frame_maps && (frames > 0 || have_weights)) atlases = qs::morph::read_normal_atlases(bake, names);
    }
    const auto t1 = Clock::now();

    std::ostringstream text;
    nlohmann::ordered_json doc = {{"format", "qs-morph"},
                                  {"version", 1},
                                  {"remesh", folder},
                                  {"vertices", set.connectivity.num_vertices()},
                                  {"faces", set.connectivity.num_faces()},
                                  {"shapes", names}};
    nlohmann::ordered_json path_names = nlohmann::ordered_json::array();
    for (int s : stops) path_names.push_back(names[s]);
    doc["path"] = path_names;
    // The options as given (not --threads: the files do not depend on it).
    doc["options"] = {{"frames", frames},
                      {"path", path_list.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(path_list)},
                      {"weights", have_weights ? nlohmann::ordered_json(weights) : nlohmann::ordered_json(nullptr)},
                      {"format", format},
                      {"glb", glb.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(glb)},
                      {"bake", bake.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(bake)},
                      {"frame_maps", frame_maps},
                      {"align", align}};

    const bool write_folder = frames > 0 || have_weights;
    // No output replaces an input; the folder is staged and moved into place at the very end, after
    // the GLB, so that a failure anywhere leaves both as they were.
    std::vector<fs::path> input_paths = {fs::path(folder) / "remesh.json"};
    for (const auto& o : in.outputs) input_paths.push_back(fs::path(folder) / o);
    if (!bake.empty()) {
      input_paths.push_back(fs::path(bake) / "bake.json");
      for (const auto& s : names)
        for (const std::string suffix : {".glb", "_normal.png"}) input_paths.push_back(fs::path(bake) / (s + suffix));
    }
    if (!glb.empty()) qs::check_not_an_input(glb, input_paths, "--glb");
    std::optional<qs::OutputFolder> out_folder;
    if (write_folder) {
      for (int f = 0; f < frames; ++f)
        qs::check_not_an_input(fs::path(outdir) / (frame_stem(f, frames) + "." + ext), input_paths, "-o");
      qs::check_not_an_input(fs::path(outdir) / "morph.json", input_paths, "-o");
      if (!glb.empty() && fs::weakly_canonical(fs::absolute(glb)) == fs::weakly_canonical(fs::absolute(fs::path(outdir) / "morph.json")))
        throw qs::UsageError("--glb " + glb + " is the morph.json this run writes; name the GLB otherwise");
      out_folder.emplace(outdir);
    }
    const fs::path staging = write_folder ? out_folder->staging() : fs::path();
    if (frames > 0) {
      const std::vector<qs::morph::PathFrame> pf = qs::morph::path_frames(n, stops, frames);
      std::vector<std::string> stems, files;
      nlohmann::ordered_json list = nlohmann::ordered_json::array();
      for (int f = 0; f < frames; ++f) {
        stems.push_back(frame_stem(f, frames));
        files.push_back(stems[f] + "." + ext);
        nlohmann::ordered_json j = {{"file", files[f]}};
        if (frame_maps) {
          j["mtl"] = stems[f] + ".mtl";
          j["normal_map"] = stems[f] + "_normal.png";
        }
        j.update({{"s", pf[f].s}, {"leg", pf[f].leg}, {"t", pf[f].t}, {"weights", pf[f].weights}});
        list.push_back(j);
      }
      if (frame_maps)
        qs::morph::write_textured_frames(staging, stems, set.positions, set.connectivity.faces, *baked, atlases, pf, threads,
                                         context);
      else
        qs::morph::write_frames(staging, files, set.positions, set.connectivity.faces, pf, ff, threads, context);
      doc["frames"] = {{"count", frames},
                       {"file_format", ext},
                       {"spacing", "uniform in the path parameter s in [0, stops - 1]; stop k is at s = k; "
                                   "weights (1 - t) on the leg's first stop and t on its second"},
                       {"list", list}};
      text << "  wrote " << frames << " frames along " << path_list_string(path_names) << " to " << outdir << "\n";
    }
    if (have_weights) {
      const std::string file = std::string("blend.") + ext;
      if (frame_maps) {
        qs::morph::PathFrame pf;
        pf.weights = weights;
        qs::morph::write_textured_frames(staging, {"blend"}, set.positions, set.connectivity.faces, *baked, atlases, {pf}, 1);
        doc["blend"] = {{"file", file}, {"mtl", "blend.mtl"}, {"normal_map", "blend_normal.png"}, {"weights", weights}};
      } else {
        qs::morph::FrameWriter(set.connectivity.faces, ff).write(staging / file, qs::morph::blend(set, weights));
        doc["blend"] = {{"file", file}, {"weights", weights}};
      }
      text << "  wrote " << (fs::path(outdir) / file).string() << "\n";
    }
    const auto t2 = Clock::now();
    if (!glb.empty()) {
      qs::morph::MorphGlbOptions go;
      go.base = stops[0];
      go.path = stops;
      if (have_weights) go.weights = weights;
      go.name = "morph";
      const qs::gltf::Mesh mesh = qs::morph::write_morph_glb(glb, set, names, go, baked ? &*baked : nullptr);
      nlohmann::ordered_json targets = nlohmann::ordered_json::array();
      for (const auto& t : mesh.targets) targets.push_back(t.name);
      nlohmann::ordered_json g = {{"file", glb}, {"base", names[go.base]}, {"targets", targets}, {"seconds_per_leg", 1.0}};
      if (baked) g["bake"] = bake;
      doc["glb"] = g;
      text << "  wrote " << glb << ": base " << names[go.base] << ", " << mesh.targets.size() << " morph targets, "
           << (stops.size() - 1) << " s animation" << (baked ? ", normal map from " + baked->glb.string() : "") << "\n";
    }
    if (write_folder) {
      qs::write_file_atomically(staging / "morph.json", qs::json_strict::dump(doc, 1) + "\n");
      out_folder->commit();
    }
    const auto t3 = Clock::now();
    if (!quiet)
      std::cout << "morph of " << n << " shapes, " << set.connectivity.num_vertices() << " vertices, "
                << set.connectivity.num_faces() << " faces\n"
                << text.str() << std::fixed << std::setprecision(3) << "  time: load " << seconds(t0, t1)
                << " s, frames+blend " << seconds(t1, t2) << " s, glb " << seconds(t2, t3) << " s\n";
    return 0;
  });
}
