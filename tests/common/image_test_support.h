#pragma once
// PNG files made by hand for the image readers' tests (no image library involved): any IHDR,
// stored (uncompressed) deflate blocks, chunks to damage; and the phrases of libpng's and
// OpenEXR's own messages that qs's messages must never quote.

#include <cstdint>
#include <string>
#include <vector>

namespace qs::test {

inline std::uint32_t png_crc32(const std::string& s) {
  std::uint32_t c = 0xFFFFFFFFu;
  for (unsigned char ch : s) {
    c ^= ch;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return c ^ 0xFFFFFFFFu;
}

inline void put_be32(std::string& s, std::uint32_t x) {
  for (int k = 24; k >= 0; k -= 8) s += static_cast<char>(x >> k);
}

/// zlib stream of `raw` in stored blocks.
inline std::string zlib_stored(const std::string& raw) {
  std::string z{char(0x78), char(0x01)};
  size_t at = 0;
  do {
    const size_t n = std::min<size_t>(raw.size() - at, 65535);
    const bool last = at + n == raw.size();
    z += static_cast<char>(last ? 1 : 0);
    z += static_cast<char>(n & 0xFF);
    z += static_cast<char>(n >> 8);
    z += static_cast<char>(~n & 0xFF);
    z += static_cast<char>((~n >> 8) & 0xFF);
    z += raw.substr(at, n);
    at += n;
  } while (at < raw.size());
  std::uint32_t a = 1, b = 0;
  for (unsigned char c : raw) {
    a = (a + c) % 65521;
    b = (b + a) % 65521;
  }
  put_be32(z, (b << 16) | a);
  return z;
}

inline void png_chunk(std::string& png, const std::string& type, const std::string& data) {
  put_be32(png, static_cast<std::uint32_t>(data.size()));
  png += type + data;
  put_be32(png, png_crc32(type + data));
}

/// A PNG of the given IHDR whose rows (filter byte 0 each) hold `samples` bytes a row, taken from
/// `fill` cyclically; `plte` adds a PLTE chunk (palette images).
inline std::string make_png(int w, int h, int depth, int color, const std::string& fill = "\x80\x80\xff",
                            const std::string& plte = "") {
  const int channels = color == 2 ? 3 : color == 6 ? 4 : color == 4 ? 2 : 1;
  const size_t row = (static_cast<size_t>(w) * channels * depth + 7) / 8;
  std::string raw;
  size_t k = 0;
  for (int y = 0; y < h; ++y) {
    raw += '\0';
    for (size_t i = 0; i < row; ++i) raw += fill[k++ % fill.size()];
  }
  std::string png = "\x89PNG\r\n\x1a\n";
  std::string ihdr;
  put_be32(ihdr, static_cast<std::uint32_t>(w));
  put_be32(ihdr, static_cast<std::uint32_t>(h));
  ihdr += std::string{static_cast<char>(depth), static_cast<char>(color), 0, 0, 0};
  png_chunk(png, "IHDR", ihdr);
  if (!plte.empty()) png_chunk(png, "PLTE", plte);
  png_chunk(png, "IDAT", zlib_stored(raw));
  png_chunk(png, "IEND", "");
  return png;
}

/// Offset of the first chunk of `type` (its length field), or npos.
inline size_t find_chunk(const std::string& png, const std::string& type) {
  size_t p = 8;
  while (p + 8 <= png.size()) {
    const std::uint32_t n = (std::uint32_t(std::uint8_t(png[p])) << 24) | (std::uint32_t(std::uint8_t(png[p + 1])) << 16) |
                            (std::uint32_t(std::uint8_t(png[p + 2])) << 8) | std::uint8_t(png[p + 3]);
    if (png.compare(p + 4, 4, type) == 0) return p;
    p += 12 + n;
  }
  return std::string::npos;
}

/// Phrases of libpng's, zlib's and OpenEXR's messages (and OpenImageIO's before them).
inline const std::vector<std::string>& library_phrases() {
  static const std::vector<std::string> p = {
      "libpng", "CRC error", "Read Error", "Read error", "hit end of file", "IDAT:", "IHDR:", "Not enough image data",
      "Too much image data", "incorrect header check", "invalid distance", "invalid block", "invalid code",
      "invalid stored", "invalid literal", "Invalid IHDR", "Not a PNG", "PNG read", "Cannot read",
      "Unexpected end", "Error reading", "end of data", "Iex", "magic number", "Imf", "OpenImageIO", "geterror",
      "unknown compression", "Cannot open"};
  return p;
}

/// The first library phrase that `message` quotes, or "".
inline std::string quoted_library_phrase(const std::string& message) {
  for (const std::string& p : library_phrases())
    if (message.find(p) != std::string::npos) return p;
  return "";
}

}  // namespace qs::test
