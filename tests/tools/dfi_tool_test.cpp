// qs-dfi as a user runs it: outputs, dfi.json, exit codes and messages.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "../common/gltf_test_support.h"
#include "qs/io/write_mesh.h"
#include "qs/shapes/shapes.h"
#include "tool_runner.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

namespace {

class DfiTool : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("qs_dfi_tool_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const qs::TriMesh& m) {
    qs::io::write_mesh(dir_ / name, m);
    return (dir_ / name).string();
  }
  fs::path dir_;
};

}  // namespace

TEST_F(DfiTool, SphereToTorusWritesFramesJsonAndGlb) {
  const std::string a = write("sphere.obj", qs::shapes::icosphere(3));
  const std::string b = write("torus.off", qs::shapes::torus(48, 16));
  const fs::path out = dir_ / "out";
  const RunResult r = run_tool("qs-dfi", a + " " + b + " --no-warp --frames 4 --grid 24 -q -o " + out.string() +
                                             " --glb " + (dir_ / "m.glb").string() + " --exact-endpoints");
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_TRUE(fs::exists(dir_ / "m.glb"));
  std::string validator_out;
  const int rc = qs::testing::run_gltf_validator(dir_ / "m.glb", &validator_out);
  if (rc != 3) {  // 3: the validator is not installed
    EXPECT_EQ(rc, 0) << validator_out;
  }
  for (int f = 0; f < 4; ++f) EXPECT_TRUE(fs::exists(out / ("frame_000" + std::to_string(f) + ".obj")));
  const auto j = nlohmann::json::parse(std::ifstream(out / "dfi.json"));
  EXPECT_EQ(j["method"], "blend");
  EXPECT_EQ(j["source"]["genus"], 0);
  EXPECT_EQ(j["target"]["genus"], 1);  // reported, not rejected
  ASSERT_EQ(j["frames"].size(), 4u);
  EXPECT_EQ(j["frames"][0]["input"], true);
  EXPECT_EQ(j["frames"][1]["input"], false);
  EXPECT_EQ(j["frames"][3]["genus"], 1);
  for (const auto& f : j["frames"]) EXPECT_GT(f["volume"].get<double>(), 0);

  // Same input and options: the same bytes, on one thread or two.
  const RunResult r1 = run_tool("qs-dfi", a + " " + b + " --no-warp --frames 3 --grid 20 -q --threads 1 -o " +
                                              (dir_ / "t1").string());
  const RunResult r2 = run_tool("qs-dfi", a + " " + b + " --no-warp --frames 3 --grid 20 -q --threads 2 -o " +
                                              (dir_ / "t2").string());
  ASSERT_EQ(r1.exit, 0) << r1.out;
  ASSERT_EQ(r2.exit, 0) << r2.out;
  for (const char* f : {"frame_0001.obj", "dfi.json", "frame_0000.obj"}) {
    std::ifstream x(dir_ / "t1" / f), y(dir_ / "t2" / f);
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(x), {}), std::string(std::istreambuf_iterator<char>(y), {})) << f;
  }
}

TEST_F(DfiTool, RejectsOpenMeshesSeveralComponentsAndBadOptions) {
  const std::string sphere = write("sphere.obj", qs::shapes::icosphere(2));
  const std::string disk = write("disk.obj", qs::shapes::open_disk(3));
  const std::string two = write("two.obj", qs::shapes::two_components());
  RunResult r = run_tool("qs-dfi", sphere + " " + disk + " --no-warp -o " + (dir_ / "o").string());
  EXPECT_EQ(r.exit, 2) << r.out;
  EXPECT_THAT(r.out, HasSubstr("boundary"));
  r = run_tool("qs-dfi", two + " " + sphere + " --no-warp -o " + (dir_ / "o").string());
  EXPECT_EQ(r.exit, 2) << r.out;
  EXPECT_THAT(r.out, HasSubstr("components"));
  r = run_tool("qs-dfi", sphere + " " + sphere + " --landmarks " + sphere + " -o " + (dir_ / "o").string());
  EXPECT_EQ(r.exit, 1) << r.out;  // --landmarks takes two files
  r = run_tool("qs-dfi", sphere + " " + (dir_ / "missing.obj").string() + " --no-warp");
  EXPECT_EQ(r.exit, 3) << r.out;
  r = run_tool("qs-dfi", sphere + " " + sphere + " --no-warp --grid 2");
  EXPECT_EQ(r.exit, 1) << r.out;
}

TEST_F(DfiTool, WarpReportsSkeletonsMatchesAnchorsAndFolds) {
  const std::string a = write("a.obj", qs::shapes::ellipsoid(1.6, 0.6, 0.5, 3));
  const std::string b = write("b.off", qs::shapes::torus(48, 16));
  const fs::path out = dir_ / "w";
  const RunResult r = run_tool("qs-dfi", a + " " + b + " --frames 3 --grid 24 --emd-voxels 300 -q -o " + out.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  const auto j = nlohmann::json::parse(std::ifstream(out / "dfi.json"));
  EXPECT_EQ(j["method"], "warp");
  EXPECT_GT(j["skeletons"]["source"]["nodes"].size(), 1u);
  EXPECT_GT(j["skeletons"]["target"]["edges"].size(), 1u);
  EXPECT_GE(j["anchors"].size(), 1u);
  EXPECT_GT(j["correspondence"]["folds"]["source_min_det"].get<double>(), 0);
  EXPECT_GT(j["correspondence"]["source_voxels"].get<int>(), 50);
  for (const auto& f : j["frames"]) EXPECT_GT(f["volume"].get<double>(), 0);
  // Even frame times (the default): from 0 to 1, increasing, with the dense samples behind them.
  EXPECT_EQ(j["timing"]["method"], "even");
  EXPECT_GE(j["timing"]["dense_t"].size(), 9u);
  EXPECT_EQ(j["timing"]["dense_change"].size() + 1, j["timing"]["dense_t"].size());
  EXPECT_EQ(j["frames"][0]["t"].get<double>(), 0.0);
  EXPECT_EQ(j["frames"][2]["t"].get<double>(), 1.0);
  EXPECT_GT(j["frames"][1]["t"].get<double>(), 0.0);
  EXPECT_LT(j["frames"][1]["t"].get<double>(), 1.0);
}

TEST_F(DfiTool, UniformTimingAndEndpointRefinement) {
  const std::string a = write("ua.obj", qs::shapes::icosphere(3));
  const std::string b = write("ub.obj", qs::shapes::torus(48, 16));
  int ends[2] = {0, 0};
  for (int refine = 1; refine <= 2; ++refine) {
    const fs::path out = dir_ / ("u" + std::to_string(refine));
    const RunResult r = run_tool("qs-dfi", a + " " + b + " --no-warp --frames 5 --grid 20 --timing uniform -q "
                                               "--endpoint-refine " + std::to_string(refine) + " -o " + out.string());
    ASSERT_EQ(r.exit, 0) << r.out;
    const auto j = nlohmann::json::parse(std::ifstream(out / "dfi.json"));
    EXPECT_EQ(j["timing"]["method"], "uniform");
    EXPECT_EQ(j["options"]["endpoint_refine"], refine);
    for (int f = 0; f < 5; ++f) EXPECT_DOUBLE_EQ(j["frames"][f]["t"].get<double>(), f / 4.0) << f;
    EXPECT_EQ(j["frames"][4]["genus"], 1);
    EXPECT_EQ(j["frames"][4]["components"], 1);
    ends[refine - 1] = j["frames"][0]["vertices"].get<int>();
  }
  EXPECT_GT(ends[1], 3 * ends[0]);  // a grid twice as fine: about four times the vertices
  const RunResult bad = run_tool("qs-dfi", a + " " + b + " --no-warp --timing sometimes -o " + (dir_ / "x").string());
  EXPECT_EQ(bad.exit, 1) << bad.out;
}

TEST_F(DfiTool, PartWarpGivesTheSameBytesOnOneOrTwoThreads) {
  // A capsule-like ellipsoid to a longer one: one matched branch, so the part warp (bones) runs.
  const std::string a = write("pa.obj", qs::shapes::ellipsoid(1.2, 0.4, 0.4, 3));
  const std::string b = write("pb.obj", qs::shapes::ellipsoid(1.6, 0.35, 0.3, 3));
  std::string bytes[2][3];
  for (int t = 1; t <= 2; ++t) {
    const fs::path out = dir_ / ("p" + std::to_string(t));
    const RunResult r = run_tool("qs-dfi", a + " " + b + " --frames 3 --grid 24 --emd-voxels 300 -q --threads " +
                                               std::to_string(t) + " -o " + out.string());
    ASSERT_EQ(r.exit, 0) << r.out;
    const auto j = nlohmann::json::parse(std::ifstream(out / "dfi.json"));
    EXPECT_EQ(j["correspondence"]["warp"], "parts");
    EXPECT_GT(j["correspondence"]["bones"].get<int>(), 0);
    for (const auto& f : j["frames"]) {
      EXPECT_EQ(f["components"], 1);
      EXPECT_EQ(f["genus"], 0);
    }
    int k = 0;
    for (const char* f : {"frame_0001.obj", "dfi.json", "frame_0000.obj"}) {
      std::ifstream x(out / f);
      bytes[t - 1][k++] = std::string(std::istreambuf_iterator<char>(x), {});
    }
  }
  EXPECT_EQ(bytes[0][0], bytes[1][0]);
  EXPECT_EQ(bytes[0][1], bytes[1][1]);
  EXPECT_EQ(bytes[0][2], bytes[1][2]);  // the refined endpoint frame
}
