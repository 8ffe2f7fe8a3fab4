// Benchmark: what each stage costs on a pair with one connectivity (vertex i <-> vertex i: a mesh
// and its pose from `qs-family pose`). The pair is dissected as qs-dissect does by default, by the
// path of other poses (DissectOptions::register_poses off: no registration), except that stages of
// B are replaced by their exact counterparts taken from A, one more per level:
//   loop    B's straightened seed loop is A's (the same curve on B's surface);
//   splits  also, before every split, B's map of the node is A's map of it (the same vertices at
//           the same (u, v)), so every cut runs through the same points of the surface and B's
//           patches are A's where the feature alignment left both meshes' nodes alike (a node
//           whose warp cut B elsewhere keeps B's own map; the output counts them);
//   maps    also every node's map, from its parameterization on (before the features are
//           aligned): B's leaves start from A's maps; what is left is the leaf repair and the
//           refinement, each on B's own surface.
// --no-refine also turns the map refinement off (before splits and after the dissection), which
// says what the refinement brings at that level; --leaf-rounds N sets the leaves' stretch rounds. Measure the folder with `qs-metro
// --correspondence OUT` (bench/pose_pairs.sh does, beside qs-dissect's own result).
//
//   usage: qs-bench-stage-attribution A B --landmarks LA LB [--exact loop|splits|maps] [--no-refine] [--leaf-rounds N] -o OUT
//   exit:  0 written (bijective), 4 written with folded leaves, 1 usage, 2 invalid input, 3 i/o
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/core/output_folder.h"
#include "qs/pipeline/pipeline.h"

namespace {

struct Args {
  std::string a, b, la, lb, out;
  bool exact_splits = false;
  bool exact_maps = false;
  bool refine = true;
  int leaf_rounds = -1;
};

bool parse(const std::vector<std::string>& args, Args& r) {
  std::vector<std::string> pos;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& s = args[i];
    if (s == "--landmarks" && i + 2 < args.size()) {
      r.la = args[++i];
      r.lb = args[++i];
    } else if (s == "-o" && i + 1 < args.size()) {
      r.out = args[++i];
    } else if (s == "--exact" && i + 1 < args.size()) {
      const std::string& v = args[++i];
      if (v != "loop" && v != "splits" && v != "maps") return false;
      r.exact_splits = v != "loop";
      r.exact_maps = v == "maps";
    } else if (s == "--leaf-rounds" && i + 1 < args.size()) {
      const std::string& v = args[++i];
      if (v.empty() || v.size() > 2 || v.find_first_not_of("0123456789") != std::string::npos) return false;
      r.leaf_rounds = std::stoi(v);  // 0..99 digits: cannot throw
    } else if (s == "--no-refine") {
      r.refine = false;
    } else if (!s.empty() && s[0] == '-') {
      return false;
    } else {
      pos.push_back(s);
    }
  }
  if (pos.size() != 2 || r.la.empty() || r.out.empty()) return false;
  r.a = pos[0];
  r.b = pos[1];
  return true;
}

// A's straightened seed loop on B: the same mesh and loop; input vertices at B's positions, each
// vertex the straightening put on an input edge of A at the same fraction of that edge on B.
qs::dissect::GeodesicLoop exact_on(const qs::dissect::GeodesicLoop& ga, const qs::TriMesh& a, const qs::TriMesh& b) {
  qs::dissect::GeodesicLoop gb = ga;
  const size_t n = a.positions.size();
  if (ga.mesh.positions.size() < n) throw qs::InternalError("the straightened loop's mesh lost vertices");
  for (size_t v = 0; v < n; ++v) gb.mesh.positions[v] = b.positions[v];
  std::vector<std::array<int, 2>> edges;
  for (const auto& f : a.faces)
    for (int k = 0; k < 3; ++k)
      if (f[k] < f[(k + 1) % 3]) edges.push_back({f[k], f[(k + 1) % 3]});
  for (size_t v = n; v < ga.mesh.positions.size(); ++v) {
    const qs::Vec3& p = ga.mesh.positions[v];
    double best = INFINITY, best_t = 0;
    std::array<int, 2> best_e{};
    for (const auto& e : edges) {
      const qs::Vec3 &x = a.positions[e[0]], &y = a.positions[e[1]];
      const qs::Vec3 d = y - x;
      const double t = std::clamp((p - x).dot(d) / d.squaredNorm(), 0.0, 1.0);
      const double dist = (x + t * d - p).squaredNorm();
      if (dist < best) {
        best = dist;
        best_t = t;
        best_e = e;
      }
    }
    gb.mesh.positions[v] = (1 - best_t) * b.positions[best_e[0]] + best_t * b.positions[best_e[1]];
  }
  return gb;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  if (!parse(std::vector<std::string>(argv + 1, argv + argc), args)) {
    std::cerr << "usage: qs-bench-stage-attribution A B --landmarks LA LB [--exact loop|splits|maps] [--no-refine] [--leaf-rounds N] -o OUT\n";
    return 1;
  }
  try {
    qs::OutputFolder folder(args.out);
    std::vector<qs::pipeline::Input> inputs;
    inputs.push_back(qs::pipeline::load_input(args.a, args.la));
    inputs.push_back(qs::pipeline::load_input(args.b, args.lb));
    const auto& a = inputs[0].valid.mesh;
    const auto& b = inputs[1].valid.mesh;
    if (a.faces != b.faces)
      throw qs::InvalidInput(args.b + ": its faces are not " + args.a + "'s; exact stages need one connectivity");
    qs::pipeline::DissectConfig config;
    // The stages of the other-pose path: a registration would put the pair in one pose.
    config.dissect.register_poses = false;
    config.refine_before_split = args.refine;
    config.refine_maps = args.refine;
    if (args.leaf_rounds >= 0) config.dissect.stretch_iterations = args.leaf_rounds;
    int loops = 0, maps = 0, maps_apart = 0;
    config.dissect.replace_seed_loops = [&](std::vector<qs::dissect::GeodesicLoop>& l) {
      if (l[1].loop.seeds != l[0].loop.seeds)
        throw qs::InvalidInput("the two meshes' seeds are not the same vertices; the exact loop needs them to be");
      l[1] = exact_on(l[0], a, b);
      ++loops;
    };
    if (args.exact_splits)
      config.dissect.replace_node_maps = [&](std::vector<qs::dissect::DissectOptions::NodeMapRef>& m,
                                             bool before_split) {
        if (!before_split && !args.exact_maps) return;
        // B's cut mesh is A's (the same new vertices in the same order) until a leaf repair refines
        // one of them; a node whose vertices differ keeps B's own map and is counted.
        if (*m[1].vertices != *m[0].vertices) {
          ++maps_apart;
          return;
        }
        *m[1].uv = *m[0].uv;
        ++maps;
      };
    const qs::pipeline::DissectResult result = qs::pipeline::dissect(inputs, config);
    qs::pipeline::write_dissection(result, folder);
    folder.commit();
    std::cout << "exact: seed loop " << (loops ? "replaced" : "not reached");
    if (args.exact_splits)
      std::cout << ", node maps replaced " << maps << " times (" << maps_apart << " nodes with other vertices kept B's)";
    std::cout << "; refinement " << (args.refine ? "on" : "off") << "; " << result.report;
    qs::pipeline::check_bijective(result);
    return 0;
  } catch (const qs::Error& e) {
    std::cerr << "qs-bench-stage-attribution: " << e.what() << "\n";
    return qs::exit_code(e.code());
  }
}
