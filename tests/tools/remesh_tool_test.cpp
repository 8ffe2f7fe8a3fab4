// qs-remesh as a user runs it: a dissected pair remeshed with one face list; exit codes.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <iterator>
#include <fstream>
#include <nlohmann/json.hpp>

#include "qs/io/read_mesh.h"
#include "qs/io/write_mesh.h"
#include "qs/mesh/validate.h"
#include "qs/shapes/shapes.h"
#include "tool_runner.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

class RemeshTool : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("qs_remesh_tool_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(RemeshTool, PairGetsIdenticalFaceListsAndErrorsFallWithLevel) {
  const qs::TriMesh a = qs::shapes::ellipsoid(1.4, 1, 0.8, 4);
  const qs::TriMesh b = qs::shapes::bumpy_sphere(0.05, 3, 4);
  qs::io::write_mesh(dir_ / "a.obj", a);
  qs::io::write_mesh(dir_ / "b.obj", b);
  const fs::path d = dir_ / "ab.dissection";
  const RunResult dr =
      run_tool("qs-dissect", (dir_ / "a.obj").string() + " " + (dir_ / "b.obj").string() + " -q -o " + d.string());
  ASSERT_EQ(dr.exit, 0) << dr.out;
  double last_error = 1e9;
  for (int level : {2, 4}) {
    const fs::path out = dir_ / ("L" + std::to_string(level));
    const RunResult r = run_tool("qs-remesh", d.string() + " --level " + std::to_string(level) + " --error -o " + out.string());
    ASSERT_EQ(r.exit, 0) << r.out;
    const auto ra = qs::io::read_mesh(out / "a.obj"), rb = qs::io::read_mesh(out / "b.obj");
    EXPECT_EQ(ra.mesh.faces, rb.mesh.faces) << "the set must share one face list";
    const auto v = qs::mesh::validate(ra.mesh);
    EXPECT_TRUE(v.report.accepted) << qs::mesh::format_report("a", v.report);
    std::ifstream in(out / "remesh.json");
    const auto j = nlohmann::json::parse(in);
    EXPECT_EQ(j["format"], "qs-remesh");
    EXPECT_EQ(j["faces"].get<size_t>(), ra.mesh.faces.size());
    EXPECT_EQ(j["vertex_patch"].size(), ra.mesh.positions.size());
    const double err = j["meshes"][1]["error"]["mean_percent"].get<double>();
    EXPECT_LT(err, last_error);
    last_error = err;
  }
  const RunResult ad = run_tool("qs-remesh", d.string() + " --adaptive 0.002 -q -o " + (dir_ / "ad").string());
  ASSERT_EQ(ad.exit, 0) << ad.out;
  EXPECT_EQ(qs::io::read_mesh(dir_ / "ad" / "a.obj").mesh.faces, qs::io::read_mesh(dir_ / "ad" / "b.obj").mesh.faces);
  // The even remesh: samples by area, one face list, closed and manifold, the same bytes twice.
  const RunResult ev = run_tool("qs-remesh", d.string() + " --level 3 -o " + (dir_ / "ev").string());
  ASSERT_EQ(ev.exit, 0) << ev.out;
  EXPECT_THAT(ev.out, HasSubstr("remesh even level 3"));
  const auto ea = qs::io::read_mesh(dir_ / "ev" / "a.obj"), eb = qs::io::read_mesh(dir_ / "ev" / "b.obj");
  EXPECT_EQ(ea.mesh.faces, eb.mesh.faces);
  for (const auto* m : {&ea.mesh, &eb.mesh}) {
    const auto v = qs::mesh::validate(*m);
    EXPECT_TRUE(v.report.accepted) << qs::mesh::format_report("even", v.report);
  }
  {
    std::ifstream in(dir_ / "ev" / "remesh.json");
    const auto j = nlohmann::json::parse(in);
    EXPECT_EQ(j["mode"], "even");
    EXPECT_EQ(j["even"]["level"], 3);
    EXPECT_EQ(j["diagonals"], "templates");
    EXPECT_FALSE(j["meshes"][0].contains("error"));
  }
  ASSERT_EQ(run_tool("qs-remesh", d.string() + " --level 3 -q -o " + (dir_ / "ev2").string()).exit, 0);
  std::ifstream f1(dir_ / "ev" / "a.obj"), f2(dir_ / "ev2" / "a.obj");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(f1), {}), std::string(std::istreambuf_iterator<char>(f2), {}));
  EXPECT_EQ(run_tool("qs-remesh", d.string() + " --adaptive 0.01 --cells square").exit, 1);
  EXPECT_EQ(run_tool("qs-remesh", d.string() + " --level 2 --cells square --quads").exit, 1);
  EXPECT_EQ(run_tool("qs-remesh", d.string() + " --level 2 --cells square --diagonals pattern").exit, 1);
}

// --level n alone is the even remesh with anisotropic cells; --uniform (or a uniform-grid
// option) gives the square grid, --cells square the even remesh's square quadtree cells.
TEST_F(RemeshTool, LevelDefaultsToTheAnisotropicEvenRemesh) {
  qs::io::write_mesh(dir_ / "a.obj", qs::shapes::ellipsoid(2.5, 1, 0.6, 4));
  qs::io::write_mesh(dir_ / "b.obj", qs::shapes::bumpy_sphere(0.05, 3, 4));
  const fs::path d = dir_ / "ab.dissection";
  ASSERT_EQ(run_tool("qs-dissect", (dir_ / "a.obj").string() + " " + (dir_ / "b.obj").string() + " -q -o " + d.string()).exit, 0);
  const RunResult def = run_tool("qs-remesh", d.string() + " --level 3");
  ASSERT_EQ(def.exit, 0) << def.out;
  EXPECT_THAT(def.out, HasSubstr("remesh even level 3 (anisotropic cells)"));
  ASSERT_TRUE(fs::exists(d / "remesh-L3" / "remesh.json"));
  auto json = [](const fs::path& f) {
    std::ifstream in(f / "remesh.json");
    return nlohmann::json::parse(in);
  };
  auto text = [](const fs::path& f) {
    std::ifstream in(f);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const auto jd = json(d / "remesh-L3");
  EXPECT_EQ(jd["mode"], "even");
  EXPECT_EQ(jd["even"]["cells"], "aniso");
  EXPECT_GE(jd["even"]["max_leaf_aspect"].get<double>(), 1.0);
  ASSERT_EQ(run_tool("qs-remesh", d.string() + " --level 3 --cells aniso -q -o " + (dir_ / "ex").string()).exit, 0);
  EXPECT_EQ(text(d / "remesh-L3" / "a.obj"), text(dir_ / "ex" / "a.obj")) << "--cells aniso is the default";
  const auto a = qs::io::read_mesh(d / "remesh-L3" / "a.obj").mesh, b = qs::io::read_mesh(d / "remesh-L3" / "b.obj").mesh;
  EXPECT_EQ(a.faces, b.faces);
  for (const auto* m : {&a, &b}) {
    const auto v = qs::mesh::validate(*m);
    EXPECT_TRUE(v.report.accepted) << qs::mesh::format_report("default", v.report);
  }
  // The uniform grid: 2 P 4^n faces; --quads, --diagonals and --grid-relax select it too.
  ASSERT_EQ(run_tool("qs-remesh", d.string() + " --level 3 --uniform -q").exit, 0);
  const auto ju = json(d / "remesh-L3-uniform");
  EXPECT_EQ(ju["mode"], "uniform");
  EXPECT_EQ(ju["faces"].get<int>(), 2 * ju["patches"].get<int>() * 64);
  ASSERT_EQ(run_tool("qs-remesh", d.string() + " --level 3 --diagonals angle -q -o " + (dir_ / "da").string()).exit, 0);
  EXPECT_EQ(text(d / "remesh-L3-uniform" / "a.obj"), text(dir_ / "da" / "a.obj"));
  ASSERT_EQ(run_tool("qs-remesh", d.string() + " --level 3 --cells square -q").exit, 0);
  EXPECT_EQ(json(d / "remesh-L3-square")["even"]["cells"], "square");
  EXPECT_EQ(run_tool("qs-remesh", d.string() + " --level 3 --uniform --cells square").exit, 1);
  EXPECT_EQ(run_tool("qs-remesh", d.string() + " --level 3 --uniform --cells aniso").exit, 1);
  EXPECT_EQ(run_tool("qs-remesh", d.string() + " --level 3 --cells square --quads").exit, 1);
  EXPECT_EQ(run_tool("qs-remesh", d.string() + " --level 3 --cells round").exit, 1);
  EXPECT_EQ(run_tool("qs-remesh", d.string() + " --adaptive 0.01 --uniform").exit, 1);
}

TEST_F(RemeshTool, ExitCodes) {
  EXPECT_EQ(run_tool("qs-remesh", (dir_ / "nothing").string() + " --level 2").exit, 3);
  fs::create_directories(dir_ / "bad");
  std::ofstream(dir_ / "bad" / "dissection.json") << "{\"format\": \"something else\"}";
  const RunResult bad = run_tool("qs-remesh", (dir_ / "bad").string() + " --level 2");
  EXPECT_EQ(bad.exit, 2) << bad.out;
  EXPECT_THAT(bad.out, HasSubstr("not a qs-dissection file"));
  EXPECT_EQ(run_tool("qs-remesh", (dir_ / "bad").string()).exit, 1);  // neither --level nor --adaptive
  EXPECT_EQ(run_tool("qs-remesh", (dir_ / "bad").string() + " --level 2 --adaptive 0.01").exit, 1);
}

TEST_F(RemeshTool, GridRelaxKeepsTheFaceListMovesTheSamplesAndIsDeterministic) {
  qs::io::write_mesh(dir_ / "a.obj", qs::shapes::ellipsoid(2.5, 1, 0.6, 4));
  qs::io::write_mesh(dir_ / "b.obj", qs::shapes::bumpy_sphere(0.05, 3, 4));
  const fs::path d = dir_ / "ab.dissection";
  ASSERT_EQ(run_tool("qs-dissect", (dir_ / "a.obj").string() + " " + (dir_ / "b.obj").string() + " -q -o " + d.string()).exit, 0);
  auto remesh = [&](const std::string& args, const std::string& name) {
    const RunResult r = run_tool("qs-remesh", d.string() + " --level 3 --diagonals pattern -q " + args + " -o " +
                                                  (dir_ / name).string());
    EXPECT_EQ(r.exit, 0) << r.out;
    std::ifstream in(dir_ / name / "remesh.json");
    return nlohmann::json::parse(in);
  };
  const auto plain = remesh("", "r0"), relaxed = remesh("--grid-relax 1", "r1");
  remesh("--grid-relax 1", "r1b");
  EXPECT_EQ(plain["grid_relax"].get<double>(), 0.0);
  EXPECT_EQ(relaxed["grid_relax"].get<double>(), 1.0);
  EXPECT_EQ(relaxed["vertex_patch"], plain["vertex_patch"]);
  EXPECT_NE(relaxed["vertex_uv"], plain["vertex_uv"]) << "the ellipsoid's squeezed map must move some samples";
  for (const char* m : {"a.obj", "b.obj"}) {
    const auto p0 = qs::io::read_mesh(dir_ / "r0" / m), p1 = qs::io::read_mesh(dir_ / "r1" / m);
    EXPECT_EQ(p1.mesh.faces, p0.mesh.faces) << m;  // same connectivity (pattern diagonals)
    const auto v = qs::mesh::validate(p1.mesh);
    EXPECT_TRUE(v.report.accepted) << qs::mesh::format_report(m, v.report);
    std::ifstream f1(dir_ / "r1" / m), f2(dir_ / "r1b" / m);
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(f1), {}), std::string(std::istreambuf_iterator<char>(f2), {}));
  }
  EXPECT_EQ(qs::io::read_mesh(dir_ / "r1" / "a.obj").mesh.faces, qs::io::read_mesh(dir_ / "r1" / "b.obj").mesh.faces);
  EXPECT_EQ(run_tool("qs-remesh", d.string() + " --level 2 --grid-relax 2.5").exit, 1);
  EXPECT_EQ(run_tool("qs-remesh", d.string() + " --level 2 --grid-relax -1").exit, 1);
  EXPECT_EQ(run_tool("qs-remesh", d.string() + " --level 2 --cells aniso --grid-relax 1").exit, 1);
  EXPECT_EQ(run_tool("qs-remesh", d.string() + " --adaptive 0.01 --grid-relax 1").exit, 1);
}
