#include "qs/bake/image_io.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "qs/core/error.h"
#include "qs/image/image_file.h"

namespace qs::bake {

namespace fs = std::filesystem;

const char* to_string(ImageFormat f) {
  switch (f) {
    case ImageFormat::Png8: return "png8";
    case ImageFormat::Png16: return "png16";
    default: return "exr";
  }
}

const char* file_suffix(ImageFormat f) {
  switch (f) {
    case ImageFormat::Png8: return "_normal.png";
    case ImageFormat::Png16: return "_normal16.png";
    default: return "_normal.exr";
  }
}

std::vector<unsigned char> encode_png8(const Rgb8Image& image) {
  if (image.width < 1 || image.height < 1 || image.rgb.size() != 3 * static_cast<size_t>(image.width) * image.height)
    throw InvalidInput("encode_png8: an image of " + std::to_string(image.width) + " x " + std::to_string(image.height) +
                       " texels needs " + std::to_string(3 * static_cast<size_t>(image.width) * image.height) + " bytes");
  return qs::image::encode_png(image.width, image.height, image.rgb);
}

std::vector<unsigned char> encode_image(const NormalAtlas& atlas, ImageFormat format) {
  if (format == ImageFormat::Png8) return encode_png8(quantize8(atlas));
  if (atlas.width < 1 || atlas.height < 1 || atlas.texels.size() != 3 * static_cast<size_t>(atlas.width) * atlas.height)
    throw InvalidInput("encode_image: an atlas of " + std::to_string(atlas.width) + " x " + std::to_string(atlas.height) +
                       " texels needs " + std::to_string(3 * static_cast<size_t>(atlas.width) * atlas.height) + " values");
  if (format == ImageFormat::Png16) {
    std::vector<unsigned short> px(atlas.texels.size());
    for (size_t i = 0; i < px.size(); ++i)
      px[i] = static_cast<unsigned short>(std::lround(std::clamp(atlas.texels[i] * 0.5 + 0.5, 0.0, 1.0) * 65535.0));
    return qs::image::encode_png16(atlas.width, atlas.height, px);
  }
  std::vector<float> px(atlas.texels.size());
  for (size_t i = 0; i < px.size(); ++i) px[i] = atlas.texels[i] * 0.5f + 0.5f;
  return qs::image::encode_exr(atlas.width, atlas.height, px);
}

NormalAtlas read_normal_image(const fs::path& path) {
  const std::vector<unsigned char> bytes = qs::image::read_file_bytes(path);
  const qs::image::RgbPixels px =
      qs::image::decode_image(bytes, path.string(), {"a normal map: an RGB PNG (8- or 16-bit) or OpenEXR image"});
  NormalAtlas a;
  a.width = px.width;
  a.height = px.height;
  a.texels.resize(static_cast<size_t>(px.width) * px.height * 3);
  for (size_t i = 0; i < a.texels.size(); ++i) a.texels[i] = px.normalized(i) * 2.0f - 1.0f;
  return a;
}

Rgb8Image read_rgb8(const fs::path& path) {
  const std::vector<unsigned char> bytes = qs::image::read_file_bytes(path);
  qs::image::RgbPixels px = qs::image::decode_png(bytes, path.string(), {"an 8-bit RGB PNG"});
  Rgb8Image img;
  img.width = px.width;
  img.height = px.height;
  if (px.bits == 8) {
    img.rgb = std::move(px.u8);
  } else {
    img.rgb.resize(static_cast<size_t>(px.width) * px.height * 3);
    for (size_t i = 0; i < img.rgb.size(); ++i) img.rgb[i] = px.to8(i);
  }
  return img;
}

}  // namespace qs::bake
