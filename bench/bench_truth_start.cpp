// Benchmark: is the map refinement's energy a guide toward the exact map?
//   usage: qs-bench-truth-start [--samples N] [--pose-pull W] [--faces F] [--variation V] [SEED ...]   (seeds 1..6)
//          qs-bench-truth-start [--samples N] [--pose-pull W] --pair A.obj B.obj LANDMARKS.json
//   (--pose-pull: the pull's weight for a pair found in one pose, default qs-dissect's 10)
// A pair whose exact map is the identity of one connectivity: a generated pair (qs::family, shapes
// 0 and 1 of the seed) with B rebuilt on A's connectivity (every vertex of A at its exact image on
// shape 1), or two meshes with identical face lists (e.g. smpl_man_14k / smpl_woman_14k) and one
// landmark file for both. The pair is dissected as qs-dissect does by default, then refined twice:
//   qs:    B's chart as dissected, refine_maps at qs-dissect's defaults (the pose pull and its
//          border Newton steps when the pair is found to share a pose);
//   exact: B's chart replaced by A's chart on B's positions (the exact map, error 0), the same
//          refine_maps.
// Prints for both the error of the chart map against the exact one (% of B's diagonal) and the
// map's isometric distortion (qs::correspondence: symDirichlet / 4 on A's faces, mean and median;
// 1 = isometric). Where the refined exact map ends with a higher distortion than qs's own result, a
// better minimizer of that energy would move qs away from the exact map, not toward it.

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <optional>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/correspondence/correspondence.h"
#include "qs/dissect/dissection.h"
#include "qs/pipeline/pipeline.h"
#include "qs/family/family.h"
#include "qs/landmarks/landmarks.h"
#include "qs/maprefine/map_refine.h"
#include "qs/mesh/validate.h"

namespace {

using qs::TriMesh;
using qs::Vec3;

// `a`'s chart carried onto `b_mesh` (a's input connectivity, other positions): every chart vertex
// keeps its place on a's input faces (the input's own vertices by id, the others through their
// closest point of a's input mesh), so the chart map a -> b is the identity of the connectivity.
qs::dissect::Dissection carry_chart(const qs::dissect::Dissection& a, const TriMesh& a_mesh, const TriMesh& b_mesh) {
  qs::dissect::Dissection out = a;
  auto& p = out.chart.mesh.positions;
  const int n = a_mesh.num_vertices();
  for (int v = 0; v < static_cast<int>(p.size()); ++v) {
    if (v < n) {
      p[v] = b_mesh.positions[v];
      continue;
    }
    const qs::landmarks::SurfacePoint sp = qs::landmarks::closest_surface_point(a_mesh, p[v]);
    p[v] = qs::landmarks::position_of(b_mesh, sp);
  }
  for (auto& s : out.seed_placements) s.position = p[s.vertex];
  return out;
}

struct Row {
  qs::correspondence::PairMeasure m;
  double energy = 0;  // refine_maps's own figure for B (its normalized energy after)
};

Row measure(const qs::correspondence::GroundTruth& truth, const std::vector<qs::dissect::Dissection>& d, double energy,
            long samples) {
  std::vector<qs::correspondence::DissectedInput> in(2);
  std::vector<std::vector<std::pair<std::string, Vec3>>> lm(2);
  for (int i = 0; i < 2; ++i) {
    lm[i] = qs::correspondence::dissection_landmarks(d[i]);
    in[i] = {&d[i].chart, lm[i]};
  }
  qs::correspondence::MeasureOptions mo;
  mo.samples = samples;
  return {qs::correspondence::measure_pair(truth, in, 0, 1, mo), energy};
}

void print_row(const char* label, const char* which, const Row& r) {
  const auto& e = r.m.dissection;
  std::printf("%-14s %-14s %7.3f %7.3f %7.3f %9.4f %9.4f %9.4f\n", label, which, e.mean, e.p95, e.max, r.m.distortion,
              r.m.distortion_median, r.energy);
}

// Dissects {A, B} (identical connectivity), refines both ways and prints the rows.
void run_pair(const char* label, const TriMesh& a, const TriMesh& b, const qs::dissect::MeshToDissect& a_in,
              const qs::dissect::MeshToDissect& b_in, long samples, double pose_pull) {
  // Dissected as qs-dissect does, the refinement left to the two runs below.
  qs::pipeline::DissectConfig config;
  config.refine_maps = false;
  if (pose_pull >= 0) config.pose_pull = pose_pull;
  const qs::pipeline::SetResult run = qs::pipeline::dissect_meshes({a_in, b_in}, config);
  const qs::dissect::DissectionSet& set = run.set;
  const qs::maprefine::RefineOptions ro = run.refine_options;
  std::vector<qs::correspondence::TruthMesh> tm(2);
  tm[0].name = "A";
  tm[0].mesh = a;  // no map: the exact map is the identity of the connectivity
  tm[1].name = "B";
  tm[1].mesh = b;
  const qs::correspondence::GroundTruth truth(std::move(tm));

  std::vector<qs::dissect::Dissection> own = set.meshes;
  const auto r_own = qs::maprefine::refine_maps(own, ro);
  std::vector<qs::dissect::Dissection> exact = {set.meshes[0], carry_chart(set.meshes[0], a, b)};
  const Row start = measure(truth, exact, 0, samples);
  const auto r_exact = qs::maprefine::refine_maps(exact, ro);
  print_row(label, "exact", {start.m, r_exact.meshes[1].energy_before});
  print_row(label, "exact refined", measure(truth, exact, r_exact.meshes[1].energy_after, samples));
  print_row(label, "qs", measure(truth, own, r_own.meshes[1].energy_after, samples));
}

TriMesh validated(const TriMesh& m, const std::string& name) {
  qs::mesh::ValidationResult v = qs::mesh::validate(m);
  if (!v.report.accepted || v.mesh.num_vertices() != m.num_vertices())
    throw qs::InvalidInput(name + ": not a valid closed genus-0 mesh with every vertex used");
  return v.mesh;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    long samples = 30000;
    int faces = 8000;
    double variation = 1.0;
    double pose_pull = -1;  // -1: qs-dissect's default
    std::vector<std::uint64_t> seeds;
    std::vector<std::string> pair;
    for (int i = 1; i < argc; ++i) {
      const std::string s = argv[i];
      if (s == "--samples" && i + 1 < argc) {
        samples = std::atol(argv[++i]);
      } else if (s == "--faces" && i + 1 < argc) {
        faces = std::atoi(argv[++i]);
      } else if (s == "--variation" && i + 1 < argc) {
        variation = std::atof(argv[++i]);
      } else if (s == "--pose-pull" && i + 1 < argc) {
        pose_pull = std::atof(argv[++i]);
      } else if (s == "--pair" && i + 3 < argc) {
        pair = {argv[i + 1], argv[i + 2], argv[i + 3]};
        i += 3;
      } else if (!s.empty() && s[0] != '-') {
        seeds.push_back(std::strtoull(s.c_str(), nullptr, 10));
      } else {
        std::fprintf(
            stderr,
            "usage: qs-bench-truth-start [--samples N] [--pose-pull W] [--faces F] [--variation V] [SEED ...]\n"
            "       qs-bench-truth-start [--samples N] [--pose-pull W] --pair A.obj B.obj LANDMARKS.json\n");
        return 1;
      }
    }
    std::printf(
        "refinement from qs's dissection and from the exact map (error %% of B's diagonal; distortion: "
        "symDirichlet/4 on A's faces, mean / median; energy: refine_maps's)\n");
    std::printf("%-14s %-14s %7s %7s %7s %9s %9s %9s\n", "pair", "start", "mean", "p95", "max", "dist mean", "dist med",
                "energy");
    if (!pair.empty()) {
      std::vector<qs::correspondence::TruthMesh> m;
      for (int i = 0; i < 2; ++i) m.push_back(qs::correspondence::load_truth_mesh(pair[i], std::nullopt));
      if (m[0].mesh.faces != m[1].mesh.faces) throw qs::InvalidInput("--pair: the two meshes' face lists differ");
      std::vector<qs::dissect::MeshToDissect> in(2);
      for (int i = 0; i < 2; ++i) {
        const qs::landmarks::Landmarks lm = qs::landmarks::read_landmarks(pair[2], qs::mesh::validate(m[i].mesh));
        if (lm.seeds.size() != 4) throw qs::InvalidInput(pair[2] + ": 4 seeds needed");
        in[i].mesh = &m[i].mesh;
        in[i].name = pair[i];
        in[i].seed_points = std::array<qs::landmarks::SurfacePoint, 4>{};
        for (int k = 0; k < 4; ++k) (*in[i].seed_points)[k] = lm.seeds[k].where;
        for (const auto& l : lm.features) in[i].features.push_back({l.name, l.vertex, l.where});
      }
      run_pair("pair", m[0].mesh, m[1].mesh, in[0], in[1], samples, pose_pull);
      return 0;
    }
    if (seeds.empty()) seeds = {1, 2, 3, 4, 5, 6};
    for (const std::uint64_t seed : seeds) {
      qs::family::FamilyOptions fo;
      fo.shapes = 2;
      fo.seed = seed;
      fo.faces = faces;
      fo.variation = variation;
      const qs::family::Family fam = qs::family::generate_family(fo);
      std::vector<qs::correspondence::TruthMesh> tm(2);
      for (int i = 0; i < 2; ++i) {
        tm[i].name = fam.shapes[i].name;
        tm[i].mesh = validated(fam.shapes[i].mesh, tm[i].name);
        tm[i].map = qs::family::SurfaceMap{qs::family::MapDomain::Sphere, fam.shapes[i].parameters, "", 0, 0, {}};
      }
      const TriMesh a = tm[0].mesh;
      const qs::correspondence::GroundTruth sphere(std::move(tm));
      // B on A's connectivity: each vertex of A at its exact image on shape 1.
      TriMesh b = a;
      std::vector<int> corner(a.num_vertices(), -1);
      for (int f = a.num_faces() - 1; f >= 0; --f)
        for (int k = 0; k < 3; ++k) corner[a.faces[f][k]] = 3 * f + k;
      for (int v = 0; v < a.num_vertices(); ++v) {
        qs::landmarks::SurfacePoint sp;
        sp.face = corner[v] / 3;
        sp.bary = {0.0, 0.0, 0.0};
        sp.bary[corner[v] % 3] = 1.0;
        b.positions[v] = qs::landmarks::position_of(sphere.mesh(1).mesh, sphere.map(0, 1, sp));
      }
      b = validated(b, "shape01 on shape00's connectivity");
      qs::dissect::MeshToDissect a_in = qs::correspondence::dissect_input(fam.shapes[0]);
      a_in.mesh = &a;
      qs::dissect::MeshToDissect b_in = a_in;  // the same landmarks: the exact map is the identity
      b_in.mesh = &b;
      b_in.name = "shape01'";
      const std::string label = "gen-s" + std::to_string(seed);
      run_pair(label.c_str(), a, b, a_in, b_in, samples, pose_pull);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "qs-bench-truth-start: %s\n", e.what());
    return 2;
  }
  return 0;
}
