#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
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
