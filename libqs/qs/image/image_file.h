#pragma once
// RGB image files: PNG (8- and 16-bit, libpng) and OpenEXR (32-bit float, OpenEXR), encoded to
// and decoded from memory. The libraries stay in the .cpp files, and so do their messages: every
// error names the file, says what is wrong in qs's words and what was expected.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace qs::image {

/// PNG bytes of width x height RGB pixels, rows top down: 8-bit channels (3 bytes a pixel) or
/// 16-bit ones (values 0..65535). Written as RGB without interlacing, an oFFs chunk (0, 0), no
/// gamma, colour-space or time chunks; zlib `level` (0..9), libpng's adaptive filters and zlib's
/// default strategy, so that the bytes depend on the pixels alone.
/// \pre width, height >= 1 and the pixel vector holds width * height * 3 values.
/// \throws InvalidInput for a size that does not match, IoError when encoding fails.
std::vector<unsigned char> encode_png(int width, int height, std::span<const std::uint8_t> rgb, int level = 6);
std::vector<unsigned char> encode_png16(int width, int height, std::span<const std::uint16_t> rgb, int level = 6);

/// OpenEXR bytes of width x height RGB pixels as 32-bit float channels R, G, B, scanline, ZIP
/// compression (16 lines a block), an empty capDate and no type attribute: the bytes depend on the
/// pixels alone. Sides up to 2^17.
/// \throws InvalidInput for a size that does not match, IoError when encoding fails.
std::vector<unsigned char> encode_exr(int width, int height, std::span<const float> rgb);

/// Decoded RGB pixels, rows top down; exactly one of the vectors holds width * height * 3 values.
struct RgbPixels {
  int width = 0, height = 0;
  int bits = 8;                      ///< 8 or 16 (PNG), 32 (EXR, float)
  std::vector<std::uint8_t> u8;      ///< bits == 8
  std::vector<std::uint16_t> u16;    ///< bits == 16
  std::vector<float> f32;            ///< bits == 32
  /// Sample i scaled to 0..1 for integer channels (c / 255, c / 65535), as stored for float.
  float normalized(std::size_t i) const;
  /// Sample i as an 8-bit value: as stored, round(c * 255 / 65535), or round(clamp(c) * 255).
  std::uint8_t to8(std::size_t i) const;
};

/// Limits that a decoder checks before it allocates: images over them are refused.
struct Limits {
  std::int64_t max_side = 1 << 17;           ///< width and height at most
  std::int64_t max_pixels = std::int64_t{1} << 28;  ///< width * height at most
};

/// What a caller expects, for messages: e.g. "an 8-bit RGB PNG (the normal map of shape 'cat',
/// written by qs-bake)".
struct Expected {
  std::string what = "an RGB image (PNG or OpenEXR)";
};

/// Decodes PNG bytes: RGB (8 or 16 bits) and palette images (expanded to 8-bit RGB) are read;
/// grey, alpha, a damaged or truncated file are refused. `where` names the file in messages.
/// \throws InvalidInput with a message that names `where`, says what is wrong and what was
/// expected.
RgbPixels decode_png(std::span<const unsigned char> bytes, const std::string& where, const Expected& expected = {},
                     const Limits& limits = {});
/// Decodes OpenEXR bytes: single-part scanline files (any compression) with channels exactly R, G,
/// B of any pixel type, read as 32-bit float; sides up to 2^17 whatever `limits` says. Tiled,
/// multi-part and deep files are refused. \throws InvalidInput as decode_png.
RgbPixels decode_exr(std::span<const unsigned char> bytes, const std::string& where, const Expected& expected = {},
                     const Limits& limits = {});
/// decode_png or decode_exr by the file's signature; anything else is refused.
/// \throws InvalidInput.
RgbPixels decode_image(std::span<const unsigned char> bytes, const std::string& where, const Expected& expected = {},
                       const Limits& limits = {});

/// The bytes of a file. \throws IoError (missing, a folder, unreadable), naming the path.
std::vector<unsigned char> read_file_bytes(const std::filesystem::path& path);

}  // namespace qs::image
