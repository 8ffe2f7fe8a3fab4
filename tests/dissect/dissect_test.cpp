#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <unistd.h>

#include "qs/core/error.h"
#include "qs/dissect/chart_io.h"
#include "qs/dissect/cut_mesh.h"
#include "qs/dissect/dissection.h"
#include "qs/dissect/dissection_json.h"
#include "qs/mesh/validate.h"
#include "qs/shapes/shapes.h"
#include "check_dissection.h"

using qs::dissect::Dissection;
using ::testing::HasSubstr;

using qs::testing::check_dissection;

TEST(Dissect, SmoothShapeNeedsOnlyTheSeedPatches) {
  // The stretch rule alone (no area cap, which is on by default).
  const auto m = qs::shapes::ellipsoid(1.5, 1, 0.8, 3);
  qs::dissect::DissectOptions o;
  o.max_patch_area = 0;
  const auto d = qs::dissect::dissect(m, std::nullopt, o);
  EXPECT_EQ(d.chart.patches.size(), 2u);
  EXPECT_LE(d.max_stretch, o.tau);
  check_dissection(d, m.num_faces());
}

TEST(Dissect, ProtrusionsForceQuinarySplitsAndEveryInvariantHolds) {
  const auto m = qs::shapes::star_blob(4, 1.5, 4);
  qs::dissect::DissectOptions o;
  o.tau = 1.4;
  const auto d = qs::dissect::dissect(m, std::nullopt, o);
  EXPECT_GT(d.chart.patches.size(), 2u);
  EXPECT_EQ((d.chart.patches.size() - 2) % 4, 0u) << "each split turns 1 patch into 5";
  check_dissection(d, m.num_faces());
  // Every split node has its 5 children, named by path.
  std::set<std::string> names;
  for (const auto& n : d.tree) names.insert(n.name);
  for (const auto& n : d.tree)
    if (n.split) {
      for (int k = 0; k < 5; ++k) { EXPECT_TRUE(names.count(n.name + "." + std::to_string(k))); }
    }
  for (const auto& p : d.chart.patches)
    if (p.stretch > o.tau) { EXPECT_NE(p.stop, qs::dissect::StopReason::None) << p.name; }
}

TEST(Dissect, SplitPutsTheCentralChildOnTheStretchPeak) {
  // A ball with one long arm along +x: the arm tip is the stretch peak of its seed patch, so it
  // ends up in the central child (".4") of that patch's first split or in its descendants.
  qs::TriMesh m = qs::shapes::displaced_sphere(
      [](const qs::Vec3& d) { return 1.0 + 2.5 * std::pow(std::max(0.0, d.x()), 40); }, 5);
  const std::array<int, 4> seeds = [&] {
    // Seeds on the equator x = 0 so that the arm lies inside one seed patch.
    std::array<int, 4> s{};
    const std::array<qs::Vec3, 4> dirs = {qs::Vec3(0, 1, 0), qs::Vec3(0, 0, 1), qs::Vec3(0, -1, 0), qs::Vec3(0, 0, -1)};
    for (int i = 0; i < 4; ++i) {
      double best = -1e9;
      for (int v = 0; v < m.num_vertices(); ++v)
        if (m.positions[v].normalized().dot(dirs[i]) > best) {
          best = m.positions[v].normalized().dot(dirs[i]);
          s[i] = v;
        }
    }
    return s;
  }();
  qs::dissect::DissectOptions o;
  o.tau = 1.5;
  const auto d = qs::dissect::dissect(m, seeds, o);
  check_dissection(d, m.num_faces());
  int tip = 0;
  for (int v = 0; v < m.num_vertices(); ++v)
    if (m.positions[v].x() > m.positions[tip].x()) tip = v;
  std::string tip_patch;
  for (int f = 0; f < d.chart.mesh.num_faces(); ++f)
    for (int k : d.chart.mesh.faces[f])
      if (k == tip) tip_patch = d.chart.patches[d.chart.face_patch[f]].name;
  ASSERT_GE(tip_patch.size(), 3u) << "the arm's seed patch was not split";
  EXPECT_EQ(tip_patch.substr(1, 2), ".4") << tip_patch;
}

TEST(Dissect, TerminatesOnAPathologicalMesh) {
  // Many long thin arms on a coarse mesh: stretch can never reach tau = 1. Splitting must stop,
  // and every patch left over tau must say why.
  const auto m = qs::shapes::star_blob(12, 3.0, 3);
  qs::dissect::DissectOptions o;
  o.tau = 1.0;
  o.max_depth = 4;
  const auto d = qs::dissect::dissect(m, std::nullopt, o);
  int depth = 0;
  for (const auto& n : d.tree) depth = std::max(depth, n.depth);
  EXPECT_LE(depth, 4);
  for (const auto& p : d.chart.patches)
    if (p.stretch > o.tau) { EXPECT_NE(p.stop, qs::dissect::StopReason::None) << p.name; }
}

TEST(Dissect, BadSeedsAndOptions) {
  const auto m = qs::shapes::icosphere(2);
  EXPECT_THROW(qs::dissect::dissect(m, std::array<int, 4>{0, 1, 1, 3}), qs::InvalidInput);
  EXPECT_THROW(qs::dissect::dissect(m, std::array<int, 4>{0, 1, 2, 99999}), qs::InvalidInput);
  qs::dissect::DissectOptions o;
  o.tau = 0.5;
  try {
    qs::dissect::dissect(m, std::nullopt, o);
    FAIL() << "tau < 1 accepted";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("tau"));
  }
}

TEST(Dissect, ChartRoundTripAndDeterminismOnAnyThreadCount) {
  const auto m = qs::shapes::star_blob(3, 1.2, 4);
  qs::dissect::DissectOptions o;
  o.tau = 1.4;
  const auto a = qs::dissect::dissect(m, std::nullopt, o);
  qs::Context one_thread;  // the leaf repairs and the seed candidates run on one thread only
  one_thread.threads = 1;
  const auto b = qs::dissect::dissect(m, std::nullopt, o, one_thread);
  qs::dissect::DissectedMesh da, db;
  da.dissection = a;
  db.dissection = b;
  EXPECT_EQ(qs::dissect::dissection_to_json({da}, o, false), qs::dissect::dissection_to_json({db}, o, false));

  const auto dir = std::filesystem::temp_directory_path() / ("qs_chart_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  qs::dissect::write_chart_ply(dir / "a.chart.ply", a.chart);
  qs::dissect::write_chart_ply(dir / "b.chart.ply", b.chart);
  auto bytes = [](const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  };
  EXPECT_EQ(bytes(dir / "a.chart.ply"), bytes(dir / "b.chart.ply"));
  const auto back = qs::dissect::read_chart_ply(dir / "a.chart.ply");
  EXPECT_EQ(back.mesh.faces, a.chart.mesh.faces);
  EXPECT_EQ(back.face_patch, a.chart.face_patch);
  EXPECT_EQ(back.patches.size(), a.chart.patches.size());
  for (size_t f = 0; f < back.face_uv.size(); ++f)
    for (int k = 0; k < 3; ++k) EXPECT_LT((back.face_uv[f][k] - a.chart.face_uv[f][k]).norm(), 1e-6);
  // A truncated chart is refused with a clear message.
  const std::string full = bytes(dir / "a.chart.ply");
  std::ofstream(dir / "cut.chart.ply", std::ios::binary) << full.substr(0, full.size() - 7);
  try {
    qs::dissect::read_chart_ply(dir / "cut.chart.ply");
    FAIL() << "truncated chart accepted";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("truncated"));
  }
  std::filesystem::remove_all(dir);
}

TEST(CutMesh, SplitsKeepTheHalfEdgeStructureConsistent) {
  qs::dissect::CutMesh cm(qs::shapes::icosphere(1));
  cm.split_edge(0, 0.3);
  cm.split_face(5, qs::Vec3(0.2, 0.3, 0.5));
  cm.split_edge(3 * 7 + 2, 0.5);
  const int nh = 3 * cm.num_faces();
  for (int h = 0; h < nh; ++h) {
    const int o = cm.opposite(h);
    ASSERT_GE(o, 0);
    EXPECT_EQ(cm.opposite(o), h);
    EXPECT_EQ(cm.tail(o), cm.head(h));
    EXPECT_EQ(cm.head(o), cm.tail(h));
  }
  for (int v = 0; v < cm.num_vertices(); ++v) EXPECT_EQ(cm.tail(cm.out_halfedge(v)), v);
  const auto valid = qs::mesh::validate(cm.to_trimesh());
  EXPECT_TRUE(valid.report.accepted);
  EXPECT_FALSE(valid.report.orientation_flipped);
  EXPECT_EQ(valid.report.euler_characteristic, 2);
}

TEST(CutMesh, RollbackUndoesEverySplitSinceTheCheckpointAndCommitKeepsThem) {
  qs::dissect::CutMesh cm(qs::shapes::icosphere(1));
  cm.split_edge(4, 0.5);  // before the checkpoint: kept by the rollback
  const qs::dissect::CutMesh before = cm;
  auto same = [](const qs::dissect::CutMesh& a, const qs::dissect::CutMesh& b) {
    if (a.positions() != b.positions() || a.faces() != b.faces() || a.face_patches() != b.face_patches()) return false;
    for (int h = 0; h < 3 * a.num_faces(); ++h)
      if (a.opposite(h) != b.opposite(h)) return false;
    for (int v = 0; v < a.num_vertices(); ++v)
      if (a.out_halfedge(v) != b.out_halfedge(v)) return false;
    return true;
  };
  cm.checkpoint();
  cm.split_edge(0, 0.3);
  cm.split_face(5, qs::Vec3(0.2, 0.3, 0.5));
  cm.split_edge(3 * (cm.num_faces() - 1), 0.5);  // an edge of a face the checkpoint did not see
  cm.split_edge(3 * 7 + 2, 0.5);
  ASSERT_FALSE(same(cm, before));
  cm.rollback();
  EXPECT_TRUE(same(cm, before));
  EXPECT_THROW(cm.rollback(), qs::InternalError);  // the rollback ended the recording
  cm.checkpoint();
  cm.split_edge(0, 0.3);
  cm.commit();
  EXPECT_EQ(cm.num_vertices(), before.num_vertices() + 1);
  EXPECT_TRUE(qs::mesh::validate(cm.to_trimesh()).report.accepted);
}

TEST(CutMesh, RefusesAFaceWithAVertexOutOfRangeAndAnOpenEdge) {
  qs::TriMesh m = qs::shapes::icosphere(0);
  qs::TriMesh bad = m;
  bad.faces[3][1] = m.num_vertices();
  EXPECT_THROW(qs::dissect::CutMesh{bad}, qs::InvalidInput);
  qs::TriMesh open = m;
  open.faces.pop_back();
  try {
    qs::dissect::CutMesh cm(open);
    FAIL() << "an open mesh was accepted";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("is not shared by exactly two oppositely oriented faces"));
  }
}

TEST(DissectionFolder, ReadsBackWhatWasWrittenIncludingAnInfiniteStretch) {
  const auto m = qs::shapes::ellipsoid(1.5, 1, 0.8, 3);
  qs::dissect::DissectedMesh dm;
  qs::dissect::DissectOptions two_patches;
  two_patches.max_patch_area = 0;
  dm.dissection = qs::dissect::dissect(m, std::nullopt, two_patches);
  dm.dissection.chart.patches[1].stretch = std::numeric_limits<double>::infinity();  // a folded leaf
  dm.file = "e.obj";
  dm.chart_file = "e.chart.ply";
  dm.seed_source = "automatic";
  const auto dir = std::filesystem::temp_directory_path() / ("qs_folder_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  qs::dissect::write_chart_ply(dir / dm.chart_file, dm.dissection.chart);
  std::ofstream(dir / "dissection.json") << qs::dissect::dissection_to_json({dm}, qs::dissect::DissectOptions{}, false);
  const auto back = qs::dissect::read_dissection(dir);
  std::filesystem::remove_all(dir);
  ASSERT_EQ(back.meshes.size(), 1u);
  const auto& c = back.meshes[0].dissection.chart;
  ASSERT_EQ(c.patches.size(), 2u);
  EXPECT_EQ(c.patches[0].corners, dm.dissection.chart.patches[0].corners);
  EXPECT_TRUE(std::isinf(c.patches[1].stretch));
  EXPECT_EQ(back.meshes[0].dissection.base.quads, dm.dissection.base.quads);
}

TEST(Dissect, AreaCapSplitsLargeSmoothPatches) {
  const auto m = qs::shapes::ellipsoid(1.5, 1, 0.8, 3);
  qs::dissect::DissectOptions o;
  o.max_patch_area = 0.15;
  const auto d = qs::dissect::dissect(m, std::nullopt, o);
  EXPECT_GT(d.chart.patches.size(), 2u) << "the two seed patches are half the surface each";
  check_dissection(d, m.num_faces());
  double total = 0;
  std::vector<double> area(d.chart.patches.size(), 0.0);
  for (int f = 0; f < d.chart.mesh.num_faces(); ++f) {
    const auto& t = d.chart.mesh.faces[f];
    const auto& x = d.chart.mesh.positions;
    const double a = 0.5 * (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]).norm();
    area[d.chart.face_patch[f]] += a;
    total += a;
  }
  for (size_t p = 0; p < area.size(); ++p)
    if (d.chart.patches[p].stop == qs::dissect::StopReason::None) {
      EXPECT_LE(area[p], 0.15 * total + 1e-12) << d.chart.patches[p].name;
    }
}

TEST(Dissect, StretchMinimizedLeavesKeepEveryInvariantAndLowerStretch) {
  const auto m = qs::shapes::star_blob(4, 1.5, 4);
  qs::dissect::DissectOptions o;
  o.tau = 1.4;
  o.stretch_iterations = 0;
  const auto plain = qs::dissect::dissect(m, std::nullopt, o);
  o.stretch_iterations = 6;
  const auto d = qs::dissect::dissect(m, std::nullopt, o);
  check_dissection(d, m.num_faces());
  ASSERT_EQ(d.chart.patches.size(), plain.chart.patches.size()) << "the patches do not change";
  EXPECT_EQ(d.chart.face_patch, plain.chart.face_patch);
  int lower = 0;
  for (size_t p = 0; p < d.chart.patches.size(); ++p) {
    EXPECT_LE(d.chart.patches[p].stretch, plain.chart.patches[p].stretch) << d.chart.patches[p].name;
    lower += d.chart.patches[p].stretch < plain.chart.patches[p].stretch * 0.999;
  }
  EXPECT_GT(lower, 0);
}

