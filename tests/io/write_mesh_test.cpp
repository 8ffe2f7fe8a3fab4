#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <unistd.h>
#include <filesystem>
#include <limits>
#include <random>

#include "qs/core/error.h"
#include "qs/io/read_mesh.h"
#include "qs/io/write_mesh.h"

namespace {

namespace fs = std::filesystem;
using qs::TriMesh;
using qs::Vec3;
using qs::io::MeshFormat;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

/// A mesh whose coordinates need all 17 significant digits, plus awkward values.
TriMesh awkward_mesh() {
  TriMesh m;
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 200; ++i) m.positions.emplace_back(u(rng), u(rng) * 1e-7, u(rng) * 1e12);
  m.positions.emplace_back(0.1, -0.0, 1.0 / 3.0);
  m.positions.emplace_back(std::numeric_limits<double>::denorm_min(), std::numeric_limits<double>::max(),
                           -std::numeric_limits<double>::min());
  for (int i = 0; i + 2 < m.num_vertices(); ++i) m.faces.push_back({i, i + 1, i + 2});
  m.faces.push_back({5, 5, 7});  // kept as written
  return m;
}

bool bit_equal(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void expect_bit_exact(const TriMesh& a, const TriMesh& b) {
  ASSERT_EQ(a.num_vertices(), b.num_vertices());
  ASSERT_EQ(a.faces, b.faces);
  for (int i = 0; i < a.num_vertices(); ++i)
    for (int k = 0; k < 3; ++k)
      ASSERT_TRUE(bit_equal(a.positions[i][k], b.positions[i][k])) << "vertex " << i << " coordinate " << k;
}

class RoundTrip : public ::testing::TestWithParam<MeshFormat> {};

TEST_P(RoundTrip, InMemoryIsBitExactAndDeterministic) {
  const TriMesh m = awkward_mesh();
  const std::string text = qs::io::mesh_to_string(m, GetParam());
  EXPECT_EQ(text, qs::io::mesh_to_string(m, GetParam()));
  const auto r = qs::io::read_mesh_from_memory(text, GetParam(), "round-trip");
  expect_bit_exact(m, r.mesh);
  EXPECT_EQ(qs::io::mesh_to_string(r.mesh, GetParam()), text);
}

TEST_P(RoundTrip, ThroughAFile) {
  const TriMesh m = awkward_mesh();
  const char* ext = GetParam() == MeshFormat::Obj ? ".obj" : GetParam() == MeshFormat::Off ? ".off" : ".ply";
  const fs::path dir = fs::temp_directory_path() / ("qs_io_write_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path path = dir / (std::string("mesh") + ext);
  qs::io::write_mesh(path, m);
  const auto r = qs::io::read_mesh(path);
  EXPECT_EQ(r.report.format, GetParam());
  expect_bit_exact(m, r.mesh);
  // Only the finished file is left behind: no temporary.
  int files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 1);
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Formats, RoundTrip,
                         ::testing::Values(MeshFormat::Obj, MeshFormat::Off, MeshFormat::Ply),
                         [](const auto& info) { return std::string(qs::io::format_name(info.param)); });

TEST(WriteMesh, NanAndInfinityRoundTrip) {
  TriMesh m;
  m.positions = {Vec3(std::nan(""), 1, 2), Vec3(std::numeric_limits<double>::infinity(), 0, 0),
                 Vec3(-std::numeric_limits<double>::infinity(), 0, 0)};
  m.faces = {{0, 1, 2}};
  for (MeshFormat f : {MeshFormat::Obj, MeshFormat::Off, MeshFormat::Ply}) {
    const auto r = qs::io::read_mesh_from_memory(qs::io::mesh_to_string(m, f), f, "nan");
    EXPECT_TRUE(std::isnan(r.mesh.positions[0].x()));
    EXPECT_EQ(r.mesh.positions[1].x(), std::numeric_limits<double>::infinity());
    EXPECT_EQ(r.mesh.positions[2].x(), -std::numeric_limits<double>::infinity());
  }
}

TEST(WriteMesh, ObjIsOneBased) {
  TriMesh m;
  m.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1.5, 0)};
  m.faces = {{0, 1, 2}};
  const std::string text = qs::io::mesh_to_string(m, MeshFormat::Obj);
  EXPECT_THAT(text, HasSubstr("v 0 1.5 0\n"));
  EXPECT_THAT(text, HasSubstr("f 1 2 3\n"));
  EXPECT_THAT(qs::io::mesh_to_string(m, MeshFormat::Off), HasSubstr("OFF\n3 1 0\n"));
}

TEST(WriteMesh, UnknownExtensionAndStl) {
  TriMesh m;
  EXPECT_THAT([&] { qs::io::write_mesh("out.xyz", m); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr(".obj .off .ply")));
  EXPECT_THAT([&] { qs::io::write_mesh("out.stl", m); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("writing STL is not supported")));
}

TEST(WriteMesh, BadFaceIndexIsRefused) {
  TriMesh m;
  m.positions = {Vec3(0, 0, 0)};
  m.faces = {{0, 0, 3}};
  EXPECT_THAT([&] { qs::io::mesh_to_string(m, MeshFormat::Off); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("face 0 references vertex 3")));
}

TEST(WriteMesh, UnwritableDirectoryIsIoError) {
  TriMesh m;
  EXPECT_THROW(qs::io::write_mesh("/nonexistent-dir-qs/out.obj", m), qs::IoError);
}

}  // namespace
