// Hostile input and unlucky output paths, as a user meets them with the tools. Each case
// gets its documented exit code (1 usage, 2 invalid input, 3 i/o), a short message naming the file,
// never a crash or exit 70, and after a failure the output folder is exactly as before the run.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
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

using qs::test::read_bytes;
using qs::test::snapshot;
using qs::test::scaled;

namespace {

void write_bytes(const fs::path& p, const std::string& s) {
  std::ofstream f(p, std::ios::binary);
  f << s;
}

// No "tmp-" staging folder is left beside `target`.
bool no_staging_left(const fs::path& target) {
  for (const auto& e : fs::directory_iterator(target.parent_path()))
    if (e.path().filename().string().rfind(target.filename().string() + ".tmp-", 0) == 0) return false;
  return true;
}

// The shape of a well-formed failure: the documented code, a one-line message naming the tool,
// no internal error, and a bounded size.
void expect_clean_failure(const RunResult& r, int code, const std::string& part) {
  EXPECT_EQ(r.exit, code) << r.out;
  EXPECT_THAT(r.out, Not(HasSubstr("internal error")));
  EXPECT_LT(r.out.size(), 4000u) << r.out.substr(0, 400);
  if (!part.empty()) {
    EXPECT_THAT(r.out, HasSubstr(part));
  }
}

}  // namespace

class RobustTool : public ::testing::Test {
 protected:
  // One dissection and one remesh of a small blob, shared by the tests (made once).
  static void SetUpTestSuite() {
    root_ = fs::temp_directory_path() / ("qs_robust_tool_" + std::to_string(::getpid()));
    fs::create_directories(root_);
    qs::io::write_mesh(root_ / "blob.obj", qs::shapes::star_blob(4, 1.5, 3));
    qs::io::write_mesh(root_ / "ball.obj", qs::shapes::icosphere(3));
    const RunResult d = run_tool("qs-dissect", (root_ / "blob.obj").string() + " " + (root_ / "ball.obj").string() +
                                                   " --tau 2 -q -o " + (root_ / "set.dissection").string());
    ASSERT_EQ(d.exit, 0) << d.out;
    const RunResult r = run_tool("qs-remesh", (root_ / "set.dissection").string() + " --level 2 -q -o " +
                                                  (root_ / "remesh").string());
    ASSERT_EQ(r.exit, 0) << r.out;
  }
  static void TearDownTestSuite() { fs::remove_all(root_); }
  void SetUp() override {
    dir_ = root_ / ::testing::UnitTest::GetInstance()->current_test_info()->name();
    fs::create_directories(dir_);
  }
  std::string write(const std::string& name, const qs::TriMesh& m) {
    qs::io::write_mesh(dir_ / name, m);
    return (dir_ / name).string();
  }
  std::string text(const std::string& name, const std::string& contents) {
    write_bytes(dir_ / name, contents);
    return (dir_ / name).string();
  }
  // A copy of the shared dissection (or remesh) to damage.
  fs::path copy_of(const std::string& what) {
    const fs::path to = dir_ / what;
    fs::copy(root_ / what, to, fs::copy_options::recursive);
    return to;
  }
  static fs::path root_;
  fs::path dir_;
};
fs::path RobustTool::root_;

// --- coordinates too large, non-finite bounding boxes ---------------------------------------------

TEST_F(RobustTool, CoordinatesTooLargeToSquareAreInvalidInputEverywhere) {
  const std::string tet = write("tet.off", scaled(qs::shapes::icosphere(0), 1e154));
  expect_clean_failure(run_tool("qs-inspect", tet), 2, "non_finite_coordinates");
  const RunResult d = run_tool("qs-dissect", tet + " -q -o " + (dir_ / "out").string());
  expect_clean_failure(d, 2, "1e100");
  EXPECT_FALSE(fs::exists(dir_ / "out"));
  EXPECT_TRUE(no_staging_left(dir_ / "out"));
  qs::TriMesh one = qs::shapes::icosphere(1);
  one.positions[3].x() = 1e200;
  const std::string far = write("far.obj", one);
  const RunResult i = run_tool("qs-inspect", far);
  expect_clean_failure(i, 2, "too large");
  EXPECT_THAT(i.out, Not(HasSubstr("diagonal: inf")));
  expect_clean_failure(run_tool("qs-metro", far + " " + far), 2, "");
}

// --- landmark files ------------------------------------------------------------------------------

TEST_F(RobustTool, DeeplyNestedLandmarkJsonIsRefusedWithoutRecursion) {
  const std::string ball = write("ball.obj", qs::shapes::icosphere(2));
  const std::string lm = text("deep.json", std::string(100000, '['));
  expect_clean_failure(run_tool("qs-inspect", ball + " --landmarks " + lm), 2, "nested more than");
  expect_clean_failure(run_tool("qs-dissect", ball + " -q --landmarks " + lm + " -o " + (dir_ / "o").string()), 2,
                       "nested more than");
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}

TEST_F(RobustTool, LargeWrongLandmarkValuesMakeShortMessages) {
  const std::string ball = write("ball.obj", qs::shapes::icosphere(2));
  std::string big = "{\"features\": {\"a\": [";
  for (int i = 0; i < 200000; ++i) big += (i ? ",1" : "1");
  big += "]}}";
  expect_clean_failure(run_tool("qs-inspect", ball + " --landmarks " + text("big.json", big)), 2, "an array of");
}

TEST_F(RobustTool, LandmarkNumbersOutOfRange) {
  const std::string ball = write("ball.obj", qs::shapes::icosphere(2));
  expect_clean_failure(
      run_tool("qs-inspect", ball + " --landmarks " + text("p1.json", R"({"features": {"a": {"point": [1e200, 0, 0]}}})")),
      2, "1e100");
  expect_clean_failure(
      run_tool("qs-inspect", ball + " --landmarks " + text("p2.json", R"({"features": {"a": {"point": [1e400, 0, 0]}}})")),
      2, "");
  // 2^64 - 1 is named as it is, never as -1.
  const RunResult big =
      run_tool("qs-inspect", ball + " --landmarks " + text("v.json", R"({"features": {"a": 18446744073709551615}})"));
  expect_clean_failure(big, 2, "18446744073709551615");
  EXPECT_THAT(big.out, Not(HasSubstr("vertex -1")));
  // A repeated key is an error, not a silent last-one-wins.
  expect_clean_failure(
      run_tool("qs-inspect", ball + " --landmarks " + text("dup.json", R"({"features": {"a": 1, "a": 2}})")), 2,
      "appears twice");
}

TEST_F(RobustTool, NonUtf8BytesNeverMakeAnInternalError) {
  const std::string ball = write("ball.obj", qs::shapes::icosphere(2));
  // A mesh file name that is not UTF-8, under --json.
  const fs::path odd = dir_ / "b\xe9.obj";
  fs::copy_file(ball, odd);
  const RunResult j = run_tool("qs-inspect", "--json '" + odd.string() + "'");
  EXPECT_EQ(j.exit, 0) << j.out;
  EXPECT_NO_THROW({ const auto parsed = nlohmann::json::parse(j.out); (void)parsed; });
  // A PLY element name that is not UTF-8, under --json.
  const std::string ply = text("weird.ply",
                               "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                               "property float z\nelement face 4\nproperty list uchar int vertex_indices\n"
                               "element w\xe9ird 1\nproperty int a\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                               "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n5\n");
  const RunResult p = run_tool("qs-inspect", "--json " + ply);
  EXPECT_EQ(p.exit, 0) << p.out;
  EXPECT_NO_THROW({ const auto parsed = nlohmann::json::parse(p.out); (void)parsed; });
  // A landmark file whose parse error quotes a non-UTF-8 byte.
  expect_clean_failure(
      run_tool("qs-inspect", "--json " + ball + " --landmarks " + text("bad.json", "{\"features\": \xff}")), 2, "");
  // A Latin-1 name in a .pp file: refused before anything is written.
  const std::string pp = text("ball.pp",
                              "<!DOCTYPE PickedPoints>\n<PickedPoints>\n"
                              " <point x=\"0\" y=\"0\" z=\"1\" name=\"n\xe9z\" active=\"1\"/>\n</PickedPoints>\n");
  expect_clean_failure(run_tool("qs-dissect", ball + " -q --landmarks " + pp + " -o " + (dir_ / "o").string()), 2,
                       "UTF-8");
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}

// --- output paths --------------------------------------------------------------------------------

TEST_F(RobustTool, OutputPathsThatCannotBeFoldersAreIoErrors) {
  const std::string ball = write("ball.obj", qs::shapes::icosphere(2));
  const std::string file = text("a_file", "keep me");
  expect_clean_failure(run_tool("qs-dissect", ball + " -q -o " + file), 3, "not a folder");
  expect_clean_failure(run_tool("qs-dissect", ball + " -q -o " + file + "/sub"), 3, "");
  expect_clean_failure(run_tool("qs-remesh", (root_ / "set.dissection").string() + " --level 1 -q -o " + file), 3,
                       "not a folder");
  expect_clean_failure(run_tool("qs-remesh", (root_ / "set.dissection").string() + " --level 1 -q -o " + file + "/x"),
                       3, "");
  EXPECT_EQ(read_bytes(file), "keep me");
  if (::geteuid() != 0) {  // root may write anywhere
    fs::create_directories(dir_ / "ro");
    fs::permissions(dir_ / "ro", fs::perms::owner_read | fs::perms::owner_exec);
    expect_clean_failure(run_tool("qs-dissect", ball + " -q -o " + (dir_ / "ro").string()), 3, "");
    fs::permissions(dir_ / "ro", fs::perms::owner_all);
  }
}

TEST_F(RobustTool, NoToolWritesOverItsOwnInput) {
  const std::string a = write("a.obj", qs::shapes::icosphere(2));
  const std::string b = write("b.obj", qs::shapes::ellipsoid(1, 1.1, 0.9, 2));
  const std::string before = read_bytes(a);
  expect_clean_failure(run_tool("qs-metro", a + " " + b + " -o " + a), 1, "input");
  expect_clean_failure(run_tool("qs-dissect", a + " -q --report " + a + " -o " + (dir_ / "d").string()), 1, "input");
  EXPECT_EQ(read_bytes(a), before);
  const fs::path remesh = copy_of("remesh");
  const std::string json_before = read_bytes(remesh / "remesh.json");
  expect_clean_failure(run_tool("qs-morph", remesh.string() + " -q --glb " + (remesh / "remesh.json").string()), 1,
                       "input");
  EXPECT_EQ(read_bytes(remesh / "remesh.json"), json_before);
  expect_clean_failure(run_tool("qs-render", a + " -o " + a), 1, "");
}

// A failure at the very end (a folder where a result file goes) leaves the target as it was.
TEST_F(RobustTool, FailedRunsLeaveTheOutputFolderAsItWas) {
  const std::string ball = write("ball.obj", qs::shapes::icosphere(2));
  auto blocked = [&](const std::string& name, const std::string& file) {
    const fs::path out = dir_ / name;
    fs::create_directories(out / file);
    write_bytes(out / "old.txt", "old");
    return out;
  };
  const fs::path d = blocked("d", "dissection.json");
  auto before = snapshot(d);
  expect_clean_failure(run_tool("qs-dissect", ball + " -q -o " + d.string()), 3, "dissection.json");
  EXPECT_EQ(snapshot(d), before);
  EXPECT_TRUE(no_staging_left(d));

  const fs::path r = blocked("r", "remesh.json");
  before = snapshot(r);
  expect_clean_failure(run_tool("qs-remesh", (root_ / "set.dissection").string() + " --level 1 -q -o " + r.string()), 3,
                       "remesh.json");
  EXPECT_EQ(snapshot(r), before);
  EXPECT_TRUE(no_staging_left(r));

  const fs::path b = blocked("b", "bake.json");
  before = snapshot(b);
  expect_clean_failure(
      run_tool("qs-bake", (root_ / "remesh").string() + " --size 8 --samples 0 -q -o " + b.string()), 3, "bake.json");
  EXPECT_EQ(snapshot(b), before);

  const fs::path m = blocked("m", "morph.json");
  before = snapshot(m);
  expect_clean_failure(run_tool("qs-morph", (root_ / "remesh").string() + " --frames 3 -q -o " + m.string()), 3,
                       "morph.json");
  EXPECT_EQ(snapshot(m), before);
  EXPECT_TRUE(no_staging_left(m));

  // And a successful run over an old folder replaces the tool's files and keeps the others.
  const fs::path ok = dir_ / "ok";
  fs::create_directories(ok);
  write_bytes(ok / "mine.txt", "mine");
  ASSERT_EQ(run_tool("qs-dissect", ball + " -q -o " + ok.string()).exit, 0);
  EXPECT_TRUE(fs::exists(ok / "dissection.json"));
  EXPECT_EQ(read_bytes(ok / "mine.txt"), "mine");
  EXPECT_TRUE(no_staging_left(ok));
}

// --- damaged dissection and remesh folders -------------------------------------------------------

TEST_F(RobustTool, DamagedChartFilesAreInvalidInput) {
  const std::string level = " --level 1 -q -o ";
  auto damaged = [&](const std::string& name, auto&& edit) {
    const fs::path d = dir_ / name;
    fs::copy(root_ / "set.dissection", d, fs::copy_options::recursive);
    std::string chart = read_bytes(d / "blob.chart.ply");
    edit(chart);
    write_bytes(d / "blob.chart.ply", chart);
    return d;
  };
  const size_t vertex_line = read_bytes(root_ / "set.dissection" / "blob.chart.ply").find("element vertex ");
  ASSERT_NE(vertex_line, std::string::npos);
  auto header_end = [](const std::string& c) { return c.find("end_header\n") + 11; };
  // "element vertex abc"
  const fs::path a = damaged("abc", [&](std::string& c) {
    const size_t eol = c.find('\n', vertex_line);
    c.replace(vertex_line, eol - vertex_line, "element vertex abc");
  });
  expect_clean_failure(run_tool("qs-remesh", a.string() + level + (dir_ / "o1").string()), 2, "blob.chart.ply");
  // The face records (chart version 2): 1 + 12 + 1 + 48 bytes (six float64 texcoords), then the
  // patch id (int32).
  const std::string chart = read_bytes(root_ / "set.dissection" / "blob.chart.ply");
  const size_t nv = std::stoul(chart.substr(vertex_line + 15));
  const size_t face0 = header_end(chart) + nv * 24;
  auto set_patch = [&](std::int32_t id) {
    return [=](std::string& c) { std::memcpy(&c[face0 + 62], &id, 4); };
  };
  for (std::int32_t id : {2147483647, 100000000}) {
    const fs::path p = damaged("patch" + std::to_string(id), set_patch(id));
    expect_clean_failure(run_tool("qs-remesh", p.string() + level + (dir_ / "o2").string()), 2, "patch");
  }
  // A NaN texcoord, and one far outside the unit square.
  for (double u : {std::numeric_limits<double>::quiet_NaN(), 1.5}) {
    const fs::path p = damaged(u > 1 ? "uv_out" : "uv_nan", [&](std::string& c) { std::memcpy(&c[face0 + 14], &u, 8); });
    expect_clean_failure(run_tool("qs-remesh", p.string() + level + (dir_ / "o3").string()), 2, "texcoord");
  }
  // A NaN position.
  const fs::path n = damaged("pos_nan", [&](std::string& c) {
    const double x = std::numeric_limits<double>::quiet_NaN();
    std::memcpy(&c[header_end(c)], &x, 8);
  });
  expect_clean_failure(run_tool("qs-remesh", n.string() + level + (dir_ / "o4").string()), 2, "vertex 0");
  EXPECT_FALSE(fs::exists(dir_ / "o1") || fs::exists(dir_ / "o2") || fs::exists(dir_ / "o3") || fs::exists(dir_ / "o4"));
  // dissection.json being a folder.
  const fs::path f = dir_ / "folder";
  fs::create_directories(f / "dissection.json");
  expect_clean_failure(run_tool("qs-remesh", f.string() + level + (dir_ / "o5").string()), 3, "is a folder");
}

TEST_F(RobustTool, NonFiniteRemeshVerticesAreRefusedBeforeAnythingIsWritten) {
  const fs::path remesh = copy_of("remesh");
  std::string obj = read_bytes(remesh / "blob.obj");
  const size_t v = obj.find("\nv ");
  ASSERT_NE(v, std::string::npos);
  obj.replace(v + 3, obj.find(' ', v + 3) - (v + 3), "nan");
  write_bytes(remesh / "blob.obj", obj);
  const fs::path out = dir_ / "morph";
  const RunResult r =
      run_tool("qs-morph", remesh.string() + " --frames 3 --align similarity -q -o " + out.string() + " --glb " +
                               (dir_ / "m.glb").string());
  expect_clean_failure(r, 2, "blob.obj");
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(dir_ / "m.glb"));
}

TEST_F(RobustTool, MalformedDissectionJsonFieldsAreInvalidInput) {
  const fs::path d = copy_of("set.dissection");
  const std::string original = read_bytes(d / "dissection.json");
  auto with = [&](const std::string& from, const std::string& to) {
    std::string s = original;
    const size_t at = s.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) s.replace(at, from.size(), to);
    write_bytes(d / "dissection.json", s);
    return run_tool("qs-remesh", d.string() + " --level 1 -q -o " + (dir_ / "o").string());
  };
  expect_clean_failure(with("\"input_faces\": ", "\"input_faces\": 1e300, \"x\": "), 2, "input_faces");
  expect_clean_failure(with("\"format\": \"qs-dissection\"", "\"format\": \"qs-dissection\", \"format\": 1"), 2,
                       "appears twice");
  expect_clean_failure(with("\"version\": 2", "\"version\": 18446744073709551615"), 2, "version");
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}

// --- resources estimated up front ----------------------------------------------------------------

TEST_F(RobustTool, LargeRequestsAreRefusedUpFrontWithTheirSize) {
  const RunResult level = run_tool("qs-remesh", (root_ / "set.dissection").string() + " --level 12 -q -o " +
                                                    (dir_ / "r").string());
  expect_clean_failure(level, 1, "GiB");
  EXPECT_THAT(level.out, HasSubstr("--max-memory"));
  EXPECT_FALSE(fs::exists(dir_ / "r"));
  const RunResult bake = run_tool("qs-bake", (root_ / "remesh").string() + " --size 4000 --max-memory 0.5 -q -o " +
                                                 (dir_ / "b").string());
  expect_clean_failure(bake, 1, "GiB");
  EXPECT_FALSE(fs::exists(dir_ / "b"));
  const std::string ball = write("ball.obj", qs::shapes::icosphere(1));
  expect_clean_failure(run_tool("qs-metro", ball + " " + ball + " --samples 99999999999"), 1, "--max-samples");
  std::string eight;
  for (int i = 0; i < 8; ++i) eight += ball + " ";
  expect_clean_failure(run_tool("qs-render", eight + "--size 8192 -o " + (dir_ / "x.png").string()), 1, "16384");
  EXPECT_FALSE(fs::exists(dir_ / "x.png"));
}

TEST_F(RobustTool, NanOptionValuesAreUsageErrors) {
  const std::string ball = write("ball.obj", qs::shapes::icosphere(1));
  expect_clean_failure(run_tool("qs-dissect", ball + " -q --max-area nan -o " + (dir_ / "o").string()), 1, "");
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}

// After exit 4 the advice follows the stop reasons: a failed split is not a depth limit. (A double
// cone whose apex fans have 10k faces ends with split_failed patches under the old maps; the test
// checks the advice for whatever the report says.)
TEST_F(RobustTool, SolverAdviceFollowsTheStopReason) {
  const int n = 10000;
  qs::TriMesh cone;
  for (int i = 0; i < n; ++i)
    cone.positions.emplace_back(std::cos(2 * M_PI * i / n), std::sin(2 * M_PI * i / n), 0);
  cone.positions.emplace_back(0, 0, 1);
  cone.positions.emplace_back(0, 0, -1);
  for (int i = 0; i < n; ++i) {
    cone.faces.push_back({i, (i + 1) % n, n});
    cone.faces.push_back({(i + 1) % n, i, n + 1});
  }
  const std::string file = write("cone.off", cone);
  // The default maps (cotangent weights on the intrinsic Delaunay triangulation) dissect the cone
  // bijectively; the old ones (edge paths, mean-value weights) end with exit 4, split_failed.
  const RunResult d = run_tool("qs-dissect", file + " -q -o " + (dir_ / "d").string());
  EXPECT_EQ(d.exit, 0) << d.out;
  write_bytes(dir_ / "old_maps.json", R"({"geodesic_seed_curves": false, "intrinsic_cotan": false})");
  const RunResult r =
      run_tool("qs-dissect", file + " --config " + (dir_ / "old_maps.json").string() + " -o " + (dir_ / "o").string());
  EXPECT_THAT(r.out, Not(HasSubstr("internal error")));
  if (r.exit != 4) GTEST_SKIP() << "the cone dissects cleanly now (exit " << r.exit << ")";
  const std::string advice = r.out.substr(r.out.find("solver error"));
  const bool split_failed = r.out.find("split_failed") != std::string::npos ||
                            r.out.find("no_progress") != std::string::npos;
  const bool limits = r.out.find("max_depth") != std::string::npos ||
                      r.out.find("too_few_faces") != std::string::npos;
  // Advice is only given for a reason the report shows (the old advice was always --max-depth).
  const bool says_split = advice.find("a split failed") != std::string::npos;
  const bool says_depth = advice.find("--max-depth") != std::string::npos;
  EXPECT_TRUE(!says_split || split_failed) << advice;
  EXPECT_TRUE(!says_depth || limits) << advice;
  EXPECT_TRUE(says_split || says_depth) << advice;
}

TEST_F(RobustTool, ToolsShareTheirCommonOptions) {
  struct Expect {
    std::string command;  // the tool, with its subcommand where it has them
    bool output, quiet, threads, json;
  };
  const std::vector<Expect> tools = {
      {"qs-dissect", true, true, true, true},   {"qs-remesh", true, true, true, false},
      {"qs-bake", true, true, true, false},     {"qs-morph", true, true, true, false},
      {"qs-merge", true, true, true, false},    {"qs-metro", true, false, true, true},
      {"qs-dfi", true, true, true, false},      {"qs-render", true, true, false, false},
      {"qs-family generate", true, true, true, false},
      {"qs-family retessellate", true, true, false, false},
      {"qs-family pose", true, true, false, false},
      {"qs-inspect", false, false, false, true},
  };
  for (const Expect& t : tools) {
    const RunResult r = run_tool(t.command, "--help");
    ASSERT_EQ(r.exit, 0) << t.command << ": " << r.out;
    EXPECT_EQ(r.out.find("-o,--output") != std::string::npos, t.output) << t.command << "\n" << r.out;
    EXPECT_EQ(r.out.find("-q,--quiet") != std::string::npos, t.quiet) << t.command << "\n" << r.out;
    EXPECT_EQ(r.out.find("--threads") != std::string::npos, t.threads) << t.command << "\n" << r.out;
    EXPECT_EQ(r.out.find("--json") != std::string::npos, t.json) << t.command << "\n" << r.out;
    EXPECT_THAT(r.out, Not(HasSubstr("--outdir"))) << t.command;
    EXPECT_THAT(r.out, Not(HasSubstr("--verbose"))) << t.command;
    EXPECT_THAT(r.out, Not(::testing::ContainsRegex("[Ii]ssue [0-9]"))) << t.command;
  }
  const std::string a = write("a.obj", qs::shapes::icosphere(2));
  const RunResult outdir = run_tool("qs-dfi", a + " " + a + " --outdir " + (dir_ / "d").string());
  EXPECT_EQ(outdir.exit, 1) << outdir.out;
  EXPECT_FALSE(fs::exists(dir_ / "d"));
  const RunResult verbose = run_tool("qs-render", a + " -v -o " + (dir_ / "v.png").string());
  EXPECT_EQ(verbose.exit, 1) << verbose.out;
  EXPECT_FALSE(fs::exists(dir_ / "v.png"));
}

TEST_F(RobustTool, RenderReportsWhatItWroteUnlessQuiet) {
  const std::string a = write("a.obj", qs::shapes::icosphere(2));
  const fs::path png = dir_ / "a.png";
  RunResult r = run_tool("qs-render", a + " --size 64 -o " + png.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("wrote " + png.string() + " (64 x 64)"));
  EXPECT_THAT(r.out, HasSubstr(a + ": read "));
  const std::string loud = read_bytes(png);
  fs::remove(png);
  r = run_tool("qs-render", a + " --size 64 --quiet --output " + png.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(read_bytes(png), loud);
}
