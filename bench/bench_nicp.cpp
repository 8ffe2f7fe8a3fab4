// Spike: how close does a non-rigid registration (ARAP + closest points, annealed) bring a pose pair?
//   usage: qs-bench-nicp A B LA LB   (B shares A's connectivity: the exact map is vertex i <-> i)
// Prints, in % of B's diagonal (vertex-area weighted over A): the similarity + nearest point map,
// and the registered map (A deformed onto B, then each vertex's nearest point of B).

#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "qs/core/mesh.h"
#include "qs/io/read_mesh.h"
#include "qs/landmarks/landmarks.h"
#include "qs/mesh/validate.h"
#include "qs/metro/metro.h"
#include "qs/register/registration.h"

namespace {
using qs::Tri;
using qs::TriMesh;
using qs::Vec3;

struct Stats {
  double mean, p95, max;
};

Stats error(const TriMesh& a, const std::vector<Vec3>& image, const TriMesh& b) {
  if (b.positions.size() != image.size()) return {-1, -1, -1};
  Eigen::Vector3d lo = b.positions[0], hi = b.positions[0];
  for (const Vec3& p : b.positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double diag = (hi - lo).norm();
  std::vector<double> area(a.positions.size(), 0.0);
  for (int f = 0; f < a.num_faces(); ++f)
    for (int v : a.faces[f]) area[v] += qs::face_area(a, f) / 3;
  std::vector<std::pair<double, double>> e;
  double sum = 0, w = 0;
  for (size_t i = 0; i < image.size(); ++i) {
    const double d = 100 * (image[i] - b.positions[i]).norm() / diag;
    e.emplace_back(d, area[i]);
    sum += d * area[i];
    w += area[i];
  }
  std::sort(e.begin(), e.end());
  double acc = 0, p95 = 0;
  for (auto& [d, wt] : e) {
    acc += wt;
    if (acc >= 0.95 * w) {
      p95 = d;
      break;
    }
  }
  return {sum / w, p95, e.back().first};
}

std::vector<Vec3> nearest(const qs::metro::SurfaceDistance& sd, const std::vector<Vec3>& x, const std::vector<Tri>& faces) {
  const auto n = qs::vertex_normals(x, faces);
  std::vector<Vec3> out(x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    auto c = sd.closest_facing(x[i], n[i], 0.3);
    if (c.face < 0) c = sd.closest(x[i]);
    out[i] = c.point;
  }
  return out;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) return 1;
  auto ra = qs::io::read_mesh(argv[1]);
  auto rb = qs::io::read_mesh(argv[2]);
  auto va = qs::mesh::validate(ra.mesh);
  auto vb = qs::mesh::validate(rb.mesh);
  auto la = qs::landmarks::read_landmarks(argv[3], va);
  auto lb = qs::landmarks::read_landmarks(argv[4], vb);
  const TriMesh& a = va.mesh;
  const TriMesh& b = vb.mesh;
  TriMesh truth = b;
  if (argc > 5) truth = qs::mesh::validate(qs::io::read_mesh(argv[5]).mesh).mesh;
  const int n = a.num_vertices();
  std::vector<Vec3> pa, pb;
  std::vector<int> lv;  // A's landmark vertices (nearest vertex of the landmark's face)
  auto add = [&](const qs::landmarks::Landmark& x, const qs::landmarks::Landmark& y) {
    pa.push_back(x.position);
    pb.push_back(y.position);
    int best = a.faces[x.where.face][0];
    for (int v : a.faces[x.where.face])
      if ((a.positions[v] - x.position).norm() < (a.positions[best] - x.position).norm()) best = v;
    lv.push_back(best);
  };
  for (int k = 0; k < 4; ++k) add(la.seeds[k], lb.seeds[k]);
  for (auto& f : la.features)
    for (auto& g : lb.features)
      if (f.name == g.name) add(f, g);
  const Eigen::Matrix4d s = qs::fit_similarity(pa, pb, true);
  std::vector<Vec3> rest(n);
  for (int i = 0; i < n; ++i) rest[i] = (s * a.positions[i].homogeneous()).head<3>();
  qs::metro::SurfaceDistance sd(b, "B");
  const auto base = nearest(sd, rest, a.faces);
  Stats st = error(a, base, truth);
  std::printf("similarity + nearest: %.2f / %.2f / %.2f\n", st.mean, st.p95, st.max);

  std::vector<qs::registration::LandmarkPair> pairs;
  for (size_t k = 0; k < pa.size(); ++k) pairs.push_back({pa[k], pb[k]});
  qs::registration::RegisterOptions ro;
  if (std::getenv("NICP_INNER")) ro.iterations = std::atoi(std::getenv("NICP_INNER"));
  const auto reg = qs::registration::register_surface(a, b, pairs, ro);
  st = error(a, nearest(sd, reg.positions, a.faces), truth);
  std::printf("registered: %.2f / %.2f / %.2f  fit %.3f%% p99 %.3f%% distortion %.4f\n", st.mean, st.p95, st.max,
              100 * reg.mean_distance, 100 * reg.p99_distance, reg.distortion);
  return 0;
}
