// Benchmark: what the seed loop's routing costs on a pair with one connectivity (vertex i <->
// vertex i: a mesh and its pose from `qs-family pose`). The pair is dissected as qs-dissect does by
// default, except that B's seed loop is replaced by A's own vertices (the exact loop: the same
// curve on B's surface); everything after it (splits, maps, refinement) runs unchanged. Measure the
// folder written with `qs-metro --correspondence OUT` and compare with qs-dissect's own result
// (bench/pose_pairs.sh does both).
//
//   usage: qs-bench-stage-attribution A B --landmarks LA LB -o OUT
//   exit:  0 written (bijective), 4 written with folded leaves, 1 usage, 2 invalid input, 3 i/o
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/core/output_folder.h"
#include "qs/pipeline/pipeline.h"

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.size() != 7 || args[2] != "--landmarks" || args[5] != "-o") {
    std::cerr << "usage: qs-bench-stage-attribution A B --landmarks LA LB -o OUT\n";
    return 1;
  }
  try {
    qs::OutputFolder folder(args[6]);
    std::vector<qs::pipeline::Input> inputs;
    inputs.push_back(qs::pipeline::load_input(args[0], args[3]));
    inputs.push_back(qs::pipeline::load_input(args[1], args[4]));
    const auto& a = inputs[0].valid.mesh;
    const auto& b = inputs[1].valid.mesh;
    if (a.faces != b.faces)
      throw qs::InvalidInput(args[1] + ": its faces are not " + args[0] + "'s; the exact loop needs one connectivity");
    qs::pipeline::DissectConfig config;
    int replaced = 0;
    config.dissect.replace_seed_loops = [&](std::vector<qs::dissect::SeedLoop>& loops) {
      if (loops[1].seeds != loops[0].seeds)
        throw qs::InvalidInput("the two meshes' seeds are not the same vertices; the exact loop needs them to be");
      loops[1] = loops[0];
      ++replaced;
    };
    const qs::pipeline::DissectResult result = qs::pipeline::dissect(inputs, config);
    qs::pipeline::write_dissection(result, folder);
    folder.commit();
    std::cout << "exact seed loop: " << (replaced ? "B's loop replaced by A's" : "not reached") << "; "
              << result.report;
    qs::pipeline::check_bijective(result);
    return 0;
  } catch (const qs::Error& e) {
    std::cerr << "qs-bench-stage-attribution: " << e.what() << "\n";
    return qs::exit_code(e.code());
  }
}
