// qs-merge as a user runs it: qs-dissect of a pair, qs-merge, then qs-morph and qs-inspect on the
// result; exact endpoints checked on the files; identical bytes on 1 and 2 threads; bad input.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "qs/io/read_mesh.h"
#include "qs/io/write_mesh.h"
#include "qs/shapes/shapes.h"
#include "../common/test_support.h"
#include "tool_runner.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;

using qs::test::read_bytes;

namespace {

class MergeTool : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("qs_merge_tool_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    // Two different shapes of different resolution.
    qs::TriMesh a = qs::shapes::ellipsoid(1.0, 0.8, 0.6, 2);
    qs::TriMesh b = qs::shapes::bumpy_sphere(0.1, 3, 3);
    qs::io::write_mesh(dir_ / "a.obj", a);
    qs::io::write_mesh(dir_ / "b.obj", b);
    qs::io::write_mesh(dir_ / "c.obj", qs::shapes::icosphere(2));
    dissect_ = run_tool("qs-dissect", (dir_ / "a.obj").string() + " " + (dir_ / "b.obj").string() +
                                          " --tau 2 --min-faces 60 -q -o " + (dir_ / "ab").string());
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static fs::path dir_;
  static RunResult dissect_;
};
fs::path MergeTool::dir_;
RunResult MergeTool::dissect_;

}  // namespace

TEST_F(MergeTool, MergesAPairThatQsMorphAndQsInspectRead) {
  ASSERT_EQ(dissect_.exit, 0) << dissect_.out;
  const fs::path out = dir_ / "merge";
  const RunResult r = run_tool("qs-merge", (dir_ / "ab").string() + " -o " + out.string() + " --threads 1");
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("slivers"));
  const nlohmann::json doc = nlohmann::json::parse(read_bytes(out / "remesh.json"));
  EXPECT_EQ(doc["mode"], "merge");
  EXPECT_EQ(doc["meshes"].size(), 2u);
  EXPECT_LE(doc["merge"]["faces_over_inputs"].get<double>(), 8.0);
  EXPECT_EQ(doc["merge"]["normal_disagreements"]["a"], 0);
  EXPECT_EQ(doc["merge"]["normal_disagreements"]["b"], 0);

  // Exact endpoints on the files: every vertex of each input is a vertex of its merged mesh, bitwise.
  for (const char* stem : {"a", "b"}) {
    const auto input = qs::io::read_mesh(dir_ / (std::string(stem) + ".obj")).mesh;
    const auto merged = qs::io::read_mesh(out / (std::string(stem) + ".obj")).mesh;
    std::set<std::array<double, 3>> have;
    for (const auto& p : merged.positions) have.insert({p.x(), p.y(), p.z()});
    int missing = 0;
    for (const auto& p : input.positions) missing += !have.count({p.x(), p.y(), p.z()});
    EXPECT_EQ(missing, 0) << stem;
    // The same surface: total areas equal.
    double area_in = 0, area_merged = 0;
    for (int f = 0; f < input.num_faces(); ++f) area_in += qs::face_area(input, f);
    for (int f = 0; f < merged.num_faces(); ++f) area_merged += qs::face_area(merged, f);
    EXPECT_NEAR(area_merged, area_in, 1e-12 * area_in) << stem;
  }

  const RunResult inspect = run_tool("qs-inspect", (out / "a.obj").string() + " " + (out / "b.obj").string());
  EXPECT_EQ(inspect.exit, 0) << inspect.out;
  EXPECT_THAT(inspect.out, HasSubstr("genus: 0"));

  const RunResult morph = run_tool("qs-morph", out.string() + " --frames 3 -o " + (dir_ / "morph").string());
  ASSERT_EQ(morph.exit, 0) << morph.out;
  // The morph's first and last frames are the merged endpoints.
  EXPECT_EQ(qs::io::read_mesh(dir_ / "morph" / "frame_0000.obj").mesh.positions,
            qs::io::read_mesh(out / "a.obj").mesh.positions);
  EXPECT_EQ(qs::io::read_mesh(dir_ / "morph" / "frame_0002.obj").mesh.positions,
            qs::io::read_mesh(out / "b.obj").mesh.positions);
}

TEST_F(MergeTool, SameBytesOnOneAndTwoThreads) {
  ASSERT_EQ(dissect_.exit, 0) << dissect_.out;
  for (int t : {1, 2}) {
    const RunResult r = run_tool("qs-merge", (dir_ / "ab").string() + " -q --format ply --threads " + std::to_string(t) +
                                                 " -o " + (dir_ / ("t" + std::to_string(t))).string());
    ASSERT_EQ(r.exit, 0) << r.out;
    EXPECT_EQ(r.out, "");
  }
  for (const char* f : {"a.ply", "b.ply", "remesh.json"})
    EXPECT_EQ(read_bytes(dir_ / "t1" / f), read_bytes(dir_ / "t2" / f)) << f;
}

TEST_F(MergeTool, BadInputGivesDocumentedExitCodes) {
  const RunResult missing = run_tool("qs-merge", (dir_ / "nowhere").string());
  EXPECT_EQ(missing.exit, 3) << missing.out;
  EXPECT_THAT(missing.out, HasSubstr("qs-merge: i/o error"));

  const RunResult usage = run_tool("qs-merge", (dir_ / "ab").string() + " --format stl");
  EXPECT_EQ(usage.exit, 1) << usage.out;

  const RunResult three = run_tool("qs-dissect", (dir_ / "a.obj").string() + " " + (dir_ / "b.obj").string() + " " +
                                                     (dir_ / "c.obj").string() + " -q -o " + (dir_ / "abc").string());
  ASSERT_EQ(three.exit, 0) << three.out;
  const RunResult r = run_tool("qs-merge", (dir_ / "abc").string());
  EXPECT_EQ(r.exit, 2) << r.out;
  EXPECT_THAT(r.out, HasSubstr("qs-merge merges exactly two: name them with --pair A,B"));
  EXPECT_FALSE(fs::exists(dir_ / "abc" / "merge"));
  const RunResult unknown = run_tool("qs-merge", (dir_ / "abc").string() + " --pair a,d");
  EXPECT_EQ(unknown.exit, 2) << unknown.out;
  EXPECT_THAT(unknown.out, HasSubstr("no mesh 'd' in the dissection (its meshes: a, b, c)"));
  EXPECT_EQ(run_tool("qs-merge", (dir_ / "abc").string() + " --pair a").exit, 1);
  // Two of three: c at t = 0, a at t = 1.
  const RunResult ca = run_tool("qs-merge", (dir_ / "abc").string() + " --pair c,a -q -o " + (dir_ / "ca").string());
  ASSERT_EQ(ca.exit, 0) << ca.out;
  const nlohmann::json doc = nlohmann::json::parse(read_bytes(dir_ / "ca" / "remesh.json"));
  EXPECT_EQ(doc["meshes"][0]["output"], "c.obj");
  EXPECT_EQ(doc["meshes"][1]["output"], "a.obj");

  // A chart whose uv triangle was flipped by hand: exit 2 naming the file and the patch.
  fs::copy(dir_ / "ab", dir_ / "flipped", fs::copy_options::recursive);
  {
    std::string chart = read_bytes(dir_ / "flipped" / "a.chart.ply");
    const size_t body = chart.find("end_header\n") + 11;
    const auto nv = qs::io::read_mesh(dir_ / "a.obj").mesh.num_vertices();
    // The chart has more vertices than the input (cut vertices): read the count from its header.
    const size_t at = chart.find("element vertex ") + 15;
    const long long cv = std::stoll(chart.substr(at));
    ASSERT_GE(cv, nv);
    // Face 0: swap the u and v of its first corner (texcoords start 14 bytes into the face).
    const size_t uv = body + static_cast<size_t>(cv) * 24 + 1 + 12 + 1;
    const std::string corner1 = chart.substr(uv + 16, 16);
    chart.replace(uv, 16, corner1);  // corner 0 takes corner 1's uv: a degenerate triangle
    std::ofstream(dir_ / "flipped" / "a.chart.ply", std::ios::binary) << chart;
  }
  const RunResult flipped = run_tool("qs-merge", (dir_ / "flipped").string());
  EXPECT_EQ(flipped.exit, 2) << flipped.out;
  EXPECT_THAT(flipped.out, HasSubstr("a.chart.ply: patch"));
  EXPECT_THAT(flipped.out, HasSubstr("degenerate uv triangle"));
}

// An output that would replace an input (a dissected mesh, a chart, dissection.json), under any
// spelling or through a link, is refused before any work; the inputs stay as they were.
TEST_F(MergeTool, RefusesAnOutputThatReplacesAnInput) {
  ASSERT_EQ(dissect_.exit, 0) << dissect_.out;
  const std::string a_before = read_bytes(dir_ / "a.obj"), b_before = read_bytes(dir_ / "b.obj");
  const std::string json_before = read_bytes(dir_ / "ab" / "dissection.json");
  std::error_code ec;
  fs::create_directory_symlink(dir_, dir_ / "link", ec);
  ASSERT_FALSE(ec) << ec.message();
  for (const fs::path& out : {dir_, dir_ / "ab" / "..", dir_ / "ab" / ".." / ".", dir_ / "link"}) {
    const RunResult r = run_tool("qs-merge", (dir_ / "ab").string() + " -o " + out.string());
    EXPECT_EQ(r.exit, 1) << out << ": " << r.out;
    EXPECT_THAT(r.out, HasSubstr("is an input of this run")) << out;
  }
  // Output PLY: a.ply does not collide with a.obj.
  const RunResult ply = run_tool("qs-merge", (dir_ / "ab").string() + " -q --format ply -o " + (dir_ / "link").string());
  EXPECT_EQ(ply.exit, 0) << ply.out;
  EXPECT_TRUE(fs::exists(dir_ / "a.ply"));
  fs::remove(dir_ / "a.ply");
  fs::remove(dir_ / "b.ply");
  fs::remove(dir_ / "remesh.json");
  // A dissection whose chart would be replaced: a copy of the folder with the chart renamed to
  // the output's name.
  fs::create_directories(dir_ / "c2");
  for (const char* f : {"a.chart.ply", "b.chart.ply"}) fs::copy_file(dir_ / "ab" / f, dir_ / "c2" / f);
  std::string json = json_before;
  for (size_t at; (at = json.find("\"a.chart.ply\"")) != std::string::npos;) json.replace(at, 13, "\"a.obj\"");
  std::ofstream(dir_ / "c2" / "dissection.json", std::ios::binary) << json;
  fs::rename(dir_ / "c2" / "a.chart.ply", dir_ / "c2" / "a.obj");
  const std::string chart_before = read_bytes(dir_ / "c2" / "a.obj");
  const RunResult chart = run_tool("qs-merge", (dir_ / "c2").string() + " -o " + (dir_ / "c2").string());
  EXPECT_EQ(chart.exit, 1) << chart.out;
  EXPECT_THAT(chart.out, HasSubstr("is an input of this run"));
  EXPECT_EQ(read_bytes(dir_ / "c2" / "a.obj"), chart_before);

  EXPECT_EQ(read_bytes(dir_ / "a.obj"), a_before);
  EXPECT_EQ(read_bytes(dir_ / "b.obj"), b_before);
  EXPECT_EQ(read_bytes(dir_ / "ab" / "dissection.json"), json_before);
  EXPECT_FALSE(fs::exists(dir_ / "remesh.json"));
  fs::remove(dir_ / "link");
  fs::remove_all(dir_ / "c2");
}

// Everything is staged: a run that fails when moving its files into place (a folder where
// remesh.json should go) leaves the output folder exactly as it was, and no staging folder.
TEST_F(MergeTool, AFailedRunLeavesTheOutputFolderAsItWas) {
  ASSERT_EQ(dissect_.exit, 0) << dissect_.out;
  const fs::path out = dir_ / "staged";
  fs::create_directories(out / "remesh.json");
  std::ofstream(out / "a.obj") << "old";
  const RunResult r = run_tool("qs-merge", (dir_ / "ab").string() + " -q -o " + out.string());
  EXPECT_EQ(r.exit, 3) << r.out;
  EXPECT_THAT(r.out, HasSubstr("is a folder"));
  EXPECT_EQ(read_bytes(out / "a.obj"), "old");
  EXPECT_FALSE(fs::exists(out / "b.obj"));
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
  // A new output folder under a file: an i/o error before any work, nothing created.
  std::ofstream(dir_ / "plain") << "x";
  const RunResult under = run_tool("qs-merge", (dir_ / "ab").string() + " -q -o " + (dir_ / "plain" / "m").string());
  EXPECT_EQ(under.exit, 3) << under.out;
  EXPECT_THAT(under.out, Not(HasSubstr("merge of")));
  fs::remove_all(out);
  fs::remove(dir_ / "plain");
}

TEST_F(MergeTool, NonFiniteOrOutOfRangeSliverDegreesAreUsageErrors) {
  ASSERT_EQ(dissect_.exit, 0) << dissect_.out;
  for (const char* v : {"nan", "NaN", "inf", "-inf", "-1", "61", "1e400"}) {
    const RunResult r =
        run_tool("qs-merge", (dir_ / "ab").string() + " --sliver-degrees " + v + " -o " + (dir_ / "sl").string());
    EXPECT_EQ(r.exit, 1) << v << ": " << r.out;
    EXPECT_THAT(r.out, HasSubstr("--sliver-degrees")) << v;
    EXPECT_FALSE(fs::exists(dir_ / "sl")) << v;
  }
}

// A mesh whose file name is not UTF-8: dissection.json (JSON) cannot name its chart, which
// qs-dissect writes with U+FFFD in its place. qs-merge says so (exit 2), not "no such file".
TEST_F(MergeTool, AMeshNameThatIsNotUtf8IsDissectedAndMerged) {
  const fs::path odd = dir_ / "x\xff.obj";
  fs::copy_file(dir_ / "a.obj", odd, fs::copy_options::overwrite_existing);
  const RunResult d = run_tool("qs-dissect", "'" + odd.string() + "' " + (dir_ / "b.obj").string() +
                                                 " --tau 2 --min-faces 60 -q -o " + (dir_ / "odd").string());
  ASSERT_EQ(d.exit, 0) << d.out;
  // The chart is named with the odd byte written %FF, and dissection.json names it so.
  ASSERT_TRUE(fs::exists(dir_ / "odd" / "x%FF.chart.ply"));
  const RunResult r = run_tool("qs-merge", (dir_ / "odd").string() + " -q -o " + (dir_ / "odd_merge").string());
  EXPECT_EQ(r.exit, 0) << r.out;
  EXPECT_TRUE(fs::exists(dir_ / "odd_merge" / "x%FF.obj"));
  // A dissection.json that lost the name (U+FFFD for the odd byte) gets a clear message.
  std::string json = read_bytes(dir_ / "odd" / "dissection.json");
  const std::string escaped = "x%FF.chart.ply";
  ASSERT_NE(json.find(escaped), std::string::npos);
  json.replace(json.find(escaped), escaped.size(), "x\xEF\xBF\xBD.chart.ply");
  std::ofstream(dir_ / "odd" / "dissection.json", std::ios::binary) << json;
  const RunResult lost = run_tool("qs-merge", (dir_ / "odd").string() + " -o " + (dir_ / "odd_merge2").string());
  EXPECT_EQ(lost.exit, 2) << lost.out;
  EXPECT_THAT(lost.out, HasSubstr("its file name was not UTF-8"));
  EXPECT_THAT(lost.out, HasSubstr("rename the mesh to a UTF-8 name and dissect it again"));
  EXPECT_FALSE(fs::exists(dir_ / "odd_merge2"));
  fs::remove_all(dir_ / "odd_merge");
  fs::remove_all(dir_ / "odd");
  fs::remove(odd);
  // A dissection folder whose own name is not UTF-8 merges (remesh.json's names with U+FFFD).
  ASSERT_EQ(dissect_.exit, 0) << dissect_.out;
  const fs::path folder = dir_ / "ab\xfe";
  fs::copy(dir_ / "ab", folder, fs::copy_options::recursive);
  const RunResult ok = run_tool("qs-merge", "'" + folder.string() + "' -q");
  EXPECT_EQ(ok.exit, 0) << ok.out;
  const nlohmann::json doc = nlohmann::json::parse(read_bytes(folder / "merge" / "remesh.json"));
  EXPECT_EQ(doc["dissection"], "ab\xEF\xBF\xBD");
  EXPECT_EQ(doc["dissection_path"], "..");
  fs::remove_all(folder);
}
