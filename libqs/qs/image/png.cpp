// PNG through libpng. libpng reports errors by longjmp: the functions that call setjmp hold no
// object with a destructor, and the callbacks record what happened in plain structs. libpng's
// message text is only classified, never shown.
#include <png.h>
#include <zlib.h>

#include <algorithm>
#include <bit>
#include <csetjmp>
#include <cstring>
#include <string>

#include "qs/core/error.h"
#include "qs/image/image_file.h"
#include "qs/image/image_file_detail.h"

namespace qs::image {
namespace {

// ---- writing ----

struct WriteCtx {
  std::vector<unsigned char>* out = nullptr;
  bool out_of_memory = false;
};

void write_fn(png_structp png, png_bytep data, size_t n) {
  auto* c = static_cast<WriteCtx*>(png_get_io_ptr(png));
  try {
    c->out->insert(c->out->end(), data, data + n);
  } catch (...) {
    c->out_of_memory = true;
  }
  if (c->out_of_memory) png_error(png, "out of memory");
}
void flush_fn(png_structp) {}
[[noreturn]] void error_fn(png_structp png, png_const_charp message) {
  if (auto* m = static_cast<char*>(png_get_error_ptr(png))) {
    std::strncpy(m, message ? message : "", detail::kMessageSize - 1);
    m[detail::kMessageSize - 1] = '\0';
  }
  png_longjmp(png, 1);
}
void warning_fn(png_structp, png_const_charp) {}  // ancillary-chunk trouble: skipped, not printed

// Returns false when libpng failed (the reason in `message`). Rows are `row_bytes` apart.
bool write_png_rows(WriteCtx* ctx, char* message, int width, int height, int depth, const unsigned char* rows,
                    size_t row_bytes, int level) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, message, error_fn, warning_fn);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_set_write_fn(png, ctx, write_fn, flush_fn);
  png_set_compression_level(png, level);
  png_set_compression_strategy(png, Z_DEFAULT_STRATEGY);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), depth, PNG_COLOR_TYPE_RGB,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_oFFs(png, info, 0, 0, PNG_OFFSET_PIXEL);
  png_write_info(png, info);
  if (depth == 16 && std::endian::native == std::endian::little) png_set_swap(png);
  for (int y = 0; y < height; ++y) png_write_row(png, rows + static_cast<size_t>(y) * row_bytes);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

std::vector<unsigned char> encode(int width, int height, int depth, const void* pixels, size_t count, int level) {
  if (width < 1 || height < 1 || count != static_cast<size_t>(width) * height * 3)
    throw InvalidInput("PNG encoding: " + std::to_string(count) + " values for " + std::to_string(width) + " x " +
                       std::to_string(height) + " RGB pixels (expected width * height * 3)");
  std::vector<unsigned char> out;
  WriteCtx ctx{&out};
  char message[detail::kMessageSize] = "";
  const size_t row_bytes = static_cast<size_t>(width) * 3 * (depth / 8);
  if (!write_png_rows(&ctx, message, width, height, depth, static_cast<const unsigned char*>(pixels), row_bytes,
                      std::clamp(level, 0, 9)))
    throw IoError("cannot encode the " + std::to_string(width) + " x " + std::to_string(height) + " RGB " +
                  std::to_string(depth) + "-bit PNG (" + (ctx.out_of_memory ? "out of memory" : "the PNG encoder failed") +
                  ")");
  return out;
}

// ---- reading ----

enum class Failure { None, Truncated, Crc, Header, TooLarge, Data, Other, OutOfMemory };

struct ReadCtx {
  const unsigned char* data = nullptr;
  size_t size = 0, pos = 0;
  bool truncated = false;
  char message[detail::kMessageSize] = "";
};

void read_fn(png_structp png, png_bytep out, size_t n) {
  auto* c = static_cast<ReadCtx*>(png_get_io_ptr(png));
  if (c->size - c->pos < n) {
    c->truncated = true;
    png_error(png, "truncated");
  }
  std::memcpy(out, c->data + c->pos, n);
  c->pos += n;
}

Failure classify(const ReadCtx& c) {
  if (c.truncated) return Failure::Truncated;
  const std::string m = c.message;
  if (m.find("CRC") != std::string::npos) return Failure::Crc;
  if (m.find("user limit") != std::string::npos) return Failure::TooLarge;
  if (m.find("IHDR") != std::string::npos || m.find("Invalid") == 0 || m.find("Image width") == 0 ||
      m.find("Image height") == 0)
    return Failure::Header;
  if (m.find("IDAT") != std::string::npos || m.find("image data") != std::string::npos ||
      m.find("zlib") != std::string::npos || m.find("ompress") != std::string::npos ||
      m.find("distance") != std::string::npos || m.find("code") != std::string::npos)
    return Failure::Data;
  if (m.find("memory") != std::string::npos) return Failure::OutOfMemory;
  return Failure::Other;
}

struct Header {
  png_uint_32 width = 0, height = 0;
  int depth = 0, color = 0, interlace = 0;
  int out_channels = 0, out_depth = 0;
  size_t out_row_bytes = 0;
};

// Reads the signature and the chunks before the pixels, sets the transforms.
bool read_header(ReadCtx* ctx, png_structp png, png_infop info, Header* h, png_uint_32 max_side) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_set_read_fn(png, ctx, read_fn);
  png_set_user_limits(png, max_side, max_side);
  png_set_chunk_malloc_max(png, 8u << 20);
  png_read_info(png, info);
  png_get_IHDR(png, info, &h->width, &h->height, &h->depth, &h->color, &h->interlace, nullptr, nullptr);
  if (h->color == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (h->depth == 16 && std::endian::native == std::endian::little) png_set_swap(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  h->out_channels = png_get_channels(png, info);
  h->out_depth = png_get_bit_depth(png, info);
  h->out_row_bytes = png_get_rowbytes(png, info);
  return true;
}

bool read_rows(ReadCtx* ctx, png_structp png, png_infop info, unsigned char* pixels, size_t row_bytes,
               png_uint_32 height, int passes) {
  if (setjmp(png_jmpbuf(png))) return false;
  (void)ctx;
  for (int p = 0; p < passes; ++p)
    for (png_uint_32 y = 0; y < height; ++y) png_read_row(png, pixels + y * row_bytes, nullptr);
  png_read_end(png, nullptr);
  (void)info;
  return true;
}

std::string depth_words(int channels, int depth, int color) {
  std::string kind = color == PNG_COLOR_TYPE_GRAY          ? "grey"
                     : color == PNG_COLOR_TYPE_GRAY_ALPHA  ? "grey with alpha"
                     : color == PNG_COLOR_TYPE_RGB_ALPHA   ? "RGB with alpha"
                     : color == PNG_COLOR_TYPE_PALETTE     ? (channels == 4 ? "palette with transparency" : "palette")
                                                           : "RGB";
  return kind + " " + std::to_string(depth) + "-bit";
}

}  // namespace

std::vector<unsigned char> encode_png(int width, int height, std::span<const std::uint8_t> rgb, int level) {
  return encode(width, height, 8, rgb.data(), rgb.size(), level);
}

std::vector<unsigned char> encode_png16(int width, int height, std::span<const std::uint16_t> rgb, int level) {
  return encode(width, height, 16, rgb.data(), rgb.size(), level);
}

RgbPixels decode_png(std::span<const unsigned char> bytes, const std::string& where, const Expected& expected,
                     const Limits& limits) {
  const auto fail = [&](const std::string& what, const std::string& why) -> RgbPixels {
    throw InvalidInput(detail::message(where, what, why, expected));
  };
  if (bytes.empty()) return fail("empty file", "0 bytes");
  if (bytes.size() < 8 || png_sig_cmp(bytes.data(), 0, 8) != 0) {
    if (bytes.size() >= 8 && png_sig_cmp(bytes.data(), 0, 4) == 0)
      return fail("not a PNG file", "its signature is damaged (a text-mode transfer changes line ends)");
    return fail("not a PNG file", "its first bytes are not PNG's signature");
  }
  const png_uint_32 max_side =
      static_cast<png_uint_32>(std::clamp<std::int64_t>(limits.max_side, 1, PNG_USER_WIDTH_MAX));
  if (bytes.size() >= 24 && std::memcmp(bytes.data() + 12, "IHDR", 4) == 0) {  // libpng says only "invalid"
    const auto be32 = [&](size_t at) {
      return (png_uint_32{bytes[at]} << 24) | (png_uint_32{bytes[at + 1]} << 16) | (png_uint_32{bytes[at + 2]} << 8) |
             bytes[at + 3];
    };
    const png_uint_32 w = be32(16), h = be32(20);
    if ((w > max_side || h > max_side) && w <= PNG_UINT_31_MAX && h <= PNG_UINT_31_MAX)
      return fail("image too large", std::to_string(w) + " x " + std::to_string(h) + " pixels, a side over the " +
                                         std::to_string(max_side) + " pixels qs reads");
  }
  ReadCtx ctx;
  ctx.data = bytes.data();
  ctx.size = bytes.size();
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, ctx.message, error_fn, warning_fn);
  if (!png) throw IoError(where + ": cannot start the PNG decoder (out of memory)");
  png_infop info = png_create_info_struct(png);
  if (!info) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    throw IoError(where + ": cannot start the PNG decoder (out of memory)");
  }
  struct Destroy {
    png_structp* png;
    png_infop* info;
    ~Destroy() { png_destroy_read_struct(png, info, nullptr); }
  } destroy{&png, &info};

  Header h;
  const bool header_read = read_header(&ctx, png, info, &h, max_side);
  const std::string size_words = std::to_string(h.width) + " x " + std::to_string(h.height);
  if (!header_read) {
    switch (classify(ctx)) {
      case Failure::Truncated: return fail("the PNG ends early", "truncated file: it ends before its pixel data");
      case Failure::Crc: return fail("damaged PNG", "a chunk's checksum does not match its bytes");
      case Failure::TooLarge:
        return fail("image too large", "a side over " + std::to_string(max_side) + " pixels, the most qs reads");
      case Failure::Header: return fail("damaged PNG", "its header chunk (IHDR) is malformed");
      case Failure::OutOfMemory: throw IoError(where + ": out of memory while reading the PNG's header");
      default: return fail("damaged PNG", "its chunks cannot be decoded");
    }
  }
  if (h.out_channels != 3 || (h.out_depth != 8 && h.out_depth != 16))
    return fail("not an RGB image", "a " + size_words + " " + depth_words(h.out_channels, h.depth, h.color) + " PNG");
  const std::int64_t pixels = std::int64_t{h.width} * h.height;
  if (pixels > limits.max_pixels)
    return fail("image too large", size_words + " pixels, over the " + std::to_string(limits.max_pixels) +
                                       " pixels qs reads");
  // Deflate expands at most about 1032 times: a file far shorter than its pixels is cut short,
  // and is refused before the pixels are allocated.
  const std::uint64_t row_in = (std::uint64_t{h.width} * (h.color == PNG_COLOR_TYPE_PALETTE ? 1 : 3) * h.depth + 7) / 8;
  const std::uint64_t raw = std::uint64_t{h.height} * (row_in + 1);
  if (raw > 1100 * static_cast<std::uint64_t>(bytes.size()) + 65536)
    return fail("the PNG ends early",
                "truncated file: " + std::to_string(bytes.size()) + " bytes cannot hold " + size_words + " pixels");

  RgbPixels out;
  out.width = static_cast<int>(h.width);
  out.height = static_cast<int>(h.height);
  out.bits = h.out_depth;
  unsigned char* dst = nullptr;
  try {
    if (h.out_depth == 8) {
      out.u8.assign(static_cast<size_t>(pixels) * 3, 0);
      dst = out.u8.data();
    } else {
      out.u16.assign(static_cast<size_t>(pixels) * 3, 0);
      dst = reinterpret_cast<unsigned char*>(out.u16.data());
    }
  } catch (const std::bad_alloc&) {
    throw IoError(where + ": out of memory for " + size_words + " pixels");
  }
  const int passes = h.interlace == PNG_INTERLACE_NONE ? 1 : 7;
  if (!read_rows(&ctx, png, info, dst, h.out_row_bytes, h.height, passes)) {
    const std::string header = "its header says " + size_words + " RGB " + std::to_string(h.out_depth) + "-bit";
    switch (classify(ctx)) {
      case Failure::Truncated: return fail("the PNG ends early", "truncated file; " + header);
      case Failure::Crc: return fail("damaged PNG", "a chunk's checksum does not match its bytes; " + header);
      case Failure::OutOfMemory: throw IoError(where + ": out of memory while decoding the PNG");
      default: return fail("damaged PNG", "its compressed pixel data does not decode to " + size_words + " pixels");
    }
  }
  return out;
}

}  // namespace qs::image
