#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/core/geometry2d.h"
#include "qs/core/mesh.h"

namespace fs = std::filesystem;

TEST(Error, ExitCodesAreTheDocumentedTable) {
  EXPECT_EQ(qs::exit_code(qs::ErrorCode::Usage), 1);
  EXPECT_EQ(qs::exit_code(qs::ErrorCode::InvalidInput), 2);
  EXPECT_EQ(qs::exit_code(qs::ErrorCode::Io), 3);
  EXPECT_EQ(qs::exit_code(qs::ErrorCode::Solver), 4);
  EXPECT_EQ(qs::exit_code(qs::ErrorCode::Internal), 70);
  EXPECT_EQ(qs::InvalidInput("x").code(), qs::ErrorCode::InvalidInput);
  EXPECT_STREQ(qs::error_name(qs::ErrorCode::Io), "i/o");
}

TEST(AtomicFile, CommitRenamesAndAbandonLeavesNothing) {
  const fs::path dir = fs::temp_directory_path() / "qs_atomic_test";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fs::path target = dir / "out.txt";
  {
    qs::AtomicFile f(target);
    f.stream() << "half";
    // destroyed without commit: as if an exception was thrown mid-write
  }
  EXPECT_FALSE(fs::exists(target));
  EXPECT_TRUE(fs::is_empty(dir)) << "the temporary file must be removed";
  qs::write_file_atomically(target, "whole");
  std::ifstream in(target);
  std::string s;
  in >> s;
  EXPECT_EQ(s, "whole");
  fs::remove_all(dir);
}

TEST(AtomicFile, UnwritableDirectoryIsAnIoError) {
  EXPECT_THROW(qs::AtomicFile("/nonexistent-dir-qs/x.obj"), qs::IoError);
}

TEST(Mesh, BoundingBoxAndArea) {
  qs::TriMesh m;
  m.positions = {{0, 0, 0}, {2, 0, 0}, {0, 1, 0}};
  m.faces = {{0, 1, 2}};
  EXPECT_DOUBLE_EQ(qs::face_area(m, 0), 1.0);
  EXPECT_DOUBLE_EQ(qs::bounding_box(m.positions).diagonal(), std::sqrt(5.0));
}

// The hierarchy only skips segments: every distance is polyline_distance's, bit for bit, on
// random walks (long, short, with repeated points) and on points near and far from them.
TEST(PolylineDistance, EqualsTheDirectScanBitForBit) {
  std::mt19937 rng(7);
  std::normal_distribution<double> step(0.0, 1.0);
  std::uniform_real_distribution<double> box(-40.0, 40.0);
  for (const int points : {1, 2, 3, 9, 10, 17, 200, 1500}) {
    std::vector<qs::Vec3> line{qs::Vec3(0, 0, 0)};
    for (int k = 1; k < points; ++k)
      line.push_back(k % 7 == 3 ? line.back() : line.back() + qs::Vec3(step(rng), step(rng), step(rng)));
    const qs::PolylineDistance to_line(line);
    for (int q = 0; q < 400; ++q) {
      const qs::Vec3 jitter(step(rng), step(rng), step(rng));
      const qs::Vec3 p = q % 2 ? line[static_cast<size_t>(q) % line.size()] + 0.01 * jitter
                               : qs::Vec3(box(rng), box(rng), box(rng));
      const double direct = qs::polyline_distance(p, line);
      ASSERT_EQ(to_line(p), direct) << points << " points, query " << q;
    }
    EXPECT_EQ(to_line(line.back()), 0.0);
  }
}
