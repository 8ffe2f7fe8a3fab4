// qs-family as a user runs it: files, determinism, the meshes pass qs-inspect, exit codes.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "qs/io/write_mesh.h"
#include "qs/shapes/shapes.h"
#include "tool_runner.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

class FamilyTool : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("qs_family_tool_" + std::to_string(::getpid()));
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
  const auto doc = nlohmann::json::parse(slurp(dir_ / "a" / "family.json"));
  EXPECT_EQ(doc["format"], "qs-family");
  EXPECT_EQ(doc["meshes"].size(), 3u);
  const auto map = nlohmann::json::parse(slurp(dir_ / "a" / "shape01.map.json"));
  EXPECT_EQ(map["domain"], "sphere");
  EXPECT_EQ(map["vertices"], 602);
}

TEST_F(FamilyTool, SameSeedGivesIdenticalBytesForAnyThreadCount) {
  ASSERT_EQ(run_tool("qs-family", "generate -n 2 --seed 3 --faces 800 --quiet -o " + (dir_ / "a").string()).exit, 0);
  ASSERT_EQ(run_tool("qs-family", "generate -n 2 --seed 3 --faces 800 -q --threads 1 --output " + (dir_ / "b").string()).exit, 0);
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir_ / "a")) {
    ++files;
    EXPECT_EQ(slurp(e.path()), slurp(dir_ / "b" / e.path().filename())) << e.path().filename();
  }
  EXPECT_EQ(files, 7);
  ASSERT_EQ(run_tool("qs-family", "generate -n 1 --seed 4 --faces 800 --quiet -o " + (dir_ / "c").string()).exit, 0);
  EXPECT_NE(slurp(dir_ / "a" / "shape00.obj"), slurp(dir_ / "c" / "shape00.obj"));
}

TEST_F(FamilyTool, BadOptionsGiveTheDocumentedExitCodes) {
  RunResult r = run_tool("qs-family", "");
  EXPECT_EQ(r.exit, 1) << r.out;
  r = run_tool("qs-family", "generate --faces 1001 -o " + (dir_ / "x").string());
  EXPECT_EQ(r.exit, 2) << r.out;
  EXPECT_THAT(r.out, HasSubstr("faces = 1001"));
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
  const auto map = nlohmann::json::parse(slurp(dir_ / "out" / "ball_r.map.json"));
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
