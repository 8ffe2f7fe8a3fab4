// Benchmark: what two triangulations cost a pair's map, whatever the dissection does.
//   usage: qs-bench-chart-floor DISSECTION [MAP_A|- MAP_B|-]
// A dissected pair (A, B) with its ground truth (as qs-metro --correspondence reads it). The map
// A -> B is A's chart (u, v), linear on A's chart faces, then B's chart, linear on B's. Even a B
// chart whose (u, v) is exact at each of its vertices differs from the truth between them, unless
// B's faces are A's (a pose of A's connectivity): this bench builds that chart, B's (u, v) at
// every vertex inside a patch replaced by A's (u, v) at the vertex's exact point of A (B's patch
// sides and the vertices whose exact point lies in another patch of A keep B's own), and measures
// both charts at A's vertices: B's own and the exact one, each vertex's image against its exact
// image, in % of B's bounding-box diagonal (mean / median / p95 / max over the vertices), for all
// of A's vertices and for those at least 0.03 and 0.1 from their patch's sides in (u, v).

#include <algorithm>
#include <cstdio>
#include <exception>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "qs/core/error.h"
#include "qs/core/geometry2d.h"
#include "qs/correspondence/dissection_measure.h"
#include "qs/dissect/dissection_json.h"
#include "qs/landmarks/landmarks.h"
#include "qs/metro/metro.h"
#include "qs/remesh/chart_sampler.h"

namespace {
using qs::TriMesh;
using qs::Vec2;
using qs::Vec3;
using qs::landmarks::SurfacePoint;

double side_distance(const Vec2& q) { return std::min({q.x(), 1 - q.x(), q.y(), 1 - q.y()}); }

SurfacePoint locate(const TriMesh& m, const qs::metro::SurfaceDistance& tree, const Vec3& x) {
  const int f = tree.closest(x).face;
  const auto& t = m.faces[f];
  return {f, qs::landmarks::closest_on_triangle(x, m.positions[t[0]], m.positions[t[1]], m.positions[t[2]])};
}

void print_stats(std::vector<double> e) {
  double sum = 0;
  for (double x : e) sum += x;
  std::sort(e.begin(), e.end());
  std::printf("%.4f / %.4f / %.4f / %.3f", sum / static_cast<double>(e.size()), e[e.size() / 2],
              e[e.size() * 95 / 100], e.back());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 && argc != 4) {
    std::fprintf(stderr, "usage: qs-bench-chart-floor DISSECTION [MAP_A|- MAP_B|-]\n");
    return 1;
  }
  try {
    const std::string folder = argv[1];
    const auto dissection = qs::dissect::read_dissection(folder);
    if (dissection.meshes.size() != 2) throw qs::InvalidInput(folder + ": not a pair");
    std::vector<std::string> maps;
    if (argc == 4) maps = {argv[2], argv[3]};
    const auto truth = qs::correspondence::load_ground_truth(
        qs::correspondence::find_truth_files(dissection, folder, maps));
    const qs::dissect::Chart& ca = dissection.meshes[0].dissection.chart;
    const qs::dissect::Chart& cb = dissection.meshes[1].dissection.chart;
    const TriMesh& ma = truth.mesh(0).mesh;
    const TriMesh& mb = truth.mesh(1).mesh;
    const double diagonal = qs::bounding_box(mb.positions).diagonal();
    const qs::metro::SurfaceDistance on_b(mb, "B"), on_a_chart(ca.mesh, "A's chart");

    // A's (u, v) at a point of A, when the point lies in patch `patch` of A's chart.
    auto uv_on_a = [&](const Vec3& x, int patch, Vec2& uv) {
      const SurfacePoint p = locate(ca.mesh, on_a_chart, x);
      if (ca.face_patch[p.face] != patch) return false;
      const auto& w = ca.face_uv[p.face];
      uv = p.bary[0] * w[0] + p.bary[1] * w[1] + p.bary[2] * w[2];
      return true;
    };
    std::vector<char> on_side(cb.mesh.positions.size(), 0);
    for (int f = 0; f < cb.mesh.num_faces(); ++f)
      for (int j = 0; j < 3; ++j)
        if (side_distance(cb.face_uv[f][j]) < 1e-12) on_side[cb.mesh.faces[f][j]] = 1;
    qs::dissect::Chart exact = cb;
    std::map<std::pair<int, int>, std::pair<bool, Vec2>> done;  // (vertex, patch) -> found, (u, v)
    long replaced = 0, kept = 0;
    for (int f = 0; f < cb.mesh.num_faces(); ++f)
      for (int j = 0; j < 3; ++j) {
        const int v = cb.mesh.faces[f][j];
        if (on_side[v]) continue;
        auto it = done.find({v, cb.face_patch[f]});
        if (it == done.end()) {
          const SurfacePoint on_a = truth.map(1, 0, locate(mb, on_b, cb.mesh.positions[v]));
          Vec2 uv = Vec2::Zero();
          const bool found = uv_on_a(qs::landmarks::position_of(ma, on_a), cb.face_patch[f], uv);
          it = done.emplace(std::make_pair(v, cb.face_patch[f]), std::make_pair(found, uv)).first;
        }
        if (it->second.first) {
          exact.face_uv[f][j] = it->second.second;
          ++replaced;
        } else {
          ++kept;
        }
      }
    int folded = 0;
    for (const auto& w : exact.face_uv)
      folded += qs::cross2(w[1] - w[0], w[2] - w[0]) <= 0;
    std::printf("%s: B's chart %d faces; exact (u, v) at %ld of its inner wedges, %ld kept (their vertex's exact "
                "point lies in another patch of A); %d faces of the exact chart folded\n",
                folder.c_str(), cb.mesh.num_faces(), replaced, kept, folded);

    const qs::remesh::ChartSampler own(cb), floor(exact);
    // Each vertex of A: the (u, v) of its first wedge in A's chart, and a face of A holding it.
    const int nv = ma.num_vertices();
    std::vector<int> wedge_face(nv, -1), wedge_corner(nv, -1), face_of(nv, -1), corner_of(nv, -1);
    for (int f = 0; f < ca.mesh.num_faces(); ++f)
      for (int j = 0; j < 3; ++j) {
        const int v = ca.mesh.faces[f][j];
        if (v < nv && wedge_face[v] < 0) wedge_face[v] = f, wedge_corner[v] = j;
      }
    for (int f = 0; f < ma.num_faces(); ++f)
      for (int j = 0; j < 3; ++j) face_of[ma.faces[f][j]] = f, corner_of[ma.faces[f][j]] = j;
    // Per vertex of A: its distance from its patch's sides in (u, v) and both charts' errors.
    std::vector<double> side, e_own, e_floor;
    for (int v = 0; v < nv; ++v) {
      if (wedge_face[v] < 0 || face_of[v] < 0) continue;
      const Vec2 uv = ca.face_uv[wedge_face[v]][wedge_corner[v]];
      const int patch = ca.face_patch[wedge_face[v]];
      SurfacePoint at{face_of[v], {0, 0, 0}};
      at.bary[corner_of[v]] = 1;
      const Vec3 image = qs::landmarks::position_of(mb, truth.map(0, 1, at));
      side.push_back(side_distance(uv));
      e_own.push_back(100 * (own.point(patch, uv) - image).norm() / diagonal);
      e_floor.push_back(100 * (floor.point(patch, uv) - image).norm() / diagonal);
    }
    std::printf("A's vertices: count, B's own chart, the exact chart (mean / median / p95 / max, %% of B's "
                "diagonal)\n");
    for (double margin : {0.0, 0.03, 0.1}) {
      std::vector<double> own_band, floor_band;
      for (size_t k = 0; k < side.size(); ++k)
        if (side[k] >= margin) own_band.push_back(e_own[k]), floor_band.push_back(e_floor[k]);
      if (own_band.empty()) continue;
      std::printf("  at least %.2f from a side: %zu, ", margin, own_band.size());
      print_stats(own_band);
      std::printf(", ");
      print_stats(floor_band);
      std::printf("\n");
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "qs-bench-chart-floor: %s\n", e.what());
    return 2;
  }
  return 0;
}
