// qs_example OUTDIR MESH...: the library's pipeline at its defaults, from an installed qs.
// Reads the meshes (landmarks from <stem>.landmarks.json or <stem>.pp beside each), dissects
// them together, writes OUTDIR/dissection/, reads it back and writes the level-4 remesh
// OUTDIR/remesh-L4/: the same bytes as
//   qs-dissect MESH... -o OUTDIR/dissection
//   qs-remesh OUTDIR/dissection --level 4 -o OUTDIR/remesh-L4
// Exit codes: 0 ok, 1 usage, 2 invalid input, 3 i/o, 4 solver, 70 internal (qs::exit_code).

#include <qs/core/error.h>
#include <qs/pipeline/pipeline.h>

#include <exception>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  if (argc < 3) {
    std::cerr << "usage: qs_example OUTDIR MESH...\n";
    return qs::exit_code(qs::ErrorCode::Usage);
  }
  const std::filesystem::path out = argv[1];
  try {
    std::vector<qs::pipeline::Input> inputs;
    for (int i = 2; i < argc; ++i) inputs.push_back(qs::pipeline::load_input(argv[i]));

    for (const std::string& w : qs::pipeline::check_inputs(inputs)) std::cerr << "qs_example: warning: " << w << "\n";
    const auto dissection = qs::pipeline::dissect(inputs);
    const auto dissection_folder = out / "dissection";
    qs::pipeline::write_dissection(dissection, dissection_folder);
    qs::pipeline::check_bijective(dissection);
    std::cout << dissection.report;

    // Remeshed from the folder as written, as qs-remesh does.
    qs::pipeline::RemeshConfig config;
    config.level = 4;
    const auto loaded = qs::pipeline::read_dissection(dissection_folder);
    const auto remesh = qs::pipeline::remesh(loaded, dissection_folder, config);
    qs::pipeline::write_remesh(remesh, out / "remesh-L4");
    std::cout << remesh.report;
    return 0;
  } catch (const qs::Error& e) {
    std::cerr << "qs_example: " << qs::error_name(e.code()) << " error: " << e.what() << "\n";
    return qs::exit_code(e.code());
  } catch (const std::exception& e) {
    std::cerr << "qs_example: internal error: " << e.what() << "\n";
    return qs::exit_code(qs::ErrorCode::Internal);
  }
}
