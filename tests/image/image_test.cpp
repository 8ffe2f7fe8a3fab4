// qs::image: PNG and OpenEXR encoded and decoded exactly, the bytes qs writes, and damaged files
// refused with messages that name the file, say what was expected and quote no library.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfOutputFile.h>
#include <half.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>

#include "../common/image_test_support.h"
#include "qs/core/error.h"
#include "qs/image/image_file.h"

namespace {

namespace fs = std::filesystem;
using qs::image::decode_exr;
using qs::image::decode_image;
using qs::image::decode_png;
using qs::image::RgbPixels;
using ::testing::HasSubstr;
using ::testing::StartsWith;

std::span<const unsigned char> bytes_of(const std::string& s) {
  return {reinterpret_cast<const unsigned char*>(s.data()), s.size()};
}
std::string str(const std::vector<unsigned char>& v) { return {v.begin(), v.end()}; }

// The message of the InvalidInput that `f` throws ("" when it throws none or another kind).
std::string invalid_input(const std::function<void()>& f) {
  try {
    f();
  } catch (const qs::InvalidInput& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("unexpected exception: ") + e.what();
  }
  return "no exception";
}

// A refusal in qs's words: names the file, says what was expected, one line, no library text.
void expect_our_words(const std::string& m, const std::string& where, const std::string& what) {
  EXPECT_THAT(m, StartsWith(where + ": ")) << m;
  EXPECT_THAT(m, HasSubstr(what)) << m;
  EXPECT_THAT(m, HasSubstr("expected an RGB test image")) << m;
  EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  EXPECT_EQ(qs::test::quoted_library_phrase(m), "") << m;
}

const qs::image::Expected kExpected{"an RGB test image"};

std::vector<std::uint8_t> ramp8(int w, int h) {
  std::vector<std::uint8_t> v(static_cast<size_t>(w) * h * 3);
  std::mt19937 rng(7);
  for (auto& x : v) x = static_cast<std::uint8_t>(rng() & 0xFF);
  return v;
}

std::string small_exr(int w, int h) {
  std::vector<float> px(static_cast<size_t>(w) * h * 3);
  for (size_t i = 0; i < px.size(); ++i) px[i] = 0.001f * static_cast<float>(i) - 0.25f;
  return str(qs::image::encode_exr(w, h, px));
}

TEST(ImageFile, PngAndExrDecodeToTheEncodedValues) {
  for (auto [w, h] : {std::pair{1, 1}, std::pair{7, 5}, std::pair{33, 17}}) {
    const auto p8 = ramp8(w, h);
    const RgbPixels d8 = decode_png(qs::image::encode_png(w, h, p8), "a.png");
    EXPECT_EQ(d8.bits, 8);
    EXPECT_EQ(d8.width, w);
    EXPECT_EQ(d8.height, h);
    EXPECT_EQ(d8.u8, p8);
    std::vector<std::uint16_t> p16(p8.size());
    for (size_t i = 0; i < p16.size(); ++i) p16[i] = static_cast<std::uint16_t>(p8[i] * 257 + (i % 3));
    const RgbPixels d16 = decode_png(qs::image::encode_png16(w, h, p16, 3), "a.png");
    EXPECT_EQ(d16.bits, 16);
    EXPECT_EQ(d16.u16, p16);
    std::vector<float> pf(p8.size());
    for (size_t i = 0; i < pf.size(); ++i) pf[i] = (p8[i] - 100.0f) / 37.0f;
    const RgbPixels df = decode_exr(qs::image::encode_exr(w, h, pf), "a.exr");
    EXPECT_EQ(df.bits, 32);
    EXPECT_EQ(df.f32, pf);
    EXPECT_EQ(decode_image(qs::image::encode_exr(w, h, pf), "a.exr").f32, pf);
    EXPECT_EQ(decode_image(qs::image::encode_png(w, h, p8), "a.png").u8, p8);
  }
  EXPECT_THROW(qs::image::encode_png(2, 2, std::vector<std::uint8_t>(11)), qs::InvalidInput);
  EXPECT_THROW(qs::image::encode_exr(0, 2, std::vector<float>()), qs::InvalidInput);
}

// The chunks OpenImageIO wrote before (and viewers expect): IHDR, oFFs (0, 0), IDAT..., IEND;
// no gamma, sRGB, pHYs or time chunk. zlib's header says the level.
TEST(ImageFile, PngHoldsOnlyTheChunksQsWrites) {
  const auto p8 = ramp8(300, 200);
  const std::string png = str(qs::image::encode_png(300, 200, p8));
  EXPECT_EQ(png, str(qs::image::encode_png(300, 200, p8))) << "deterministic";
  std::vector<std::string> types;
  for (size_t p = 8; p + 8 <= png.size();) {
    const std::uint32_t n = (std::uint32_t(std::uint8_t(png[p])) << 24) | (std::uint32_t(std::uint8_t(png[p + 1])) << 16) |
                            (std::uint32_t(std::uint8_t(png[p + 2])) << 8) | std::uint8_t(png[p + 3]);
    if (types.empty() || types.back() != png.substr(p + 4, 4)) types.push_back(png.substr(p + 4, 4));
    p += 12 + n;
  }
  EXPECT_EQ(types, (std::vector<std::string>{"IHDR", "oFFs", "IDAT", "IEND"}));
  const size_t idat = qs::test::find_chunk(png, "IDAT");
  EXPECT_EQ(png.substr(idat + 8, 2), "\x78\x9c") << "zlib level 6";
  const std::string fast = str(qs::image::encode_png(300, 200, p8, 3));
  EXPECT_EQ(fast.substr(qs::test::find_chunk(fast, "IDAT") + 8, 2), "\x78\x5e") << "zlib level 3";
}

TEST(ImageFile, ExrHasZipFloatChannelsAndNoVaryingAttribute) {
  const std::string exr = small_exr(4, 3);
  EXPECT_EQ(exr, small_exr(4, 3));
  EXPECT_NE(exr.find(std::string("capDate\0string\0\0\0\0\0", 19)), std::string::npos) << "an empty capDate";
  EXPECT_NE(exr.find(std::string("compression\0compression\0\1\0\0\0\3", 29)), std::string::npos) << "ZIP";
  EXPECT_EQ(exr.find("scanlineimage"), std::string::npos) << "no type attribute";
}

TEST(ImageFile, ReadsPaletteAndSixteenBitPngs) {
  const std::string plte("\x00\x00\x00\x80\x80\xff", 6);
  const RgbPixels pal = decode_png(bytes_of(qs::test::make_png(3, 2, 8, 3, std::string("\x01\x00", 2), plte)), "p.png");
  ASSERT_EQ(pal.bits, 8);
  EXPECT_EQ(pal.u8, (std::vector<std::uint8_t>{128, 128, 255, 0, 0, 0, 128, 128, 255, 0, 0, 0, 128, 128, 255, 0, 0, 0}));
  const RgbPixels d16 = decode_png(bytes_of(qs::test::make_png(2, 2, 16, 2, "\x12\x34")), "s.png");
  ASSERT_EQ(d16.bits, 16);
  EXPECT_EQ(d16.u16[0], 0x1234);
  EXPECT_EQ(d16.to8(0), (0x1234 * 255 + 32767) / 65535);
}

TEST(ImageFile, DamagedPngsAreRefusedInQsWords) {
  const std::string good = str(qs::image::encode_png(16, 12, ramp8(16, 12)));
  ASSERT_NO_THROW(decode_png(bytes_of(good), "n.png", kExpected));
  const auto refuse = [&](const std::string& bytes, const std::string& what) {
    const std::string m = invalid_input([&] { decode_png(bytes_of(bytes), "dir/n.png", kExpected); });
    expect_our_words(m, "dir/n.png", what);
  };
  const size_t idat = qs::test::find_chunk(good, "IDAT"), iend = qs::test::find_chunk(good, "IEND");
  // Truncated: in the signature, after IHDR, inside IDAT, before IEND.
  refuse(good.substr(0, 5), "not a PNG file");
  refuse(good.substr(0, 33), "the PNG ends early");
  refuse(good.substr(0, idat + 20), "the PNG ends early");
  refuse(good.substr(0, iend), "the PNG ends early");
  // A changed byte in the pixel data: the chunk's checksum no longer matches.
  std::string data = good;
  data[idat + 30] ^= 0x40;
  refuse(data, "damaged PNG");
  EXPECT_THAT(invalid_input([&] { decode_png(bytes_of(data), "n.png", kExpected); }), HasSubstr("does not decode"));
  // A changed checksum (of IHDR, of IEND).
  for (size_t at : {size_t{30}, iend + 9}) {
    std::string crc = good;
    crc[at] ^= 0x01;
    refuse(crc, "damaged PNG");
    EXPECT_THAT(invalid_input([&] { decode_png(bytes_of(crc), "n.png", kExpected); }), HasSubstr("checksum"));
  }
  // Wrong size: a header that promises more rows than the pixel data holds (checksums right).
  std::string tall = qs::test::make_png(8, 8, 8, 2);
  tall[8 + 8 + 7] = 9;  // height 9
  const size_t ihdr = 8;
  const std::uint32_t c = qs::test::png_crc32(tall.substr(ihdr + 4, 17));
  for (int k = 0; k < 4; ++k) tall[ihdr + 21 + k] = static_cast<char>(c >> (24 - 8 * k));
  refuse(tall, "damaged PNG");
  EXPECT_THAT(invalid_input([&] { decode_png(bytes_of(tall), "n.png", kExpected); }), HasSubstr("8 x 9"));
  // Not an image, empty, the signature of a text-mode transfer.
  refuse("v 0 0 0\nv 1 0 0\n", "not a PNG file");
  refuse("", "empty file");
  refuse("\x89PNG\n\x1a\n\n" + good.substr(8), "not a PNG file");
  // Not RGB: grey, grey + alpha, RGBA.
  refuse(qs::test::make_png(4, 4, 8, 0), "not an RGB image");
  refuse(qs::test::make_png(4, 4, 8, 4), "not an RGB image");
  refuse(qs::test::make_png(4, 4, 8, 6), "not an RGB image");
  refuse(qs::test::make_png(4, 4, 16, 6), "RGB with alpha 16-bit");
  // A malformed header (bit depth 7).
  std::string bad_depth = qs::test::make_png(4, 4, 8, 2);
  bad_depth[8 + 8 + 8] = 7;
  const std::uint32_t c2 = qs::test::png_crc32(bad_depth.substr(12, 17));
  for (int k = 0; k < 4; ++k) bad_depth[29 + k] = static_cast<char>(c2 >> (24 - 8 * k));
  refuse(bad_depth, "damaged PNG");
}

// A header that claims a huge image is refused before its pixels are allocated (fuzz safety).
TEST(ImageFile, HugeClaimsAreRefusedBeforeAllocating) {
  std::string huge = qs::test::make_png(4, 4, 8, 2);
  for (int k : {16, 20}) {  // width and height 10000
    huge[k] = 0, huge[k + 1] = 0, huge[k + 2] = 0x27, huge[k + 3] = 0x10;
  }
  const std::uint32_t c = qs::test::png_crc32(huge.substr(12, 17));
  for (int k = 0; k < 4; ++k) huge[29 + k] = static_cast<char>(c >> (24 - 8 * k));
  const auto t0 = std::chrono::steady_clock::now();
  expect_our_words(invalid_input([&] { decode_png(bytes_of(huge), "h.png", kExpected); }), "h.png", "the PNG ends early");
  qs::image::Limits small;
  small.max_side = 1000;
  expect_our_words(invalid_input([&] { decode_png(bytes_of(huge), "h.png", kExpected, small); }), "h.png",
                   "image too large");
  small.max_side = 1 << 17;
  small.max_pixels = 10;
  expect_our_words(invalid_input([&] { decode_png(bytes_of(qs::test::make_png(4, 4, 8, 2)), "h.png", kExpected, small); }),
                   "h.png", "image too large");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 1.0);
}

TEST(ImageFile, DamagedExrsAreRefusedInQsWords) {
  const std::string good = small_exr(40, 40);
  ASSERT_NO_THROW(decode_exr(bytes_of(good), "n.exr", kExpected));
  const auto refuse = [&](const std::string& bytes, const std::string& what) {
    const std::string m = invalid_input([&] { decode_exr(bytes_of(bytes), "dir/n.exr", kExpected); });
    expect_our_words(m, "dir/n.exr", what);
  };
  refuse(good.substr(0, 3), "not an OpenEXR file");
  refuse(good.substr(0, 40), "ends early");
  refuse(good.substr(0, good.size() / 2), "");
  refuse(good.substr(0, good.size() - 10), "");
  refuse("not an image at all", "not an OpenEXR file");
  refuse("", "empty file");
  // Damaged pixel data: the compressed blocks no longer decode (or the offsets point nowhere).
  const size_t header_end = good.find("screenWindowWidth") + 32;
  for (size_t at : {header_end + 8, good.size() - 50, good.size() / 2}) {
    std::string bad = good;
    for (size_t k = at; k < at + 8 && k < bad.size(); ++k) bad[k] = static_cast<char>(bad[k] ^ 0x5A);
    const std::string m = invalid_input([&] { decode_exr(bytes_of(bad), "dir/n.exr", kExpected); });
    if (m == "no exception") continue;  // a change the format cannot see (a float's bits): not an error
    expect_our_words(m, "dir/n.exr", "");
  }
  // Tiled, multi-part, deep: refused from the version flags, before OpenEXR reads the header.
  for (char flag : {char(0x02), char(0x10), char(0x08)}) {
    std::string other = good;
    other[5] = static_cast<char>(other[5] | flag);
    refuse(other, "not a scanline OpenEXR image");
  }
  // An attribute whose declared size disagrees with its type's value (OpenEXR reads the value by
  // its type and would go on from another place; an unknown type's size would be allocated).
  std::string bad_size = good;
  const size_t chlist = bad_size.find(std::string("chlist\0", 7)) + 7;
  bad_size[chlist] = static_cast<char>(bad_size[chlist] + 1);
  refuse(bad_size, "damaged OpenEXR file");
  std::string huge_opaque = good.substr(0, 8) + std::string("x\0y\0\xff\xff\xff\x7f", 8) + good.substr(8);
  refuse(huge_opaque, "the OpenEXR file ends early");
  // A damaged header: the channel list's name overwritten.
  std::string bad_header = good;
  bad_header.replace(bad_header.find("channels"), 8, "chXnnels");
  refuse(bad_header, "");
  // Truncation at every 97th byte: always a refusal in qs's words, never a crash.
  for (size_t n = 0; n < good.size(); n += 97) refuse(good.substr(0, n), "");
}

// An OpenEXR file of other channels (RGBA, half): half is read, four channels refused.
class MemoryOut : public Imf::OStream {
 public:
  MemoryOut() : Imf::OStream("m") {}
  void write(const char c[], int n) override {
    if (pos + n > bytes.size()) bytes.resize(pos + n);
    std::memcpy(bytes.data() + pos, c, n);
    pos += n;
  }
  uint64_t tellp() override { return pos; }
  void seekp(uint64_t p) override { pos = p; }
  std::string bytes;
  size_t pos = 0;
};

std::string exr_of(const std::vector<std::string>& channels, Imf::PixelType type) {
  Imf::Header header(2, 2);
  for (const auto& c : channels) header.channels().insert(c, Imf::Channel(type));
  std::vector<half> px(2 * 2 * channels.size(), half(0.5f));
  Imf::FrameBuffer fb;
  const size_t xs = sizeof(half) * channels.size();
  for (size_t i = 0; i < channels.size(); ++i)
    fb.insert(channels[i], Imf::Slice(Imf::HALF, reinterpret_cast<char*>(px.data() + i), xs, xs * 2));
  MemoryOut out;
  {
    Imf::OutputFile f(out, header, 0);
    f.setFrameBuffer(fb);
    f.writePixels(2);
  }
  return out.bytes;
}

TEST(ImageFile, ExrOfHalfChannelsIsReadAndOfFourIsRefused) {
  const RgbPixels h = decode_exr(bytes_of(exr_of({"R", "G", "B"}, Imf::HALF)), "h.exr");
  EXPECT_EQ(h.f32, std::vector<float>(12, 0.5f));
  const std::string m = invalid_input([&] { decode_exr(bytes_of(exr_of({"R", "G", "B", "A"}, Imf::HALF)), "a.exr", kExpected); });
  expect_our_words(m, "a.exr", "not an RGB image");
  EXPECT_THAT(m, HasSubstr("4 channels (A, B, G, R)"));
}

TEST(ImageFile, OtherFilesAndMissingOnesAreRefused) {
  expect_our_words(invalid_input([] { decode_image(bytes_of("GIF89a...."), "x.gif", kExpected); }), "x.gif",
                   "not an image qs reads");
  const fs::path dir = fs::temp_directory_path() / ("qs_image_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  EXPECT_THROW(qs::image::read_file_bytes(dir / "missing.png"), qs::IoError);
  EXPECT_THROW(qs::image::read_file_bytes(dir), qs::IoError);
  std::ofstream(dir / "f.png", std::ios::binary) << "abc";
  EXPECT_EQ(str(qs::image::read_file_bytes(dir / "f.png")), "abc");
  fs::remove_all(dir);
}

}  // namespace
