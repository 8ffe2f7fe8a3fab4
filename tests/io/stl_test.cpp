#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>

#include "qs/core/error.h"
#include "qs/io/read_mesh.h"

namespace {

using qs::Tri;
using qs::Vec3;
using qs::io::MeshFormat;
using qs::io::read_mesh_from_memory;
using ::testing::Contains;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

qs::io::ReadResult read_stl(std::string_view bytes) {
  return read_mesh_from_memory(bytes, MeshFormat::Stl, "part.stl");
}

const char kAscii[] =
    "solid thing\n"
    "  facet normal 0 0 1\n"
    "    outer loop\n"
    "      vertex 0 0 0\n"
    "      vertex 1 0 0\n"
    "      vertex 0 1 0\n"
    "    endloop\n"
    "  endfacet\n"
    "  FACET NORMAL 0 0 1\r\n"
    "    OUTER LOOP\r\n"
    "      VERTEX 1 0 0\r\n"
    "      VERTEX 1 1 0\r\n"
    "      VERTEX 0 1 -1.5e-3\r\n"
    "    ENDLOOP\r\n"
    "  ENDFACET\r\n"
    "endsolid thing\n";

TEST(ReadStl, AsciiGivesEveryTriangleItsOwnVertices) {
  const auto r = read_stl(kAscii);
  EXPECT_EQ(r.report.format, MeshFormat::Stl);
  EXPECT_EQ(r.report.variant, "ascii");
  ASSERT_EQ(r.mesh.num_vertices(), 6);  // not welded: (1,0,0) and (0,1,0) appear twice
  ASSERT_EQ(r.mesh.num_faces(), 2);
  EXPECT_EQ(r.mesh.faces[0], (Tri{0, 1, 2}));
  EXPECT_EQ(r.mesh.faces[1], (Tri{3, 4, 5}));
  EXPECT_EQ(r.mesh.positions[5], Vec3(0, 1, -1.5e-3));
  EXPECT_THAT(r.report.notes, Contains(HasSubstr("STL stores unshared vertices")));
}

std::string binary_stl(std::string header80, std::uint32_t n, int triangles_written) {
  header80.resize(80, ' ');
  std::string out = header80;
  out.append(reinterpret_cast<const char*>(&n), 4);
  for (int t = 0; t < triangles_written; ++t) {
    const float v[12] = {0, 0, 1, float(t), 0, 0, float(t) + 1, 0, 0, float(t), 1, 0};
    out.append(reinterpret_cast<const char*>(v), sizeof v);
    out.append("\0\0", 2);
  }
  return out;
}

TEST(ReadStl, Binary) {
  const auto r = read_stl(binary_stl("binary header", 2, 2));
  EXPECT_EQ(r.report.variant, "binary");
  ASSERT_EQ(r.mesh.num_vertices(), 6);
  ASSERT_EQ(r.mesh.num_faces(), 2);
  EXPECT_EQ(r.mesh.faces[1], (Tri{3, 4, 5}));
  EXPECT_EQ(r.mesh.positions[4], Vec3(2, 0, 0));
  EXPECT_THAT(r.report.notes, Contains(HasSubstr("unshared")));
}

TEST(ReadStl, BinaryWhoseHeaderStartsWithSolid) {
  const auto r = read_stl(binary_stl("solid exported by a CAD tool", 3, 3));
  EXPECT_EQ(r.report.variant, "binary");
  EXPECT_EQ(r.mesh.num_faces(), 3);
}

TEST(ReadStl, TruncatedBinary) {
  std::string data = binary_stl("binary", 3, 3);
  data.resize(data.size() - 20);
  EXPECT_THAT([&] { read_stl(data); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("part.stl: byte offset 184: binary STL header claims 3 triangles")));
  // With a "solid" header, truncated binary is recognised as binary data.
  std::string solid = binary_stl("solid x", 3, 3);
  solid.resize(solid.size() - 20);
  EXPECT_THAT([&] { read_stl(solid); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("contains binary data")));
}

TEST(ReadStl, TruncatedAscii) {
  const std::string text = kAscii;
  EXPECT_THAT([&] { read_stl(text.substr(0, text.find("endloop"))); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("file ends inside the facet that starts on line 2")));
  EXPECT_THAT([&] { read_stl(text.substr(0, text.find("endsolid"))); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("without 'endsolid'")));
}

TEST(ReadStl, AsciiErrors) {
  EXPECT_THAT([] { read_stl("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("part.stl:4: expected 3 vertex coordinates, found 2")));
  EXPECT_THAT([] { read_stl("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 a\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("part.stl:4: vertex coordinate 'a' is not a number")));
  EXPECT_THAT([] { read_stl("solid x\nbanana\nendsolid\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("part.stl:2: unexpected 'banana'")));
}

TEST(ReadStl, TooShort) {
  EXPECT_THAT([] { read_stl("hello"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("neither an ASCII STL")));
}

}  // namespace
