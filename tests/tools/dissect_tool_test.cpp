// qs-dissect as a user runs it: outputs, exit codes, messages.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "qs/io/write_mesh.h"
#include "qs/shapes/shapes.h"
#include "../common/shared_meshes.h"
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
  /// qs-metro's correspondence error of the dissection in `out` (its first pair, the charts' map).
  nlohmann::json correspondence_error(const fs::path& out) {
    const fs::path json = out.string() + ".error.json";
    const RunResult r =
        run_tool("qs-metro", "--correspondence " + out.string() + " --samples 20000 --json -o " + json.string());
    EXPECT_EQ(r.exit, 0) << r.out;
    return r.exit == 0 ? nlohmann::json::parse(std::ifstream(json))["pairs"][0]["dissection"] : nlohmann::json();
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
  ASSERT_EQ(run_tool("qs-dissect", blob + " --tau 1.5 -q -o " + out2.string() + " --report " +
                                       (dir_ / "report2.txt").string())
                .exit,
            0);
  auto bytes = [](const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
  };
  EXPECT_EQ(bytes(out / "dissection.json"), bytes(out2 / "dissection.json"));
  EXPECT_EQ(bytes(out / "blob.chart.ply"), bytes(out2 / "blob.chart.ply"));
  // The report's wall time per stage, with or without the progress on stderr.
  for (const char* report : {"report.txt", "report2.txt"}) {
    EXPECT_THAT(bytes(dir_ / report), HasSubstr("\n  stages: setup ")) << report;
    EXPECT_THAT(bytes(dir_ / report), HasSubstr(", quinary subdivision ")) << report;
  }
}

// The maps (geodesic seed curves and intrinsic cotangent weights, the defaults), each turned off
// alone and both (the old maps) through --config: exit 0, every leaf bijective, the output
// deterministic; the options record what was asked and "maps" what was used.
TEST_F(DissectTool, GeodesicSeedCurvesAndCotanWeights) {
  const qs::TriMesh mesh = qs::shapes::bumpy_sphere(0.15, 4, 4);
  const std::string in = write("bumpy.obj", mesh);
  auto bytes = [](const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
  };
  for (const std::string maps : {"", "edge", "mean", "edge mean"}) {
    SCOPED_TRACE(maps);
    const bool edge = maps.find("edge") != std::string::npos, mean = maps.find("mean") != std::string::npos;
    const fs::path config = dir_ / "config.json";
    std::ofstream(config) << "{\"geodesic_seed_curves\": " << (edge ? "false" : "true")
                          << ", \"intrinsic_cotan\": " << (mean ? "false" : "true") << "}";
    const std::string opts = "--config " + config.string();
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
    EXPECT_EQ(j["options"]["geodesic_seed_curves"], !edge);
    EXPECT_EQ(j["options"]["intrinsic_cotan"], !mean);
    EXPECT_EQ(j["maps"], std::string(edge ? "edge" : "geodesic") + "+" + (mean ? "mean-value" : "cotan"));
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
  const RunResult nan_tau = run_tool("qs-dissect", ball + " --tau nan");
  EXPECT_EQ(nan_tau.exit, 1) << nan_tau.out;
  EXPECT_EQ(run_tool("qs-dissect", ball + " --same-pose maybe").exit, 1);
  // --config: out of range, wrong type, unknown key, not JSON: usage errors that say what is wrong.
  const std::string config = (dir_ / "config.json").string();
  for (const auto& [text, says] :
       std::vector<std::pair<std::string, std::string>>{{R"({"min_split_area": 1.5})", "\"min_split_area\" must be a number in [0, 1]"},
                                                        {R"({"force_split_area": -0.1})", "force_split_area"},
                                                        {R"({"area_extra_depth": 13})", "an integer in [0, 12]"},
                                                        {R"({"refine_maps": 1})", "true or false"},
                                                        {R"({"max_depth": 2.5})", "max_depth"},
                                                        {R"({"relax_rounds": 1})", "unknown option \"relax_rounds\""},
                                                        {R"({"tau": 3,})", "config.json"},
                                                        {R"([1, 2])", "expected a JSON object"}}) {
    std::ofstream(config) << text;
    const RunResult r = run_tool("qs-dissect", ball + " --config " + config + " -o " + (dir_ / "x").string());
    EXPECT_EQ(r.exit, 1) << text << ": " << r.out;
    EXPECT_THAT(r.out, HasSubstr(says)) << text;
  }
  EXPECT_FALSE(fs::exists(dir_ / "x"));
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

// --config replays a run from its own output folder, byte for byte, whether given the whole
// dissection.json or its "options" object; options on the command line override it.
TEST_F(DissectTool, ConfigReplaysARun) {
  const std::string blob = write("blob.obj", qs::shapes::star_blob(4, 1.5, 4));
  auto bytes = [](const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
  };
  const fs::path a = dir_ / "a", b = dir_ / "b", c = dir_ / "c", d = dir_ / "d";
  ASSERT_EQ(run_tool("qs-dissect", blob + " --tau 1.5 --max-depth 4 -q -o " + a.string()).exit, 0);
  const RunResult r = run_tool("qs-dissect", blob + " -q --config " + (a / "dissection.json").string() + " -o " + b.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_EQ(bytes(a / "dissection.json"), bytes(b / "dissection.json"));
  EXPECT_EQ(bytes(a / "blob.chart.ply"), bytes(b / "blob.chart.ply"));
  const auto j = nlohmann::ordered_json::parse(bytes(a / "dissection.json"));
  EXPECT_EQ(j["options"]["tau"], 1.5);
  EXPECT_EQ(j["options"]["max_depth"], 4);
  std::ofstream(dir_ / "options.json") << j["options"].dump(1);
  ASSERT_EQ(run_tool("qs-dissect", blob + " -q --config " + (dir_ / "options.json").string() + " -o " + c.string()).exit, 0);
  EXPECT_EQ(bytes(a / "dissection.json"), bytes(c / "dissection.json"));
  ASSERT_EQ(run_tool("qs-dissect", blob + " -q --tau 3 --config " + (dir_ / "options.json").string() + " -o " + d.string()).exit,
            0);
  EXPECT_EQ(nlohmann::json::parse(bytes(d / "dissection.json"))["options"]["tau"], 3.0);
}

// The help a person reads: at most 15 options, no history; --help-all adds every --config key.
TEST_F(DissectTool, HelpIsShort) {
  const RunResult h = run_tool("qs-dissect", "--help");
  ASSERT_EQ(h.exit, 0);
  int options = 0;
  ASSERT_NE(h.out.find("Options:"), std::string::npos) << h.out;
  std::istringstream lines(h.out.substr(h.out.find("Options:")));
  for (std::string line; std::getline(lines, line);)
    if (line.rfind("  -", 0) == 0) ++options;
  EXPECT_GT(options, 5) << h.out;
  EXPECT_LE(options, 15) << h.out;
  EXPECT_THAT(h.out, ::testing::Not(HasSubstr("issue")));
  EXPECT_THAT(h.out, ::testing::Not(HasSubstr("refine_corners")));
  const RunResult all = run_tool("qs-dissect", "--help-all");
  ASSERT_EQ(all.exit, 0);
  for (const char* key : {"tau", "refine_corners", "same_pose_detect", "pose_pull", "protrusion_stretch"})
    EXPECT_THAT(all.out, HasSubstr(std::string("  ") + key + " ")) << key;
}

// --json: a summary on stdout that parses, naming the folder and each mesh's chart.
TEST_F(DissectTool, JsonSummary) {
  const std::string blob = write("blob.obj", qs::shapes::star_blob(4, 1.5, 4));
  const RunResult r = run_tool("qs-dissect", blob + " --json -o " + (dir_ / "j").string());
  ASSERT_EQ(r.exit, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out.substr(r.out.find('{')));
  EXPECT_EQ(j["output"], (dir_ / "j").string());
  EXPECT_EQ(j["meshes"][0]["chart"], "blob.chart.ply");
  EXPECT_TRUE(j["bijective"].get<bool>());
}

// Seeds given in an order whose loop winds around the shape: taken in the set's shortest cyclic
// order, the same for every mesh, and said in the report; the result equals the belt order's.
TEST_F(DissectTool, WindingSeedOrderIsReorderedAndReported) {
  const qs::TriMesh m = qs::shapes::ellipsoid(1.0, 0.8, 2.5, 4);
  const std::string fa = write("a.obj", m), fb = write("b.obj", m);
  int s[4] = {0, 0, 0, 0};
  const qs::Vec3 dirs[4] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}};  // +x, -x, +y, -y: winds
  for (int i = 0; i < 4; ++i)
    for (int v = 0; v < m.num_vertices(); ++v)
      if (m.positions[v].dot(dirs[i]) > m.positions[s[i]].dot(dirs[i])) s[i] = v;
  auto seeds = [&](int a, int b, int c, int d) {
    return "{\"seeds\": [" + std::to_string(s[a]) + ", " + std::to_string(s[b]) + ", " + std::to_string(s[c]) + ", " +
           std::to_string(s[d]) + "]}";
  };
  std::ofstream(dir_ / "a.landmarks.json") << seeds(0, 1, 2, 3);
  std::ofstream(dir_ / "b.landmarks.json") << seeds(0, 1, 2, 3);
  const RunResult wound = run_tool("qs-dissect", fa + " " + fb + " -o " + (dir_ / "wound").string());
  ASSERT_EQ(wound.exit, 0) << wound.out;
  EXPECT_THAT(wound.out, HasSubstr("seed order: the seeds taken as s0 s2 s1 s3"));
  std::ofstream(dir_ / "a.landmarks.json") << seeds(0, 2, 1, 3);
  std::ofstream(dir_ / "b.landmarks.json") << seeds(0, 2, 1, 3);
  const RunResult belt = run_tool("qs-dissect", fa + " " + fb + " -o " + (dir_ / "belt").string());
  ASSERT_EQ(belt.exit, 0) << belt.out;
  EXPECT_THAT(belt.out, ::testing::Not(HasSubstr("seed order:")));
  auto bytes = [](const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
  };
  EXPECT_EQ(bytes(dir_ / "wound" / "a.chart.ply"), bytes(dir_ / "belt" / "a.chart.ply"));
}

// The horse in another pose (qs-family pose, seed 7: four limbs bent or turned). With only two
// features besides the seeds the registration leaves a limb off (99% of the area within 5% of the
// diagonal, not 1%); it is tried again with the horse's points farthest from the landmarks held
// too, matched by their distances along the surface, and then fits: the set is one pose and the
// correspondence follows (1.39% of the diagonal off on average through the common (u,v), 25%
// at most, without them; under 1% and 10% with them). The cat in another pose (seed 12) with
// its four seeds alone (at four paws; head and tail free) fits at once: B's points pull A too, so
// the free head does not slide off B's (0.73% mean, 8.4% max). With the pose tool's landmarks (every limb's tip) no point is added.
TEST_F(DissectTool, ARegistrationThatDoesNotFitIsTriedWithTheFarthestPointsHeld) {
  const fs::path horse = qs::testing::shared_meshes_dir() / "horse_5k.obj";
  const fs::path cat = qs::testing::shared_meshes_dir() / "cat_sumner_14k.obj";
  if (!fs::exists(horse) || !fs::exists(cat)) GTEST_SKIP() << "no " << horse << " or " << cat;
  auto report = [&](const fs::path& a, const fs::path& b, const std::string& landmarks, const std::string& name) {
    const RunResult d = run_tool("qs-dissect", a.string() + " " + b.string() + " --landmarks " + landmarks + " -o " +
                                                   (dir_ / name).string() + " --quiet --report " +
                                                   (dir_ / (name + ".txt")).string());
    EXPECT_EQ(d.exit, 0) << d.out;
    std::ifstream in(dir_ / (name + ".txt"));
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const fs::path posed = dir_ / "horse.obj";
  RunResult r = run_tool("qs-family", "pose " + horse.string() + " --seed 7 -q -o " + posed.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  const fs::path few = dir_ / "few.landmarks.json";  // the same vertex ids on both: one connectivity
  std::ofstream(few) << R"({"seeds": [1612, 1324, 291, 187], "features": {"fa": 299, "fb": 908}})";
  EXPECT_THAT(report(horse, posed, few.string() + " " + few.string(), "few"),
              testing::ContainsRegex("\\): one pose through the registrations, with [0-9]+ more points held \\(the "
                                     "first mesh's points farthest from the landmarks"));
  const nlohmann::json error = correspondence_error(dir_ / "few");
  ASSERT_FALSE(error.is_null());
  EXPECT_LT(error["mean_percent"].get<double>(), 1.0);
  EXPECT_LT(error["max_percent"].get<double>(), 10.0);
  // With a landmark at every limb's tip (the pose tool's own picks) the first registration fits.
  EXPECT_THAT(report(horse, posed,
                     (dir_ / "horse.source.landmarks.json").string() + " " + (dir_ / "horse.landmarks.json").string(),
                     "tips"),
              HasSubstr("): one pose through the registrations\n"));

  const fs::path cat_posed = dir_ / "cat.obj";
  r = run_tool("qs-family", "pose " + cat.string() + " --seed 12 -q -o " + cat_posed.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  const fs::path seeds = dir_ / "seeds.landmarks.json";
  std::ofstream(seeds) << R"({"seeds": [7179, 3545, 2875, 1817]})";
  EXPECT_THAT(report(cat, cat_posed, seeds.string() + " " + seeds.string(), "cat"),
              HasSubstr("): one pose through the registrations\n"));
  const nlohmann::json cat_error = correspondence_error(dir_ / "cat");
  ASSERT_FALSE(cat_error.is_null());
  EXPECT_LT(cat_error["mean_percent"].get<double>(), 1.0);
  EXPECT_LT(cat_error["max_percent"].get<double>(), 10.0);
}

// A pig with one leg turned about itself (qs-family pose --pose twist --limbs 1) and no landmark on
// that leg lies where it lay: close enough for one pose by the similarity, but far at the leg, so
// the set is registered. Taken as one pose by nearest points after the similarity, it is 0.72% off
// at the 95th percentile and 5.7% at most.
TEST_F(DissectTool, APartThatMovedInPlaceIsRegistered) {
  const fs::path pig = qs::testing::shared_meshes_dir() / "pig_4k.off";
  if (!fs::exists(pig)) GTEST_SKIP() << "no " << pig << " (the shared test meshes)";
  const fs::path posed = dir_ / "posed.obj";
  RunResult r =
      run_tool("qs-family", "pose " + pig.string() + " --pose twist --limbs 1 --seed 1 -q -o " + posed.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  const fs::path few = dir_ / "few.landmarks.json";  // the same vertex ids on both: one connectivity
  std::ofstream(few) << R"({"seeds": [294, 730, 1632, 1702], "features": {"tip4": 1651, "tip5": 688}})";
  r = run_tool("qs-dissect", pig.string() + " " + posed.string() + " --landmarks " + few.string() + " " + few.string() +
                                 " -o " + (dir_ / "out").string() + " --quiet --report " +
                                 (dir_ / "report.txt").string());
  ASSERT_EQ(r.exit, 0) << r.out;
  std::ifstream in(dir_ / "report.txt");
  const std::string report((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_THAT(report, testing::ContainsRegex("one pose: at most 1% and 2%\\): within both, but the 99% quantile is "
                                             "[0-9.]+ times the mean \\(over 10: a part moved in place, as a limb "
                                             "turned about itself\\): registered\n"));
  EXPECT_THAT(report, HasSubstr("): one pose through the registrations\n"));
  // The registration's time is its own stage, between the pose test and the seed loops.
  EXPECT_THAT(report, testing::ContainsRegex("\n  stages: setup [0-9.]+ s, registration [0-9.]+ s, seed loops "));
  const nlohmann::json error = correspondence_error(dir_ / "out");
  ASSERT_FALSE(error.is_null());
  EXPECT_LT(error["p95_percent"].get<double>(), 0.62);
  EXPECT_LT(error["max_percent"].get<double>(), 4.5);
}

// The horse against its pose, re-tessellated (qs-family pose, seed 1): on the re-tessellation the
// shortest loop puts feature tip7 (a weak extremity on the head) on the other side, and no loop
// through the seeds brings it back; the set takes that mesh's arrangement instead of refusing.
// The pair is one surface, registered: the refinement pulls toward the registration 100 times as
// strongly as pose_pull says, with 4 times the steps per side.
TEST_F(DissectTool, FeatureSidesTakeTheArrangementEveryMeshCanReach) {
  const fs::path horse = qs::testing::shared_meshes_dir() / "horse_5k.obj";
  if (!fs::exists(horse)) GTEST_SKIP() << "no " << horse << " (the shared test meshes)";
  const fs::path posed = dir_ / "posed.obj";
  RunResult r = run_tool("qs-family", "pose " + horse.string() + " --seed 1 --retessellate --keep-shape -q -o " +
                                          posed.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  r = run_tool("qs-dissect", horse.string() + " " + (dir_ / "posed_r.obj").string() + " --landmarks " +
                                 (dir_ / "posed.source.landmarks.json").string() + " " +
                                 (dir_ / "posed_r.landmarks.json").string() + " -o " + (dir_ / "out").string() +
                                 " --report " + (dir_ / "report.txt").string());
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("bijective: yes"));
  std::ifstream in(dir_ / "report.txt");
  const std::string report((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_THAT(report, HasSubstr("registration: "));
  EXPECT_THAT(report, HasSubstr("'s nearest points (one pose), weight 1000\n"));
  EXPECT_THAT(report, HasSubstr("(Newton steps per side: at most 20)"));
}
