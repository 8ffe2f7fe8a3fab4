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

qs::io::ReadResult read_off(std::string_view text) {
  return read_mesh_from_memory(text, MeshFormat::Off, "bunny.off");
}

TEST(ReadOff, Tetrahedron) {
  const auto r = read_off("OFF\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n");
  EXPECT_EQ(r.report.format, MeshFormat::Off);
  EXPECT_EQ(r.report.variant, "OFF");
  ASSERT_EQ(r.mesh.num_vertices(), 4);
  ASSERT_EQ(r.mesh.num_faces(), 4);
  EXPECT_EQ(r.mesh.faces[0], (Tri{0, 2, 1}));
  EXPECT_EQ(r.mesh.positions[3], qs::Vec3(0, 0, 1));
}

TEST(ReadOff, CommentsBlankLinesTrailingSpacesAndCountsOnTheHeaderLine) {
  const auto r = read_off(
      "# leading comment\n"
      "\n"
      "OFF 4 2 5   # counts on the header line\n"
      "# comment between\n"
      "0 0 0   \n"
      "\n"
      "1 0 0\t\n"
      "  1 1 0 # trailing comment\n"
      "0 1 0\n"
      "\n"
      "4 0 1 2 3   \n"
      "3 0 2 3\n"
      "\n");
  ASSERT_EQ(r.mesh.num_vertices(), 4);
  ASSERT_EQ(r.mesh.num_faces(), 3);
  EXPECT_EQ(r.mesh.faces[1], (Tri{0, 2, 3}));
  EXPECT_EQ(r.report.polygons_triangulated, 1);
  EXPECT_EQ(r.mesh.positions[2], qs::Vec3(1, 1, 0));
}

TEST(ReadOff, CoffColoursNoffNormalsAndFaceColoursAreIgnored) {
  const auto c = read_off(
      "COFF\r\n3 1 0\r\n0 0 0 255 0 0 255\r\n1 0 0 0 255 0 255\r\n0 1 0 0 0 255 255\r\n"
      "3 0 1 2 0.5 0.5 0.5 1\r\n");
  EXPECT_EQ(c.report.variant, "COFF");
  ASSERT_EQ(c.mesh.num_vertices(), 3);
  EXPECT_EQ(c.mesh.positions[1], qs::Vec3(1, 0, 0));
  EXPECT_EQ(c.mesh.faces[0], (Tri{0, 1, 2}));

  const auto n = read_off("NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n");
  EXPECT_EQ(n.report.variant, "NOFF");
  EXPECT_EQ(n.mesh.positions[2], qs::Vec3(0, 1, 0));

  const auto st = read_off("STCNOFF\n3 1 0\n0 0 0 1 1 1 1 0 0 1 0.5 0.5\n1 0 0 1 1 1 1 0 0 1 0 0\n"
                           "0 1 0 1 1 1 1 0 0 1 0 1\n3 2 1 0\n");
  EXPECT_EQ(st.report.variant, "STCNOFF");
  EXPECT_EQ(st.mesh.faces[0], (Tri{2, 1, 0}));
}

TEST(ReadOff, CountsOnTheirOwnLineAfterComments) {
  const auto r = read_off("OFF\n# comment\n3 1\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(r.mesh.num_faces(), 1);
}

TEST(ReadOff, TooFewCoordinatesNamesTheLine) {
  EXPECT_THAT([] { read_off("OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n"); },
              ThrowsMessage<qs::InvalidInput>(
                  HasSubstr("bunny.off:4: expected 3 vertex coordinates, found 2")));
}

TEST(ReadOff, IndexOutOfRange) {
  EXPECT_THAT([] { read_off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"); },
              ThrowsMessage<qs::InvalidInput>(
                  HasSubstr("bunny.off:6: face 0 references vertex 3 but the file has 3 vertices")));
  EXPECT_THAT([] { read_off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("bunny.off:6:")));
}

TEST(ReadOff, TooFewIndices) {
  EXPECT_THAT([] { read_off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("bunny.off:6: expected 3 vertex indices, found 2")));
}

TEST(ReadOff, MismatchedCounts) {
  // Fewer faces than claimed.
  EXPECT_THAT([] { read_off("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("file ends after 1 of 2 faces")));
  // More faces than claimed.
  EXPECT_THAT([] { read_off("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 2 1 0\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("bunny.off:7: unexpected data after the last of 1 faces")));
  // More vertices than present: the faces are read as vertices and the faces run out.
  EXPECT_THAT([] { read_off("OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("file ends after 0 of 1 faces")));
}

TEST(ReadOff, NegativeAndBadCounts) {
  EXPECT_THAT([] { read_off("OFF\n-3 1 0\n0 0 0\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("bunny.off:2: negative number of vertices")));
  EXPECT_THAT([] { read_off("OFF\n3\n0 0 0\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("bunny.off:2: expected the counts")));
  EXPECT_THAT([] { read_off("OFF\nthree 1 0\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("bunny.off:2: expected the number of vertices")));
}

TEST(ReadOff, WrongHeader) {
  EXPECT_THAT([] { read_off("PLY\n3 1 0\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("bunny.off:1: expected an OFF header")));
  EXPECT_THAT([] { read_off("4OFF\n1 0 0\n0 0 0 1\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("not supported")));
  EXPECT_THAT([] { read_off("OFF BINARY\n"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("binary OFF is not supported")));
}

TEST(ReadOff, MissingKeywordIsTolerated) {
  const auto r = read_off("3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(r.mesh.num_faces(), 1);
  EXPECT_FALSE(r.report.notes.empty());
}

}  // namespace
