// libFuzzer target: the PLY reader (and validation of what it read).
#include "fuzz_mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return fuzz_mesh(data, size, qs::io::MeshFormat::Ply);
}
