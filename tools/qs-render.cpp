// qs-render: render meshes and dissection charts to a PNG, for looking at qs outputs.
//
// Each input is a mesh (.obj .off .ply .stl) or a chart written by qs-dissect (*.chart.ply, faces
// coloured by patch). Several inputs are rendered side by side with the same view, each fitted
// to its own bounding box. --patch-edges draws patch boundaries of charts; --uv shows a chart's
// uv layout (one tile per patch) instead of its 3D view. Both apply to charts; plain meshes are
// rendered as usual beside them.
//
// Exit codes: 0 written, 1 usage, 2 invalid input (unparsable mesh, unknown extension), 3 a file
// that cannot be read or written, 70 internal error. No partial PNG is ever left behind.

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <regex>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/core/output_folder.h"
#include "qs/dissect/chart_io.h"
#include "qs/io/read_mesh.h"
#include "qs/render/render.h"
#include "resource_limits.h"
#include "tool_main.h"

namespace fs = std::filesystem;

namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

bool is_chart(const std::string& file) {
  const std::string f = lower(fs::path(file).filename().string());
  const std::string suffix = ".chart.ply";
  return f.size() >= suffix.size() && f.compare(f.size() - suffix.size(), suffix.size(), suffix) == 0;
}

qs::Vec3 to_vec3(const std::vector<double>& v, const char* option) {
  if (v.size() != 3)
    throw qs::UsageError(std::string(option) + " needs three comma-separated numbers, like 0.3,0.4,1");
  const qs::Vec3 out(v[0], v[1], v[2]);
  if (!out.allFinite() || out.norm() == 0)
    throw qs::UsageError(std::string(option) + " must be a non-zero finite vector");
  return out;
}

// Edges whose faces carry different patch labels, as sorted vertex pairs (deterministic order).
std::vector<std::array<int, 2>> patch_boundary_edges(const qs::TriMesh& mesh, const std::vector<int>& face_patch) {
  struct Entry {
    int a, b, face;
  };
  std::vector<Entry> entries;
  entries.reserve(3 * mesh.faces.size());
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.faces[f][k], b = mesh.faces[f][(k + 1) % 3];
      entries.push_back({std::min(a, b), std::max(a, b), f});
    }
  std::sort(entries.begin(), entries.end(),
            [](const Entry& x, const Entry& y) { return std::tie(x.a, x.b, x.face) < std::tie(y.a, y.b, y.face); });
  std::vector<std::array<int, 2>> edges;
  for (size_t i = 0; i < entries.size();) {
    size_t j = i + 1;
    bool differ = false;
    while (j < entries.size() && entries[j].a == entries[i].a && entries[j].b == entries[i].b) {
      differ |= face_patch[entries[j].face] != face_patch[entries[i].face];
      ++j;
    }
    if (differ) edges.push_back({entries[i].a, entries[i].b});
    i = j;
  }
  return edges;
}

// The peak memory of a run, in bytes, on the safe side. Measured peaks (resident set size):
// about 130 MiB for the program and its libraries; 16 bytes a pixel while a view is drawn
// (colour, depth, face id, shade, edge mask), 3 more for each finished view kept and 3 per view
// for the joined picture; a mesh in memory is 1.6 (OBJ) to 3.9 (binary PLY, smooth and wireframe)
// times its file, and one mesh is read at a time. Here: 160 MiB + W·H·(16 + 6k) + 8 x the
// largest input file.
double render_memory_estimate(int width, int height, int views, double largest_input_bytes) {
  const double pixels = static_cast<double>(width) * height;
  return 160.0 * 1024 * 1024 + pixels * (16.0 + 6.0 * views) + 8.0 * largest_input_bytes;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Render meshes and qs charts to a PNG (orthographic, z-buffered, deterministic).\n"
               "Exit codes: 0 ok, 1 usage, 2 invalid input, 3 i/o, 70 internal.",
               "qs-render"};
  std::vector<std::string> inputs;
  std::string output, size = "800";
  std::vector<double> view_v, up_v;
  bool uv = false, patch_edges = false, quiet = false;
  qs::render::RenderOptions opt;
  app.add_option("inputs", inputs,
                 "Meshes (.obj .off .ply .stl) and charts (*.chart.ply); several are drawn side by side")
      ->required();
  app.add_option("-o,--output", output, "Output PNG file")->required();
  app.add_option("--size", size, "Size of each view in pixels: W or WxH")->capture_default_str();
  app.add_option("--view", view_v,
                 "Direction from the object towards the camera: x,y,z (default 0.3,0.4,1); or one x,y,z per "
                 "input, all in one list, for shapes that face different ways")
      ->delimiter(',');
  app.add_option("--up", up_v, "Up direction in the image: x,y,z (default 0,1,0)")->delimiter(',');
  app.add_flag("--wireframe", opt.wireframe, "Draw every triangle edge");
  app.add_flag("--smooth", opt.smooth, "Smooth shading (interpolated vertex normals)");
  app.add_flag("--patch-edges", patch_edges, "Charts: draw patch boundaries as thick dark lines");
  app.add_flag("--uv", uv, "Charts: draw the uv layout (one tile per patch; red = flipped or overlapping)");
  double max_memory = qs::tools::kDefaultMaxMemoryGiB;
  qs::tools::add_max_memory_option(app, max_memory);
  app.add_flag("-q,--quiet", quiet, "Print nothing but errors");

  return qs::tools::run_tool(app, argc, argv, [&] {
    std::smatch m;
    static const std::regex size_re(R"((\d{1,5})(?:[xX](\d{1,5}))?)");
    if (!std::regex_match(size, m, size_re))
      throw qs::UsageError("--size '" + size + "' is not W or WxH (e.g. 800 or 1024x768)");
    opt.width = std::stoi(m[1].str());
    opt.height = m[2].matched ? std::stoi(m[2].str()) : opt.width;
    if (opt.width < 16 || opt.height < 16 || opt.width > 8192 || opt.height > 8192)
      throw qs::UsageError("--size " + size + " is out of range; width and height must be 16..8192");
    // The whole picture, checked before any view is drawn: the views side by side must fit in one
    // PNG (16384 pixels wide), and the run's peak memory in --max-memory.
    if (!std::isfinite(max_memory))
      throw qs::UsageError("--max-memory " + std::to_string(max_memory) + " is not a finite number of GiB");
    const long long total_width = static_cast<long long>(opt.width) * static_cast<long long>(inputs.size());
    if (total_width > 16384)
      throw qs::UsageError(std::to_string(inputs.size()) + " views of width " + std::to_string(opt.width) + " are " +
                           std::to_string(total_width) + " pixels wide side by side, more than 16384; use a smaller "
                           "--size or fewer inputs");
    {
      std::uintmax_t largest_input = 0;
      for (const std::string& file : inputs) {
        std::error_code ec;
        const std::uintmax_t bytes = fs::file_size(file, ec);
        if (!ec) largest_input = std::max(largest_input, bytes);  // a missing file is reported when read
      }
      qs::tools::check_memory(render_memory_estimate(opt.width, opt.height, static_cast<int>(inputs.size()),
                                                     static_cast<double>(largest_input)),
                              max_memory,
                              std::to_string(inputs.size()) + (inputs.size() == 1 ? " view of " : " views of ") +
                                  std::to_string(opt.width) + " x " + std::to_string(opt.height));
    }
    {
      std::vector<fs::path> input_paths(inputs.begin(), inputs.end());
      qs::check_not_an_input(output, input_paths, "-o");
    }
    std::vector<qs::Vec3> views_dir;  // one per input when several were given
    if (view_v.size() == 3 * inputs.size() && inputs.size() > 1) {
      for (size_t k = 0; k < inputs.size(); ++k)
        views_dir.push_back(to_vec3({view_v.begin() + 3 * k, view_v.begin() + 3 * k + 3}, "--view"));
    } else if (!view_v.empty()) {
      if (view_v.size() != 3)
        throw qs::UsageError("--view takes x,y,z or one x,y,z per input (" + std::to_string(3 * inputs.size()) +
                             " numbers), not " + std::to_string(view_v.size()) + " numbers");
      opt.view_dir = to_vec3(view_v, "--view");
    }
    if (!up_v.empty()) opt.up = to_vec3(up_v, "--up");
    if (lower(fs::path(output).extension().string()) != ".png")
      throw qs::UsageError("output '" + output + "' must end in .png (qs-render writes PNG only)");
    if ((uv || patch_edges) && std::none_of(inputs.begin(), inputs.end(), is_chart))
      throw qs::UsageError(std::string(uv ? "--uv" : "--patch-edges") +
                           " needs a chart (*.chart.ply, written by qs-dissect) among the inputs");

    using clock = std::chrono::steady_clock;
    const auto ms = [](clock::time_point a, clock::time_point b) {
      return std::chrono::duration<double, std::milli>(b - a).count();
    };
    std::vector<qs::render::Image> views;
    for (size_t k = 0; k < inputs.size(); ++k) {
      const std::string& file = inputs[k];
      if (!views_dir.empty()) opt.view_dir = views_dir[k];
      const auto t0 = clock::now();
      qs::render::Image img;
      auto t1 = t0;
      if (is_chart(file)) {
        const qs::dissect::Chart chart = qs::dissect::read_chart_ply(file);
        int patches = static_cast<int>(chart.patches.size());
        for (int p : chart.face_patch) patches = std::max(patches, p + 1);
        if (patches > 1000000)
          throw qs::InvalidInput(file + ": " + std::to_string(patches) + " patch labels; not a chart qs-dissect wrote");
        std::vector<qs::render::Rgb> colours(patches);
        for (int p = 0; p < patches; ++p) {
          const auto c = qs::dissect::patch_colour(p);
          colours[p] = {c[0], c[1], c[2]};
        }
        t1 = clock::now();
        if (uv) {
          int cols = 1;
          while (cols * cols < std::max(1, patches)) ++cols;
          const int rows = (std::max(1, patches) + cols - 1) / cols;
          const int tile = std::clamp(std::min(opt.width / cols, opt.height / rows), 8, 4096);
          img = qs::render::render_uv_layout(chart.face_uv, chart.face_patch, std::max(1, patches), tile, colours);
        } else {
          std::vector<qs::render::Rgb> face_colours(chart.face_patch.size());
          for (size_t f = 0; f < face_colours.size(); ++f) face_colours[f] = colours[chart.face_patch[f]];
          std::vector<std::array<int, 2>> edges;
          if (patch_edges) edges = patch_boundary_edges(chart.mesh, chart.face_patch);
          img = qs::render::render_mesh(chart.mesh, &face_colours, opt, patch_edges ? &edges : nullptr);
        }
      } else {
        const qs::io::ReadResult read = qs::io::read_mesh(file);
        t1 = clock::now();
        img = qs::render::render_mesh(read.mesh, nullptr, opt);
      }
      if (!quiet)
        std::cout << "  " << file << ": read " << ms(t0, t1) << " ms, render " << ms(t1, clock::now()) << " ms\n";
      views.push_back(std::move(img));
    }
    const auto t2 = clock::now();
    const qs::render::Image picture = views.size() == 1 ? views.front() : qs::render::side_by_side(views);
    qs::render::write_png(output, picture);
    if (!quiet)
      std::cout << "  wrote " << output << " (" << picture.width << " x " << picture.height << ") in "
                << ms(t2, clock::now()) << " ms\n";
    return 0;
  });
}
