// Benchmark that chose the default dissection options: for every closed genus-0 mesh of
// a folder and every candidate option set, the patches, the dissection time, the level-5 uniform
// remesh's mean error (Metro two-sided, % of the original's bounding-box diagonal, 20000 samples
// per direction as qs-remesh measures it), the level-4 remesh's smallest-angle shares and median,
// the level-5 remesh's vertex-density spread (p95 / p5 over the surface) and the texel-density
// spread of a normal-map atlas (chart density, p95 / p5). Each candidate's second row ("/even")
// measures the same dissection with the even remesh (qs-remesh --level: about the uniform level's
// face count spread by area) and 256-texel tiles sized by area (qs-bake --tiles area), with the
// even level-5 face count relative to the uniform one in the time column.
//   usage: qs-bench-defaults [MESH_DIR] [CANDIDATES] [MESH_FILTER]
//   MESH_DIR default ../shared/meshes; CANDIDATES a comma-separated list of candidate names (default
//   all; "default" is DissectOptions{} as compiled; relax* and cotan* also set the uniform remesh's
//   grid relaxation, UniformOptions::relax, which the "/even" rows do not use); MESH_FILTER a
//   substring of the file names.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "bench_args.h"
#include "qs/bake/atlas.h"
#include "qs/core/error.h"
#include "qs/dissect/dissection.h"
#include "qs/io/read_mesh.h"
#include "qs/mesh/validate.h"
#include "qs/metro/metro.h"
#include "qs/remesh/adaptive.h"
#include "qs/remesh/anisotropic.h"
#include "qs/remesh/quality.h"
#include "qs/remesh/uniform.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

struct Candidate {
  std::string name;
  qs::dissect::DissectOptions options;
  double relax = qs::remesh::UniformOptions{}.relax;  ///< the uniform remesh's grid relaxation
};

qs::dissect::DissectOptions protrusion(double s) {
  qs::dissect::DissectOptions o;
  o.protrusion_stretch = s;
  return o;
}

qs::dissect::DissectOptions cotan() {
  qs::dissect::DissectOptions o;
  o.intrinsic_cotan = true;
  return o;
}

qs::dissect::DissectOptions make(double tau, double max_area, int stretch_iterations) {
  qs::dissect::DissectOptions o;
  o.tau = tau;
  o.max_patch_area = max_area;
  o.stretch_iterations = stretch_iterations;
  return o;
}

std::vector<Candidate> candidates() {
  return {
      {"default", qs::dissect::DissectOptions{}},
      {"old", make(3, 0, 0)},             // no area cap, no leaf stretch minimization
      {"recipe", make(3, 0.15, 0)},       // the area cap alone
      {"a15s10", make(3, 0.15, 10)},
      {"a10s10", make(3, 0.10, 10)},
      {"t2a15s10", make(2, 0.15, 10)},
      {"t2.5a10s10", make(2.5, 0.10, 10)},
      // Remesh grid relaxation (UniformOptions::relax) on the default dissection, and cotan maps.
      {"relax0", qs::dissect::DissectOptions{}, 0.0},
      {"relax50", qs::dissect::DissectOptions{}, 0.5},
      {"relax90", qs::dissect::DissectOptions{}, 0.9},
      {"cotan", cotan(), 0.0},
      {"cotan_relax90", cotan(), 0.9},
      // Squeezed protrusions split with the w rule (DissectOptions::protrusion_stretch 0: the
      // defaults before it).
      {"protrusion0", protrusion(0)},
  };
}

}  // namespace

int main(int argc, char** argv) {
  const fs::path dir = argc > 1 ? argv[1] : QS_SOURCE_DIR "/../shared/meshes";
  const std::vector<std::string> wanted = argc > 2 ? qs::bench::split_list(argv[2]) : std::vector<std::string>{};
  const std::string filter = argc > 3 ? argv[3] : "";
  if (!fs::is_directory(dir)) {
    std::fprintf(stderr, "qs-bench-defaults: %s is not a folder of meshes\n", dir.string().c_str());
    return 3;
  }
  std::vector<Candidate> cands;
  for (const auto& c : candidates())
    if (wanted.empty() || std::find(wanted.begin(), wanted.end(), c.name) != wanted.end()) cands.push_back(c);
  if (cands.empty()) {
    std::fprintf(stderr, "qs-bench-defaults: no candidate named in %s; known:", argv[2]);
    for (const auto& c : candidates()) std::fprintf(stderr, " %s", c.name.c_str());
    std::fprintf(stderr, "\n");
    return 1;
  }
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string ext = e.path().extension().string();
    if ((ext == ".obj" || ext == ".off" || ext == ".ply") &&
        e.path().filename().string().find(filter) != std::string::npos)
      files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  std::printf("candidates (tau, max patch area, leaf stretch rounds, cotan, remesh grid relax):\n");
  for (const auto& c : cands)
    std::printf("  %-12s tau %.2f, max-area %.3g, stretch_iterations %d, cotan %d, relax %.2f\n", c.name.c_str(),
                c.options.tau, c.options.max_patch_area, c.options.stretch_iterations, int(c.options.intrinsic_cotan),
                c.relax);
  std::printf("\nerr5 = level-5 mean error (%% of diagonal); <5/<10/<20 = %% of level-4 faces with a smallest angle "
              "under 5/10/20 deg, med = median (deg); vsp = level-5 vertex-density spread p95/p5; tsp = texel-density "
              "spread p95/p5; time = dissection s\n\n");
  std::printf("%-22s %-12s %6s %8s %6s %6s %6s %6s %7s %7s %7s\n", "mesh", "candidate", "patch", "err5_%", "<5",
              "<10", "<20", "med", "vsp", "tsp", "time_s");
  struct Sum {
    int meshes = 0;
    double err = 0, u10 = 0, med = 0, time = 0;
    double worst_vsp = 0, worst_tsp = 0, worst_u10 = 0, worst_med = 90;
    double heads_tsp_lo = 1e300, heads_tsp_hi = 0;  // igea, mannequin, max_planck, venus
  };
  std::map<std::string, Sum> sums;
  for (const auto& f : files) {
    qs::TriMesh mesh;
    try {
      const auto v = qs::mesh::validate(qs::io::read_mesh(f).mesh);
      if (!v.report.accepted) continue;  // not closed genus 0: qs does not take it
      mesh = v.mesh;
    } catch (const qs::Error&) {
      continue;
    }
    for (const auto& c : cands) {
      try {
        const auto t0 = Clock::now();
        const auto d = qs::dissect::dissect(mesh, std::nullopt, c.options);
        const double time = seconds_since(t0);
        const std::string stem = f.stem().string();
        const bool head = stem.rfind("igea", 0) == 0 || stem.rfind("mannequin", 0) == 0 ||
                          stem.rfind("max_planck", 0) == 0 || stem.rfind("venus_100k", 0) == 0;
        qs::metro::MetroOptions mo;
        mo.face_samples = 20000;
        mo.sample_vertices_b = false;
        // One row: the level-4 remesh's angles, the level-5 remesh's error and vertex spread, the
        // texel spread `tsp` and the last column; added to the candidate's summary `label`.
        auto row = [&](const std::string& label, const qs::TriMesh& l4, const qs::TriMesh& l5, double tsp,
                       double last) {
          const auto a = qs::remesh::smallest_angle_stats(l4);
          const auto e = qs::metro::metro(d.chart.mesh, l5, mo);
          const double err = 100 * e.mean / e.diagonal;
          const auto vd = qs::remesh::vertex_density(l5);
          std::printf("%-22s %-12s %6zu %8.4f %6.2f %6.2f %6.2f %6.1f %7.2f %7.2f %7.3f\n", f.filename().c_str(),
                      label.c_str(), d.chart.patches.size(), err, 100 * a.under_5, 100 * a.under_10,
                      100 * a.under_20, a.median, vd.spread, tsp, last);
          std::fflush(stdout);
          Sum& s = sums[label];
          ++s.meshes;
          s.err += err, s.u10 += 100 * a.under_10, s.med += a.median, s.time += last;
          s.worst_vsp = std::max(s.worst_vsp, vd.spread);
          s.worst_tsp = std::max(s.worst_tsp, tsp);
          s.worst_u10 = std::max(s.worst_u10, 100 * a.under_10);
          s.worst_med = std::min(s.worst_med, a.median);
          if (head) s.heads_tsp_lo = std::min(s.heads_tsp_lo, tsp), s.heads_tsp_hi = std::max(s.heads_tsp_hi, tsp);
          return static_cast<double>(l5.faces.size());
        };

        qs::remesh::UniformOptions uo;  // as qs-remesh cuts the cells
        uo.diagonals = qs::remesh::DiagonalRule::BestAngle;
        uo.relax = c.relax;
        const double uniform_faces = row(c.name, qs::remesh::remesh_uniform(d.chart, 4, uo).mesh(),
                                         qs::remesh::remesh_uniform(d.chart, 5, uo).mesh(),
                                         qs::remesh::chart_density(d.chart, 255).spread, time);

        // The same dissection, sampled by area: the even remesh and area-sized tiles; then with
        // anisotropic cells (qs-remesh --level: split in u or v alone on long cells). Their last
        // column is the level-5 face count over the uniform grid's.
        const std::vector<const qs::dissect::Chart*> charts = {&d.chart};
        const std::vector<int> sides = qs::bake::tile_sizes_by_area(qs::remesh::patch_texel_shares(charts), 256);
        std::vector<double> per_patch(sides.size());
        for (size_t p = 0; p < sides.size(); ++p) per_patch[p] = sides[p] - 1.0;
        const double area_tsp = qs::remesh::chart_density(d.chart, per_patch).spread;
        const auto e5 = qs::remesh::remesh_even(charts, 5).remesh;
        row(c.name + "/even", qs::remesh::remesh_even(charts, 4).remesh.mesh(0), e5.mesh(0), area_tsp,
            static_cast<double>(e5.connectivity.faces.size()) / uniform_faces);
        const auto a5 = qs::remesh::remesh_even_anisotropic(charts, 5).remesh;
        row(c.name + "/aniso", qs::remesh::remesh_even_anisotropic(charts, 4).remesh.mesh(0), a5.mesh(0), area_tsp,
            static_cast<double>(a5.connectivity.faces.size()) / uniform_faces);
      } catch (const qs::Error& e) {
        std::printf("%-22s %-12s error: %s\n", f.filename().c_str(), c.name.c_str(), e.what());
      }
    }
  }
  std::printf("\nsummary over the meshes: mean of err5, mean and worst <10, mean and worst median angle, worst vsp, "
              "worst tsp, the heads' tsp range, total dissection time (/even: mean face ratio even / uniform)\n");
  std::printf("%-17s %6s %8s %7s %7s %6s %6s %8s %8s %13s %8s\n", "candidate", "meshes", "err5_%", "<10", "<10max", "med",
              "medmin", "vsp_max", "tsp_max", "heads_tsp", "time_s");
  for (const auto& c : cands)
    for (const std::string& name : {c.name, c.name + "/even", c.name + "/aniso"}) {
      const Sum& s = sums[name];
      if (s.meshes == 0) continue;
      char heads[32] = "-";
      if (s.heads_tsp_hi > 0) std::snprintf(heads, sizeof heads, "%.2f-%.2f", s.heads_tsp_lo, s.heads_tsp_hi);
      std::printf("%-17s %6d %8.4f %7.2f %7.2f %6.1f %6.1f %8.2f %8.2f %13s %8.3f\n", name.c_str(), s.meshes,
                  s.err / s.meshes, s.u10 / s.meshes, s.worst_u10, s.med / s.meshes, s.worst_med, s.worst_vsp,
                  s.worst_tsp, heads, name == c.name ? s.time : s.time / s.meshes);
    }
  return 0;
}
