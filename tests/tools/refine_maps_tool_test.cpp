// qs-dissect's map refinement as a user runs it: refined charts that the later tools read as before.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "tool_runner.h"
#include "../common/test_support.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;

using qs::test::read_bytes;

namespace {

class RefineMapsTool : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("qs_refine_tool_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    ASSERT_EQ(run_tool("qs-family", "generate -n 2 --seed 3 --faces 1600 --limbs 4 --quiet -o " + d()).exit, 0);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string d() const { return dir_.string(); }
  std::string pair() const { return d() + "/shape00.obj " + d() + "/shape01.obj"; }
  // " --config FILE" for the options object `json` (written to d()/<name>.json).
  std::string config(const std::string& name, const std::string& json) const {
    const fs::path file = dir_ / (name + ".json");
    std::ofstream(file) << json;
    return " --config " + file.string();
  }
  std::string inside_only() const { return config("inside", R"({"refine_across_borders": false})"); }
  // Dissects the pair with `flags` into d()/name twice, checks that the reference's chart is left
  // as the default refinement leaves it, that the runs are byte-identical and that the remesh,
  // merge and correspondence measure read the result; returns qs-metro's run on it.
  RunResult expect_refined_run(const std::string& flags, const std::string& name, const std::string& report_line) {
    RunResult r = run_tool("qs-dissect", pair() + " " + flags + " -o " + d() + "/" + name);
    EXPECT_EQ(r.exit, 0) << r.out;
    EXPECT_THAT(r.out, HasSubstr("refine maps: distortion to mesh 0 "));
    EXPECT_THAT(r.out, HasSubstr(report_line));
    EXPECT_THAT(r.out, HasSubstr(" 0 flipped or zero-area uv faces\n"));
    // "plain": the refinement inside the patches only.
    EXPECT_EQ(run_tool("qs-dissect", pair() + inside_only() + " --quiet -o " + d() + "/plain").exit, 0);
    const fs::path out = dir_ / name;
    EXPECT_EQ(read_bytes(out / "shape00.chart.ply"), read_bytes(dir_ / "plain/shape00.chart.ply"));
    // The cuts add vertices and faces to the refined mesh's chart.
    EXPECT_GT(read_bytes(out / "shape01.chart.ply").size(), read_bytes(dir_ / "plain/shape01.chart.ply").size());
    EXPECT_EQ(run_tool("qs-dissect", pair() + " " + flags + " --quiet -o " + d() + "/" + name + "2").exit, 0);
    EXPECT_EQ(read_bytes(out / "shape01.chart.ply"), read_bytes(dir_ / (name + "2") / "shape01.chart.ply"));
    EXPECT_EQ(read_bytes(out / "dissection.json"), read_bytes(dir_ / (name + "2") / "dissection.json"));
    r = run_tool("qs-remesh", d() + "/" + name + " --level 3 -q -o " + d() + "/" + name + "-remesh");
    EXPECT_EQ(r.exit, 0) << r.out;
    r = run_tool("qs-merge", d() + "/" + name + " -o " + d() + "/" + name + "-merge");
    EXPECT_EQ(r.exit, 0) << r.out;
    r = run_tool("qs-metro", "--correspondence " + d() + "/" + name + " --samples 5000");
    EXPECT_EQ(r.exit, 0) << r.out;
    return r;
  }
  fs::path dir_;
};

}  // namespace

TEST_F(RefineMapsTool, RefinesWritesTheSameFormatAndIsDeterministic) {
  // Inside the patches only (refine_across_borders false): the chart keeps its vertices and faces.
  RunResult r = run_tool("qs-dissect", pair() + inside_only() + " -o " + d() + "/ref");
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("refine maps: reference (not moved)"));
  EXPECT_THAT(r.out, HasSubstr("refine maps: distortion to mesh 0 "));
  EXPECT_THAT(r.out, HasSubstr(" 0 flipped or zero-area uv faces\n"));
  EXPECT_THAT(r.out, HasSubstr(", refine maps "));
  ASSERT_EQ(run_tool("qs-dissect", pair() + " --no-refine-maps --quiet -o " + d() + "/plain").exit, 0);
  // The reference's chart is the plain one; the other mesh's differs (same size: same format).
  EXPECT_EQ(read_bytes(dir_ / "ref/shape00.chart.ply"), read_bytes(dir_ / "plain/shape00.chart.ply"));
  EXPECT_NE(read_bytes(dir_ / "ref/shape01.chart.ply"), read_bytes(dir_ / "plain/shape01.chart.ply"));
  EXPECT_EQ(read_bytes(dir_ / "ref/shape01.chart.ply").size(), read_bytes(dir_ / "plain/shape01.chart.ply").size());
  // Same input, same bytes.
  ASSERT_EQ(run_tool("qs-dissect", pair() + inside_only() + " --quiet -o " + d() + "/ref2").exit, 0);
  EXPECT_EQ(read_bytes(dir_ / "ref/shape01.chart.ply"), read_bytes(dir_ / "ref2/shape01.chart.ply"));
  EXPECT_EQ(read_bytes(dir_ / "ref/dissection.json"), read_bytes(dir_ / "ref2/dissection.json"));
  // The refinement across the patch borders too is the default for a set: no option is
  // refine_maps and refine_across_borders true, byte for byte, and the cuts add to the chart.
  r = run_tool("qs-dissect", pair() + " -o " + d() + "/default");
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("  refine across borders: "));
  ASSERT_EQ(run_tool("qs-dissect", pair() + config("both", R"({"refine_maps": true, "refine_across_borders": true})") +
                                       " --quiet -o " + d() + "/both")
                .exit,
            0);
  EXPECT_EQ(read_bytes(dir_ / "both/shape01.chart.ply"), read_bytes(dir_ / "default/shape01.chart.ply"));
  EXPECT_EQ(read_bytes(dir_ / "both/dissection.json"), read_bytes(dir_ / "default/dissection.json"));
  EXPECT_EQ(read_bytes(dir_ / "default/shape00.chart.ply"), read_bytes(dir_ / "plain/shape00.chart.ply"));
  EXPECT_GT(read_bytes(dir_ / "default/shape01.chart.ply").size(), read_bytes(dir_ / "ref/shape01.chart.ply").size());
  // The later stages consume it unchanged.
  r = run_tool("qs-remesh", d() + "/ref --level 3 -q -o " + d() + "/remesh");
  EXPECT_EQ(r.exit, 0) << r.out;
  r = run_tool("qs-metro", "--correspondence " + d() + "/ref --samples 5000");
  EXPECT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("  dissection: mean "));
}

TEST_F(RefineMapsTool, OneMeshIsLeftAsDissectedAndBadOptionsAreUsageErrors) {
  RunResult r = run_tool("qs-dissect", d() + "/shape00.obj -o " + d() + "/one");
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, Not(HasSubstr("refine maps")));
  r = run_tool("qs-dissect", pair() + config("bad", R"({"refine_iterations": -1})") + " -o " + d() + "/bad");
  EXPECT_EQ(r.exit, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("refine_iterations"));
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
}

TEST_F(RefineMapsTool, AcrossBordersMovesTheCurvesAndTheLaterStagesReadIt) {
  expect_refined_run("", "across", "  refine across borders: ");
  const RunResult r = run_tool("qs-morph", d() + "/across-remesh -o " + d() + "/morph");
  EXPECT_EQ(r.exit, 0) << r.out;
  const RunResult bad =
      run_tool("qs-dissect", pair() + config("bad", R"({"refine_border_sweeps": 21})") + " -o " + d() + "/bad");
  EXPECT_EQ(bad.exit, 1) << bad.out;
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
}

TEST_F(RefineMapsTool, CornersMoveDeterministicallyAndTheLaterStagesReadIt) {
  RunResult r = expect_refined_run(config("corners", R"({"refine_corners": true})"), "corners", "  refine corners: ");
  EXPECT_THAT(r.out, HasSubstr("  patch corners: B's corner to the exact image of A's corner"));
  for (const char* bad : {R"({"refine_corners": true, "refine_corner_sweeps": 21})",
                          R"({"refine_corners": true, "refine_corner_chart": "power"})"}) {
    r = run_tool("qs-dissect", pair() + config("bad", bad) + " -o " + d() + "/bad");
    EXPECT_EQ(r.exit, 1) << bad << "\n" << r.out;
    EXPECT_FALSE(fs::exists(dir_ / "bad"));
  }
}

// Refinement before a split (on by default): the maps of the split nodes are refined before the
// cuts; the set stays bijective, the run is deterministic, refine_before_split true says the
// default out loud, false changes the charts.
TEST_F(RefineMapsTool, RefineBeforeSplitIsTheDeterministicDefaultAndCanBeTurnedOff) {
  RunResult r = run_tool("qs-dissect", pair() + " -o " + d() + "/rbs");
  EXPECT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("\nrefine before split: split nodes' maps of every mesh but the first refined "
                               "against the first's, seen as composition: "));
  EXPECT_THAT(r.out, Not(HasSubstr("bijective: NO")));
  const std::string flags = config("rbs", R"({"refine_before_split": true})");
  EXPECT_EQ(run_tool("qs-dissect", pair() + flags + " --quiet -o " + d() + "/rbs2").exit, 0);
  for (const char* f : {"shape00.chart.ply", "shape01.chart.ply", "dissection.json"})
    EXPECT_EQ(read_bytes(dir_ / "rbs" / f), read_bytes(dir_ / "rbs2" / f)) << f;
  r = run_tool("qs-metro", "--correspondence " + d() + "/rbs --samples 5000");
  EXPECT_EQ(r.exit, 0) << r.out;
  r = run_tool("qs-dissect", pair() + config("own", R"({"refine_before_split": false})") + " -o " + d() + "/own");
  EXPECT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, Not(HasSubstr("refine before split")));
  EXPECT_NE(read_bytes(dir_ / "rbs" / "shape01.chart.ply"), read_bytes(dir_ / "own" / "shape01.chart.ply"));
  r = run_tool("qs-dissect", pair() + config("bad", R"({"refine_before_split_metric": "face"})") + " -o " + d() +
                                 "/bad");
  EXPECT_EQ(r.exit, 1) << r.out;
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
}
