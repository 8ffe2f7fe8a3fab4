// qs-dfi as a user runs it: outputs, dfi.json, exit codes and messages.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "../common/gltf_test_support.h"
#include "qs/core/mesh.h"
#include "qs/io/write_mesh.h"
#include "qs/shapes/shapes.h"
#include "../common/test_support.h"
#include "tool_runner.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

using qs::test::read_bytes;
using qs::test::scaled;

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

// --matching and --interpolation: the report says which ran; nearest-first casts no votes; the
// ARAP warp reports its centres; unknown words are usage errors.
TEST_F(DfiTool, MatchingAndInterpolationChoices) {
  const std::string a = write("ma.obj", qs::shapes::ellipsoid(1.6, 0.6, 0.5, 3));
  const std::string b = write("mb.obj", qs::shapes::ellipsoid(1.2, 0.7, 0.6, 3));
  const std::string common = " --frames 3 --grid 20 --emd-voxels 200 --timing uniform --endpoint-refine 1 -q -o ";
  const RunResult n = run_tool("qs-dfi", a + " " + b + " --matching nearest" + common + (dir_ / "mn").string());
  ASSERT_EQ(n.exit, 0) << n.out;
  const auto jn = nlohmann::json::parse(std::ifstream(dir_ / "mn" / "dfi.json"));
  EXPECT_EQ(jn["matches"]["method"], "nearest");
  ASSERT_GE(jn["matches"]["nodes"].size(), 1u);
  for (const auto& node : jn["matches"]["nodes"]) EXPECT_EQ(node["votes"].get<double>(), 0.0);
  const RunResult v = run_tool("qs-dfi", a + " " + b + " --interpolation arap" + common + (dir_ / "ma").string());
  ASSERT_EQ(v.exit, 0) << v.out;
  const auto jv = nlohmann::json::parse(std::ifstream(dir_ / "ma" / "dfi.json"));
  EXPECT_EQ(jv["matches"]["method"], "voting");
  EXPECT_EQ(jv["correspondence"]["warp"], "arap");
  EXPECT_GT(jv["correspondence"]["arap_centres"].get<int>(), 8);
  for (const auto& f : jv["frames"]) EXPECT_EQ(f["components"], 1);
  EXPECT_EQ(run_tool("qs-dfi", a + " " + b + " --matching random -o " + (dir_ / "x").string()).exit, 1);
  EXPECT_EQ(run_tool("qs-dfi", a + " " + b + " --interpolation spline -o " + (dir_ / "x").string()).exit, 1);
  EXPECT_FALSE(fs::exists(dir_ / "x"));
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

namespace {

// The vertices of an OBJ frame, as written.
std::vector<qs::Vec3> obj_vertices(const fs::path& p) {
  std::vector<qs::Vec3> v;
  std::ifstream f(p);
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("v ", 0) == 0) {
      std::istringstream s(line.substr(2));
      qs::Vec3 x;
      s >> x.x() >> x.y() >> x.z();
      v.push_back(x);
    }
  return v;
}

}  // namespace

TEST_F(DfiTool, ExtremeCoordinatesMorphLikeTheUnitSizedPair) {
  const qs::TriMesh a = qs::shapes::ellipsoid(1.5, 0.7, 0.6, 2), b = qs::shapes::torus(32, 12);
  const std::string opts = " --no-warp --timing uniform --frames 3 --grid 16 --endpoint-refine 2 -q -o ";
  ASSERT_EQ(run_tool("qs-dfi", write("a.obj", a) + " " + write("b.obj", b) + opts + (dir_ / "o1").string()).exit, 0);
  for (const double s : {1e30, 1e-30}) {
    const std::string tag = s > 1 ? "big" : "small";
    const fs::path out = dir_ / tag;
    const RunResult r = run_tool("qs-dfi", write(tag + "a.obj", scaled(a, s)) + " " + write(tag + "b.obj", scaled(b, s)) +
                                               opts + out.string());
    ASSERT_EQ(r.exit, 0) << r.out;
    for (const char* f : {"frame_0000.obj", "frame_0001.obj", "frame_0002.obj"}) {
      const auto one = obj_vertices(dir_ / "o1" / f), many = obj_vertices(out / f);
      ASSERT_EQ(one.size(), many.size()) << tag << " " << f;
      ASSERT_GT(one.size(), 100u);
      double worst = 0;
      for (size_t i = 0; i < one.size(); ++i) worst = std::max(worst, (many[i] / s - one[i]).norm());
      EXPECT_LT(worst, 1e-12) << tag << " " << f;  // the same frames, scaled
    }
  }
  // With the warp and the alignment: a pair at 1e90, and a target 1e90 times the source.
  const std::string big_a = write("ha.obj", scaled(a, 1e90)), big_b = write("hb.obj", scaled(b, 1e90));
  const std::string warp = " --frames 3 --grid 16 --emd-voxels 200 --endpoint-refine 1 -q -o ";
  RunResult r = run_tool("qs-dfi", big_a + " " + big_b + warp + (dir_ / "w90").string());
  ASSERT_EQ(r.exit, 0) << r.out;
  r = run_tool("qs-dfi", write("sa.obj", a) + " " + big_b + warp + (dir_ / "s90").string() + " --align similarity");
  ASSERT_EQ(r.exit, 0) << r.out;
  const auto j = nlohmann::json::parse(std::ifstream(dir_ / "s90" / "dfi.json"));
  EXPECT_NEAR(std::log10(j["alignment"]["scale"].get<double>()), -90, 0.5);
  for (const char* f : {"frame_0000.obj", "frame_0001.obj", "frame_0002.obj"})
    for (const auto& p : obj_vertices(dir_ / "s90" / f)) ASSERT_TRUE(p.allFinite()) << f;
  // The last frame is the target, in its own units (within two of its voxels).
  qs::Vec3 lo = qs::Vec3::Constant(1e300), hi = -lo;
  for (const auto& p : obj_vertices(dir_ / "s90" / "frame_0002.obj")) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const qs::Box3 tb = qs::bounding_box(scaled(b, 1e90).positions);
  EXPECT_LT((lo - tb.min).norm() + (hi - tb.max).norm(), 0.2 * tb.diagonal());
}

TEST_F(DfiTool, RefusesOutputsThatAreItsInputs) {
  fs::create_directories(dir_ / "in");
  const std::string src = write("in/frame_0000.obj", qs::shapes::icosphere(2));
  const std::string tgt = write("in/t.obj", qs::shapes::torus(32, 12));
  const std::string before_src = read_bytes(src), before_tgt = read_bytes(tgt);
  fs::create_directory_symlink(dir_ / "in", dir_ / "link");
  const std::string base = src + " " + tgt + " --no-warp --frames 3 --grid 16 -q";
  for (const std::string& extra :
       {" --glb " + src, " --glb " + (dir_ / "in" / "." / ".." / "in" / "t.obj").string(), " -o " + (dir_ / "in").string(),
        " -o " + (dir_ / "link").string() + "/", " -o " + (dir_ / "x" / ".." / "in").string(),
        " --glb " + (dir_ / "link" / "t.obj").string()}) {
    const RunResult r = run_tool("qs-dfi", base + extra);
    EXPECT_EQ(r.exit, 1) << extra << "\n" << r.out;
    EXPECT_THAT(r.out, HasSubstr("is an input of this run")) << extra;
  }
  // The GLB onto a file the run writes into -o.
  const RunResult r = run_tool("qs-dfi", base + " -o " + (dir_ / "o").string() + " --glb " + (dir_ / "o" / "dfi.json").string());
  EXPECT_EQ(r.exit, 1) << r.out;
  EXPECT_EQ(read_bytes(src), before_src);
  EXPECT_EQ(read_bytes(tgt), before_tgt);
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}

TEST_F(DfiTool, BadOptionsAndFailuresLeaveNothingBehind) {
  const std::string a = write("a.obj", qs::shapes::icosphere(2)), b = write("b.obj", qs::shapes::torus(32, 12));
  const fs::path out = dir_ / "out";
  const std::string base =
      a + " " + b + " --no-warp --timing uniform --endpoint-refine 1 --frames 3 --grid 16 -q -o " + out.string();
  struct Case {
    std::string args;
    int exit;
  };
  for (const Case& c : std::vector<Case>{{" --fps nan --glb " + (dir_ / "g.glb").string(), 1},
                                         {" --fps 1e-300 --glb " + (dir_ / "g.glb").string(), 1},
                                         {" --fps 1e300 --glb " + (dir_ / "g.glb").string(), 1},
                                         {" --fps -1", 1},
                                         {" --max-memory nan", 1},
                                         {" --glb " + a + "/x.glb", 3},  // a folder that is a file
                                         {" --glb " + dir_.string(), 3}}) {
    const RunResult r = run_tool("qs-dfi", base + c.args);
    EXPECT_EQ(r.exit, c.exit) << c.args << "\n" << r.out;
    EXPECT_FALSE(fs::exists(out)) << c.args;
    EXPECT_FALSE(fs::exists(dir_ / "g.glb")) << c.args;
    for (const auto& e : fs::directory_iterator(dir_))
      EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << c.args << ": " << e.path();
  }
  // A failure after the staging began (the warp finds no interior voxel in a shape 1e-20 times
  // the other's size): neither a frame nor the GLB, and no staging folder.
  const std::string tiny = write("tiny.obj", scaled(qs::shapes::icosphere(2), 1e-20));
  const RunResult late = run_tool("qs-dfi", tiny + " " + b + " --frames 3 --grid 16 -q -o " + out.string() +
                                                " --glb " + (dir_ / "g.glb").string());
  EXPECT_EQ(late.exit, 2) << late.out;
  EXPECT_THAT(late.out, HasSubstr("no interior voxel"));
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(dir_ / "g.glb"));
  for (const auto& e : fs::directory_iterator(dir_))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
  // A GLB in folders that do not exist yet: made at the end; the extreme frame rates validate.
  for (const char* fps : {"0.001", "1000"}) {
    const fs::path glb = dir_ / "new" / fps / "m.glb";
    const RunResult r = run_tool("qs-dfi", base + fps + std::string("x") + " --fps " + fps + " --glb " + glb.string());
    ASSERT_EQ(r.exit, 0) << r.out;
    EXPECT_TRUE(fs::exists(fs::path(out.string() + fps + "x") / "dfi.json"));
    std::string validator_out;
    const int rc = qs::testing::run_gltf_validator(glb, &validator_out);
    if (rc != 3) {
      EXPECT_EQ(rc, 0) << validator_out;
    }
  }
}

TEST_F(DfiTool, AnInterruptedRunLeavesNothingInTheTarget) {
  const std::string a = write("a.obj", qs::shapes::icosphere(2)), b = write("b.obj", qs::shapes::torus(32, 12));
  const fs::path out = dir_ / "out";
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const std::string tool = std::string(QS_TOOLS_DIR) + "/qs-dfi";
    ::execl(tool.c_str(), "qs-dfi", a.c_str(), b.c_str(), "--no-warp", "--timing", "uniform", "--endpoint-refine", "1",
            "--frames", "400", "--grid", "24", "-q", "-o", out.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  const fs::path third = dir_ / ("out.tmp-" + std::to_string(pid)) / "frame_0002.obj";
  for (int i = 0; i < 2000 && !fs::exists(third); ++i) ::usleep(5000);
  EXPECT_TRUE(fs::exists(third));  // three frames written (staged)
  ::kill(pid, SIGINT);
  int status = 0;
  ::waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFSIGNALED(status));
  EXPECT_FALSE(fs::exists(out));  // the target never saw a frame
}

TEST_F(DfiTool, NamesThatAreNotUtf8Work) {
  const std::string a = write("\xff.obj", qs::shapes::icosphere(2)), b = write("b.obj", qs::shapes::torus(32, 12));
  const fs::path out = dir_ / "d\xfe" / "o";
  const RunResult r = run_tool("qs-dfi", "'" + a + "' " + b + " --no-warp --frames 3 --grid 16 -o '" + out.string() + "'");
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("\\xff.obj"));
  const auto j = nlohmann::json::parse(std::ifstream(out / "dfi.json"));
  EXPECT_THAT(j["source"]["file"].get<std::string>(), HasSubstr("\\xff.obj"));
}

TEST_F(DfiTool, LargeRequestsAreRefusedUpFrontWithTheEstimate) {
  const std::string a = write("a.obj", qs::shapes::icosphere(2)), b = write("b.obj", qs::shapes::torus(32, 12));
  const fs::path out = dir_ / "out";
  for (const std::string& args : {std::string(" --grid 1024 --endpoint-refine 2"), std::string(" --frames 100000"),
                                  std::string(" --frames 100000 --timing uniform --glb ") + (dir_ / "g.glb").string(),
                                  std::string(" --max-memory 0.01")}) {
    const auto t0 = std::chrono::steady_clock::now();
    const RunResult r = run_tool("qs-dfi", a + " " + b + args + " -o " + out.string());
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(r.exit, 1) << args << "\n" << r.out;
    EXPECT_THAT(r.out, HasSubstr("GiB of memory, more than --max-memory")) << args;
    EXPECT_LT(s, 1.0) << args;
    EXPECT_FALSE(fs::exists(out));
    EXPECT_FALSE(fs::exists(dir_ / "g.glb"));
  }
  // The grid of the end frames has its own bound.
  const RunResult r = run_tool("qs-dfi", a + " " + b + " --grid 1024 -o " + out.string());
  EXPECT_EQ(r.exit, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("2048"));
}
