// Benchmark: dissection time of each mesh at the default options, beside the time of one sparse
// direct solve of the mean-value system of the whole mesh (the floor: every tree level solves
// about the whole mesh once), and their ratio.
//   usage: qs-bench-dissect [MESH_DIR]   (default ../shared/meshes)

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/dissect/dissection.h"
#include "qs/dissect/seed_loop.h"
#include "qs/io/read_mesh.h"
#include "qs/mesh/validate.h"
#include "qs/param/square_param.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// The floor: the whole mesh as one patch. A closed mesh has no boundary, so the star of vertex 0
// is removed, leaving a disk with nearly every vertex interior, parameterized onto the square.
qs::param::PatchMesh whole_mesh_patch(const qs::TriMesh& mesh) {
  // Remove the star of vertex 0; its link is the boundary (CCW as seen from outside = patch left).
  qs::param::PatchMesh pm;
  std::vector<int> keep(mesh.num_vertices(), -1);
  std::vector<std::pair<int, int>> link;  // directed link edges of removed faces
  for (const qs::Tri& t : mesh.faces) {
    const int k = static_cast<int>(std::find(t.begin(), t.end(), 0) - t.begin());
    if (k < 3) link.emplace_back(t[(k + 2) % 3], t[(k + 1) % 3]);  // reversed: the patch is on its left
  }
  for (int v = 1; v < mesh.num_vertices(); ++v) {
    keep[v] = static_cast<int>(pm.positions.size());
    pm.positions.push_back(mesh.positions[v]);
  }
  for (const qs::Tri& t : mesh.faces)
    if (t[0] != 0 && t[1] != 0 && t[2] != 0) pm.faces.push_back({keep[t[0]], keep[t[1]], keep[t[2]]});
  std::vector<int> next(mesh.num_vertices(), -1);
  for (auto [a, b] : link) next[a] = b;
  for (int v = link.front().first;;) {
    pm.boundary.push_back(keep[v]);
    v = next[v];
    if (v == link.front().first) break;
  }
  const int n = static_cast<int>(pm.boundary.size());
  pm.corner_index = {0, n / 4, n / 2, (3 * n) / 4};
  return pm;
}

}  // namespace

int main(int argc, char** argv) {
  const fs::path dir = argc > 1 ? argv[1] : QS_SOURCE_DIR "/../shared/meshes";
  if (!fs::is_directory(dir)) {
    std::fprintf(stderr, "qs-bench-dissect: %s is not a directory\n", dir.c_str());
    return 3;
  }
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string ext = e.path().extension().string();
    if (ext == ".obj" || ext == ".off" || ext == ".ply") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  const qs::dissect::DissectOptions opt;
  std::printf("default options: tau %.2f, max depth %d, min faces %d\n\n", opt.tau, opt.max_depth,
              opt.min_faces_to_split);
  std::printf("%-24s %7s %7s %6s %8s %5s %9s %9s %6s\n", "mesh", "F", "chartF", "patch", "max_str", "over",
              "dissect_s", "floor_s", "ratio");
  double venus = -1, horse = -1, worst_ratio = 0;
  for (const auto& f : files) {
    try {
      const auto mesh = qs::mesh::validate(qs::io::read_mesh(f).mesh).mesh;
      const auto pm = whole_mesh_patch(mesh);
      double floor_s = 1e30, dissect_s = 1e30;
      qs::dissect::Dissection d;
      const int runs = mesh.num_faces() > 50000 ? 2 : 3;
      for (int r = 0; r < runs; ++r) {
        auto t = Clock::now();
        const auto sp = qs::param::parameterize_square(pm);
        floor_s = std::min(floor_s, seconds_since(t));
        t = Clock::now();
        d = qs::dissect::dissect(mesh, std::nullopt, opt);
        dissect_s = std::min(dissect_s, seconds_since(t));
      }
      int over = 0;
      for (const auto& p : d.chart.patches) over += p.stop != qs::dissect::StopReason::None;
      const double ratio = dissect_s / floor_s;
      worst_ratio = std::max(worst_ratio, ratio);
      std::printf("%-24s %7d %7d %6zu %8.2f %5d %9.3f %9.3f %6.2f\n", f.filename().c_str(), mesh.num_faces(),
                  d.chart.mesh.num_faces(), d.chart.patches.size(), d.max_stretch, over, dissect_s, floor_s, ratio);
      if (f.filename() == "venus_100k.off") venus = dissect_s;
      if (f.filename() == "horse_40k.off") horse = dissect_s;
    } catch (const qs::Error& e) {
      std::printf("%-24s error: %s\n", f.filename().c_str(), e.what());
    }
  }
  std::printf("\n");
  if (venus >= 0) std::printf("target: venus_100k dissection < 2 s: %.3f s (%.2f of the budget)\n", venus, venus / 2);
  if (horse >= 0) std::printf("target: horse_40k dissection < 1 s: %.3f s (%.2f of the budget)\n", horse, horse);
  std::printf("target: dissection / floor <= 10: worst %.2f\n", worst_ratio);
  return 0;
}
