#include "qs/bake/image_io.h"

#include <unistd.h>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <string>

#include "qs/core/error.h"

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

namespace {

// OpenImageIO's error text can span lines (libpng's own message appended): one line for qs's.
std::string one_line(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  for (char& c : s)
    if (c == '\n') c = ';';
  return s;
}

// Encodes width x height x 3 pixels of `type` into the bytes of a file of extension `ext`:
// through an in-memory proxy when the writer supports one, else through a temporary file.
std::vector<unsigned char> encode(const std::string& ext, int width, int height, OIIO::TypeDesc type, const void* pixels,
                                  const std::string& compression) {
  const std::string name = "normal-map." + ext;
  const auto fail = [&](const std::string& why) -> std::vector<unsigned char> {
    throw IoError("cannot encode the " + std::to_string(width) + " x " + std::to_string(height) + " normal map as " + ext +
                  " (" + why + ")");
  };
  OIIO::ImageSpec spec(width, height, 3, type);
  if (!compression.empty()) spec.attribute("compression", compression);
  // OpenImageIO stamps an EXR with the time of writing (capDate) unless given one: an empty one
  // keeps the file the same from run to run.
  if (ext == "exr") spec.attribute("DateTime", "");
  {
    auto probe = OIIO::ImageOutput::create(name);
    if (!probe) return fail("OpenImageIO has no " + ext + " writer: " + OIIO::geterror());
    if (probe->supports("ioproxy")) {
      OIIO::Filesystem::IOVecOutput proxy;
      auto out = OIIO::ImageOutput::create(name, &proxy);
      if (!out || !out->open(name, spec)) return fail(out ? out->geterror() : OIIO::geterror());
      const bool wrote = out->write_image(type, pixels);
      const bool closed = out->close();
      if (!wrote || !closed) return fail(out->geterror());
      return proxy.buffer();
    }
  }
  const fs::path tmp = fs::temp_directory_path() / ("qs-bake-" + std::to_string(::getpid()) + "-" + name);
  std::vector<unsigned char> bytes;
  std::string why;
  {
    auto out = OIIO::ImageOutput::create(tmp.string());
    if (!out || !out->open(tmp.string(), spec)) {
      why = out ? out->geterror() : OIIO::geterror();
    } else {
      const bool wrote = out->write_image(type, pixels);
      if (!out->close() || !wrote) why = out->geterror();
    }
  }
  if (why.empty()) {
    std::ifstream in(tmp, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    if (!in.good() && !in.eof()) why = "cannot read the temporary file back";
  }
  std::error_code ec;
  fs::remove(tmp, ec);
  if (!why.empty()) return fail(why);
  return bytes;
}

}  // namespace

std::vector<unsigned char> encode_png8(const Rgb8Image& image) {
  if (image.width < 1 || image.height < 1 || image.rgb.size() != 3 * static_cast<size_t>(image.width) * image.height)
    throw InvalidInput("encode_png8: an image of " + std::to_string(image.width) + " x " + std::to_string(image.height) +
                       " texels needs " + std::to_string(3 * static_cast<size_t>(image.width) * image.height) + " bytes");
  return encode("png", image.width, image.height, OIIO::TypeDesc::UINT8, image.rgb.data(), "");
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
    return encode("png", atlas.width, atlas.height, OIIO::TypeDesc::UINT16, px.data(), "");
  }
  std::vector<float> px(atlas.texels.size());
  for (size_t i = 0; i < px.size(); ++i) px[i] = atlas.texels[i] * 0.5f + 0.5f;
  return encode("exr", atlas.width, atlas.height, OIIO::TypeDesc::FLOAT, px.data(), "zip");
}

namespace {

// Reads the first three channels as `type`. Returns width, height through the spec.
template <class T>
std::vector<T> read_pixels(const fs::path& path, OIIO::TypeDesc type, int& width, int& height) {
  if (!fs::exists(path)) throw IoError(path.string() + ": no such file");
  auto in = OIIO::ImageInput::open(path.string());
  if (!in) throw IoError(path.string() + ": cannot read the image (" + one_line(OIIO::geterror()) + ")");
  const OIIO::ImageSpec& spec = in->spec();
  if (spec.nchannels != 3)
    throw InvalidInput(path.string() + ": " + std::to_string(spec.nchannels) + " channels, a normal map has 3 (RGB)");
  width = spec.width;
  height = spec.height;
  std::vector<T> px(static_cast<size_t>(width) * height * 3);
  if (!in->read_image(0, 0, 0, 3, type, px.data()))
    throw IoError(path.string() + ": cannot read the pixels (" + one_line(in->geterror()) + ")");
  in->close();
  return px;
}

}  // namespace

NormalAtlas read_normal_image(const fs::path& path) {
  NormalAtlas a;
  std::vector<float> px = read_pixels<float>(path, OIIO::TypeDesc::FLOAT, a.width, a.height);
  for (float& x : px) x = x * 2.0f - 1.0f;
  a.texels = std::move(px);
  return a;
}

Rgb8Image read_rgb8(const fs::path& path) {
  Rgb8Image img;
  img.rgb = read_pixels<unsigned char>(path, OIIO::TypeDesc::UINT8, img.width, img.height);
  return img;
}

}  // namespace qs::bake
