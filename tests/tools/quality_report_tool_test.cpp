// The quality figures of qs-remesh (smallest angles, vertex density, the error's sample count) and
// qs-bake (texel density), checked against values computed here from the files the tools wrote.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <vector>

#include "qs/io/read_mesh.h"
#include "qs/io/write_mesh.h"
#include "qs/shapes/shapes.h"
#include "tool_runner.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

namespace {

nlohmann::json read_json(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

/// Smallest angle of every face, in degrees, by the law of cosines (independent of the library).
std::vector<double> smallest_angles(const qs::TriMesh& m) {
  std::vector<double> out;
  for (const auto& f : m.faces) {
    const qs::Vec3 &a = m.positions[f[0]], &b = m.positions[f[1]], &c = m.positions[f[2]];
    const double la = (b - c).norm(), lb = (c - a).norm(), lc = (a - b).norm();
    auto angle = [](double opp, double s1, double s2) {
      return std::acos(std::clamp((s1 * s1 + s2 * s2 - opp * opp) / (2 * s1 * s2), -1.0, 1.0)) * 180.0 / M_PI;
    };
    out.push_back(std::min({angle(la, lb, lc), angle(lb, lc, la), angle(lc, la, lb)}));
  }
  return out;
}

}  // namespace

class QualityReport : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("qs_quality_tool_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    qs::io::write_mesh(dir_ / "egg.obj", qs::shapes::ellipsoid(2.0, 1.0, 0.7, 4));
    const RunResult d = run_tool("qs-dissect", (dir_ / "egg.obj").string() + " -q -o " + (dir_ / "d").string());
    ASSERT_EQ(d.exit, 0) << d.out;
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static fs::path dir_;
};
fs::path QualityReport::dir_;

TEST_F(QualityReport, RemeshReportsAnglesDensityAndErrorSamples) {
  const fs::path out = dir_ / "L3";
  const RunResult r = run_tool("qs-remesh", (dir_ / "d").string() + " --level 3 --metro-samples 5000 -o " + out.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("smallest angle median"));
  EXPECT_THAT(r.out, HasSubstr("vertices per unit area, 5th-95th percentile"));
  EXPECT_THAT(r.out, HasSubstr("(5000 samples per direction)"));
  const auto j = read_json(out / "remesh.json");
  EXPECT_EQ(j["mode"], "even");  // --level n: the even remesh with anisotropic cells
  EXPECT_EQ(j["even"]["cells"], "aniso");
  EXPECT_EQ(j["diagonals"], "templates");
  const auto& m = j["meshes"][0];
  EXPECT_EQ(m["error"]["samples_per_direction"], 5000);
  const auto mesh = qs::io::read_mesh(out / "egg.obj").mesh;
  std::vector<double> a = smallest_angles(mesh);
  const double n = static_cast<double>(a.size());
  auto share = [&](double limit) { return std::count_if(a.begin(), a.end(), [&](double x) { return x < limit; }) / n; };
  EXPECT_EQ(m["angles"]["faces"].get<size_t>(), a.size());
  EXPECT_NEAR(m["angles"]["under_5_deg"].get<double>(), share(5), 1e-12);
  EXPECT_NEAR(m["angles"]["under_10_deg"].get<double>(), share(10), 1e-12);
  EXPECT_NEAR(m["angles"]["under_20_deg"].get<double>(), share(20), 1e-12);
  std::sort(a.begin(), a.end());
  const double median = a.size() % 2 ? a[a.size() / 2] : 0.5 * (a[a.size() / 2 - 1] + a[a.size() / 2]);
  EXPECT_NEAR(m["angles"]["median_deg"].get<double>(), median, 1e-6);
  EXPECT_NEAR(m["angles"]["min_deg"].get<double>(), a.front(), 1e-6);
  // Vertex density: 1 / (2 face area), area-weighted percentiles; p5 <= p50 <= p95.
  const auto& vd = m["vertex_density"];
  EXPECT_LE(vd["p5"].get<double>(), vd["p50"].get<double>());
  EXPECT_LE(vd["p50"].get<double>(), vd["p95"].get<double>());
  EXPECT_NEAR(vd["spread"].get<double>(), vd["p95"].get<double>() / vd["p5"].get<double>(), 1e-9);
}

TEST_F(QualityReport, ErrorReportIsOptIn) {
  const fs::path plain = dir_ / "plain", with = dir_ / "with";
  const RunResult r = run_tool("qs-remesh", (dir_ / "d").string() + " --level 2 -o " + plain.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, ::testing::Not(HasSubstr("error mean")));
  EXPECT_FALSE(read_json(plain / "remesh.json")["meshes"][0].contains("error"));
  const RunResult e = run_tool("qs-remesh", (dir_ / "d").string() + " --level 2 --error -o " + with.string());
  ASSERT_EQ(e.exit, 0) << e.out;
  EXPECT_THAT(e.out, HasSubstr("error mean"));
  const auto err = read_json(with / "remesh.json")["meshes"][0]["error"];
  EXPECT_EQ(err["samples_per_direction"], 20000);
  EXPECT_GT(err["mean_percent"].get<double>(), 0.0);
  // The same meshes either way: the report only measures.
  EXPECT_EQ(qs::io::read_mesh(plain / "egg.obj").mesh.positions, qs::io::read_mesh(with / "egg.obj").mesh.positions);
  EXPECT_EQ(run_tool("qs-remesh", (dir_ / "d").string() + " --level 2 --no-metro").exit, 1);  // no such option
}

TEST_F(QualityReport, AngleDiagonalsAreNoWorseThanThePattern) {
  const fs::path pa = dir_ / "pattern", an = dir_ / "angle";
  ASSERT_EQ(run_tool("qs-remesh", (dir_ / "d").string() + " --level 4 --diagonals pattern -q -o " + pa.string()).exit, 0);
  ASSERT_EQ(run_tool("qs-remesh", (dir_ / "d").string() + " --level 4 --diagonals angle -q -o " + an.string()).exit, 0);
  const auto mp = qs::io::read_mesh(pa / "egg.obj").mesh, ma = qs::io::read_mesh(an / "egg.obj").mesh;
  ASSERT_EQ(mp.positions, ma.positions);  // the same samples, only the cells are cut differently
  ASSERT_EQ(mp.faces.size(), ma.faces.size());
  const auto ap = smallest_angles(mp), aa = smallest_angles(ma);
  // Each cell (faces 2k, 2k+1) keeps its diagonal or gets a better worst angle.
  int changed = 0;
  for (size_t k = 0; k + 1 < ap.size(); k += 2) {
    const double before = std::min(ap[k], ap[k + 1]), after = std::min(aa[k], aa[k + 1]);
    EXPECT_GE(after, before - 1e-9) << "cell " << k / 2;
    changed += mp.faces[k] != ma.faces[k];
  }
  EXPECT_GT(changed, 0);
  EXPECT_EQ(run_tool("qs-remesh", (dir_ / "d").string() + " --level 2 --diagonals best").exit, 1);
}

TEST_F(QualityReport, BakeReportsTexelDensity) {
  const fs::path rm = dir_ / "L2";
  ASSERT_EQ(run_tool("qs-remesh", (dir_ / "d").string() + " --level 2 -q -o " + rm.string()).exit, 0);
  double p50[2];
  int k = 0;
  for (int size : {17, 33}) {
    const fs::path out = dir_ / ("bake" + std::to_string(size));
    const RunResult r =
        run_tool("qs-bake", rm.string() + " --size " + std::to_string(size) + " --tiles uniform --samples 0 -o " + out.string());
    ASSERT_EQ(r.exit, 0) << r.out;
    EXPECT_THAT(r.out, HasSubstr("texels per unit area, 5th-95th percentile"));
    const auto doc = read_json(out / "bake.json");
    const auto& t = doc["meshes"][0]["texel_density"];
    EXPECT_LE(t["p5"].get<double>(), t["p50"].get<double>());
    EXPECT_LE(t["p50"].get<double>(), t["p95"].get<double>());
    EXPECT_GE(t["spread"].get<double>(), 1.0);
    p50[k++] = t["p50"].get<double>();
  }
  // (S - 1)^2 texels per unit square: 32^2 / 16^2.
  EXPECT_NEAR(p50[1] / p50[0], 4.0, 1e-9);
}
