// qs-family as a user runs it: files, determinism, the meshes pass qs-inspect, exit codes.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "qs/io/write_mesh.h"
#include "qs/shapes/shapes.h"
#include "../common/test_support.h"
#include "tool_runner.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

using qs::test::read_bytes;
using qs::test::snapshot;

namespace {

// A shell word for `s` (names with any bytes).
std::string quoted(const fs::path& p) {
  std::string q = "'";
  for (char c : p.string()) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

class FamilyTool : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("qs_family_tool_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

}  // namespace

TEST_F(FamilyTool, GeneratesMeshesLandmarksAndMapsThatQsInspectAccepts) {
  const RunResult r = run_tool("qs-family", "generate -n 3 --seed 7 --faces 1200 -o " + (dir_ / "a").string());
  ASSERT_EQ(r.exit, 0) << r.out;
  for (const char* stem : {"shape00", "shape01", "shape02"}) {
    for (const char* ext : {".obj", ".landmarks.json", ".map.json"})
      EXPECT_TRUE(fs::exists(dir_ / "a" / (std::string(stem) + ext))) << stem << ext;
    const RunResult i = run_tool("qs-inspect", (dir_ / "a" / (std::string(stem) + ".obj")).string());
    EXPECT_EQ(i.exit, 0) << i.out;
    EXPECT_THAT(i.out, HasSubstr("accepted"));
    EXPECT_THAT(i.out, HasSubstr("4 seeds"));
  }
  const auto doc = nlohmann::json::parse(read_bytes(dir_ / "a" / "family.json"));
  EXPECT_EQ(doc["format"], "qs-family");
  EXPECT_EQ(doc["meshes"].size(), 3u);
  const auto map = nlohmann::json::parse(read_bytes(dir_ / "a" / "shape01.map.json"));
  EXPECT_EQ(map["domain"], "sphere");
  EXPECT_EQ(map["vertices"], 602);
}

TEST_F(FamilyTool, SameSeedGivesIdenticalBytesForAnyThreadCount) {
  ASSERT_EQ(run_tool("qs-family", "generate -n 2 --seed 3 --faces 800 --quiet -o " + (dir_ / "a").string()).exit, 0);
  ASSERT_EQ(run_tool("qs-family", "generate -n 2 --seed 3 --faces 800 -q --threads 1 --output " + (dir_ / "b").string()).exit, 0);
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir_ / "a")) {
    ++files;
    EXPECT_EQ(read_bytes(e.path()), read_bytes(dir_ / "b" / e.path().filename())) << e.path().filename();
  }
  EXPECT_EQ(files, 7);
  ASSERT_EQ(run_tool("qs-family", "generate -n 1 --seed 4 --faces 800 --quiet -o " + (dir_ / "c").string()).exit, 0);
  EXPECT_NE(read_bytes(dir_ / "a" / "shape00.obj"), read_bytes(dir_ / "c" / "shape00.obj"));
}

TEST_F(FamilyTool, BadOptionsGiveTheDocumentedExitCodes) {
  RunResult r = run_tool("qs-family", "");
  EXPECT_EQ(r.exit, 1) << r.out;
  r = run_tool("qs-family", "generate --faces 1001 -o " + (dir_ / "x").string());
  EXPECT_EQ(r.exit, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("--faces: Value 1001: expected an even count"));
  EXPECT_FALSE(fs::exists(dir_ / "x" / "shape00.obj"));
  r = run_tool("qs-family", "retessellate " + (dir_ / "missing.obj").string() + " -o " + (dir_ / "y.obj").string());
  EXPECT_EQ(r.exit, 3) << r.out;
  qs::io::write_mesh(dir_ / "open.obj", qs::shapes::open_disk(3));
  r = run_tool("qs-family", "retessellate " + (dir_ / "open.obj").string() + " -o " + (dir_ / "y.obj").string());
  EXPECT_EQ(r.exit, 2) << r.out;
  EXPECT_FALSE(fs::exists(dir_ / "y.obj"));
}

TEST_F(FamilyTool, RetessellateWritesOriginsAndTransfersLandmarks) {
  qs::io::write_mesh(dir_ / "ball.obj", qs::shapes::bumpy_sphere(0.2, 3, 4));
  std::ofstream(dir_ / "ball.landmarks.json") << R"({"seeds": [0, 5, 9, 20], "features": {"tip": 100}})";
  fs::create_directories(dir_ / "out");
  const RunResult r = run_tool("qs-family", "retessellate " + (dir_ / "ball.obj").string() + " --faces 3000 -o " +
                                                (dir_ / "out" / "ball_r.obj").string());
  ASSERT_EQ(r.exit, 0) << r.out;
  // Chords of a convex bumpy ball: a little less area, said as a signed percentage.
  EXPECT_THAT(r.out, ::testing::ContainsRegex(" faces, area -0\\.[0-9]{2}% against the input"));
  EXPECT_THAT(r.out, ::testing::ContainsRegex("surfaces at most 0\\.[0-9]{3}% of the diagonal apart"));
  const auto map = nlohmann::json::parse(read_bytes(dir_ / "out" / "ball_r.map.json"));
  EXPECT_EQ(map["domain"], "surface");
  EXPECT_EQ(map["reference"], "../ball.obj");
  EXPECT_EQ(map["reference_faces"], 5120);
  const RunResult i = run_tool("qs-inspect", (dir_ / "out" / "ball_r.obj").string());
  EXPECT_EQ(i.exit, 0) << i.out;
  EXPECT_THAT(i.out, HasSubstr("4 seeds, 1 features"));
  // --keep-shape: the same files, a surface no farther from the input (the ball has no thin parts).
  const RunResult k =
      run_tool("qs-family", "retessellate " + (dir_ / "ball.obj").string() + " --faces 3000 --keep-shape -o " +
                                (dir_ / "out" / "ball_k.obj").string());
  ASSERT_EQ(k.exit, 0) << k.out;
  auto gap = [](const std::string& out) {
    const auto at = out.find("surfaces at most ");
    return at == std::string::npos ? -1.0 : std::stod(out.substr(at + 17));
  };
  EXPECT_GT(gap(k.out), 0);
  EXPECT_LE(gap(k.out), gap(r.out));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "ball_k.map.json"));
  EXPECT_EQ(run_tool("qs-inspect", (dir_ / "out" / "ball_k.obj").string()).exit, 0);
}

// A small family member with landmarks, the input of retessellate and pose below.
class FamilyToolInputs : public FamilyTool {
 protected:
  void SetUp() override {
    FamilyTool::SetUp();
    ASSERT_EQ(run_tool("qs-family", "generate -n 1 --seed 2 --faces 600 --limbs 4 -q -o " + (dir_ / "fam").string()).exit,
              0);
    fs::create_directories(dir_ / "sub");
    fs::copy_file(dir_ / "fam" / "shape00.obj", dir_ / "sub" / "m.obj");
    fs::copy_file(dir_ / "fam" / "shape00.landmarks.json", dir_ / "sub" / "m.landmarks.json");
    before_ = snapshot(dir_ / "sub");
  }
  std::map<std::string, std::string> before_;
};

TEST_F(FamilyToolInputs, AnOutputThatIsAnInputIsRefusedUnderAnySpelling) {
  const fs::path sub = dir_ / "sub";
  fs::create_directory_symlink(sub, dir_ / "link_dir");
  fs::create_symlink(sub / "m.obj", dir_ / "link.obj");
  const std::vector<std::string> outputs = {
      (sub / "m.obj").string(),
      (sub / ".." / "sub" / "." / "m.obj").string(),
      (dir_ / "link.obj").string(),
      (dir_ / "link_dir" / "m.obj").string(),
      (sub / "m.off").string(),  // would write m.landmarks.json, the input's landmarks
  };
  for (const char* sub_command : {"retessellate", "pose"}) {
    for (const std::string& out : outputs) {
      const RunResult r = run_tool("qs-family", std::string(sub_command) + " " + (sub / "m.obj").string() + " -o " + out);
      EXPECT_EQ(r.exit, 1) << sub_command << " -o " << out << ": " << r.out;
      EXPECT_THAT(r.out, HasSubstr("an input of this run")) << r.out;
      EXPECT_EQ(snapshot(sub), before_) << sub_command << " -o " << out;
    }
  }
  // The landmarks given with --landmarks, and the sidecars of pose --retessellate.
  RunResult r = run_tool("qs-family", "retessellate " + (sub / "m.obj").string() + " --landmarks " +
                                          (dir_ / "fam" / "shape00.landmarks.json").string() + " -o " +
                                          (dir_ / "fam" / "shape00.ply").string());
  EXPECT_EQ(r.exit, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("would also write"));
  r = run_tool("qs-family", "pose " + (sub / "m.obj").string() + " --retessellate --landmarks " +
                                (sub / "m.landmarks.json").string() + " -o " + (sub / "x.obj").string());
  EXPECT_EQ(r.exit, 0) << r.out;  // x_r.landmarks.json is not an input
  fs::rename(sub / "x_r.landmarks.json", sub / "lm.json");
  for (const char* f : {"x.obj", "x.landmarks.json", "x.source.landmarks.json", "x.pose.json", "x_r.obj", "x_r.map.json"})
    fs::remove(sub / f);
  fs::rename(sub / "lm.json", sub / "x_r.landmarks.json");
  const auto with_lm = snapshot(sub);
  r = run_tool("qs-family", "pose " + (sub / "m.obj").string() + " --retessellate --landmarks " +
                                (sub / "x_r.landmarks.json").string() + " -o " + (sub / "x.obj").string());
  EXPECT_EQ(r.exit, 1) << r.out;
  EXPECT_EQ(snapshot(sub), with_lm);
}

TEST_F(FamilyToolInputs, RetessellateAndPoseWriteAllTheirFilesOrNone) {
  const fs::path out = dir_ / "out";
  fs::create_directories(out / "r.map.json");  // a folder where the map would go
  std::ofstream(out / "keep.txt") << "keep";
  const auto before = snapshot(out);
  RunResult r = run_tool("qs-family", "retessellate " + (dir_ / "sub" / "m.obj").string() + " -o " + (out / "r.obj").string());
  EXPECT_EQ(r.exit, 3) << r.out;
  EXPECT_THAT(r.out, HasSubstr("r.map.json: is a folder"));
  EXPECT_EQ(snapshot(out), before);
  fs::create_directories(out / "p_r.landmarks.json");
  r = run_tool("qs-family", "pose " + (dir_ / "sub" / "m.obj").string() + " --retessellate -o " + (out / "p.obj").string());
  EXPECT_EQ(r.exit, 3) << r.out;
  EXPECT_EQ(snapshot(out).size(), before.size() + 1);
  EXPECT_FALSE(fs::exists(out / "p.obj"));
  // Into a new folder: everything at once, and nothing staged is left.
  r = run_tool("qs-family", "retessellate " + (dir_ / "sub" / "m.obj").string() + " -q -o " +
                                (dir_ / "new" / "deeper" / "r.obj").string());
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_EQ(snapshot(dir_ / "new" / "deeper").size(), 3u);
  const auto map = nlohmann::json::parse(read_bytes(dir_ / "new" / "deeper" / "r.map.json"));
  EXPECT_EQ(map["reference"], "../../sub/m.obj");  // from the final folder, not the staging one
}

TEST_F(FamilyTool, AFailedGenerateLeavesNothingBehind) {
  // Shape 3 of this family folds in every sampling: shapes 0-2 were made and staged first.
  const std::string args = "generate -n 6 --faces 200 --variation 2 --seed 4 --threads 1 -q -o ";
  RunResult r = run_tool("qs-family", args + (dir_ / "new").string());
  EXPECT_EQ(r.exit, 2) << r.out;
  EXPECT_THAT(r.out, HasSubstr("shape03"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), {}), 0);
  fs::create_directories(dir_ / "old");
  std::ofstream(dir_ / "old" / "shape00.obj") << "the user's";
  r = run_tool("qs-family", args + (dir_ / "old").string());
  EXPECT_EQ(r.exit, 2) << r.out;
  EXPECT_EQ(snapshot(dir_ / "old"), (std::map<std::string, std::string>{{"shape00.obj", "the user's"}}));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), {}), 1);
}

TEST_F(FamilyTool, AnInterruptedGenerateLeavesNothingAndTheNextRunRemovesItsStaging) {
  const fs::path target = dir_ / "fam";
  const std::string tool = std::string(QS_TOOLS_DIR) + "/qs-family";
  std::vector<std::string> args = {tool, "generate", "-n", "40", "--faces", "4000", "--threads", "1", "-q", "-o",
                                   target.string()};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t defaults;
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGINT);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGDEF);
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, tool.c_str(), nullptr, &attr, argv.data(), environ), 0);
  posix_spawnattr_destroy(&attr);
  const fs::path staging = dir_ / ("fam.tmp-" + std::to_string(pid));
  const auto start = std::chrono::steady_clock::now();
  while (!fs::exists(staging / "shape00.map.json") && std::chrono::steady_clock::now() - start < std::chrono::seconds(20))
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ::kill(pid, SIGINT);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the run ended before it was interrupted";
  EXPECT_FALSE(fs::exists(target));       // nothing in the target
  EXPECT_TRUE(fs::is_directory(staging));  // what a kill cannot clean up
  const RunResult r = run_tool("qs-family", "generate -n 1 --faces 400 -q -o " + target.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_FALSE(fs::exists(staging));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), {}), 1);
}

TEST_F(FamilyToolInputs, NamesThatAreNotUtf8GiveAMessageOrWork) {
  const fs::path odd = dir_ / "d\xff";
  fs::create_directories(odd);
  fs::copy_file(dir_ / "sub" / "m.obj", odd / "m\xfe.obj");
  fs::copy_file(dir_ / "sub" / "m.obj", odd / "m.obj");
  // The map file would have to hold "m\xfe.obj": refused, saying why, with the bytes escaped.
  RunResult r = run_tool("qs-family", "retessellate " + quoted(odd / "m\xfe.obj") + " -o " + quoted(odd / "r.obj"));
  EXPECT_EQ(r.exit, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("m\\xfe.obj"));
  EXPECT_THAT(r.out, HasSubstr("UTF-8"));
  EXPECT_FALSE(fs::exists(odd / "r.obj"));
  // A folder that is not UTF-8 around a map whose path within it is: works.
  r = run_tool("qs-family", "retessellate " + quoted(odd / "m.obj") + " -q -o " + quoted(odd / "r\xfd.obj"));
  EXPECT_EQ(r.exit, 0) << r.out;
  EXPECT_EQ(nlohmann::json::parse(read_bytes(odd / "r\xfd.map.json"))["reference"], "m.obj");
  // pose records its input's name escaped; its re-tessellation's map would hold "p\xfd.obj": refused.
  r = run_tool("qs-family", "pose " + quoted(odd / "m\xfe.obj") + " -q -o " + quoted(odd / "p\xfd.obj"));
  EXPECT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(read_bytes(odd / "p\xfd.pose.json"), HasSubstr("m\\\\xfe.obj"));
  r = run_tool("qs-family", "pose " + quoted(odd / "m\xfe.obj") + " --retessellate -o " + quoted(odd / "q\xfd.obj"));
  EXPECT_EQ(r.exit, 1) << r.out;
  EXPECT_FALSE(fs::exists(odd / "q\xfd.obj"));
  r = run_tool("qs-family", "generate -n 1 --faces 400 -q -o " + quoted(odd / "g\xfc"));
  EXPECT_EQ(r.exit, 0) << r.out;
  EXPECT_TRUE(fs::exists(odd / "g\xfc" / "shape00.map.json"));
}

TEST_F(FamilyTool, NumericOptionsAreCheckedBeforeAnyWork) {
  const fs::path mesh = dir_ / "ball.obj";
  qs::io::write_mesh(mesh, qs::shapes::icosphere(2));
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"generate --seed -1", "--seed"},
      {"generate --seed 18446744073709551616", "--seed"},
      {"generate --seed 1e3", "--seed"},
      {"generate -n 0", "--shapes"},
      {"generate -n 257", "--shapes"},
      {"generate --faces 2000002", "--faces"},
      {"generate --faces -4", "--faces"},
      {"generate --variation nan", "--variation"},
      {"generate --variation 1e400", "--variation"},
      {"generate --variation -0.5", "--variation"},
      {"generate --limbs 7", "--limbs"},
      {"generate --threads -1", "--threads"},
      {"generate --max-memory nan", "--max-memory"},
      {"retessellate " + mesh.string() + " --faces 99", "--faces"},
      {"retessellate " + mesh.string() + " --faces 4294967396", "--faces"},
      {"retessellate " + mesh.string() + " --iterations 0", "--iterations"},
      {"retessellate " + mesh.string() + " --max-memory inf", "--max-memory"},
      {"pose " + mesh.string() + " --seed -1", "--seed"},
      {"pose " + mesh.string() + " --limbs -1", "--limbs"},
      {"pose " + mesh.string() + " --min-angle nan", "--min-angle"},
      {"pose " + mesh.string() + " --max-angle 121", "--max-angle"},
      {"pose " + mesh.string() + " --min-angle 70 --max-angle 60", "--min-angle 70 is larger"},
      {"pose " + mesh.string() + " --retessellate --faces 50", "--faces"},
  };
  for (const auto& [args, says] : cases) {
    const RunResult r = run_tool("qs-family", args + " -o " + (dir_ / "out" / "o.obj").string());
    EXPECT_EQ(r.exit, 1) << args << ": " << r.out;
    EXPECT_THAT(r.out, HasSubstr(says)) << args;
    EXPECT_FALSE(fs::exists(dir_ / "out")) << args;
  }
  // The largest seed is a seed.
  EXPECT_EQ(run_tool("qs-family", "generate -n 1 --faces 400 -q --seed 18446744073709551615 -o " + (dir_ / "s").string()).exit, 0);
  EXPECT_EQ(nlohmann::json::parse(read_bytes(dir_ / "s" / "family.json"))["seed"], 18446744073709551615ull);
}

TEST_F(FamilyTool, LargeRequestsAreRefusedUpFrontWithTheirSize) {
  const fs::path mesh = dir_ / "ball.obj";
  qs::io::write_mesh(mesh, qs::shapes::icosphere(2));
  struct Case {
    std::string args, says;
  };
  const std::vector<Case> cases = {
      // One 2M-face shape does not fit in 0.3 GiB.
      {"generate -n 256 --faces 2000000 --max-memory 0.3 -o " + (dir_ / "fam").string(),
       "generate -n 256 --faces 2000000 (one shape at a time) needs about"},
      // The finer remesh of --keep-shape holds 18M faces.
      {"retessellate " + mesh.string() + " --keep-shape --faces 2000000 -o " + (dir_ / "r.obj").string(),
       "retessellate --keep-shape of 320 faces to 2000000 needs about"},
      {"pose " + mesh.string() + " --retessellate --keep-shape --faces 2000000 -o " + (dir_ / "p.obj").string(),
       "needs about"},
  };
  for (const Case& c : cases) {
    const auto start = std::chrono::steady_clock::now();
    const RunResult r = run_tool("qs-family", c.args);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(r.exit, 1) << c.args << ": " << r.out;
    EXPECT_THAT(r.out, HasSubstr(c.says)) << r.out;
    EXPECT_THAT(r.out, ::testing::ContainsRegex("needs about [0-9.]+ GiB of memory, more than --max-memory"));
    EXPECT_LT(seconds, 1.0) << c.args;
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), {}), 1);  // the ball only
}
