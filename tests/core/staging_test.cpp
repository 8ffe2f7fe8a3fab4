// Staging left by killed runs: removed by the next run into the same target, never while its
// process runs.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/core/output_folder.h"
#include "../common/test_support.h"

namespace fs = std::filesystem;

using qs::test::read_bytes;

namespace {

class StagingTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("qs_staging_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    for (pid_t p : children_) {
      ::kill(p, SIGKILL);
      ::waitpid(p, nullptr, 0);
    }
    fs::remove_all(dir_);
  }
  // A child process that runs until killed.
  pid_t live_child() {
    const pid_t pid = ::fork();
    if (pid == 0) {
      for (;;) ::pause();
    }
    children_.push_back(pid);
    return pid;
  }
  static void stop(pid_t pid) {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, nullptr, 0);
  }
  // The id of a process that has exited and been reaped.
  static pid_t dead_pid() {
    const pid_t pid = ::fork();
    if (pid == 0) ::_exit(0);
    ::waitpid(pid, nullptr, 0);
    return pid;
  }
  static fs::path staged(const fs::path& target, pid_t pid) {
    return target.parent_path() / (target.filename().string() + ".tmp-" + std::to_string(pid));
  }
  fs::path dir_;
  std::vector<pid_t> children_;
};

TEST_F(StagingTest, AKilledRunsStagingFolderIsRemovedByTheNextRun) {
  const fs::path target = dir_ / "out";
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t child = ::fork();
  if (child == 0) {
    // A run that stages a file and is killed before it commits.
    qs::OutputFolder f(target);
    qs::write_file_atomically(f.staging() / "half.txt", "half");
    const char c = 'r';
    if (::write(ready[1], &c, 1) != 1) ::_exit(1);
    for (;;) ::pause();
  }
  children_.push_back(child);
  char c = 0;
  ASSERT_EQ(::read(ready[0], &c, 1), 1);
  ::close(ready[0]);
  ::close(ready[1]);
  EXPECT_TRUE(fs::exists(staged(target, child) / "half.txt"));
  // While the run is alive, its staging folder is its own.
  {
    qs::OutputFolder f(target);
    EXPECT_TRUE(fs::exists(staged(target, child) / "half.txt"));
  }
  stop(child);
  EXPECT_TRUE(fs::is_directory(staged(target, child)));  // the kill left it
  EXPECT_FALSE(fs::exists(target));
  {
    qs::OutputFolder f(target);
    qs::write_file_atomically(f.staging() / "x.txt", "x");
    EXPECT_FALSE(fs::exists(staged(target, child)));
    f.commit();
  }
  EXPECT_EQ(read_bytes(target / "x.txt"), "x");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), {}), 1);
}

TEST_F(StagingTest, OnlyTheSameTargetsFoldersOfGoneProcessesAreRemoved) {
  const fs::path target = dir_ / "out";
  const pid_t gone = dead_pid(), live = live_child();
  fs::create_directories(staged(target, gone) / "sub");
  fs::create_directories(staged(target, live));
  fs::create_directories(staged(dir_ / "other", gone));           // another target
  fs::create_directories(dir_ / ("out.tmp-" + std::to_string(gone) + "x"));  // not a process id
  fs::create_directories(dir_ / "out.tmp-");
  std::ofstream(staged(target, gone + 0).string() + "0") << "";  // a file, "out.tmp-<pid>0"
  EXPECT_EQ(qs::remove_stale_staging(target, true), 1);
  EXPECT_FALSE(fs::exists(staged(target, gone)));
  EXPECT_TRUE(fs::exists(staged(target, live)));
  EXPECT_TRUE(fs::exists(staged(dir_ / "other", gone)));
  EXPECT_TRUE(fs::exists(dir_ / ("out.tmp-" + std::to_string(gone) + "x")));
  EXPECT_TRUE(fs::exists(dir_ / "out.tmp-"));
  stop(live);
  { qs::OutputFolder f(target); }
  EXPECT_FALSE(fs::exists(staged(target, live)));
  EXPECT_FALSE(fs::exists(target));
}

TEST_F(StagingTest, AReusedProcessIdDoesNotKeepAnOldFolderAlive) {
  const fs::path target = dir_ / "out";
  const pid_t live = live_child();
  // The id belongs to a process started now; a folder last changed an hour ago is not its own.
  fs::create_directories(staged(target, live));
  fs::last_write_time(staged(target, live), fs::file_time_type::clock::now() - std::chrono::hours(1));
  EXPECT_FALSE(qs::staging_owner_running(live, fs::last_write_time(staged(target, live))));
  EXPECT_TRUE(qs::staging_owner_running(live, fs::file_time_type::clock::now()));
  EXPECT_TRUE(qs::staging_owner_running(::getpid(), fs::file_time_type::clock::now() - std::chrono::hours(1)));
  EXPECT_EQ(qs::remove_stale_staging(target, true), 1);
  EXPECT_FALSE(fs::exists(staged(target, live)));
}

TEST_F(StagingTest, AtomicFilesRemoveTheTemporaryFilesOfGoneProcesses) {
  const fs::path file = dir_ / "x.txt";
  const pid_t gone = dead_pid(), live = live_child();
  std::ofstream(staged(file, gone)) << "half";
  std::ofstream(staged(file, live)) << "being written";
  std::ofstream(staged(dir_ / "y.txt", gone)) << "another file's";
  qs::write_file_atomically(file, "whole");
  EXPECT_EQ(read_bytes(file), "whole");
  EXPECT_FALSE(fs::exists(staged(file, gone)));
  EXPECT_EQ(read_bytes(staged(file, live)), "being written");
  EXPECT_TRUE(fs::exists(staged(dir_ / "y.txt", gone)));
  // A folder of that name is an OutputFolder's, not a file's: left alone.
  const pid_t gone2 = dead_pid();
  fs::create_directories(staged(file, gone2));
  qs::write_file_atomically(file, "again");
  EXPECT_TRUE(fs::is_directory(staged(file, gone2)));
}

TEST_F(StagingTest, FilesBesideOthersAreStagedInsideTheFolder) {
  const fs::path folder = dir_ / "meshes";
  fs::create_directories(folder);
  std::ofstream(folder / "input.obj") << "input";
  std::ofstream(folder / "out.obj") << "old";
  const pid_t gone = dead_pid();
  fs::create_directories(staged(folder / "out.obj", gone));
  {
    qs::OutputFolder f(folder, "out.obj");
    EXPECT_EQ(f.staging(), staged(folder / "out.obj", ::getpid()));
    EXPECT_FALSE(fs::exists(staged(folder / "out.obj", gone)));
    qs::write_file_atomically(f.staging() / "out.obj", "new");
    qs::write_file_atomically(f.staging() / "out.map.json", "{}");
    EXPECT_EQ(read_bytes(folder / "out.obj"), "old");
    EXPECT_FALSE(fs::exists(folder / "out.map.json"));
    f.commit();
  }
  EXPECT_EQ(read_bytes(folder / "out.obj"), "new");
  EXPECT_EQ(read_bytes(folder / "out.map.json"), "{}");
  EXPECT_EQ(read_bytes(folder / "input.obj"), "input");
  EXPECT_EQ(std::distance(fs::directory_iterator(folder), {}), 3);
  // A failed run into a folder it had to create leaves nothing, not even the folder.
  try {
    qs::OutputFolder f(dir_ / "new" / "deeper", "out.obj");
    qs::write_file_atomically(f.staging() / "out.obj", "x");
    throw std::runtime_error("the run failed");
  } catch (const std::runtime_error&) {
  }
  EXPECT_FALSE(fs::exists(dir_ / "new"));
  EXPECT_THROW(qs::OutputFolder(folder / "input.obj", "out.obj"), qs::IoError);
}

}  // namespace
