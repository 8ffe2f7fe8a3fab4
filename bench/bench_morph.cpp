// Morph benchmarks: 100 frames of a ~50k-vertex morph written as OBJ and as binary PLY
// (target < 1 s), building + writing a GLB with 8 morph targets, and one --frame-maps normal map.
// Shapes made in code: cube_sphere(91) (49,688 vertices, 99,372 faces) and displaced copies.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "qs/gltf/glb.h"
#include "qs/morph/blend.h"
#include "qs/morph/frame_maps.h"
#include "qs/morph/frames.h"
#include "qs/morph/morph_glb.h"
#include "qs/shapes/shapes.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Shape k: the cube-sphere's vertices moved radially by smooth bumps and stretched along an axis.
std::vector<qs::Vec3> deformed(const std::vector<qs::Vec3>& p, int k) {
  std::vector<qs::Vec3> out(p.size());
  const double f = 2 + k;
  for (size_t v = 0; v < p.size(); ++v) {
    const qs::Vec3 d = p[v].normalized();
    const double r = 1 + 0.08 * std::sin(f * d.x()) * std::cos(f * d.y()) + 0.05 * k * d.z() * d.z();
    out[v] = qs::Vec3(d.x() * (1 + 0.1 * k), d.y(), d.z() * (1 - 0.03 * k)) * r;
  }
  return out;
}

uint64_t folder_bytes(const fs::path& dir) {
  uint64_t n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += fs::file_size(e.path());
  return n;
}

}  // namespace

int main() {
  const qs::TriMesh base = qs::shapes::cube_sphere(91);
  std::vector<std::vector<qs::Vec3>> shapes;
  for (int k = 0; k < 9; ++k) shapes.push_back(k == 0 ? base.positions : deformed(base.positions, k));
  std::printf("morph benchmark: %d vertices, %d faces per shape (cube_sphere(91) + displaced copies), %u hardware threads\n",
              base.num_vertices(), base.num_faces(), std::thread::hardware_concurrency());

  const fs::path root = fs::temp_directory_path() / ("qs_bench_morph_" + std::to_string(::getpid()));
  const int frames = 100, repeats = 3;
  const std::vector<std::vector<qs::Vec3>> pair = {shapes[0], shapes[1]};
  const auto pf = qs::morph::path_frames(2, {0, 1}, frames);
  std::vector<std::string> files;
  for (int f = 0; f < frames; ++f) files.push_back("frame_" + std::to_string(f));

  // Blending alone (no text, no disk), for reference.
  {
    auto t = Clock::now();
    double checksum = 0;
    for (const auto& fr : pf) checksum += qs::morph::blend(pair, fr.weights)[7].x();
    std::printf("  blend only: %d frames in %.3f s (checksum %.3f)\n", frames, since(t), checksum);
  }
  for (auto format : {qs::morph::FrameFormat::Obj, qs::morph::FrameFormat::Ply}) {
    for (int threads : {1, 0}) {
      std::vector<double> times;
      uint64_t bytes = 0;
      for (int r = 0; r < repeats; ++r) {
        const fs::path dir = root / "frames";
        fs::remove_all(dir);
        fs::create_directories(dir);
        std::vector<std::string> named;
        for (const auto& f : files) named.push_back(f + "." + qs::morph::extension(format));
        const auto t = Clock::now();
        qs::morph::write_frames(dir, named, pair, base.faces, pf, format, threads);
        times.push_back(since(t));
        bytes = folder_bytes(dir);
      }
      std::sort(times.begin(), times.end());
      const double median = times[repeats / 2];
      std::printf("  %d frames, %s, %s: median %.3f s of %d (min %.3f), %.1f MB, %.0f MB/s; target < 1 s: ratio %.2f\n",
                  frames, format == qs::morph::FrameFormat::Obj ? "OBJ text" : "PLY binary",
                  threads == 1 ? "1 thread " : "all threads", median, repeats, times[0], bytes / 1e6,
                  bytes / 1e6 / median, median / 1.0);
    }
  }
  fs::remove_all(root / "frames");

  // GLB with 8 morph targets (9 shapes).
  {
    qs::remesh::SemiRegularSet set;
    set.connectivity.faces = base.faces;
    set.positions = shapes;
    std::vector<std::string> names;
    for (int k = 0; k < 9; ++k) names.push_back("shape" + std::to_string(k));
    qs::morph::MorphGlbOptions o;
    o.path = {0, 1, 2, 3, 4, 5, 6, 7, 8};
    std::vector<double> times;
    uint64_t size = 0;
    for (int r = 0; r < repeats; ++r) {
      const auto t = Clock::now();
      const qs::gltf::Mesh m = qs::morph::morph_glb_mesh(set, names, o);
      const double build = since(t);
      qs::gltf::write_glb(root / "eight.glb", m);
      times.push_back(since(t));
      size = fs::file_size(root / "eight.glb");
      if (r == 0) std::printf("  GLB, 8 targets: build %.3f s (normals, deltas, checks)\n", build);
    }
    std::sort(times.begin(), times.end());
    std::printf("  GLB, 8 targets + 8 s animation: build + write median %.3f s of %d, %.1f MB (%.1f bytes per vertex)\n",
                times[repeats / 2], repeats, size / 1e6, double(size) / base.num_vertices());
  }
  // --frame-maps: one in-between normal map of a 4096 x 4096 atlas (blend of two, PNG encoding).
  {
    qs::morph::NormalAtlases atlases;
    atlases.width = atlases.height = 4096;
    for (int k = 0; k < 2; ++k) {
      std::vector<unsigned char> rgb(size_t(4096) * 4096 * 3);
      for (size_t t = 0; t < rgb.size() / 3; ++t) {
        const double a = 0.002 * double(t % 4096) * (k + 1), b = 0.003 * double(t / 4096);
        const qs::Vec3 nrm = qs::Vec3(0.4 * std::sin(a), 0.4 * std::cos(b), 1).normalized();
        for (int c = 0; c < 3; ++c) rgb[3 * t + c] = static_cast<unsigned char>(std::lround((nrm[c] * 0.5 + 0.5) * 255));
      }
      atlases.rgb.push_back(std::move(rgb));
    }
    auto t = Clock::now();
    const auto mid = qs::morph::blend_normal_maps(atlases, {0.5, 0.5});
    const double blend_s = since(t);
    t = Clock::now();
    const auto png = qs::morph::encode_png_rgb8(4096, 4096, mid);
    std::printf("  frame map 4096 x 4096: blend %.3f s, PNG encode %.3f s (%.1f MB) per in-between frame\n", blend_s,
                since(t), png.size() / 1e6);
  }
  fs::remove_all(root);
  return 0;
}
