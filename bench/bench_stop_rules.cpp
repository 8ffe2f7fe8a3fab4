// The dissection's stop rules against even sampling: for each mesh and each variant
// of the stop and split rules, the leaves (patches, how many are left over tau and the share of the
// surface they hold, the largest stretch), the dissection time, and the default remesh of qs-remesh
// (`--level 5`: the even remesh with anisotropic cells, remesh_even_anisotropic): its vertex-density
// spread (p95 / p5 of vertices per unit area, as qs-remesh reports it), its smallest-angle shares
// and the ratio of its surface area to the original's. A ratio well above 1 means remesh triangles
// that are needles across the surface rather than on it (cells far longer than wide where a leaf's
// map is strongly anisotropic): their areas, not the sample counts, then set the density spread.
//   usage: qs-bench-stop-rules [VARIANTS] MESH...
//   VARIANTS: a comma-separated list of variant names (default: all), or "all"; the known names are
//   printed with each run.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "bench_args.h"
#include "qs/core/error.h"
#include "qs/dissect/dissection.h"
#include "qs/io/read_mesh.h"
#include "qs/mesh/validate.h"
#include "qs/remesh/anisotropic.h"
#include "qs/remesh/quality.h"

namespace {

using Clock = std::chrono::steady_clock;

struct Variant {
  std::string name;
  std::string what;
  qs::dissect::DissectOptions options;
};

std::vector<Variant> variants() {
  std::vector<Variant> v;
  auto add = [&](const std::string& name, const std::string& what, auto&& set) {
    qs::dissect::DissectOptions o;
    set(o);
    v.push_back({name, what, o});
  };
  add("default", "DissectOptions{} as compiled", [](auto&) {});
  add("before12", "min_split_area 0, force_split_area 0 (the no-progress rule alone)", [](auto& o) {
    o.min_split_area = 0;
    o.force_split_area = 0;
  });
  add("xdepth0", "area_extra_depth 0 (max_depth for every patch)",
      [](auto& o) { o.area_extra_depth = 0; });
  add("msa0", "min_split_area 0", [](auto& o) { o.min_split_area = 0; });
  add("msa0.003", "min_split_area 0.003", [](auto& o) { o.min_split_area = 0.003; });
  add("fsa0.005", "force_split_area 0.005", [](auto& o) { o.force_split_area = 0.005; });
  add("depth8", "--max-depth 8", [](auto& o) { o.max_depth = 8; });
  add("tau2", "--tau 2", [](auto& o) { o.tau = 2; });
  add("margin0.4", "peak_margin 0.4 (default 0.35)", [](auto& o) { o.peak_margin = 0.4; });
  add("wmax0.55", "w_max 0.55 (default 0.65)", [](auto& o) { o.w_max = 0.55; });
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: qs-bench-stop-rules VARIANTS|all MESH...\nvariants:\n");
    for (const auto& v : variants()) std::fprintf(stderr, "  %-12s %s\n", v.name.c_str(), v.what.c_str());
    return 1;
  }
  std::vector<Variant> chosen;
  const std::vector<std::string> wanted = qs::bench::split_list(argv[1]);
  for (const auto& v : variants())
    if (wanted == std::vector<std::string>{"all"} || std::find(wanted.begin(), wanted.end(), v.name) != wanted.end())
      chosen.push_back(v);
  if (chosen.empty()) {
    std::fprintf(stderr, "qs-bench-stop-rules: no known variant in '%s'; run it without arguments for the list\n",
                 argv[1]);
    return 1;
  }
  std::printf("variants:\n");
  for (const auto& v : chosen) std::printf("  %-12s %s\n", v.name.c_str(), v.what.c_str());
  std::printf("\nover = leaves over tau (share of the surface); time = dissection s; remesh = qs-remesh --level 5 "
              "(anisotropic even remesh): vsp = vertex-density spread p95/p5, area = remesh area / surface area, "
              "<10 = %% of faces under 10 deg, med = median smallest angle (deg)\n\n");
  std::printf("%-20s %-12s %6s %12s %10s %7s %8s %7s %6s %6s\n", "mesh", "variant", "patch", "over", "max_str",
              "time_s", "vsp", "area", "<10", "med");
  int failures = 0;
  for (int a = 2; a < argc; ++a) {
    const std::filesystem::path file = argv[a];
    qs::TriMesh mesh;
    try {
      const auto v = qs::mesh::validate(qs::io::read_mesh(file).mesh);
      if (!v.report.accepted) {
        std::printf("%-20s not closed genus 0: skipped\n", file.filename().c_str());
        continue;
      }
      mesh = v.mesh;
    } catch (const qs::Error& e) {
      std::printf("%-20s %s\n", file.filename().c_str(), e.what());
      ++failures;
      continue;
    }
    for (const auto& v : chosen) {
      try {
        const auto t0 = Clock::now();
        const auto d = qs::dissect::dissect(mesh, std::nullopt, v.options);
        const double time = std::chrono::duration<double>(Clock::now() - t0).count();
        std::vector<double> area(d.chart.patches.size(), 0.0);
        double surface = 0;
        for (int f = 0; f < d.chart.mesh.num_faces(); ++f) {
          const double fa = qs::face_area(d.chart.mesh, f);
          area[static_cast<size_t>(d.chart.face_patch[static_cast<size_t>(f)])] += fa;
          surface += fa;
        }
        int over = 0;
        double over_area = 0;
        for (size_t p = 0; p < d.chart.patches.size(); ++p)
          if (d.chart.patches[p].stretch > v.options.tau) ++over, over_area += area[p];
        const std::vector<const qs::dissect::Chart*> charts = {&d.chart};
        const qs::TriMesh r = qs::remesh::remesh_even_anisotropic(charts, 5).remesh.mesh(0);
        double remesh_area = 0;
        for (int f = 0; f < r.num_faces(); ++f) remesh_area += qs::face_area(r, f);
        const auto vd = qs::remesh::vertex_density(r);
        const auto an = qs::remesh::smallest_angle_stats(r);
        char over_s[32];
        std::snprintf(over_s, sizeof over_s, "%d (%.0f%%)", over, 100 * over_area / surface);
        std::printf("%-20s %-12s %6zu %12s %10.4g %7.3f %8.2f %7.3f %6.2f %6.1f\n", file.filename().c_str(),
                    v.name.c_str(), d.chart.patches.size(), over_s, d.max_stretch, time, vd.spread,
                    remesh_area / surface, 100 * an.under_10, an.median);
        std::fflush(stdout);
      } catch (const qs::Error& e) {
        std::printf("%-20s %-12s error: %s\n", file.filename().c_str(), v.name.c_str(), e.what());
        ++failures;
      }
    }
  }
  return failures == 0 ? 0 : 4;
}
