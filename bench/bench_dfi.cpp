// qs-dfi benchmark: for each pair of ../shared/meshes and each method (the
// skeleton-guided warp with per-part transport, the same with one global transport, the plain
// blend; "/parts" or "/linear" says which warp ran), the correspondence (distance fields,
// skeletons, matching, harmonic fields, transport, warp) and every frame at a 150^3 grid (targets: correspondence < 60 s, < 10 s per frame on a
// 2-core machine), endpoints against the inputs (Hausdorff in voxels), the
// topology of every frame, the middle frame's volume against the endpoints' mean (in morph space),
// the smoothness of the sequence (largest / median Hausdorff distance between consecutive frames),
// and whether 1 and 2 threads give the same bytes.
//
// Usage: qs-bench-dfi [--grid N] [--frames K] [--smoothness] [--retime] [--refine-ends R] [--free-volume] [--no-topology] [--methods warp,global,blend] [pair ...]   (pairs: sphere-torus,
// horse-knot, spot-eight, femur-elephant, horse-camel, cat-koala; default all)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "qs/core/error.h"
#include "qs/dfi/pipeline.h"
#include "qs/dfi/retime.h"
#include "qs/io/read_mesh.h"
#include "qs/mesh/validate.h"
#include "qs/metro/metro.h"
#include "qs/shapes/shapes.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using namespace qs;

namespace {

double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

struct Pair {
  std::string name, a, b;  // mesh files under ../shared/meshes, or "sphere" / "torus"
};

TriMesh load(const std::string& name) {
  if (name == "sphere") return shapes::icosphere(4);
  if (name == "torus") return shapes::torus(128, 48);
  const fs::path file = fs::path(QS_SOURCE_DIR) / ".." / "shared" / "meshes" / name;
  mesh::ValidateOptions vo;
  vo.allow_any_genus = true;
  auto v = mesh::validate(io::read_mesh(file).mesh, vo);
  if (!v.report.accepted) throw InvalidInput(name + ": rejected");
  return v.mesh;
}

}  // namespace

int main(int argc, char** argv) {
  int grid = 150, frames = 11, refine_ends = 1;
  bool smoothness = false, retime = false, free_volume = false, no_topology = false;
  std::string methods = "warp,global,blend";
  std::vector<std::string> wanted;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--grid") && i + 1 < argc) grid = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--frames") && i + 1 < argc) frames = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--smoothness")) smoothness = true;
    else if (!std::strcmp(argv[i], "--retime")) retime = true;
    else if (!std::strcmp(argv[i], "--free-volume")) free_volume = true;
    else if (!std::strcmp(argv[i], "--no-topology")) no_topology = true;
    else if (!std::strcmp(argv[i], "--refine-ends") && i + 1 < argc) refine_ends = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--methods") && i + 1 < argc) methods = argv[++i];
    else wanted.push_back(argv[i]);
  }
  const std::vector<Pair> pairs = {{"sphere-torus", "sphere", "torus"},
                                   {"horse-knot", "horse_5k.obj", "knot1.off"},
                                   {"spot-eight", "spot_2k.obj", "eight.off"},
                                   {"femur-elephant", "femur.off", "elephant_12k.obj"},
                                   {"horse-camel", "horse_5k.obj", "camel_4k_fixed.obj"},
                                   {"cat-koala", "cat_16k.obj", "koala_7k.obj"}};
  std::printf("dfi benchmark: methods %s, --align similarity, grid %d, %d frames, %u hardware threads\n", methods.c_str(),
              grid, frames, std::thread::hardware_concurrency());
  std::printf("%-15s %-14s %9s %8s %8s %8s %9s %14s %10s %8s  %s\n", "pair", "method", "corr. s", "frame s", "max fr s",
              "ends vox", "1 comp", "mid vol/mean", "smooth", "threads", "genus per frame");
  for (const Pair& p : pairs) {
    if (!wanted.empty() && std::find(wanted.begin(), wanted.end(), p.name) == wanted.end()) continue;
    TriMesh a, b;
    try {
      a = load(p.a);
      b = load(p.b);
    } catch (const std::exception& e) {
      std::printf("%-15s skipped: %s\n", p.name.c_str(), e.what());
      continue;
    }
    for (const std::string method : {"warp", "global", "blend"}) {
    if (methods.find(method) == std::string::npos) continue;
    dfi::MorphOptions opt;
    opt.grid = grid;
    opt.align = dfi::Align::Similarity;
    opt.warp = method != "blend";
    opt.part_transport = method == "warp";
    // The plain blend is the paper's baseline: its zero level, whatever volume it encloses.
    opt.volume = method == "blend" || free_volume ? dfi::FrameVolume::Free : dfi::FrameVolume::Linear;
    // Topology control (topology.h) for the warps unless --no-topology (it acts only where both
    // inputs are genus 0, and on an end whose input is); the plain blend stays the paper's baseline.
    opt.topology_control = !no_topology && method != "blend";
    auto t0 = Clock::now();
    const dfi::PreparedMorph m = dfi::prepare_morph(a, b, opt);
    const double fields_s = since(t0);
    // Frame times: uniform, or (--retime) at equal steps of the change (retime.h).
    std::vector<double> times(frames);
    for (int f = 0; f < frames; ++f) times[f] = f / (frames - 1.0);
    double retime_s = 0;
    if (retime) {
      t0 = Clock::now();
      times = dfi::even_frame_times(m, frames).times;
      retime_s = since(t0);
    }
    double total = 0, worst = 0, end_vox = 0, mid_volume = 0;
    int one_component = 0;
    std::string genera, removed;
    std::vector<TriMesh> seq;
    for (int f = 0; f < frames; ++f) {
      const double t = times[f];
      t0 = Clock::now();
      const bool end = f == 0 || f == frames - 1;
      TriMesh morph_space, mesh;  // mesh: what qs-dfi writes, the frame at its placement
      dfi::BallReport ball;
      if (end && refine_ends > 1) {
        mesh = dfi::endpoint_frame(m, f == 0 ? a : b, f != 0, refine_ends, {}, {}, &ball);
        morph_space = mesh;
        if (f != 0) for (Vec3& q : morph_space.positions) q = m.target_to_source.apply(q);
      } else {
        dfi::BlendInfo info;
        morph_space = dfi::polygonize(dfi::blend_field(m, t, 0, &info));
        ball = info.ball;
        mesh = morph_space;
        for (Vec3& q : mesh.positions) q = dfi::placement(m.target_to_source, t, q);
      }
      const double s = since(t0);
      total += s;
      worst = std::max(worst, s);
      const dfi::MeshStats st = dfi::mesh_stats(mesh);
      one_component += st.components == 1;
      if (f) genera += ',';
      genera += std::to_string(st.genus);
      if (f) removed += ',';
      removed += dfi::controls_topology(m, t) ? std::to_string(ball.removed) : "-";
      if (2 * f == frames - 1) mid_volume = dfi::mesh_stats(morph_space).volume;
      if (f == 0 || f == frames - 1) {
        const double d = metro::metro(mesh, f == 0 ? a : b).max;
        const double voxel = f == 0 ? m.source_sdf.spacing : m.source_sdf.spacing / m.target_to_source.scale;
        end_vox = std::max(end_vox, d / voxel);
      }
      if (smoothness) seq.push_back(morph_space);
    }
    // Volumes in morph space: the target's is scaled to the source's by the alignment.
    const double mean_end = 0.5 * (m.source_volume + m.target_volume * std::pow(m.target_to_source.scale, 3));
    std::string smooth = "-";
    if (smoothness) {
      std::vector<double> d;
      for (size_t f = 1; f < seq.size(); ++f) d.push_back(metro::metro(seq[f - 1], seq[f]).max);
      std::vector<double> sorted = d;
      std::sort(sorted.begin(), sorted.end());
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.2f", *std::max_element(d.begin(), d.end()) / sorted[sorted.size() / 2]);
      smooth = buf;
      std::printf("%-15s consecutive Hausdorff (morph space):", p.name.c_str());
      for (double x : d) std::printf(" %.4f", x);
      std::printf("\n");
    }
    // Determinism: the source field and the middle frame's field on 1 and 2 threads.
    dfi::SdfOptions one = opt.sdf, two = opt.sdf;
    one.threads = 1;
    two.threads = 2;
    const bool same = dfi::signed_distance(a, m.source_sdf, one).values == dfi::signed_distance(a, m.source_sdf, two).values &&
                      dfi::blend_field(m, 0.5, 1).values == dfi::blend_field(m, 0.5, 2).values;
    char mid[32];
    std::snprintf(mid, sizeof mid, "%.3f", mid_volume / mean_end);
    // Which warp ran: the part warp (bones) or the linear one (no matched branch, or it folds).
    const std::string label = method + (m.warp ? (m.bones.empty() ? "/linear" : "/parts") : "");
    if (retime) {
      std::printf("%-15s retime %.2f s, times", p.name.c_str(), retime_s);
      for (double t : times) std::printf(" %.3f", t);
      std::printf("\n");
    }
    std::printf("%-15s %-14s topology control: inside samples left out per frame %s\n", p.name.c_str(), method.c_str(),
                removed.c_str());
    std::printf("%-15s %-14s %9.2f %8.2f %8.2f %8.2f %6d/%-2d %14s %10s %8s  %s\n", p.name.c_str(), label.c_str(), fields_s,
                total / frames, worst, end_vox, one_component, frames, mid, smooth.c_str(), same ? "same" : "DIFFER",
                genera.c_str());
    std::fflush(stdout);
    }
  }
  return 0;
}
