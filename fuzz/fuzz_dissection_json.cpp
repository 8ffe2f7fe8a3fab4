// libFuzzer target: dissection.json, read with the fixture's chart (fuzz/fixture/dissection).
#include "fuzz_folder.h"
#include "qs/core/error.h"
#include "qs/dissect/dissection_json.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path dir = fuzz_folder("dissection", QS_FUZZ_FIXTURE "/dissection");
  fuzz_write(dir / "dissection.json", data, size);
  try {
    (void)qs::dissect::read_dissection(dir);
  } catch (const qs::Error&) {
  }
  return 0;
}
