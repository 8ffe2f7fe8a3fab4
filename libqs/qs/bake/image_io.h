#pragma once
// Normal-map files, through qs::image (libpng, OpenEXR). Every format stores x * 0.5 + 0.5 per
// channel, RGB, linear: no sRGB or gamma tag is written.

#include <filesystem>
#include <vector>

#include "qs/bake/bake.h"

namespace qs::bake {

enum class ImageFormat { Png8, Png16, Exr };
const char* to_string(ImageFormat f);   ///< "png8", "png16", "exr"
const char* file_suffix(ImageFormat f); ///< "_normal.png", "_normal16.png", "_normal.exr"

/// The encoded file: PNG 8-bit from quantize8's values, PNG 16-bit (rounded to 0..65535), or
/// OpenEXR with 32-bit float channels (ZIP compressed). \throws IoError when encoding fails.
std::vector<unsigned char> encode_png8(const Rgb8Image& image);
std::vector<unsigned char> encode_image(const NormalAtlas& atlas, ImageFormat format);

/// Reads a normal-map file of any of these formats back as vectors (c * 2 - 1 per channel, not
/// normalized). \throws IoError for a missing or unreadable file, InvalidInput for one that is
/// damaged, truncated, not a PNG or OpenEXR image, or not RGB (the message names the file).
NormalAtlas read_normal_image(const std::filesystem::path& path);
/// Reads an RGB PNG as 8-bit (a PNG written by encode_png8; 16-bit ones rounded). \throws IoError,
/// InvalidInput as read_normal_image.
Rgb8Image read_rgb8(const std::filesystem::path& path);

}  // namespace qs::bake
