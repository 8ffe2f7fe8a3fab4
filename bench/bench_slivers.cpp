// Where the slivers of the default remesh are: for every mesh of a folder (at the default
// dissection), the level-n anisotropic even remesh's faces with a smallest angle under a bound,
// sorted by what their cell is and what the chart's map does inside it:
//   cell      2 (cut in two), 3 (one hanging vertex), fan (a fan around the centre);
//   border    how many of the face's corners lie on the patch border, and whether one is a patch
//             corner (with the base vertex's valence);
//   bilinear  the face's smallest angle when its corners are placed by the bilinear map of the
//             cell's four 3D corners instead of the chart: a face that is bad here too is bad by
//             the cell's shape and cut; one that is good here is bad because the map varies inside
//             the cell (more than four corners tell);
//   aspect    the cell's worst measured aspect (leaf_aspect) and its four 3D sides' ratio and
//             smallest corner angle (shear).
// and, for the four patches with the most such faces, their share of the mesh's area and their
// squareness on the surface (area / (perimeter / 4)^2: 1 for a square, near 0 for a leaf whose
// sides run close together, where every face is a sliver whatever the remesh does).
//   usage: qs-bench-slivers [MESH_DIR | DISSECTION_DIR] [MESH_FILTER] [LEVEL] [BOUND_DEG] [PATCH...]
//   (a folder with dissection.json: its set remeshed together, each mesh's faces; PATCH: print the
//   map's angle between u and v on an 8 x 8 grid of that patch)

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/dissect/dissection.h"
#include "qs/dissect/dissection_json.h"
#include "qs/io/read_mesh.h"
#include "qs/mesh/validate.h"
#include "qs/remesh/anisotropic.h"
#include "qs/remesh/chart_sampler.h"
#include "qs/remesh/quality.h"

namespace fs = std::filesystem;
using qs::Vec2;
using qs::Vec3;

namespace {

double min_angle_deg(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 p[3] = {a, b, c};
  double m = 180;
  for (int k = 0; k < 3; ++k) {
    const Vec3 e1 = p[(k + 1) % 3] - p[k], e2 = p[(k + 2) % 3] - p[k];
    const double n1 = e1.norm(), n2 = e2.norm();
    if (!(n1 > 0 && n2 > 0)) return 0;
    m = std::min(m, std::acos(std::clamp(e1.dot(e2) / (n1 * n2), -1.0, 1.0)) * 180 / M_PI);
  }
  return m;
}

struct Tally {
  long faces = 0;
  std::map<std::string, long> by;
  void add(const std::string& k) { ++by[k]; }
};

// The faces of mesh m of remesh r under `bound` degrees, sorted (see the top); the named patches'
// maps.
void analyze(const std::string& name, const std::vector<const qs::dissect::Chart*>& charts,
             const qs::remesh::AnisotropicRemesh& r, size_t m, double bound, const std::vector<int>& patches) {
  const qs::remesh::ChartSampler s(*charts[m]);
  for (int p : patches) {
    const auto& t = s.topology();
    std::printf("patch %d, corner valences %d %d %d %d; per cell of an 8 x 8 grid (v rows top down): the angle "
                "between the u and v directions in 3D / |du| / |dv|\n", p, t.valence[t.quads[p][0]],
                t.valence[t.quads[p][1]], t.valence[t.quads[p][2]], t.valence[t.quads[p][3]]);
    const int N = 8;
    const double h = 1e-3;
    for (int j = N - 1; j >= 0; --j) {
      for (int i = 0; i < N; ++i) {
        const Vec2 uv((i + 0.5) / N, (j + 0.5) / N);
        const Vec3 du = (s.point(p, uv + Vec2(h, 0)) - s.point(p, uv - Vec2(h, 0))) / (2 * h);
        const Vec3 dv = (s.point(p, uv + Vec2(0, h)) - s.point(p, uv - Vec2(0, h))) / (2 * h);
        std::printf(" %3.0f/%4.1f", std::acos(std::clamp(du.dot(dv) / (du.norm() * dv.norm()), -1.0, 1.0)) * 180 / M_PI,
                    du.norm() / dv.norm());
      }
      std::printf("\n");
    }
  }
  const auto& c = r.remesh.connectivity;
  const auto& x = r.remesh.positions[m];
  const auto& t = s.topology();
  std::vector<int> leaf_faces(r.leaves.size(), 0);
  for (int l : r.face_leaf) ++leaf_faces[l];
  Tally all;
  std::map<int, long> per_patch;
  long bad = 0;
  for (int fi = 0; fi < c.num_faces(); ++fi) {
    const auto& tri = c.faces[fi];
    const double a = min_angle_deg(x[tri[0]], x[tri[1]], x[tri[2]]);
    if (a >= bound) continue;
    ++bad;
    const int li = r.face_leaf[fi];
    const auto& n = r.leaves[li];
    const int p = n.patch;
    ++per_patch[p];
    const double su = 1.0 / (1 << n.lu), sv = 1.0 / (1 << n.lv), u0 = n.i * su, v0 = n.j * sv;
    // The leaf's 9 points (corners, side midpoints, centre) and their 3D points.
    Vec2 pts[9];
    Vec3 px[9];
    for (int b = 0; b < 3; ++b)
      for (int k = 0; k < 3; ++k) {
        pts[3 * b + k] = Vec2(u0 + 0.5 * k * su, v0 + 0.5 * b * sv);
        px[3 * b + k] = s.point(p, pts[3 * b + k]);
      }
    const Vec3 C[4] = {px[0], px[2], px[8], px[6]};
    int on_border = 0, corner_valence = 0;
    Vec2 fuv[3];
    for (int k = 0; k < 3; ++k) {
      const int w = tri[k];
      if (w < c.num_base_vertices) {
        corner_valence = std::max(corner_valence, t.valence[w]);
        ++on_border;
      } else {
        const Vec2 uv = c.vertex_uv[w];
        if (uv.x() <= 0 || uv.x() >= 1 || uv.y() <= 0 || uv.y() >= 1) ++on_border;
      }
      if (c.vertex_patch[w] == p && w >= c.num_base_vertices) {
        fuv[k] = c.vertex_uv[w];
      } else {
        int best = 0;
        for (int q = 1; q < 9; ++q)
          if ((px[q] - x[w]).squaredNorm() < (px[best] - x[w]).squaredNorm()) best = q;
        fuv[k] = pts[best];
      }
    }
    auto bil = [&](const Vec2& uv) {
      const double a1 = (uv.x() - u0) / su, b1 = (uv.y() - v0) / sv;
      return (1 - a1) * (1 - b1) * C[0] + a1 * (1 - b1) * C[1] + a1 * b1 * C[2] + (1 - a1) * b1 * C[3];
    };
    const double bil_angle = min_angle_deg(bil(fuv[0]), bil(fuv[1]), bil(fuv[2]));
    double smin = 1e300, smax = 0, cmin = 180;
    for (int k = 0; k < 4; ++k) {
      const double l = (C[(k + 1) % 4] - C[k]).norm();
      smin = std::min(smin, l), smax = std::max(smax, l);
      const Vec3 e1 = C[(k + 1) % 4] - C[k], e2 = C[(k + 3) % 4] - C[k];
      cmin = std::min(cmin, std::acos(std::clamp(e1.dot(e2) / (e1.norm() * e2.norm()), -1.0, 1.0)) * 180 / M_PI);
    }
    const int nf = leaf_faces[li];
    all.add(std::string("cell ") + (nf == 2 ? "2" : nf == 3 ? "3" : "fan"));
    all.add("border " + std::to_string(on_border) + (corner_valence ? " corner v" + std::to_string(corner_valence) : ""));
    all.add(std::string("bilinear ") + (bil_angle < bound ? "bad too (cell shape/cut)" : "good (map varies inside)"));
    const double asp = r.leaf_aspect[li];
    all.add(std::string("leaf_aspect ") + (asp < 1.5 ? "<1.5" : asp < 2.1 ? "1.5-2.1" : asp < 3 ? "2.1-3" : ">=3"));
    const double sr = smax / std::max(smin, 1e-300);
    all.add(std::string("corner sides ratio ") + (sr < 2 ? "<2" : sr < 3 ? "2-3" : sr < 5 ? "3-5" : ">=5"));
    all.add(std::string("corner min angle ") + (cmin < 30 ? "<30" : cmin < 45 ? "30-45" : cmin < 60 ? "45-60" : ">=60"));
    all.add(std::string("cell/bilinear ") + (nf == 2 ? "2" : nf == 3 ? "3" : "fan") + (bil_angle < bound ? " bad" : " good"));
  }
  std::printf("%s: %d patches, %d faces, %ld under %.0f deg (%.2f%%), %d leaves, %d fans\n", name.c_str(),
              static_cast<int>(charts[m]->patches.size()), c.num_faces(), bad, bound, 100.0 * bad / c.num_faces(),
              static_cast<int>(r.leaves.size()), r.stats.fan_leaves);
  for (const auto& [k, v] : all.by) std::printf("   %-40s %6ld  %5.1f%%\n", k.c_str(), v, 100.0 * v / std::max(bad, 1L));
  std::vector<std::pair<long, int>> pp;
  for (const auto& [p, v] : per_patch) pp.push_back({v, p});
  std::sort(pp.rbegin(), pp.rend());
  std::printf("   worst patches:");
  for (size_t k = 0; k < std::min<size_t>(8, pp.size()); ++k) std::printf(" p%d:%ld", pp[k].second, pp[k].first);
  std::printf("\n");
  // The worst patches' shape on the surface: their share of the mesh's area and their squareness,
  // the area over (perimeter / 4)^2 (1 for a square, near 0 for a leaf whose sides run close
  // together: every cell of such a patch is a sliver whatever one (u,v) per vertex does).
  const auto& mesh = charts[m]->mesh;
  double total = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) total += qs::face_area(mesh, f);
  for (size_t k = 0; k < std::min<size_t>(4, pp.size()); ++k) {
    const int p = pp[k].second;
    double area = 0;
    for (const int* f = s.patch_faces_begin(p); f != s.patch_faces_end(p); ++f) area += qs::face_area(mesh, *f);
    double perimeter = 0;
    const int n = 64;
    for (int side = 0; side < 4; ++side)
      for (int i = 0; i < n; ++i) {
        auto at = [&](double f) {
          return side == 0 ? Vec2(f, 0) : side == 1 ? Vec2(1, f) : side == 2 ? Vec2(1 - f, 1) : Vec2(0, 1 - f);
        };
        perimeter += (s.point(p, at(static_cast<double>(i + 1) / n)) - s.point(p, at(static_cast<double>(i) / n))).norm();
      }
    std::printf("   p%d: %.2f%% of the area, squareness %.2f (area / (perimeter / 4)^2)\n", p, 100 * area / total,
                perimeter > 0 ? area / (perimeter * perimeter / 16) : 0.0);
  }
}

}  // namespace

int main(int argc, char** argv) {
  const fs::path dir = argc > 1 ? argv[1] : QS_SOURCE_DIR "/../shared/meshes";
  const std::string filter = argc > 2 ? argv[2] : "";
  const int level = argc > 3 ? std::atoi(argv[3]) : 4;
  const double bound = argc > 4 ? std::atof(argv[4]) : 10.0;
  std::vector<int> patches;
  for (int a = 5; a < argc; ++a) patches.push_back(std::atoi(argv[a]));
  if (!fs::is_directory(dir)) {
    std::fprintf(stderr,
                 "qs-bench-slivers: %s is not a folder of meshes or a dissection folder\n"
                 "usage: qs-bench-slivers [MESH_DIR | DISSECTION_DIR] [MESH_FILTER] [LEVEL] [BOUND_DEG] [PATCH...]\n",
                 dir.string().c_str());
    return 3;
  }
  if (fs::exists(dir / "dissection.json")) {  // a dissection folder: its set, remeshed together
    const auto in = qs::dissect::read_dissection(dir);
    std::vector<const qs::dissect::Chart*> charts;
    for (const auto& m : in.meshes) charts.push_back(&m.dissection.chart);
    const auto r = qs::remesh::remesh_even_anisotropic(charts, level);
    for (size_t m = 0; m < charts.size(); ++m)
      if (in.meshes[m].file.find(filter) != std::string::npos) analyze(in.meshes[m].file, charts, r, m, bound, patches);
    return 0;
  }
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string ext = e.path().extension().string();
    if ((ext == ".obj" || ext == ".off" || ext == ".ply") && e.path().filename().string().find(filter) != std::string::npos)
      files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    qs::TriMesh mesh;
    try {
      const auto v = qs::mesh::validate(qs::io::read_mesh(f).mesh);
      if (!v.report.accepted) continue;
      mesh = v.mesh;
    } catch (const qs::Error&) {
      continue;
    }
    const auto d = qs::dissect::dissect(mesh, std::nullopt, {});
    const std::vector<const qs::dissect::Chart*> charts = {&d.chart};
    const auto r = qs::remesh::remesh_even_anisotropic(charts, level);
    analyze(f.filename().string(), charts, r, 0, bound, patches);
  }
  return 0;
}
