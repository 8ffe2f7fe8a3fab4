// qs-metro as a user runs it: text and JSON reports, exit codes, messages.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "qs/io/write_mesh.h"
#include "qs/shapes/shapes.h"
#include "../common/test_support.h"
#include "tool_runner.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;

using qs::test::scaled;

namespace {

RunResult metro(const std::string& args) { return run_tool("qs-metro", args); }

class MetroTool : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("qs_metro_tool_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const qs::TriMesh& m) {
    qs::io::write_mesh(dir_ / name, m);
    return (dir_ / name).string();
  }
  std::string write_text(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name, std::ios::binary) << text;
    return (dir_ / name).string();
  }
  fs::path dir_;
};
}  // namespace

TEST_F(MetroTool, PrintsBothDirectionsAndTheTwoSidedDistance) {
  const std::string a = write("a.obj", qs::shapes::icosphere(3));
  const std::string b = write("b.ply", scaled(qs::shapes::icosphere(3), 1.1));
  const RunResult r = metro(a + " " + b + " --samples 5000");
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("qs-metro: A = " + a + " (642 vertices, 1280 faces), B = " + b));
  EXPECT_THAT(r.out, HasSubstr("bounding box diagonal of A: "));
  EXPECT_THAT(r.out, HasSubstr("(used for the percentages)"));
  EXPECT_THAT(r.out, HasSubstr("A -> B: mean 0.09"));
  EXPECT_THAT(r.out, HasSubstr("(5000 surface samples + 642 vertices)"));
  EXPECT_THAT(r.out, HasSubstr("B -> A: mean "));
  EXPECT_THAT(r.out, HasSubstr("Hausdorff (two-sided): max "));
  EXPECT_THAT(r.out, HasSubstr("%)"));
  // The same inputs give the same report, byte for byte.
  EXPECT_EQ(metro(a + " " + b + " --samples 5000").out, r.out);
}

TEST_F(MetroTool, JsonReportHasEveryNumber) {
  const std::string a = write("a.off", qs::shapes::icosphere(3));
  // B as an ASCII STL, a soup of separate triangles (STL has no shared vertices).
  std::ostringstream stl;
  stl << "solid b\n";
  const qs::TriMesh sb = scaled(qs::shapes::icosphere(2), 1.1);
  for (const auto& f : sb.faces) {
    stl << "facet normal 0 0 0\nouter loop\n";
    for (int v : f) {
      const auto& p = sb.positions[static_cast<size_t>(v)];
      stl << "vertex " << p.x() << " " << p.y() << " " << p.z() << "\n";
    }
    stl << "endloop\nendfacet\n";
  }
  stl << "endsolid b\n";
  const std::string b = write_text("b.stl", stl.str());
  const RunResult r = metro("--json --samples 4000 --seed 7 " + a + " " + b);
  ASSERT_EQ(r.exit, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["a"]["file"], a);
  EXPECT_EQ(j["a"]["faces"], 1280);
  EXPECT_EQ(j["b"]["faces"], 320);
  EXPECT_EQ(j["diagonal_of"], "A");
  EXPECT_EQ(j["seed"], 7);
  const double d = j["diagonal"].get<double>();
  EXPECT_GT(d, 3.0);
  for (const char* side : {"a_to_b", "b_to_a"}) {
    const auto& s = j[side];
    for (const char* key : {"mean", "rms", "max", "mean_percent", "rms_percent", "max_percent", "max_at",
                            "samples", "vertex_samples"})
      EXPECT_TRUE(s.contains(key)) << side << "." << key;
    EXPECT_EQ(s["samples"], 4000);
    EXPECT_NEAR(s["mean"].get<double>(), 0.1, 0.02);  // B is coarse: its faces sag
    EXPECT_NEAR(s["max_percent"].get<double>(), 100 * s["max"].get<double>() / d, 1e-9);
  }
  const auto& two = j["two_sided"];
  EXPECT_EQ(two["max"].get<double>(),
            std::max(j["a_to_b"]["max"].get<double>(), j["b_to_a"]["max"].get<double>()));
  for (const char* key : {"mean", "rms", "mean_percent", "rms_percent", "max_percent"})
    EXPECT_TRUE(two.contains(key)) << key;
  // The soup of 320 separate triangles is no qs input, but it is measurable.
  EXPECT_EQ(j["b"]["vertices"], 960);
  EXPECT_THAT(j["b"]["problems"].get<std::vector<std::string>>(), ::testing::Contains("boundary_edges"));
  EXPECT_TRUE(j["a"]["problems"].empty());
}

TEST_F(MetroTool, WritesTheReportToAFile) {
  const std::string a = write("a.obj", qs::shapes::icosphere(2));
  const fs::path out = dir_ / "report.json";
  const RunResult r = metro(a + " " + a + " --json --samples 1000 -o " + out.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_EQ(r.out, "");
  std::ifstream in(out);
  const auto j = nlohmann::json::parse(in);
  EXPECT_LT(j["two_sided"]["max"].get<double>(), 1e-12);
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_THAT(e.path().filename().string(), ::testing::Not(HasSubstr(".tmp"))) << "temporary left behind";
}

TEST_F(MetroTool, TheReportDoesNotDependOnTheThreadCount) {
  const std::string a = write("a.obj", qs::shapes::icosphere(3));
  const std::string b = write("b.obj", qs::shapes::torus(32, 12));
  const RunResult one = metro(a + " " + b + " --json --samples 20000 --threads 1");
  const RunResult three = metro(a + " " + b + " --json --samples 20000 --threads 3");
  ASSERT_EQ(one.exit, 0) << one.out;
  ASSERT_EQ(three.exit, 0) << three.out;
  EXPECT_EQ(one.out, three.out);
  EXPECT_EQ(metro(a + " " + b + " --threads -1").exit, 1);
}

TEST_F(MetroTool, OpenMeshesAreMeasuredWithANote) {
  const std::string a = write("disk.obj", qs::shapes::open_disk(4));
  const RunResult r = metro(a + " " + a + " --samples 1000");
  EXPECT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("note: A is not a closed genus-0 mesh (boundary_edges); measured anyway"));
}

TEST_F(MetroTool, ExitCodesForUsageIoAndInvalidInput) {
  const std::string ok = write("ok.obj", qs::shapes::icosphere(1));
  EXPECT_EQ(metro("").exit, 1);
  EXPECT_EQ(metro(ok).exit, 1);  // B missing
  EXPECT_EQ(metro(ok + " " + ok + " " + ok).exit, 1);
  EXPECT_EQ(metro(ok + " " + ok + " --samples 0").exit, 1);
  EXPECT_EQ(metro(ok + " " + ok + " --samples -5").exit, 1);
  EXPECT_EQ(metro(ok + " " + ok + " --bogus").exit, 1);
  EXPECT_EQ(metro("--help").exit, 0);

  const RunResult missing = metro(ok + " " + (dir_ / "nope.obj").string());
  EXPECT_EQ(missing.exit, 3) << missing.out;
  EXPECT_THAT(missing.out, HasSubstr("nope.obj"));
  const RunResult unwritable = metro(ok + " " + ok + " -o " + (dir_ / "no_dir" / "r.txt").string());
  EXPECT_EQ(unwritable.exit, 3) << unwritable.out;

  const RunResult empty = metro(write_text("empty.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n") + " " + ok);
  EXPECT_EQ(empty.exit, 2) << empty.out;
  EXPECT_THAT(empty.out, HasSubstr("empty.off (A): cannot measure"));
  const RunResult nan =
      metro(ok + " " + write_text("nan.off", "OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n"));
  EXPECT_EQ(nan.exit, 2) << nan.out;
  EXPECT_THAT(nan.out, HasSubstr("nan.off (B)"));
  EXPECT_THAT(nan.out, HasSubstr("coordinate"));
  const RunResult parse = metro(write_text("bad.off", "OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n") + " " + ok);
  EXPECT_EQ(parse.exit, 2) << parse.out;
  EXPECT_THAT(parse.out, HasSubstr("bad.off:4"));
  const RunResult flat = metro(write_text("flat.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n2 0 0\n3 0 1 2\n") + " " + ok);
  EXPECT_EQ(flat.exit, 2) << flat.out;
  EXPECT_THAT(flat.out, HasSubstr("A: every face has zero area"));
  EXPECT_THAT(flat.out, HasSubstr("A = " + (dir_ / "flat.off").string()));
}

// -o is opened before any work: a report that cannot be written (a folder, a missing folder) is
// an i/o error without measuring; a report that is an input is a usage error.
TEST_F(MetroTool, AReportThatCannotBeWrittenFailsBeforeMeasuring) {
  const std::string a = write("a.obj", qs::shapes::icosphere(2));
  const std::string b = write("b.obj", scaled(qs::shapes::icosphere(2), 1.1));
  RunResult r = metro(a + " " + b + " -o " + dir_.string());
  EXPECT_EQ(r.exit, 3) << r.out;
  EXPECT_THAT(r.out, HasSubstr("is a folder"));
  r = metro(a + " " + b + " -o " + (dir_ / "nodir" / "r.txt").string());
  EXPECT_EQ(r.exit, 3) << r.out;
  r = metro(a + " " + b + " -o " + (dir_ / "." / "b.obj").string());
  EXPECT_EQ(r.exit, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("is an input of this run"));
  // Only the inputs are left.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 2);
}

// Every numeric option is checked for range (without wrapping) and finiteness before any work.
TEST_F(MetroTool, NumericOptionsOutOfRangeAreUsageErrors) {
  const std::string a = write("a.obj", qs::shapes::icosphere(1));
  const std::string b = write("b.obj", scaled(qs::shapes::icosphere(1), 1.1));
  for (const char* bad : {"--seed -1", "--seed 18446744073709551616", "--seed 1.5", "--seed 0x10", "--samples 0",
                          "--samples -5", "--samples 1e400", "--samples nan", "--max-samples 0", "--threads -1",
                          "--samples 20 --max-samples 10"}) {
    const RunResult r = metro(a + " " + b + " " + bad);
    EXPECT_EQ(r.exit, 1) << bad << ": " << r.out;
    EXPECT_THAT(r.out, Not(HasSubstr("qs-metro: A = "))) << bad;
  }
  const RunResult top = metro(a + " " + b + " --samples 100 --seed 18446744073709551615 --json");
  ASSERT_EQ(top.exit, 0) << top.out;
  EXPECT_EQ(nlohmann::json::parse(top.out)["seed"], 18446744073709551615ull);
}
