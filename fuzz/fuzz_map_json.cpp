// libFuzzer target: a map file (<stem>.map.json, qs::family::parse_surface_map), as qs-metro
// --correspondence --map reads it.
#include <cstddef>
#include <cstdint>
#include <string>

#include "qs/core/error.h"
#include "qs/family/surface_map.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)qs::family::parse_surface_map(std::string(reinterpret_cast<const char*>(data), size), "map.json");
  } catch (const qs::Error&) {
  }
  return 0;
}
