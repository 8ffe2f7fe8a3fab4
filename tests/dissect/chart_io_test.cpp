// The chart file: version 2 (float64 uv) round-trips bit for bit; version 1 (float32 uv) is still read.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "qs/core/error.h"
#include "qs/dissect/chart_io.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

namespace {

qs::dissect::Chart tetra_chart() {
  qs::dissect::Chart c;
  c.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  c.mesh.faces = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  // uv with more digits than a float holds
  for (int f = 0; f < 4; ++f)
    c.face_uv.push_back({qs::Vec2(0.1 + f / 5.0, 1.0 / 7), qs::Vec2(0.9, 0.123456789012345), qs::Vec2(1e-17, 1)});
  c.face_patch = {0, 0, 1, 1};
  c.patches.resize(2);
  return c;
}

template <class T>
void put(std::ostream& out, T v) {
  out.write(reinterpret_cast<const char*>(&v), sizeof(T));
}

}  // namespace

TEST(ChartIo, Version2KeepsUvBitForBit) {
  const fs::path dir = fs::temp_directory_path() / ("qs_chart_io_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const auto c = tetra_chart();
  qs::dissect::write_chart_ply(dir / "t.chart.ply", c);
  std::ifstream in(dir / "t.chart.ply", std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  EXPECT_THAT(s.str(), HasSubstr("comment qs chart version 2\n"));
  EXPECT_THAT(s.str(), HasSubstr("property list uchar double texcoord\n"));
  const auto back = qs::dissect::read_chart_ply(dir / "t.chart.ply");
  EXPECT_EQ(back.face_uv, c.face_uv);
  EXPECT_EQ(back.mesh.positions, c.mesh.positions);
  EXPECT_EQ(back.mesh.faces, c.mesh.faces);
  EXPECT_EQ(back.face_patch, c.face_patch);
  fs::remove_all(dir);
}

TEST(ChartIo, Version1WithFloatUvIsStillRead) {
  const fs::path dir = fs::temp_directory_path() / ("qs_chart_v1_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const auto c = tetra_chart();
  {
    std::ofstream out(dir / "old.chart.ply", std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\ncomment qs chart: cut mesh, per-face patch and wedge uv\n"
        << "element vertex 4\nproperty double x\nproperty double y\nproperty double z\nelement face 4\n"
        << "property list uchar int vertex_indices\nproperty list uchar float texcoord\nproperty int patch\n"
        << "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
    for (const auto& p : c.mesh.positions)
      for (int k = 0; k < 3; ++k) put<double>(out, p[k]);
    for (int f = 0; f < 4; ++f) {
      put<std::uint8_t>(out, 3);
      for (int k = 0; k < 3; ++k) put<std::int32_t>(out, c.mesh.faces[f][k]);
      put<std::uint8_t>(out, 6);
      for (int k = 0; k < 3; ++k)
        for (int d = 0; d < 2; ++d) put<float>(out, static_cast<float>(c.face_uv[f][k][d]));
      put<std::int32_t>(out, c.face_patch[f]);
      for (int k = 0; k < 3; ++k) put<std::uint8_t>(out, 200);
    }
  }
  const auto back = qs::dissect::read_chart_ply(dir / "old.chart.ply");
  ASSERT_EQ(back.face_uv.size(), 4u);
  for (int f = 0; f < 4; ++f)
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 2; ++d) EXPECT_EQ(back.face_uv[f][k][d], static_cast<float>(c.face_uv[f][k][d]));
  EXPECT_EQ(back.patches.size(), 2u);
  fs::remove_all(dir);
}
