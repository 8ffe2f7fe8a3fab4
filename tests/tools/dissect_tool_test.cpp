// qs-dissect as a user runs it: outputs, exit codes, messages.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "qs/io/write_mesh.h"
#include "qs/shapes/shapes.h"
#include "tool_runner.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class DissectTool : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("qs_dissect_tool_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const qs::TriMesh& m) {
    qs::io::write_mesh(dir_ / name, m);
    return (dir_ / name).string();
  }
  fs::path dir_;
};

TEST_F(DissectTool, WritesTheChartAndTheJsonContract) {
  const std::string blob = write("blob.obj", qs::shapes::star_blob(4, 1.5, 4));
  const fs::path out = dir_ / "out";
  const RunResult r = run_tool("qs-dissect", blob + " --tau 1.5 -o " + out.string() + " --report " +
                                                 (dir_ / "report.txt").string());
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("bijective: yes"));
  ASSERT_TRUE(fs::exists(out / "blob.chart.ply"));
  ASSERT_TRUE(fs::exists(dir_ / "report.txt"));
  std::ifstream in(out / "dissection.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["format"], "qs-dissection");
  EXPECT_EQ(j["version"], 1);
  EXPECT_EQ(j["base_domain"]["euler_characteristic"], 2);
  EXPECT_TRUE(j["base_domain"]["closed_conforming"].get<bool>());
  const auto& mesh = j["meshes"][0];
  EXPECT_EQ(mesh["chart"], "blob.chart.ply");
  EXPECT_EQ(mesh["patches"].size(), j["base_domain"]["patches"].size());
  EXPECT_GT(mesh["patches"].size(), 2u);
  for (const auto& p : mesh["patches"]) {
    EXPECT_EQ(p["flipped_faces"], 0);
    if (p["stretch"].get<double>() > 1.5) { EXPECT_TRUE(p.contains("stop_reason")) << p.dump(); }
  }
  // The same input and options give byte-identical files.
  const fs::path out2 = dir_ / "out2";
  ASSERT_EQ(run_tool("qs-dissect", blob + " --tau 1.5 -q -o " + out2.string()).exit, 0);
  auto bytes = [](const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
  };
  EXPECT_EQ(bytes(out / "dissection.json"), bytes(out2 / "dissection.json"));
  EXPECT_EQ(bytes(out / "blob.chart.ply"), bytes(out2 / "blob.chart.ply"));
}

TEST_F(DissectTool, ExitCodes) {
  const std::string torus = write("torus.obj", qs::shapes::torus(12, 8));
  const RunResult bad = run_tool("qs-dissect", torus + " -o " + (dir_ / "t").string());
  EXPECT_EQ(bad.exit, 2) << bad.out;
  EXPECT_THAT(bad.out, HasSubstr("genus"));
  EXPECT_FALSE(fs::exists(dir_ / "t" / "dissection.json"));
  const std::string ball = write("ball.obj", qs::shapes::icosphere(2));
  EXPECT_EQ(run_tool("qs-dissect", ball + " " + ball).exit, 1);
  EXPECT_EQ(run_tool("qs-dissect", ball + " --tau 0.5").exit, 1);
  EXPECT_EQ(run_tool("qs-dissect", (dir_ / "missing.obj").string()).exit, 3);
  std::ofstream(dir_ / "ball.landmarks.json") << R"({"seeds": [0, 1, 1, 2]})";
  const RunResult dup = run_tool("qs-dissect", ball + " -o " + (dir_ / "b").string());
  EXPECT_EQ(dup.exit, 2) << dup.out;
  EXPECT_THAT(dup.out, HasSubstr("same point"));
  std::ofstream(dir_ / "ball.landmarks.json") << R"({"seeds": [0, 40, 80, 120]})";
  const RunResult ok = run_tool("qs-dissect", ball + " -o " + (dir_ / "c").string());
  EXPECT_EQ(ok.exit, 0) << ok.out;
  EXPECT_THAT(ok.out, HasSubstr("ball.landmarks.json"));
}
