// libFuzzer target: the PNG and OpenEXR readers (qs::image::decode_image, by the bytes' signature),
// with limits that keep an image under 1 M pixels. Only qs::Error may leave the reader; any
// other exception, crash, hang or sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <span>

#include "qs/core/error.h"
#include "qs/image/image_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  qs::image::Limits limits;
  limits.max_side = 4096;
  limits.max_pixels = 1 << 20;
  try {
    const qs::image::RgbPixels px = qs::image::decode_image(std::span<const unsigned char>(data, size), "fuzz", {}, limits);
    float sum = 0;  // touch every decoded value
    for (std::size_t i = 0; i < static_cast<std::size_t>(px.width) * px.height * 3; ++i) sum += px.normalized(i);
    (void)sum;
  } catch (const qs::Error&) {
  }
  return 0;
}
