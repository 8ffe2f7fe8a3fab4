#include "qs/image/image_file.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "qs/core/error.h"
#include "qs/core/json_strict.h"
#include "qs/image/image_file_detail.h"

namespace qs::image {

namespace fs = std::filesystem;

float RgbPixels::normalized(std::size_t i) const {
  if (bits == 8) return u8[i] / 255.0f;
  if (bits == 16) return u16[i] / 65535.0f;
  return f32[i];
}

std::uint8_t RgbPixels::to8(std::size_t i) const {
  if (bits == 8) return u8[i];
  if (bits == 16) return static_cast<std::uint8_t>((std::uint32_t{u16[i]} * 255 + 32767) / 65535);
  const float c = f32[i];
  return static_cast<std::uint8_t>(std::lround((c > 0 ? std::min(c, 1.0f) : 0.0f) * 255.0f));
}

RgbPixels decode_image(std::span<const unsigned char> bytes, const std::string& where, const Expected& expected,
                       const Limits& limits) {
  static constexpr unsigned char png_sig[4] = {0x89, 'P', 'N', 'G'};
  static constexpr unsigned char exr_sig[4] = {0x76, 0x2f, 0x31, 0x01};
  if (bytes.size() >= 4 && std::memcmp(bytes.data(), png_sig, 4) == 0) return decode_png(bytes, where, expected, limits);
  if (bytes.size() >= 4 && std::memcmp(bytes.data(), exr_sig, 4) == 0) return decode_exr(bytes, where, expected, limits);
  throw InvalidInput(detail::message(where, bytes.empty() ? "empty file" : "not an image qs reads",
                                     bytes.empty() ? "0 bytes" : "neither a PNG nor an OpenEXR signature", expected));
}

std::vector<unsigned char> read_file_bytes(const fs::path& path) {
  const std::string text = json_strict::read_text_file(path, "PNG or OpenEXR image");
  return {text.begin(), text.end()};
}

}  // namespace qs::image
