// Benchmark: uniform and adaptive remeshing (paper tables 1 and 2): per mesh and level, the
// faces, the remesh time after the dissection is loaded, and the Metro error against the
// original (two-sided mean and max, % of the original's bounding-box diagonal). Per mesh a
// "report" line times qs-remesh's error report at level 5 (qs-remesh --error: 20000 samples per
// direction, the original's vertices for the maximum) against the level-5 remesh itself, and the
// even remesh (qs-remesh --level 5).
//   usage: qs-bench-remesh [MESH_DIR] [TAU] [MAX_AREA] [STRETCH_ROUNDS]
//   (defaults ../shared/meshes, 3, 0.15, 0: qs-dissect --max-area 0.15, the remeshing recipe)

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

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

int main(int argc, char** argv) {
  const fs::path dir = argc > 1 ? argv[1] : QS_SOURCE_DIR "/../shared/meshes";
  const double tau = argc > 2 ? std::stod(argv[2]) : 3.0;
  const double max_area = argc > 3 ? std::stod(argv[3]) : 0.15;
  const int stretch_rounds = argc > 4 ? std::stoi(argv[4]) : 0;
  if (!fs::is_directory(dir)) {
    std::fprintf(stderr, "qs-bench-remesh: %s is not a folder of meshes\n", dir.string().c_str());
    return 2;
  }
  std::printf("dissection tau %.2f, max patch area %.3g, stretch rounds %d; error = Metro two-sided, %% of the original's bbox diagonal\n\n", tau, max_area,
              stretch_rounds);
  std::printf("%-24s %7s %-10s %9s %9s %10s %9s\n", "mesh", "patches", "remesh", "faces", "time_s", "mean_%", "max_%");
  for (const char* name : {"max_planck_11k.obj", "igea_17k.off", "mannequin_head_23k.off", "venus_100k.off",
                           "horse_40k.off", "armadillo_29k.obj"}) {
    const auto r = qs::io::read_mesh(dir / name);
    const auto v = qs::mesh::validate(r.mesh);
    qs::dissect::DissectOptions o;
    o.tau = tau;
    o.max_patch_area = max_area;
    o.stretch_iterations = stretch_rounds;
    const auto d = qs::dissect::dissect(v.mesh, std::nullopt, o);
    auto report = [&](const std::string& what, const qs::TriMesh& m, double sec) {
      const auto e = qs::metro::metro(d.chart.mesh, m);
      std::printf("%-24s %7zu %-10s %9zu %9.4f %10.4f %9.3f\n", name, d.chart.patches.size(), what.c_str(),
                  m.faces.size(), sec, 100 * e.mean / e.diagonal, 100 * e.max / e.diagonal);
    };
    {
      // qs-remesh --level 5 [--error]: the remesh, the error report, the quality figures.
      auto t0 = Clock::now();
      const auto s = qs::remesh::remesh_uniform(d.chart, 5);
      const double remesh_s = std::chrono::duration<double>(Clock::now() - t0).count();
      const auto mesh = s.mesh();
      t0 = Clock::now();
      qs::metro::MetroOptions mo;
      mo.face_samples = 20000;
      mo.sample_vertices_b = false;
      const auto e = qs::metro::metro(d.chart.mesh, mesh, mo);
      const double metro_s = std::chrono::duration<double>(Clock::now() - t0).count();
      t0 = Clock::now();
      const auto vd = qs::remesh::vertex_density(mesh);
      qs::remesh::smallest_angle_stats(mesh);
      const double quality_s = std::chrono::duration<double>(Clock::now() - t0).count();
      t0 = Clock::now();
      const auto ev = qs::remesh::remesh_even({&d.chart}, 5);
      const double even_s = std::chrono::duration<double>(Clock::now() - t0).count();
      const auto evd = qs::remesh::vertex_density(ev.remesh.mesh(0));
      t0 = Clock::now();
      const auto an = qs::remesh::remesh_even_anisotropic({&d.chart}, 5);  // qs-remesh --level 5
      const double aniso_s = std::chrono::duration<double>(Clock::now() - t0).count();
      const auto avd = qs::remesh::vertex_density(an.remesh.mesh(0));
      std::printf("%-24s report level 5: remesh %.4f s, error report %.4f s (%.1fx the remesh, mean %.4f%%), quality "
                  "%.4f s; vertex spread %.2f; even (square cells): %zu faces, %.4f s, vertex spread %.2f; even "
                  "(anisotropic cells, the default): %zu faces, %.4f s, vertex spread %.2f\n",
                  name, remesh_s, metro_s, metro_s / remesh_s, 100 * e.mean / e.diagonal, quality_s, vd.spread,
                  ev.remesh.connectivity.faces.size(), even_s, evd.spread, an.remesh.connectivity.faces.size(), aniso_s,
                  avd.spread);
    }
    size_t l6_faces = 0;
    for (int level = 3; level <= 6; ++level) {
      const auto t0 = Clock::now();
      const auto s = qs::remesh::remesh_uniform(d.chart, level);
      const double sec = std::chrono::duration<double>(Clock::now() - t0).count();
      if (level == 6) l6_faces = s.connectivity.faces.size();
      report("level " + std::to_string(level), s.mesh(), sec);
    }
    for (double eps : {0.01, 0.0025}) {
      qs::remesh::AdaptiveOptions ao;
      ao.epsilon = eps;
      const auto t0 = Clock::now();
      const auto a = qs::remesh::remesh_adaptive(std::vector<qs::dissect::Chart>{d.chart}, ao);
      const double sec = std::chrono::duration<double>(Clock::now() - t0).count();
      char what[32];
      std::snprintf(what, sizeof what, "eps %.4g", eps);
      report(what, a.remesh.mesh(0), sec);
      if (eps == 0.0025)
        std::printf("%-24s %7s adaptive 0.0025 / uniform level 6 faces: %.3f\n", "", "",
                    static_cast<double>(a.remesh.connectivity.faces.size()) / static_cast<double>(l6_faces));
    }
  }
  return 0;
}
