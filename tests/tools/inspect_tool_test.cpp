// Runs the qs-inspect binary as a user would and checks exit codes and messages.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include "qs/io/write_mesh.h"
#include "tool_runner.h"
#include "qs/shapes/shapes.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

namespace {

RunResult inspect(const std::string& args) { return run_tool("qs-inspect", args); }

class InspectTool : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("qs_inspect_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const qs::TriMesh& m) {
    const fs::path p = dir_ / name;
    qs::io::write_mesh(p, m);
    return p.string();
  }
  std::string write_text(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }
  fs::path dir_;
};

}  // namespace

TEST_F(InspectTool, AcceptsAClosedGenusZeroMesh) {
  const RunResult r = inspect(write("ball.obj", qs::shapes::icosphere(2)));
  EXPECT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("accepted"));
}

TEST_F(InspectTool, RejectsEachNegativeCaseWithItsReason) {
  const RunResult torus = inspect(write("torus.off", qs::shapes::torus(12, 8)));
  EXPECT_EQ(torus.exit, 2) << torus.out;
  EXPECT_THAT(torus.out, HasSubstr("genus 1"));
  const RunResult disk = inspect(write("disk.ply", qs::shapes::open_disk(3)));
  EXPECT_EQ(disk.exit, 2) << disk.out;
  EXPECT_THAT(disk.out, HasSubstr("boundary"));
  const RunResult two = inspect(write("two.obj", qs::shapes::two_components()));
  EXPECT_EQ(two.exit, 2) << two.out;
  EXPECT_THAT(two.out, HasSubstr("components"));
  const RunResult fan = inspect(write("fan.obj", qs::shapes::nonmanifold_fan()));
  EXPECT_EQ(fan.exit, 2) << fan.out;
  EXPECT_THAT(fan.out, HasSubstr("non-manifold"));
}

TEST_F(InspectTool, ExitCodesForUsageIoAndParseErrors) {
  EXPECT_EQ(inspect("").exit, 1);
  EXPECT_EQ(inspect("--bogus x.obj").exit, 1);
  EXPECT_EQ(inspect("--help").exit, 0);
  const RunResult missing = inspect((dir_ / "nope.obj").string());
  EXPECT_EQ(missing.exit, 3) << missing.out;
  EXPECT_THAT(missing.out, HasSubstr("nope.obj"));
  const RunResult bad = inspect(write_text("bad.off", "OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n"));
  EXPECT_EQ(bad.exit, 2) << bad.out;
  EXPECT_THAT(bad.out, HasSubstr("bad.off:4"));
  const RunResult ext = inspect(write_text("mesh.xyz", "1 2 3\n"));
  EXPECT_EQ(ext.exit, 2) << ext.out;
  // The worst outcome wins: one good, one unreadable.
  EXPECT_EQ(inspect(write("ok.obj", qs::shapes::icosphere(1)) + " " + (dir_ / "gone.obj").string()).exit, 3);
}

TEST_F(InspectTool, JsonReportAndLandmarksBesideTheMesh) {
  const std::string ball = write("ball.obj", qs::shapes::icosphere(2));
  write_text("ball.landmarks.json", R"({"seeds": [0, 1, 2, 3], "features": {"top": 5}})");
  const std::string torus = write("torus.obj", qs::shapes::torus(10, 6));
  const RunResult r = inspect("--json " + ball + " " + torus);
  EXPECT_EQ(r.exit, 2);
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j.size(), 2u);
  EXPECT_TRUE(j[0]["accepted"].get<bool>());
  EXPECT_EQ(j[0]["landmarks"]["seeds"].size(), 4u);
  EXPECT_EQ(j[0]["landmarks"]["features"][0]["name"], "top");
  EXPECT_FALSE(j[1]["accepted"].get<bool>());
  EXPECT_EQ(j[1]["validation"]["genus"], 1);

  write_text("bad.landmarks.json", R"({"seeds": [0, 1, 2, 99999]})");
  const RunResult lm = inspect(ball + " --landmarks " + (dir_ / "bad.landmarks.json").string());
  EXPECT_EQ(lm.exit, 2) << lm.out;
  EXPECT_THAT(lm.out, HasSubstr("out of range"));
}
