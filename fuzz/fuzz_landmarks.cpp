// libFuzzer target: the landmark reader, JSON or MeshLab .pp (by the first byte: '<' is .pp), on a
// fixed valid mesh (a subdivided icosahedron) so that references are resolved and snapped too.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "qs/core/error.h"
#include "qs/landmarks/landmarks.h"
#include "qs/mesh/validate.h"
#include "qs/shapes/shapes.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const qs::mesh::ValidationResult mesh = qs::mesh::validate(qs::shapes::icosphere(2));
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const auto format = !text.empty() && text.front() == '<' ? qs::landmarks::LandmarkFormat::PickedPoints
                                                           : qs::landmarks::LandmarkFormat::Json;
  try {
    (void)qs::landmarks::parse_landmarks(text, format, "fuzz", mesh);
  } catch (const qs::Error&) {
  }
  return 0;
}
