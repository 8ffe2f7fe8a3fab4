// The seed-loop stage alone on pairs with one connectivity (vertex i <-> vertex i, e.g. a mesh
// and its pose from `qs-family pose`): the share of A's area that lies on the same side of B's
// loop as of A's, for B's own shortest loop and for B's loop routed along A's in geodesic
// coordinates (trace_intrinsic_loop), at several band widths.
//
//   usage: qs-bench-seed-loops A B LANDMARKS_A LANDMARKS_B [A2 B2 LA2 LB2 ...]
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/dissect/loop_guide.h"
#include "qs/dissect/seed_loop.h"
#include "qs/io/read_mesh.h"
#include "qs/landmarks/landmarks.h"
#include "qs/mesh/validate.h"

namespace {

struct Input {
  qs::mesh::ValidationResult valid;
  std::array<int, 4> seeds{};
  std::vector<int> features;
};

int vertex_of(const qs::TriMesh& m, const qs::landmarks::Landmark& l) {
  if (l.vertex >= 0) return l.vertex;
  const auto& b = l.where.bary;
  const int c = b[0] >= b[1] && b[0] >= b[2] ? 0 : b[1] >= b[2] ? 1 : 2;
  return m.faces[l.where.face][c];
}

Input load(const std::string& mesh, const std::string& lm) {
  Input in;
  in.valid = qs::mesh::validate(qs::io::read_mesh(mesh).mesh);
  if (!in.valid.report.accepted) throw qs::InvalidInput(mesh + ": rejected");
  const auto l = qs::landmarks::read_landmarks(lm, in.valid);
  if (l.seeds.size() != 4) throw qs::InvalidInput(lm + ": needs 4 seeds");
  for (int k = 0; k < 4; ++k) in.seeds[k] = vertex_of(in.valid.mesh, l.seeds[k]);
  for (const auto& f : l.features) in.features.push_back(vertex_of(in.valid.mesh, f));
  return in;
}

double same_side(const qs::TriMesh& a, const std::vector<int>& la, const std::vector<int>& lb) {
  double same = 0, total = 0;
  for (int f = 0; f < a.num_faces(); ++f) {
    const double w = qs::face_area(a, f);
    total += w;
    if (la[f] == lb[f]) same += w;
  }
  return same / total;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5 || (argc - 1) % 4 != 0) {
    std::cerr << "usage: qs-bench-seed-loops A B LANDMARKS_A LANDMARKS_B [...]\n";
    return 1;
  }
  const std::vector<double> sigmas{0.02, 0.05, 0.1, 0.2};
  std::printf("%-28s %8s", "pair", "own");
  for (double s : sigmas) std::printf("  s=%-5.2f", s);
  std::printf("\n");
  for (int k = 1; k + 3 < argc; k += 4) {
    try {
      const Input a = load(argv[k], argv[k + 2]), b = load(argv[k + 1], argv[k + 3]);
      const auto& ma = a.valid.mesh;
      const auto& mb = b.valid.mesh;
      if (ma.faces != mb.faces) throw qs::InvalidInput("the pair does not share its connectivity");
      const auto loop_a = qs::dissect::trace_seed_loop(ma, a.seeds, a.features);
      const auto labels_a = qs::dissect::seed_patch_of_faces(ma, loop_a);
      const auto own = qs::dissect::trace_seed_loop(mb, b.seeds, b.features);
      std::vector<int> lm_a(a.seeds.begin(), a.seeds.end()), lm_b(b.seeds.begin(), b.seeds.end());
      lm_a.insert(lm_a.end(), a.features.begin(), a.features.end());
      lm_b.insert(lm_b.end(), b.features.begin(), b.features.end());
      const auto ref = qs::dissect::loop_coordinates(qs::dissect::geodesic_coordinates(ma, lm_a), loop_a);
      const auto cb = qs::dissect::geodesic_coordinates(mb, lm_b);
      std::printf("%-28s %7.2f%%", argv[k + 1], 100 * same_side(ma, labels_a, qs::dissect::seed_patch_of_faces(mb, own)));
      for (double s : sigmas) {
        try {
          const auto l = qs::dissect::trace_intrinsic_loop(mb, b.seeds, cb, ref, s, b.features);
          std::printf("  %7.2f%%", 100 * same_side(ma, labels_a, qs::dissect::seed_patch_of_faces(mb, l)));
        } catch (const qs::Error& e) {
          std::printf("  %8s", "fail");
        }
      }
      std::printf("\n");
    } catch (const std::exception& e) {
      std::printf("%-28s error: %s\n", argv[k + 1], e.what());
    }
  }
  return 0;
}
