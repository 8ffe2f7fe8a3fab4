// qs-dfi benchmark: for each pair of ../shared/meshes (the genus-0 animal pairs, and pairs of
// every genus up to 2) and each method (the skeleton-guided warp with per-part transport, the same
// with one global transport, the plain blend; "/parts" or "/linear" says which warp ran), the
// correspondence (distance fields, skeletons, matching, harmonic fields, transport, warp) and
// every frame at a 150^3 grid (targets: correspondence < 60 s, <= 2 s per frame on a 2-core
// machine). Per frame: t, components, genus, volume over the linear interpolation of the inputs'
// volumes (morph space), the step from the frame before (Hausdorff distance, in voxels) and the
// time. Per pair: frames in one component, the volume ratios' range, steps largest / median, the
// ends against the inputs (Hausdorff in voxels), the most inside samples the topology control left
// out of a frame (per mille: a part cut off or a handle closed), the most processor time of a
// frame between the ends (all threads: on 2 threads half of it is an idle 2-core machine's wall
// clock), whether 1 and 2 threads give the same bytes.
//
// Usage: qs-bench-dfi [--grid N] [--frames K] [--no-steps] [--retime] [--refine-ends R] [--free-volume]
//                     [--no-topology] [--no-voting] [--arap] [--bone-segments N] [--methods warp,global,blend] [pair ...]
// (pairs: cat-koala, horse-camel, cow-pig, sphere-torus, horse-knot, spot-eight, femur-elephant,
// eight-double-torus, knot-double-torus; default all)
#include <algorithm>
#include <chrono>
#include <ctime>
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
// Processor time of the process (all threads), seconds: on a loaded machine the wall clock grows,
// this does not; over 2 threads, half of it is the wall clock of an idle 2-core machine.
double cpu_now() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

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
  int grid = 150, frames = 11, refine_ends = 1, bone_segments = 8;
  bool steps = true, retime = false, free_volume = false, no_topology = false, no_voting = false, arap = false;
  std::string methods = "warp";
  std::vector<std::string> wanted;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--grid") && i + 1 < argc) grid = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--frames") && i + 1 < argc) frames = std::max(3, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--no-steps")) steps = false;
    else if (!std::strcmp(argv[i], "--retime")) retime = true;
    else if (!std::strcmp(argv[i], "--free-volume")) free_volume = true;
    else if (!std::strcmp(argv[i], "--no-topology")) no_topology = true;
    else if (!std::strcmp(argv[i], "--no-voting")) no_voting = true;
    else if (!std::strcmp(argv[i], "--arap")) arap = true;
    else if (!std::strcmp(argv[i], "--refine-ends") && i + 1 < argc) refine_ends = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--bone-segments") && i + 1 < argc) bone_segments = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--methods") && i + 1 < argc) methods = argv[++i];
    else wanted.push_back(argv[i]);
  }
  const std::vector<Pair> pairs = {{"cat-koala", "cat_16k.obj", "koala_7k.obj"},
                                   {"horse-camel", "horse_5k.obj", "camel_4k_fixed.obj"},
                                   {"cow-pig", "cow2_9k.off", "pig_4k.off"},
                                   {"sphere-torus", "sphere", "torus"},
                                   {"horse-knot", "horse_5k.obj", "knot1.off"},
                                   {"spot-eight", "spot_2k.obj", "eight.off"},
                                   {"femur-elephant", "femur.off", "elephant_12k.obj"},
                                   {"eight-double-torus", "eight.off", "double-torus-example.off"},
                                   {"knot-double-torus", "knot1.off", "double-torus-example.off"}};
  std::printf("dfi benchmark: methods %s, --align similarity, grid %d, %d frames%s%s, %u hardware threads\n",
              methods.c_str(), grid, frames, retime ? ", even timing" : ", uniform timing",
              no_voting ? ", nearest-first matching" : "", std::thread::hardware_concurrency());
  std::vector<std::string> summary;
  for (const Pair& p : pairs) {
    if (!wanted.empty() && std::find(wanted.begin(), wanted.end(), p.name) == wanted.end()) continue;
    TriMesh a, b;
    try {
      a = load(p.a);
      b = load(p.b);
    } catch (const std::exception& e) {
      std::printf("%-18s skipped: %s\n", p.name.c_str(), e.what());
      continue;
    }
    for (const std::string method : {"warp", "global", "blend"}) {
    if (methods.find(method) == std::string::npos) continue;
    dfi::MorphOptions opt;
    opt.grid = grid;
    opt.align = dfi::Align::Similarity;
    opt.warp = method != "blend";
    opt.part_transport = method == "warp";
    opt.bone_segments = bone_segments;
    opt.voting = !no_voting;
    opt.interpolation = arap ? dfi::Interpolation::Arap : dfi::Interpolation::Parts;
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
    // The inputs' volumes in morph space (the target's through the alignment).
    const double k0 = m.source_to_morph.scale, k1 = m.target_to_morph.scale;
    const double v0 = m.source_volume * k0 * k0 * k0, v1 = m.target_volume * k1 * k1 * k1;
    const double voxel = m.source_sdf.spacing;  // morph space
    const dfi::MeshStats in0 = dfi::mesh_stats(a), in1 = dfi::mesh_stats(b);
    const bool ends_one = in0.components == 1 && in1.components == 1;
    double total = 0, worst = 0, end_vox = 0, vmin = 1e300, vmax = 0, worst_dropped = 0, worst_cpu = 0;
    int one_component = 0;
    std::vector<double> step;
    TriMesh previous;
    const std::string label = method + (m.warp ? (!m.arap.empty() ? "/arap" : m.bones.empty() ? "/linear" : "/parts") : "");
    std::printf("%-18s %-14s correspondence %.2f s%s, %zu node and %zu branch matches (%d voted), input genus %d -> %d\n",
                p.name.c_str(), label.c_str(), fields_s, retime ? (", retime " + std::to_string(retime_s) + " s").c_str() : "",
                m.matching.nodes.size(), m.matching.branches.size(),
                static_cast<int>(std::count_if(m.matching.nodes.begin(), m.matching.nodes.end(),
                                               [](const dfi::NodePair& n) { return n.votes > 0; })),
                in0.genus, in1.genus);
    if (!m.arap.empty())
      std::printf("%-18s %-14s arap: %zu centres, thin-plate smoothing %g, smallest Jacobian determinant %.3f\n", p.name.c_str(),
                  label.c_str(), m.arap.source.size(), m.arap_lambda, m.arap_min_det);
    std::printf("%-18s %6s %5s %5s %9s %8s %8s %8s %9s %7s\n", "  frame", "t", "comp", "genus", "vol/lin", "step vox", "time s", "iso vox",
                "drop o/oo", "cpu s");
    for (int f = 0; f < frames; ++f) {
      const double t = times[f];
      t0 = Clock::now();
      const double c0 = cpu_now();
      const bool end = f == 0 || f == frames - 1;
      TriMesh morph_space, mesh;  // mesh: what qs-dfi writes, the frame at its placement
      dfi::BlendInfo info;
      if (end && refine_ends > 1) {
        mesh = dfi::endpoint_frame(m, f == 0 ? a : b, f != 0, refine_ends);
        morph_space = mesh;
        const dfi::Similarity to_morph = f == 0 ? m.source_to_morph : m.target_to_morph;
        for (Vec3& q : morph_space.positions) q = to_morph.apply(q);
      } else {
        morph_space = dfi::polygonize(dfi::blend_field(m, t, 0, &info));
        mesh = morph_space;  // as frame_mesh places it
        const dfi::Similarity back = m.source_to_morph.inverse();
        for (Vec3& q : mesh.positions) q = dfi::placement(m.target_to_source, t, back.apply(q));
      }
      const double s = since(t0), cpu = cpu_now() - c0;
      total += s;
      if (!end) worst_cpu = std::max(worst_cpu, cpu);
      worst = std::max(worst, s);
      const dfi::MeshStats st = dfi::mesh_stats(morph_space);
      one_component += st.components == 1;
      const double lin = (1 - t) * v0 + t * v1;
      const double ratio = st.volume / lin;
      vmin = std::min(vmin, ratio);
      vmax = std::max(vmax, ratio);
      double d = 0;
      if (steps && f > 0) {
        d = metro::metro(previous, morph_space).max / voxel;
        step.push_back(d);
      }
      if (end) {
        const double e = metro::metro(mesh, f == 0 ? a : b).max;
        end_vox = std::max(end_vox, e / (m.spacing() / (f == 0 ? 1.0 : m.target_to_source.scale)));
      }
      // Inside samples the topology control left out (a part cut off, a handle closed), per mille.
      const double dropped = info.ball.inside ? 1000.0 * info.ball.removed / info.ball.inside : 0.0;
      worst_dropped = std::max(worst_dropped, dropped);
      std::printf("%-18s %6.3f %5d %5d %9.3f %8.2f %8.2f %8.2f %9.1f %7.2f\n", ("  " + std::to_string(f)).c_str(), t, st.components,
                  st.genus, ratio, d, s, info.iso_shift / voxel, dropped, cpu);
      std::fflush(stdout);
      if (steps) previous = std::move(morph_space);
    }
    std::string smooth = "-";
    if (steps && !step.empty()) {
      std::vector<double> sorted = step;
      std::sort(sorted.begin(), sorted.end());
      const double median = sorted.size() % 2 ? sorted[sorted.size() / 2]
                                              : 0.5 * (sorted[sorted.size() / 2 - 1] + sorted[sorted.size() / 2]);
      char buf[48];
      std::snprintf(buf, sizeof buf, "%.2f/%.2f=%.2f", sorted.back(), median, sorted.back() / median);
      smooth = buf;
    }
    // Determinism: the source field and the middle frame's field on 1 and 2 threads.
    dfi::SdfOptions one = opt.sdf, two = opt.sdf;
    one.threads = 1;
    two.threads = 2;
    const bool same = dfi::signed_distance(a, m.source_sdf, one).values == dfi::signed_distance(a, m.source_sdf, two).values &&
                      dfi::blend_field(m, 0.5, 1).values == dfi::blend_field(m, 0.5, 2).values;
    char line[512];
    std::snprintf(line, sizeof line, "%-18s %-14s %7.2f %7.2f %7.2f %6d/%-2d%s %6.3f %6.3f %22s %8.2f %7.1f %7.2f %7s", p.name.c_str(),
                  label.c_str(), fields_s, total / frames, worst, one_component, frames, ends_one ? " " : "*", vmin, vmax,
                  smooth.c_str(), end_vox, worst_dropped, worst_cpu, same ? "same" : "DIFFER");
    summary.push_back(line);
    std::printf("%s\n", line);
    std::fflush(stdout);
    }
  }
  std::printf("\nsummary (grid %d, %d frames; * : an input has several components)\n", grid, frames);
  std::printf("%-18s %-14s %7s %7s %7s %9s %6s %6s %22s %8s %7s %7s %7s\n", "pair", "method", "corr s", "frame s", "max fr",
              "1 comp", "vol lo", "vol hi", "steps max/median vox", "ends vox", "drop", "cpu fr", "threads");
  for (const std::string& l : summary) std::printf("%s\n", l.c_str());
  return 0;
}
