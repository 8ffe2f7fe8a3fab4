// qs-bake as a user runs it: dissect + remesh + bake of a bumpy sphere; files, bake.json, the GLB
// through the Khronos validator (when installed), exit codes and no partial output on errors.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <set>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>

#include "qs/io/write_mesh.h"
#include "qs/shapes/shapes.h"
#include "tool_runner.h"
#include "../common/gltf_test_support.h"
#include "../common/test_support.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

using qs::test::read_bytes;

namespace {

int count_files(const fs::path& dir) {
  if (!fs::exists(dir)) return 0;
  return static_cast<int>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

}  // namespace

class BakeTool : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("qs_bake_tool_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    qs::io::write_mesh(dir_ / "bumpy.obj", qs::shapes::bumpy_sphere(0.06, 4, 4));
    const RunResult d = run_tool("qs-dissect", (dir_ / "bumpy.obj").string() + " -q -o " + (dir_ / "d").string());
    ASSERT_EQ(d.exit, 0) << d.out;
    const RunResult r = run_tool("qs-remesh", (dir_ / "d").string() + " --level 2 -q -o " + remesh().string());
    ASSERT_EQ(r.exit, 0) << r.out;
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static fs::path remesh() { return dir_ / "d" / "L2"; }
  static fs::path dir_;
};
fs::path BakeTool::dir_;

TEST_F(BakeTool, WritesMapsGlbAndReport) {
  const fs::path out = dir_ / "bake";
  const RunResult r =
      run_tool("qs-bake", remesh().string() + " --size 32 --gutter 3 --tiles uniform --format png16 exr -o " + out.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("with the map"));
  for (const char* f : {"bumpy_normal.png", "bumpy_normal16.png", "bumpy_normal.exr", "bumpy.glb", "bake.json"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  EXPECT_EQ(read_bytes(out / "bumpy_normal.png").substr(1, 3), "PNG");
  EXPECT_EQ(read_bytes(out / "bumpy.glb").substr(0, 4), "glTF");
  const auto j = nlohmann::json::parse(read_bytes(out / "bake.json"));
  EXPECT_EQ(j["format"], "qs-bake");
  EXPECT_EQ(j["options"]["space"], "tangent");
  EXPECT_EQ(j["options"]["green"], "opengl");
  const auto& a = j["atlas"];
  const int patches = static_cast<int>(a["patches"].size());
  ASSERT_GE(patches, 2);
  EXPECT_EQ(a["columns"].get<int>(), static_cast<int>(std::ceil(std::sqrt(patches) - 1e-12)));
  EXPECT_EQ(a["width"].get<int>(), a["columns"].get<int>() * (32 + 6));
  EXPECT_EQ(a["patches"][1]["x"].get<int>(), 38 + 3);
  const auto& m = j["meshes"][0];
  EXPECT_EQ(m["maps"]["png16"], "bumpy_normal16.png");
  const double with = m["shading"]["mean_deg_with_map"], without = m["shading"]["mean_deg_without_map"];
  EXPECT_LT(with, 1.5);
  EXPECT_GT(without, 2 * with);
  EXPECT_GT(m["glb_vertices"].get<int>(), 0);

  // Deterministic: the same run on one thread gives the same bytes.
  const fs::path again = dir_ / "bake-again";
  ASSERT_EQ(run_tool("qs-bake", remesh().string() + " --size 32 --gutter 3 --tiles uniform -q --threads 1 -o " +
                                    again.string()).exit,
            0);
  EXPECT_EQ(read_bytes(out / "bumpy_normal.png"), read_bytes(again / "bumpy_normal.png"));
  EXPECT_EQ(read_bytes(out / "bumpy.glb"), read_bytes(again / "bumpy.glb"));
}

TEST_F(BakeTool, TilesSizedByAreaByDefault) {
  const fs::path out = dir_ / "bake-area", again = dir_ / "bake-area-again", grid = dir_ / "bake-grid";
  const RunResult r = run_tool("qs-bake", remesh().string() + " --size 32 --gutter 3 --samples 20000 -o " + out.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("tiles sized by area"));
  const auto j = nlohmann::json::parse(read_bytes(out / "bake.json"));
  EXPECT_EQ(j["options"]["tiles"], "area");
  const auto& a = j["atlas"];
  EXPECT_EQ(a["layout"], "shelves");
  const int W = a["width"], H = a["height"], G = a["gutter"];
  std::set<int> sides;
  for (const auto& t : a["patches"]) {
    const int x = t["x"], y = t["y"], s = t["width"];
    EXPECT_EQ(t["height"].get<int>(), s);
    EXPECT_GE(x - G, 0);
    EXPECT_GE(y - G, 0);
    EXPECT_LE(x + s + G, W);
    EXPECT_LE(y + s + G, H);
    sides.insert(s);
  }
  EXPECT_GT(sides.size(), 1u) << "the bumpy sphere's patches differ in area";
  // The map still works through the GLB's texture coordinates.
  const auto& m = j["meshes"][0];
  EXPECT_LT(m["shading"]["mean_deg_with_map"].get<double>(), 1.5);
  ASSERT_EQ(run_tool("qs-bake", remesh().string() + " --size 32 --gutter 3 --samples 0 --tiles uniform -q -o " + grid.string()).exit, 0);
  const auto g = nlohmann::json::parse(read_bytes(grid / "bake.json"));
  EXPECT_EQ(g["atlas"]["layout"], "grid");
  EXPECT_LE(m["texel_density"]["spread"].get<double>(), g["meshes"][0]["texel_density"]["spread"].get<double>());
  ASSERT_EQ(run_tool("qs-bake", remesh().string() + " --size 32 --gutter 3 --samples 20000 -q -o " + again.string()).exit, 0);
  EXPECT_EQ(read_bytes(out / "bumpy_normal.png"), read_bytes(again / "bumpy_normal.png"));
  EXPECT_EQ(read_bytes(out / "bumpy.glb"), read_bytes(again / "bumpy.glb"));
  EXPECT_EQ(run_tool("qs-bake", remesh().string() + " --tiles square -q -o " + (dir_ / "bad").string()).exit, 1);
}

TEST_F(BakeTool, GlbPassesTheKhronosValidator) {
  const fs::path out = dir_ / "bake-validate";
  ASSERT_EQ(run_tool("qs-bake", remesh().string() + " --size 16 -q -o " + out.string()).exit, 0);
  std::string text;
  const int code = qs::testing::run_gltf_validator(out / "bumpy.glb", &text);
  if (code == 3) GTEST_SKIP() << "glTF validator not installed: " << text;
  EXPECT_EQ(code, 0) << text;
  EXPECT_THAT(text, HasSubstr("0 errors"));
}

TEST_F(BakeTool, DirectXAndObjectSpace) {
  const fs::path gl = dir_ / "gl", dx = dir_ / "dx", os = dir_ / "os";
  ASSERT_EQ(run_tool("qs-bake", remesh().string() + " --size 16 -q -o " + gl.string()).exit, 0);
  const RunResult r = run_tool("qs-bake", remesh().string() + " --size 16 --green directx -q -o " + dx.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_NE(read_bytes(gl / "bumpy_normal.png"), read_bytes(dx / "bumpy_normal.png"));
  const auto jg = nlohmann::json::parse(read_bytes(gl / "bake.json")), jd = nlohmann::json::parse(read_bytes(dx / "bake.json"));
  EXPECT_EQ(jd["options"]["green"], "directx");
  // The check decodes each map with its own convention: both restore the detail equally well.
  EXPECT_NEAR(jd["meshes"][0]["shading"]["mean_deg_with_map"].get<double>(),
              jg["meshes"][0]["shading"]["mean_deg_with_map"].get<double>(), 0.05);
  ASSERT_EQ(run_tool("qs-bake", remesh().string() + " --size 16 --space object -q -o " + os.string()).exit, 0);
  const auto jo = nlohmann::json::parse(read_bytes(os / "bake.json"));
  EXPECT_EQ(jo["meshes"][0]["glb_normal_texture"], false);
  EXPECT_LT(jo["meshes"][0]["shading"]["mean_deg_with_map"].get<double>(), 1.5);
}

TEST_F(BakeTool, ExitCodesAndNoPartialOutput) {
  const fs::path out = dir_ / "never";
  auto expect = [&](const std::string& args, int code, const std::string& text) {
    const RunResult r = run_tool("qs-bake", args + " -o " + out.string());
    EXPECT_EQ(r.exit, code) << args << "\n" << r.out;
    EXPECT_THAT(r.out, HasSubstr(text)) << args;
    EXPECT_EQ(count_files(out), 0) << args << ": nothing may be written on an error";
  };
  const std::string rm = remesh().string();
  expect(rm + " --size 0", 1, "--size");
  expect(rm + " --size 1", 1, "--size");
  expect(rm + " --space tangential", 1, "--space");
  expect(rm + " --green up", 1, "--green");
  expect(rm + " --format jpg", 1, "--format");
  expect(rm + " --space object --green directx", 1, "tangent-space maps only");
  expect("", 1, "remesh");
  expect((dir_ / "nowhere").string(), 3, "no such folder");
  fs::create_directories(dir_ / "empty");
  expect((dir_ / "empty").string(), 3, "qs-remesh output folder");
  fs::create_directories(dir_ / "bad");
  std::ofstream(dir_ / "bad" / "remesh.json") << "{\"format\": \"qs-dissection\"}";
  expect((dir_ / "bad").string(), 2, "not a qs-remesh file");
  // A remesh folder moved away from its dissection.
  const fs::path moved = dir_ / "moved";
  fs::create_directories(moved);
  for (const auto& e : fs::directory_iterator(remesh())) fs::copy(e.path(), moved / e.path().filename());
  expect(moved.string(), 3, "pass --dissection");
  // ... found again with --dissection.
  const RunResult ok = run_tool("qs-bake", moved.string() + " --dissection " + (dir_ / "d").string() + " --size 8 -q");
  EXPECT_EQ(ok.exit, 0) << ok.out;
  EXPECT_TRUE(fs::exists(moved / "bake-8" / "bumpy.glb"));
  // The wrong dissection: another mesh's charts.
  qs::io::write_mesh(dir_ / "other.obj", qs::shapes::ellipsoid(1.5, 1, 0.6, 3));
  ASSERT_EQ(run_tool("qs-dissect", (dir_ / "other.obj").string() + " -q -o " + (dir_ / "od").string()).exit, 0);
  expect(rm + " --dissection " + (dir_ / "od").string(), 2, "not the dissection it was made from");
  // An output path that is a file.
  std::ofstream(dir_ / "a-file") << "x";
  const RunResult f = run_tool("qs-bake", rm + " --size 8 -o " + (dir_ / "a-file").string());
  EXPECT_EQ(f.exit, 3) << f.out;
}
