// Benchmark: the registration alone (qs::registration::register_surface) on a pose pair, as a map.
//   usage: qs-bench-registration A B LANDMARKS_A LANDMARKS_B [TRUTH [MAP]]
// A and TRUTH share their connectivity (vertex i <-> vertex i is the exact map: a pose from
// `qs-family pose`); B is TRUTH itself or its re-tessellation (default: B), whose map file MAP
// gives each vertex's point of TRUTH. A's vertices are mapped to B by nearest points, after the
// landmarks' similarity (the baseline) and after the registration; each image's distance to the
// exact one, per vertex area of A, in % of TRUTH's bounding-box diagonal: mean / p95 / max. Then
// the registration's inverse, as qs-dissect uses it (transfer_node_map, the refinement's pull):
// each vertex of B taken into A's frame and to A's nearest facing point, its distance to the
// exact point of A, per vertex area of B, in % of A's diagonal (needs MAP when B is not TRUTH).
// Also the registration's fit (99% of both surfaces' area within), distortion and wall time; for
// an A or a B large enough for the coarse stages (RegisterOptions::coarse_faces), the same with
// every stage on A itself and toward B itself, and the speed-up.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/core/mesh.h"
#include "qs/core/weighted.h"
#include "qs/dissect/dissection.h"
#include "qs/family/surface_map.h"
#include "qs/io/read_mesh.h"
#include "qs/landmarks/landmarks.h"
#include "qs/mesh/validate.h"
#include "qs/metro/metro.h"
#include "qs/register/registration.h"

namespace {
using qs::TriMesh;
using qs::Vec3;

struct Stats {
  double mean = 0, p95 = 0, max = 0;
};

// Mean / p95 / max of weighted values.
Stats summarize(std::vector<std::pair<double, double>> e) {
  double sum = 0, total = 0;
  for (const auto& [d, w] : e) sum += d * w, total += w;
  std::sort(e.begin(), e.end());
  return Stats{sum / total, qs::value_at_weight(e, 0.95 * total), e.back().first};
}

// Each vertex's image (its nearest point of `b` from at[i], facing as A's face there) against
// truth.positions[i].
Stats error(const TriMesh& a, const std::vector<Vec3>& at, const qs::metro::SurfaceDistance& b,
            const TriMesh& truth) {
  const double diag = qs::bounding_box(truth.positions).diagonal();
  const auto normal = qs::vertex_normals(at, a.faces);
  std::vector<double> area(a.positions.size(), 0.0);
  for (int f = 0; f < a.num_faces(); ++f)
    for (int v : a.faces[f]) area[v] += qs::face_area(a, f) / 3;
  std::vector<std::pair<double, double>> e;
  for (size_t i = 0; i < at.size(); ++i) {
    auto c = b.closest_facing(at[i], normal[i], 0.3);
    if (c.face < 0) c = b.closest(at[i]);
    e.emplace_back(100 * (c.point - truth.positions[i]).norm() / diag, area[i]);
  }
  return summarize(std::move(e));
}

// The registration's inverse: each vertex of b into a's frame, to a's nearest point facing as it
// does (as transfer_node_map takes it), against exact[j], per vertex area of b.
Stats inverse_error(const TriMesh& a, const TriMesh& b, const qs::registration::Pose& pose,
                    const std::vector<Vec3>& exact) {
  const double diag = qs::bounding_box(a.positions).diagonal();
  const qs::metro::SurfaceDistance on_a(a, "A");
  const auto normal = qs::vertex_normals(b.positions, b.faces);
  std::vector<double> area(b.positions.size(), 0.0);
  for (int f = 0; f < b.num_faces(); ++f)
    for (int v : b.faces[f]) area[v] += qs::face_area(b, f) / 3;
  std::vector<std::pair<double, double>> e;
  for (size_t j = 0; j < b.positions.size(); ++j) {
    const auto [q, facing] = pose.inverse(b.positions[j], normal[j]);
    auto c = on_a.closest_facing(q, facing, qs::dissect::kSamePoseFacingCos);
    if (c.face < 0) c = on_a.closest(q);
    e.emplace_back(100 * (c.point - exact[j]).norm() / diag, area[j]);
  }
  return summarize(std::move(e));
}

TriMesh read(const char* path) {
  auto v = qs::mesh::validate(qs::io::read_mesh(path).mesh);
  if (!v.report.accepted) throw qs::InvalidInput(std::string(path) + ": not a valid mesh");
  return v.mesh;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5 || argc > 7) {
    std::fprintf(stderr, "usage: qs-bench-registration A B LANDMARKS_A LANDMARKS_B [TRUTH [MAP]]\n");
    return 1;
  }
  try {
    const auto va = qs::mesh::validate(qs::io::read_mesh(argv[1]).mesh);
    const auto vb = qs::mesh::validate(qs::io::read_mesh(argv[2]).mesh);
    const TriMesh& a = va.mesh;
    const TriMesh& b = vb.mesh;
    const TriMesh truth = argc >= 6 ? read(argv[5]) : b;
    if (truth.num_vertices() != a.num_vertices()) throw qs::InvalidInput("TRUTH does not share A's vertices");
    // Each vertex of B's exact point of A: its own index when B is TRUTH, else its map's origin.
    std::vector<Vec3> exact;
    if (argc == 7) {
      const auto map = qs::family::read_surface_map(argv[6]);
      if (map.domain != qs::family::MapDomain::Surface || map.num_vertices() != b.num_vertices() ||
          map.reference_faces != a.num_faces())
        throw qs::InvalidInput(std::string(argv[6]) + ": not a surface map of B onto TRUTH");
      for (const auto& o : map.origins) {
        const auto& t = a.faces[o.face];
        exact.push_back(o.bary[0] * a.positions[t[0]] + o.bary[1] * a.positions[t[1]] + o.bary[2] * a.positions[t[2]]);
      }
    } else if (b.positions == truth.positions && b.faces == truth.faces) {
      exact = a.positions;
    }
    const auto la = qs::landmarks::read_landmarks(argv[3], va);
    const auto lb = qs::landmarks::read_landmarks(argv[4], vb);
    std::vector<qs::registration::LandmarkPair> pairs;
    std::vector<Vec3> from, to;
    for (int k = 0; k < 4; ++k) pairs.push_back({la.seeds[k].position, lb.seeds[k].position});
    for (const auto& f : la.features)
      for (const auto& g : lb.features)
        if (f.name == g.name) pairs.push_back({f.position, g.position});
    for (const auto& p : pairs) from.push_back(p.on_a), to.push_back(p.on_b);
    const Eigen::Matrix4d s = qs::fit_similarity(from, to);
    std::vector<Vec3> moved;
    for (const Vec3& x : a.positions) moved.push_back((s * x.homogeneous()).head<3>());
    const qs::metro::SurfaceDistance on_b(b, "B");
    const Stats base = error(a, moved, on_b, truth);
    std::printf("similarity + nearest point: %.2f / %.2f / %.2f%%\n", base.mean, base.p95, base.max);
    auto run = [&](const char* what, const qs::registration::RegisterOptions& options, bool inverse) {
      const auto t0 = std::chrono::steady_clock::now();
      auto r = qs::registration::register_surface(a, b, pairs, options);
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const Stats reg = error(a, r.positions, on_b, truth);
      std::printf("%s: %.2f / %.2f / %.2f%% (fit: 99%% within %.3f%%, distortion %.4f, %.2f s)\n", what, reg.mean,
                  reg.p95, reg.max, 100 * r.p99_distance, r.distortion, seconds);
      if (inverse && !exact.empty()) {
        const Stats inv = inverse_error(a, b, qs::registration::Pose(a, std::move(r)), exact);
        std::printf("registered, inverse (B -> A): %.2f / %.2f / %.2f%%\n", inv.mean, inv.p95, inv.max);
      }
      return seconds;
    };
    const qs::registration::RegisterOptions defaults;
    const double t = run("registered + nearest point", defaults, true);
    if (a.num_faces() > 2 * defaults.coarse_faces || b.num_faces() > 2 * defaults.coarse_faces) {
      qs::registration::RegisterOptions fine = defaults;  // the coarse stages were used: against none
      fine.coarse_faces = 0;
      const double t_fine = run("every stage on A itself, toward B itself", fine, false);
      std::printf("coarse stages: %.2fx faster\n", t_fine / t);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "qs-bench-registration: %s\n", e.what());
    return 2;
  }
  return 0;
}
