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
  EXPECT_EQ(j["version"], 2);
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

// Issue 17's maps (geodesic seed curves and intrinsic cotangent weights, the defaults), each turned
// off alone and both (the old maps): exit 0, every leaf bijective, the output deterministic; the
// options record which maps were used.
TEST_F(DissectTool, GeodesicSeedCurvesAndCotanWeights) {
  const qs::TriMesh mesh = qs::shapes::bumpy_sphere(0.15, 4, 4);
  const std::string in = write("bumpy.obj", mesh);
  auto bytes = [](const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
  };
  for (const std::string opts : {"", "--edge-seed-paths", "--mean-value", "--edge-seed-paths --mean-value"}) {
    SCOPED_TRACE(opts);
    const fs::path out = dir_ / "o1", out2 = dir_ / "o2";
    fs::remove_all(out);
    fs::remove_all(out2);
    const RunResult r = run_tool("qs-dissect", in + " " + opts + " -q -o " + out.string());
    ASSERT_EQ(r.exit, 0) << r.out;
    ASSERT_EQ(run_tool("qs-dissect", in + " " + opts + " -q -o " + out2.string()).exit, 0);
    EXPECT_EQ(bytes(out / "dissection.json"), bytes(out2 / "dissection.json"));
    EXPECT_EQ(bytes(out / "bumpy.chart.ply"), bytes(out2 / "bumpy.chart.ply"));
    std::ifstream js(out / "dissection.json");
    const auto j = nlohmann::json::parse(js);
    EXPECT_EQ(j["options"]["geodesic_seed_curves"], opts.find("--edge-seed-paths") == std::string::npos);
    EXPECT_EQ(j["options"]["intrinsic_cotan"], opts.find("--mean-value") == std::string::npos);
    EXPECT_EQ(j["maps"], std::string(opts.find("--edge-seed-paths") == std::string::npos ? "geodesic" : "edge") + "+" +
                             (opts.find("--mean-value") == std::string::npos ? "cotan" : "mean-value"));
    for (const auto& p : j["meshes"][0]["patches"]) {
      EXPECT_EQ(p["flipped_faces"], 0);
      EXPECT_EQ(p["zero_area_faces"], 0);
    }
  }
}

TEST_F(DissectTool, ExitCodes) {
  const std::string torus = write("torus.obj", qs::shapes::torus(12, 8));
  const RunResult bad = run_tool("qs-dissect", torus + " -o " + (dir_ / "t").string());
  EXPECT_EQ(bad.exit, 2) << bad.out;
  EXPECT_THAT(bad.out, HasSubstr("genus"));
  EXPECT_FALSE(fs::exists(dir_ / "t" / "dissection.json"));
  const std::string ball = write("ball.obj", qs::shapes::icosphere(2));
  EXPECT_EQ(run_tool("qs-dissect", ball + " " + ball + " --landmarks " + ball).exit, 1);  // 1 file, 2 meshes
  EXPECT_EQ(run_tool("qs-dissect", ball + " --tau 0.5").exit, 1);
  EXPECT_EQ(run_tool("qs-dissect", ball + " --min-split-area 1.5").exit, 1);
  EXPECT_EQ(run_tool("qs-dissect", ball + " --force-split-area -0.1").exit, 1);
  const RunResult nan_area = run_tool("qs-dissect", ball + " --min-split-area nan");
  EXPECT_EQ(nan_area.exit, 1) << nan_area.out;
  EXPECT_THAT(nan_area.out, HasSubstr("--min-split-area"));
  EXPECT_EQ(run_tool("qs-dissect", ball + " --area-extra-depth 13").exit, 1);
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

TEST_F(DissectTool, SetOfTwoMeshesWithFeatures) {
  // The same sphere twice, stretched: seeds and features by vertex id in landmark files.
  qs::TriMesh a = qs::shapes::icosphere(3), b = a;
  for (auto& p : b.positions) p = qs::Vec3(1.6 * p.x(), p.y(), 0.8 * p.z() + 0.2 * p.x() * p.x());
  const std::string fa = write("a.obj", a), fb = write("b.obj", b);
  int top = 0, other = 0;
  for (int v = 0; v < a.num_vertices(); ++v) {
    if (a.positions[v].z() > a.positions[top].z()) top = v;
    if ((a.positions[v] - qs::Vec3(0.5, 0.5, 0.7)).norm() < (a.positions[other] - qs::Vec3(0.5, 0.5, 0.7)).norm()) other = v;
  }
  int s[4] = {0, 0, 0, 0};
  const qs::Vec3 dirs[4] = {{1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
  for (int i = 0; i < 4; ++i)
    for (int v = 0; v < a.num_vertices(); ++v)
      if (a.positions[v].dot(dirs[i]) > a.positions[s[i]].dot(dirs[i])) s[i] = v;
  const std::string lm = "{\"seeds\": [" + std::to_string(s[0]) + ", " + std::to_string(s[1]) + ", " +
                         std::to_string(s[2]) + ", " + std::to_string(s[3]) + "], \"features\": {\"top\": " +
                         std::to_string(top) + ", \"side\": " + std::to_string(other) + "}}";
  std::ofstream(dir_ / "a.landmarks.json") << lm;
  std::ofstream(dir_ / "b.landmarks.json") << lm;
  const fs::path out = dir_ / "set";
  const RunResult r = run_tool("qs-dissect", fa + " " + fb + " --tau 1.2 -o " + out.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("set: 2 meshes"));
  std::ifstream in(out / "dissection.json");
  const auto j = nlohmann::json::parse(in);
  ASSERT_EQ(j["meshes"].size(), 2u);
  EXPECT_EQ(j["meshes"][0]["chart"], "a.chart.ply");
  EXPECT_EQ(j["meshes"][1]["chart"], "b.chart.ply");
  EXPECT_EQ(j["meshes"][0]["patches"].size(), j["meshes"][1]["patches"].size());
  ASSERT_EQ(j["meshes"][0]["features"].size(), 2u);
  for (int k = 0; k < 2; ++k) {
    const auto& f0 = j["meshes"][0]["features"][k];
    const auto& f1 = j["meshes"][1]["features"][k];
    EXPECT_EQ(f0["patch"], f1["patch"]);
    EXPECT_NEAR(f0["uv"][0].get<double>(), f1["uv"][0].get<double>(), 1e-6);
    EXPECT_NEAR(f0["uv"][1].get<double>(), f1["uv"][1].get<double>(), 1e-6);
  }
  // A feature missing from one mesh: exit 2, naming it.
  std::ofstream(dir_ / "b.landmarks.json") << "{\"seeds\": [" << s[0] << ", " << s[1] << ", " << s[2] << ", " << s[3]
                                           << "], \"features\": {\"top\": " << top << "}}";
  const RunResult missing = run_tool("qs-dissect", fa + " " + fb + " -o " + (dir_ / "set2").string());
  EXPECT_EQ(missing.exit, 2) << missing.out;
  EXPECT_THAT(missing.out, HasSubstr("lacks 'side'"));
  // Seeds on one mesh only: exit 2.
  fs::remove(dir_ / "b.landmarks.json");
  const RunResult half = run_tool("qs-dissect", fa + " " + fb + " -o " + (dir_ / "set3").string());
  EXPECT_EQ(half.exit, 2) << half.out;
  EXPECT_THAT(half.out, HasSubstr("has no seeds"));
}
