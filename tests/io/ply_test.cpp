#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "qs/core/error.h"
#include "qs/io/read_mesh.h"

namespace {

using qs::Tri;
using qs::Vec3;
using qs::io::MeshFormat;
using qs::io::read_mesh_from_memory;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

qs::io::ReadResult read_ply(std::string_view bytes) {
  return read_mesh_from_memory(bytes, MeshFormat::Ply, "test.ply");
}

/// Builds binary PLY bodies in either byte order.
class Bytes {
 public:
  explicit Bytes(bool big_endian) : big_(big_endian) {}
  template <class T>
  Bytes& put(T value) {
    char b[sizeof(T)];
    std::memcpy(b, &value, sizeof(T));
    if (big_) std::reverse(b, b + sizeof(T));  // the test machine is little-endian
    data_.append(b, sizeof(T));
    return *this;
  }
  Bytes& text(std::string_view s) {
    data_ += s;
    return *this;
  }
  const std::string& str() const { return data_; }

 private:
  bool big_;
  std::string data_;
};

const char kAsciiCube[] =
    "ply\n"
    "format ascii 1.0\n"
    "comment a comment\n"
    "obj_info made by hand\n"
    "element vertex 4\n"
    "property float x\n"
    "property float y\n"
    "property float z\n"
    "property uchar red\n"
    "property list uchar float extra\n"
    "element face 2\n"
    "property list uchar int vertex_indices\n"
    "property uchar flags\n"
    "element edge 1\n"
    "property int vertex1\n"
    "property int vertex2\n"
    "end_header\n"
    "0 0 0 255 2 0.5 0.5\n"
    "1 0 0 255 0\n"
    "1 1 0 255 1 7\n"
    "0 1 0.5 255 0\n"
    "4 0 1 2 3 9\n"
    "3 2 1 0 9\n"
    "0 1\n";

TEST(ReadPly, AsciiWithExtraPropertiesListsAndOtherElements) {
  const auto r = read_ply(kAsciiCube);
  EXPECT_EQ(r.report.format, MeshFormat::Ply);
  EXPECT_EQ(r.report.variant, "ascii");
  ASSERT_EQ(r.mesh.num_vertices(), 4);
  EXPECT_EQ(r.mesh.positions[3], Vec3(0, 1, 0.5));
  ASSERT_EQ(r.mesh.num_faces(), 3);
  EXPECT_EQ(r.mesh.faces[0], (Tri{0, 1, 2}));
  EXPECT_EQ(r.mesh.faces[1], (Tri{0, 2, 3}));
  EXPECT_EQ(r.mesh.faces[2], (Tri{2, 1, 0}));
  EXPECT_EQ(r.report.polygons_triangulated, 1);
}

TEST(ReadPly, AsciiCrlfHeaderAndVertexIndexName) {
  const auto r = read_ply(
      "ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty double x\r\nproperty double y\r\n"
      "property double z\r\nelement face 1\r\nproperty list int int vertex_index\r\nend_header\r\n"
      "0 0 0\r\n1 0 0\r\n0 1 0\r\n3 0 1 2\r\n");
  EXPECT_EQ(r.mesh.num_faces(), 1);
}

/// A binary PLY of two triangles with mixed property types: vertex (float x, uchar r,
/// double y, list uchar int, short z), face (uchar flag, list `count` `index` vertex_indices),
/// an edge element, and a material element with a list.
template <class Count, class Index>
std::string binary_ply(bool big, const char* count_type, const char* index_type) {
  Bytes b(big);
  b.text(std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
         " 1.0\ncomment binary\nelement vertex 4\nproperty float32 x\nproperty uint8 red\n"
         "property double y\nproperty list uchar int junk\nproperty int16 z\n"
         "element material 1\nproperty list uint8 float32 colour\nproperty ushort id\n"
         "element face 2\nproperty uchar flag\nproperty list " + count_type + " " + index_type +
         " vertex_indices\nelement edge 2\nproperty int v1\nproperty uint v2\nend_header\n");
  const float xs[4] = {0.f, 1.5f, 0.f, -2.25f};
  const double ys[4] = {0.0, 0.1, 1.0, 1e-300};
  const std::int16_t zs[4] = {0, 0, -3, 7};
  for (int i = 0; i < 4; ++i) {
    b.put(xs[i]).put(std::uint8_t{200}).put(ys[i]);
    b.put(std::uint8_t(i % 2 ? 2 : 0));
    if (i % 2) b.put(std::int32_t{11}).put(std::int32_t{12});
    b.put(zs[i]);
  }
  b.put(std::uint8_t{3}).put(0.5f).put(0.5f).put(0.5f).put(std::uint16_t{9});
  b.put(std::uint8_t{1}).put(Count(3)).put(Index(0)).put(Index(1)).put(Index(2));
  b.put(std::uint8_t{0}).put(Count(4)).put(Index(0)).put(Index(2)).put(Index(3)).put(Index(1));
  b.put(std::int32_t{0}).put(std::uint32_t{1}).put(std::int32_t{1}).put(std::uint32_t{2});
  return b.str();
}

void expect_binary_mesh(const qs::io::ReadResult& r) {
  ASSERT_EQ(r.mesh.num_vertices(), 4);
  EXPECT_EQ(r.mesh.positions[1], Vec3(1.5, 0.1, 0));
  EXPECT_EQ(r.mesh.positions[2], Vec3(0, 1, -3));
  EXPECT_EQ(r.mesh.positions[3], Vec3(-2.25, 1e-300, 7));
  ASSERT_EQ(r.mesh.num_faces(), 3);
  EXPECT_EQ(r.mesh.faces[0], (Tri{0, 1, 2}));
  EXPECT_EQ(r.mesh.faces[1], (Tri{0, 2, 3}));
  EXPECT_EQ(r.mesh.faces[2], (Tri{0, 3, 1}));
  EXPECT_EQ(r.report.polygons_triangulated, 1);
  EXPECT_TRUE(r.report.notes.empty());
}

TEST(ReadPly, BinaryLittleEndian) {
  const auto r = read_ply(binary_ply<std::uint8_t, std::int32_t>(false, "uchar", "int"));
  EXPECT_EQ(r.report.variant, "binary_little_endian");
  expect_binary_mesh(r);
}

TEST(ReadPly, BinaryBigEndian) {
  const auto r = read_ply(binary_ply<std::uint8_t, std::int32_t>(true, "uchar", "int"));
  EXPECT_EQ(r.report.variant, "binary_big_endian");
  expect_binary_mesh(r);
}

TEST(ReadPly, OtherCountAndIndexTypes) {
  expect_binary_mesh(read_ply(binary_ply<std::int32_t, std::uint32_t>(false, "int", "uint")));
  expect_binary_mesh(read_ply(binary_ply<std::uint16_t, std::uint16_t>(true, "ushort", "uint16")));
  expect_binary_mesh(read_ply(binary_ply<std::int8_t, std::uint8_t>(false, "int8", "uchar")));
  expect_binary_mesh(read_ply(binary_ply<std::uint32_t, std::int16_t>(true, "uint32", "short")));
}

TEST(ReadPly, IntegerAndDoubleCoordinates) {
  Bytes b(false);
  b.text("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty int x\nproperty uchar y\n"
         "property double z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n");
  b.put(std::int32_t{-5}).put(std::uint8_t{250}).put(0.125);
  b.put(std::int32_t{1}).put(std::uint8_t{0}).put(0.0);
  b.put(std::int32_t{0}).put(std::uint8_t{1}).put(0.0);
  b.put(std::uint8_t{3}).put(std::uint32_t{0}).put(std::uint32_t{1}).put(std::uint32_t{2});
  const auto r = read_ply(b.str());
  EXPECT_EQ(r.mesh.positions[0], Vec3(-5, 250, 0.125));
  EXPECT_EQ(r.mesh.num_faces(), 1);
}

TEST(ReadPly, TriangleStripsWithRestartAndAlternateWinding) {
  const auto r = read_ply(
      "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
      "element tristrips 1\nproperty list int int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 2 0\n1 2 0\n"
      "9 0 1 2 3 -1 2 3 4 5\n");
  ASSERT_EQ(r.mesh.num_faces(), 2 + 2);
  EXPECT_EQ(r.mesh.faces[0], (Tri{0, 1, 2}));
  EXPECT_EQ(r.mesh.faces[1], (Tri{2, 1, 3}));  // odd triangle flipped
  EXPECT_EQ(r.mesh.faces[2], (Tri{2, 3, 4}));  // a new strip starts with even winding
  EXPECT_EQ(r.mesh.faces[3], (Tri{4, 3, 5}));
}

TEST(ReadPly, BinaryTriangleStrips) {
  Bytes b(true);
  b.text("ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
         "property float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n");
  for (int i = 0; i < 4; ++i) b.put(float(i % 2)).put(float(i / 2)).put(0.f);
  b.put(std::int32_t{4});
  for (int i : {0, 1, 2, 3}) b.put(std::int32_t(i));
  const auto r = read_ply(b.str());
  ASSERT_EQ(r.mesh.num_faces(), 2);
  EXPECT_EQ(r.mesh.faces[0], (Tri{0, 1, 2}));
  EXPECT_EQ(r.mesh.faces[1], (Tri{2, 1, 3}));
}

TEST(ReadPly, DegenerateStripJoinsAreSkipped) {
  const auto r = read_ply(
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element tristrips 1\nproperty list int int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n1 1 0\n"
      "6 0 1 2 2 3 3\n");
  EXPECT_EQ(r.mesh.num_faces(), 1);
  ASSERT_EQ(r.report.notes.size(), 1u);
  EXPECT_THAT(r.report.notes[0], HasSubstr("degenerate"));
}

TEST(ReadPly, FacesWithFewerThanThreeCornersAreDropped) {
  const auto r = read_ply(
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 3\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n2 0 1\n0\n");
  EXPECT_EQ(r.mesh.num_faces(), 1);
  EXPECT_EQ(r.report.degenerate_polygons_dropped, 2);
}

TEST(ReadPly, IndexOutOfRangeAscii) {
  EXPECT_THAT([] {
    read_ply("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
             "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
             "0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  }, ThrowsMessage<qs::InvalidInput>(HasSubstr("test.ply:13: face 0 references vertex 3")));
}

TEST(ReadPly, IndexOutOfRangeBinaryNamesTheByteOffset) {
  Bytes b(false);
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  b.text(header);
  for (int i = 0; i < 9; ++i) b.put(0.f);
  b.put(std::uint8_t{3}).put(std::int32_t{0}).put(std::int32_t{7}).put(std::int32_t{1});
  const std::size_t offset = header.size() + 36 + 1 + 4;
  EXPECT_THAT([&] { read_ply(b.str()); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr(
                  "test.ply: byte offset " + std::to_string(offset) + ": face 0 references vertex 7")));
}

TEST(ReadPly, HeaderErrors) {
  EXPECT_THAT([] { read_ply("plx\nformat ascii 1.0\nend_header\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("test.ply:1: expected 'ply'")));
  EXPECT_THAT([] { read_ply("ply\nformat binary_middle_endian 1.0\nend_header\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("test.ply:2: unknown PLY format")));
  EXPECT_THAT([] { read_ply("ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("test.ply:4: unknown property type 'float128'")));
  EXPECT_THAT([] { read_ply("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("no 'end_header'")));
  EXPECT_THAT([] { read_ply("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("test.ply:3: element vertex lacks one of the properties x, y, z")));
  EXPECT_THAT([] { read_ply("ply\nformat ascii 1.0\nelement vertex -1\nend_header\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("test.ply:3: negative count")));
  EXPECT_THAT([] {
    read_ply("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 1\nproperty list uchar int indices\nend_header\n0 0 0\n3 0 0 0\n");
  }, ThrowsMessage<qs::InvalidInput>(HasSubstr("test.ply:7: element face has no list property 'vertex_indices'")));
}

TEST(ReadPly, AsciiUnparsableNumberAndTrailingData) {
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  EXPECT_THAT([&] { read_ply(header + "0 0 0\n1 0 oops\n0 1 0\n3 0 1 2\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("test.ply:11: property 'z' of vertex 1: 'oops' is not a number")));
  EXPECT_THAT([&] { read_ply(header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("test.ply:14: unexpected data")));
}

// Only "face" and "tristrips" hold faces: an "edge" element with a vertex_indices list is skipped.
TEST(ReadPly, OtherElementsWithVertexIndicesAreNotFaces) {
  const auto r = read_ply(
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 4\nproperty list uchar int vertex_indices\n"
      "element edge 2\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n3 0 1 2\n3 1 2 3\n");
  EXPECT_EQ(r.mesh.num_faces(), 4);
  EXPECT_EQ(r.mesh.faces[3], (Tri{1, 2, 3}));
}

}  // namespace
