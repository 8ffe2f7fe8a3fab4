#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "qs/core/error.h"
#include "qs/io/read_mesh.h"

namespace {

using qs::Tri;
using qs::io::MeshFormat;
using qs::io::read_mesh_from_memory;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

qs::io::ReadResult read_obj(std::string_view text) {
  return read_mesh_from_memory(text, MeshFormat::Obj, "test.obj");
}

TEST(ReadObj, AllFourFaceSyntaxes) {
  const auto r = read_obj(
      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
      "vt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n"
      "f 1 2 3\n"
      "f 1/1 2/2 4/3\n"
      "f 1//1 3//1 4//1\n"
      "f 2/2/1 3/3/1 4/1/1\n");
  EXPECT_EQ(r.report.format, MeshFormat::Obj);
  ASSERT_EQ(r.mesh.num_vertices(), 4);
  ASSERT_EQ(r.mesh.num_faces(), 4);
  EXPECT_EQ(r.mesh.faces[0], (Tri{0, 1, 2}));
  EXPECT_EQ(r.mesh.faces[1], (Tri{0, 1, 3}));
  EXPECT_EQ(r.mesh.faces[2], (Tri{0, 2, 3}));
  EXPECT_EQ(r.mesh.faces[3], (Tri{1, 2, 3}));
  EXPECT_EQ(r.mesh.positions[3], qs::Vec3(0, 0, 1));
}

TEST(ReadObj, NegativeIndicesAreRelativeToTheVerticesSoFar) {
  const auto r = read_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 5 5 5\nf -4 -1 -2\n");
  ASSERT_EQ(r.mesh.num_faces(), 2);
  EXPECT_EQ(r.mesh.faces[0], (Tri{0, 1, 2}));
  EXPECT_EQ(r.mesh.faces[1], (Tri{0, 3, 2}));
}

TEST(ReadObj, PolygonsAreFanTriangulatedAndShortFacesDropped) {
  const auto r = read_obj(
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 2 0\n"
      "f 1 2 3 4\n"
      "f 1 2 3 5 4\n"
      "f 1 2\n"
      "f 3\n");
  ASSERT_EQ(r.mesh.num_faces(), 2 + 3);
  EXPECT_EQ(r.mesh.faces[0], (Tri{0, 1, 2}));
  EXPECT_EQ(r.mesh.faces[1], (Tri{0, 2, 3}));
  EXPECT_EQ(r.mesh.faces[4], (Tri{0, 4, 3}));
  EXPECT_EQ(r.report.polygons_triangulated, 2);
  EXPECT_EQ(r.report.degenerate_polygons_dropped, 2);
}

TEST(ReadObj, IgnoredLinesCrlfAndExtraVertexComponents) {
  const auto r = read_obj(
      "# a comment\r\n"
      "mtllib x.mtl\r\n"
      "o thing\r\n"
      "g group one\r\n"
      "\r\n"
      "   \t \r\n"
      "v 0 0 0 1.0\r\n"          // w
      "v 1 0 0 0.5 0.25 0.125\r\n"  // vertex colour
      "v 0 1 0\r\n"
      "vn 0 0 1\r\n"
      "vt 0.5 0.5\r\n"
      "usemtl red\r\n"
      "s off\r\n"
      "s 1\r\n"
      "l 1 2\r\n"
      "f 1 2 3\r\n");
  ASSERT_EQ(r.mesh.num_vertices(), 3);
  ASSERT_EQ(r.mesh.num_faces(), 1);
  EXPECT_EQ(r.mesh.positions[1], qs::Vec3(1, 0, 0));
  EXPECT_EQ(r.mesh.faces[0], (Tri{0, 1, 2}));
  EXPECT_TRUE(r.report.notes.empty());
}

TEST(ReadObj, CoincidentVerticesAreNotWelded) {
  const auto r = read_obj("v 0 0 0\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 3 4\nf 2 4 3\n");
  EXPECT_EQ(r.mesh.num_vertices(), 4);
  EXPECT_EQ(r.mesh.faces[1], (Tri{1, 3, 2}));
}

TEST(ReadObj, NumbersWithSignsAndExponents) {
  const auto r = read_obj("v +1.5 -2e3 3.25E-2\nv 1 1 1\nv 2 2 2\nf 1 2 3\n");
  EXPECT_EQ(r.mesh.positions[0], qs::Vec3(1.5, -2000, 0.0325));
}

TEST(ReadObj, IndexZeroIsAnErrorNamingTheLine) {
  EXPECT_THAT([] { read_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("test.obj:4: vertex index 0")));
}

TEST(ReadObj, IndexOutOfRangeNamesTheLine) {
  EXPECT_THAT([] { read_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\n# c\nf 1 2 3\nf 1 2 4\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("test.obj:6: vertex index 4 is out of range")));
  EXPECT_THAT([] { read_obj("v 0 0 0\nv 1 0 0\nf -3 1 2\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("test.obj:3: relative vertex index -3")));
}

TEST(ReadObj, TooFewCoordinates) {
  EXPECT_THAT([] { read_obj("v 0 0 0\nv 1 0\n"); },
              ThrowsMessage<qs::InvalidInput>(
                  HasSubstr("test.obj:2: expected 3 vertex coordinates, found 2")));
}

TEST(ReadObj, UnparsableNumberAndBadCorner) {
  EXPECT_THAT([] { read_obj("v 0 0 0\nv 1 0 zero\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("test.obj:2: vertex coordinate 'zero' is not a number")));
  EXPECT_THAT([] { read_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 x/2 3\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("test.obj:4: face corner 'x/2'")));
  EXPECT_THAT([] { read_obj("v 0 0 0\nv 1 0 1.0.0\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("test.obj:2:")));
}

TEST(ReadObj, NoVerticesIsAnError) {
  EXPECT_THAT([] { read_obj("# only a comment\ng x\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("no vertex ('v') lines")));
}

TEST(ReadObj, UnknownKeywordsAreNoted) {
  const auto r = read_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nfoo bar\nfoo baz\nf 1 2 3\n");
  ASSERT_EQ(r.report.notes.size(), 1u);
  EXPECT_THAT(r.report.notes[0], HasSubstr("'foo'"));
}

}  // namespace
