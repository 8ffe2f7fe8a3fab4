// OutputFolder: all-or-nothing output folders; check_not_an_input.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/core/output_folder.h"
#include "../common/test_support.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

using qs::test::read_bytes;

namespace {

class OutputFolderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("qs_output_folder_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  static void write(const fs::path& p, const std::string& s) { std::ofstream(p) << s; }
  int entries() const { return static_cast<int>(std::distance(fs::directory_iterator(dir_), {})); }
  fs::path dir_;
};

TEST_F(OutputFolderTest, NewFolderAppearsOnlyOnCommit) {
  const fs::path target = dir_ / "a" / "b" / "out";
  {
    qs::OutputFolder f(target);
    qs::write_file_atomically(f.staging() / "x.txt", "x");
    EXPECT_FALSE(fs::exists(target));
    f.commit();
  }
  EXPECT_EQ(read_bytes(target / "x.txt"), "x");
  EXPECT_EQ(std::distance(fs::directory_iterator(target.parent_path()), {}), 1);  // no staging left
}

TEST_F(OutputFolderTest, FailureLeavesNothingBehindNotEvenCreatedParents) {
  const fs::path target = dir_ / "new" / "deeper" / "out";
  try {
    qs::OutputFolder f(target);
    qs::write_file_atomically(f.staging() / "x.txt", "x");
    throw std::runtime_error("the run failed");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(entries(), 0);
}

TEST_F(OutputFolderTest, ExistingFolderKeepsOtherFilesAndGetsTheNewOnes) {
  const fs::path target = dir_ / "out";
  fs::create_directories(target);
  write(target / "keep.txt", "keep");
  write(target / "x.txt", "old");
  {
    qs::OutputFolder f(target);
    qs::write_file_atomically(f.staging() / "x.txt", "new");
    EXPECT_EQ(read_bytes(target / "x.txt"), "old");  // untouched until commit
    f.commit();
  }
  EXPECT_EQ(read_bytes(target / "x.txt"), "new");
  EXPECT_EQ(read_bytes(target / "keep.txt"), "keep");
  EXPECT_EQ(entries(), 1);
}

TEST_F(OutputFolderTest, AFolderInTheWayOfAFileFailsBeforeAnythingMoves) {
  const fs::path target = dir_ / "out";
  fs::create_directories(target / "b.txt");
  qs::OutputFolder f(target);
  qs::write_file_atomically(f.staging() / "a.txt", "a");
  qs::write_file_atomically(f.staging() / "b.txt", "b");
  try {
    f.commit();
    FAIL() << "commit should fail";
  } catch (const qs::IoError& e) {
    EXPECT_THAT(e.what(), HasSubstr("b.txt"));
  }
  EXPECT_FALSE(fs::exists(target / "a.txt"));
}

TEST_F(OutputFolderTest, TargetsThatCannotBeFoldersAreIoErrors) {
  write(dir_ / "file", "f");
  EXPECT_THROW(qs::OutputFolder(dir_ / "file"), qs::IoError);
  EXPECT_THROW(qs::OutputFolder(dir_ / "file" / "sub"), qs::IoError);
  EXPECT_EQ(read_bytes(dir_ / "file"), "f");
  EXPECT_EQ(entries(), 1);
}

TEST_F(OutputFolderTest, AnOutputThatIsAnInputIsAUsageError) {
  write(dir_ / "a.obj", "a");
  const fs::path same = dir_ / "." / "a.obj";
  EXPECT_THROW(qs::check_not_an_input(same, {dir_ / "a.obj"}, "-o"), qs::UsageError);
  fs::create_symlink(dir_ / "a.obj", dir_ / "link.obj");
  EXPECT_THROW(qs::check_not_an_input(dir_ / "link.obj", {dir_ / "a.obj"}, "-o"), qs::UsageError);
  EXPECT_NO_THROW(qs::check_not_an_input(dir_ / "b.obj", {dir_ / "a.obj"}, "-o"));
}

}  // namespace
