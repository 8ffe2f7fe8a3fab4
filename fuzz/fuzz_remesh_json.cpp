// libFuzzer target: remesh.json, read with the fixture's remesh meshes (fuzz/fixture/remesh).
#include "fuzz_folder.h"
#include "qs/core/error.h"
#include "qs/remesh/remesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path dir = fuzz_folder("remesh", QS_FUZZ_FIXTURE "/remesh");
  fuzz_write(dir / "remesh.json", data, size);
  try {
    (void)qs::remesh::read_remesh(dir);
  } catch (const qs::Error&) {
  }
  return 0;
}
