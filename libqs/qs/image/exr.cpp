// OpenEXR through the OpenEXR library, to and from memory. The library's exceptions are caught
// here and turned into qs's messages; their text is never shown.
#include <Iex.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStandardAttributes.h>
#include <ImfStringAttribute.h>
#include <ImfTestFile.h>
#include <ImfVersion.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <mutex>

#include "qs/core/error.h"
#include "qs/image/image_file.h"
#include "qs/image/image_file_detail.h"

namespace qs::image {
namespace {

constexpr int kMaxSide = 1 << 17;  // OpenEXR's header check: no window side over this

class MemoryOStream : public Imf::OStream {
 public:
  MemoryOStream() : Imf::OStream("memory") {}
  void write(const char c[], int n) override {
    const size_t end = pos_ + static_cast<size_t>(n);
    if (end > bytes.size()) bytes.resize(end);
    std::memcpy(bytes.data() + pos_, c, static_cast<size_t>(n));
    pos_ = end;
  }
  uint64_t tellp() override { return pos_; }
  void seekp(uint64_t pos) override { pos_ = static_cast<size_t>(pos); }
  std::vector<unsigned char> bytes;

 private:
  size_t pos_ = 0;
};

class MemoryIStream : public Imf::IStream {
 public:
  explicit MemoryIStream(std::span<const unsigned char> bytes) : Imf::IStream("memory"), bytes_(bytes) {}
  bool read(char c[], int n) override {
    if (n < 0 || pos_ > bytes_.size() || bytes_.size() - pos_ < static_cast<size_t>(n)) {
      truncated = true;
      throw Iex::InputExc("end of data");
    }
    std::memcpy(c, bytes_.data() + pos_, static_cast<size_t>(n));
    pos_ += static_cast<size_t>(n);
    return pos_ < bytes_.size();
  }
  uint64_t tellg() override { return pos_; }
  void seekg(uint64_t pos) override { pos_ = static_cast<size_t>(std::min<uint64_t>(pos, bytes_.size() + 1)); }
  bool truncated = false;

 private:
  std::span<const unsigned char> bytes_;
  size_t pos_ = 0;
};

}  // namespace

std::vector<unsigned char> encode_exr(int width, int height, std::span<const float> rgb) {
  if (width < 1 || height < 1 || rgb.size() != static_cast<size_t>(width) * height * 3)
    throw InvalidInput("OpenEXR encoding: " + std::to_string(rgb.size()) + " values for " + std::to_string(width) +
                       " x " + std::to_string(height) + " RGB pixels (expected width * height * 3)");
  try {
    Imf::Header header(width, height);
    header.compression() = Imf::ZIP_COMPRESSION;
    for (const char* name : {"R", "G", "B"}) header.channels().insert(name, Imf::Channel(Imf::FLOAT));
    header.insert("capDate", Imf::StringAttribute(""));
    MemoryOStream stream;
    {
      Imf::OutputFile file(stream, header, 0);
      Imf::FrameBuffer fb;
      const size_t xs = 3 * sizeof(float), ys = xs * static_cast<size_t>(width);
      auto* base = const_cast<char*>(reinterpret_cast<const char*>(rgb.data()));
      fb.insert("R", Imf::Slice(Imf::FLOAT, base, xs, ys));
      fb.insert("G", Imf::Slice(Imf::FLOAT, base + sizeof(float), xs, ys));
      fb.insert("B", Imf::Slice(Imf::FLOAT, base + 2 * sizeof(float), xs, ys));
      file.setFrameBuffer(fb);
      file.writePixels(height);
    }
    return std::move(stream.bytes);
  } catch (const std::bad_alloc&) {
    throw IoError("cannot encode the " + std::to_string(width) + " x " + std::to_string(height) +
                  " OpenEXR image (out of memory)");
  } catch (const std::exception&) {
    throw IoError("cannot encode the " + std::to_string(width) + " x " + std::to_string(height) +
                  " OpenEXR image (the OpenEXR encoder failed)");
  }
}

RgbPixels decode_exr(std::span<const unsigned char> bytes, const std::string& where, const Expected& expected,
                     const Limits& limits) {
  const auto fail = [&](const std::string& what, const std::string& why) -> RgbPixels {
    throw InvalidInput(detail::message(where, what, why, expected));
  };
  if (bytes.empty()) return fail("empty file", "0 bytes");
  if (bytes.size() < 4 || !Imf::isImfMagic(reinterpret_cast<const char*>(bytes.data())))
    return fail("not an OpenEXR file", "its first bytes are not OpenEXR's signature");
  // Tiled, multi-part and deep files (version flags 0x200, 0x1000, 0x800): qs writes none, and
  // their offset tables and tile buffers are sized by the header alone.
  if (bytes.size() < 8) return fail("the OpenEXR file ends early", "truncated file: its header is incomplete");
  if (bytes[5] & 0x1A)
    return fail("not a scanline OpenEXR image",
                std::string((bytes[5] & 0x10) ? "a multi-part" : (bytes[5] & 0x08) ? "a deep" : "a tiled") +
                    " file, qs reads single-part scanline files");
  // The header's attributes, walked before OpenEXR reads them: it allocates an unknown
  // attribute's declared size (and a preview's pixels) before it reads the bytes, and reads a
  // known type's value by the type, not by the declared size; every size must therefore fit in
  // the file and agree with its type.
  {
    const auto incomplete = [&] { return fail("the OpenEXR file ends early", "truncated file: its header is incomplete"); };
    const auto damaged = [&] { return fail("damaged OpenEXR file", "its header cannot be decoded"); };
    const auto le32 = [&](size_t at) {
      return std::uint32_t{bytes[at]} | (std::uint32_t{bytes[at + 1]} << 8) | (std::uint32_t{bytes[at + 2]} << 16) |
             (std::uint32_t{bytes[at + 3]} << 24);
    };
    // A NUL-terminated name of at most 255 bytes at p: its length, or -1 (past the end), -2 (too long).
    const auto name_at = [&](size_t p) -> long {
      const size_t end = std::min(bytes.size(), p + 256);
      const auto* nul = std::find(bytes.data() + p, bytes.data() + end, 0);
      if (nul != bytes.data() + end) return nul - (bytes.data() + p);
      return end == bytes.size() ? -1 : -2;
    };
    static const std::pair<const char*, std::uint32_t> fixed[] = {
        {"box2i", 16}, {"box2f", 16}, {"chromaticities", 32}, {"compression", 1}, {"double", 8}, {"envmap", 1},
        {"float", 4}, {"int", 4}, {"keycode", 28}, {"lineOrder", 1}, {"m33f", 36}, {"m33d", 72}, {"m44f", 64},
        {"m44d", 128}, {"rational", 8}, {"tiledesc", 9}, {"timecode", 8}, {"v2i", 8}, {"v2f", 8}, {"v2d", 16},
        {"v3i", 12}, {"v3f", 12}, {"v3d", 24}, {"deepImageState", 1}};
    for (size_t p = 8;;) {
      if (p >= bytes.size()) return incomplete();
      if (bytes[p] == 0) break;
      const long name_len = name_at(p);
      if (name_len < 0) return name_len == -1 ? incomplete() : damaged();
      p += static_cast<size_t>(name_len) + 1;
      const long type_len = name_at(p);
      if (type_len < 0) return type_len == -1 ? incomplete() : damaged();
      const std::string type(reinterpret_cast<const char*>(bytes.data() + p), static_cast<size_t>(type_len));
      p += static_cast<size_t>(type_len) + 1;
      if (bytes.size() - p < 4) return incomplete();
      const std::uint32_t size = le32(p);
      p += 4;
      if (size > 0x7fffffffu) return damaged();
      if (size > bytes.size() - p) return incomplete();
      for (const auto& [t, n] : fixed)
        if (type == t && size != n) return damaged();
      if (type == "chlist") {  // channel records up to an empty name: exactly `size` bytes
        size_t q = p;
        for (;;) {
          if (q >= p + size) return damaged();
          if (bytes[q] == 0) {
            ++q;
            break;
          }
          const long n = name_at(q);
          if (n < 0) return n == -1 ? incomplete() : damaged();
          q += static_cast<size_t>(n) + 1 + 16;
        }
        if (q != p + size) return damaged();
      }
      if (type == "preview" && (size < 8 || std::uint64_t{le32(p)} * le32(p + 4) * 4 + 8 != size)) return damaged();
      p += size;
    }
  }
  // OpenEXR's own check of a header's window, before it allocates anything (once, for every
  // thread: the bound is global in OpenEXR).
  static std::once_flag bound;
  std::call_once(bound, [] {
    Imf::Header::setMaxImageSize(kMaxSide, kMaxSide);
    Imf::Header::setMaxTileSize(1, 1);
  });
  const std::int64_t max_side = std::clamp<std::int64_t>(limits.max_side, 1, kMaxSide);
  MemoryIStream stream(bytes);
  RgbPixels out;
  std::string size_words = "its header";
  bool header_read = false;
  try {
    Imf::InputFile file(stream, 0);
    header_read = true;
    const Imf::Header& header = file.header();
    const Imath::Box2i dw = header.dataWindow();
    const std::int64_t w = std::int64_t{dw.max.x} - dw.min.x + 1, h = std::int64_t{dw.max.y} - dw.min.y + 1;
    size_words = std::to_string(w) + " x " + std::to_string(h);
    if (w < 1 || h < 1 || w > max_side || h > max_side)
      return fail("image too large or empty", "a data window of " + size_words + " pixels");
    if (w * h > limits.max_pixels)
      return fail("image too large",
                  size_words + " pixels, over the " + std::to_string(limits.max_pixels) + " pixels qs reads");
    std::string names;
    int count = 0;
    for (auto it = header.channels().begin(); it != header.channels().end(); ++it, ++count)
      names += std::string(count ? ", " : "") + it.name();
    const Imf::ChannelList& ch = header.channels();
    if (count != 3 || !ch.findChannel("R") || !ch.findChannel("G") || !ch.findChannel("B"))
      return fail("not an RGB image", std::to_string(count) + " channels (" + names + ")");
    for (const char* c : {"R", "G", "B"})
      if (ch.findChannel(c)->xSampling != 1 || ch.findChannel(c)->ySampling != 1)
        return fail("not an RGB image", "subsampled channels");
    // Compression expands at most a few thousand times: a file far shorter than its pixels is cut
    // short, and is refused before the pixels are allocated.
    if (static_cast<std::uint64_t>(w * h) * 12 > 4096 * static_cast<std::uint64_t>(bytes.size()) + (1u << 20))
      return fail("the OpenEXR file ends early",
                  "truncated file: " + std::to_string(bytes.size()) + " bytes cannot hold " + size_words + " pixels");
    out.width = static_cast<int>(w);
    out.height = static_cast<int>(h);
    out.bits = 32;
    out.f32.assign(static_cast<size_t>(w * h) * 3, 0.0f);
    Imf::FrameBuffer fb;
    const size_t xs = 3 * sizeof(float), ys = xs * static_cast<size_t>(w);
    char* base = reinterpret_cast<char*>(out.f32.data());
    fb.insert("R", Imf::Slice::Make(Imf::FLOAT, base, dw, xs, ys));
    fb.insert("G", Imf::Slice::Make(Imf::FLOAT, base + sizeof(float), dw, xs, ys));
    fb.insert("B", Imf::Slice::Make(Imf::FLOAT, base + 2 * sizeof(float), dw, xs, ys));
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
  } catch (const qs::Error&) {
    throw;
  } catch (const std::bad_alloc&) {
    throw IoError(where + ": out of memory while reading the OpenEXR file");
  } catch (const std::exception&) {
    if (stream.truncated)
      return fail("the OpenEXR file ends early", header_read ? "truncated file; its header says " + size_words + " RGB"
                                                               : "truncated file: its header is incomplete");
    if (!header_read) return fail("damaged OpenEXR file", "its header cannot be decoded");
    return fail("damaged OpenEXR file", "its pixel data does not decode to " + size_words + " pixels");
  }
  return out;
}

}  // namespace qs::image
