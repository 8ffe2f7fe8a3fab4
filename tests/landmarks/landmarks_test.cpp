#include "qs/landmarks/landmarks.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "qs/core/error.h"
#include "qs/shapes/shapes.h"

using qs::landmarks::LandmarkFormat;
using ::testing::HasSubstr;

namespace {

qs::mesh::ValidationResult sphere() {
  static const auto v = qs::mesh::validate(qs::shapes::icosphere(2));
  return v;
}

qs::landmarks::Landmarks parse_json(const std::string& text) {
  return qs::landmarks::parse_landmarks(text, LandmarkFormat::Json, "lm.json", sphere());
}

template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const qs::InvalidInput& e) {
    return e.what();
  }
  return "<no InvalidInput thrown>";
}

}  // namespace

TEST(Landmarks, AllFourReferenceKinds) {
  const auto& m = sphere();
  const qs::Vec3 p5 = m.mesh.positions[5] * 1.001;  // just off the surface at vertex 5
  const std::string text = R"({"seeds": [0, {"vertex": 1}, {"point": [)" + std::to_string(p5.x()) + "," +
                           std::to_string(p5.y()) + "," + std::to_string(p5.z()) +
                           R"(]}, {"face": 7, "bary": [0.2, 0.3, 0.5]}],
      "features": {"nose": 10, "tail": {"face": 3, "bary": [1, 0, 0]}}})";
  const auto lm = parse_json(text);
  ASSERT_EQ(lm.seeds.size(), 4u);
  EXPECT_EQ(lm.seeds[0].vertex, 0);
  EXPECT_EQ(lm.seeds[1].vertex, 1);
  EXPECT_EQ(lm.seeds[2].vertex, 5);
  EXPECT_NEAR(lm.seeds[2].snap_distance, 0.001 * m.mesh.positions[5].norm(), 1e-5);
  EXPECT_EQ(lm.seeds[3].where.face, 7);
  EXPECT_EQ(lm.seeds[3].vertex, -1);
  const qs::Tri& t = m.mesh.faces[7];
  const qs::Vec3 expect = 0.2 * m.mesh.positions[t[0]] + 0.3 * m.mesh.positions[t[1]] + 0.5 * m.mesh.positions[t[2]];
  EXPECT_LT((lm.seeds[3].position - expect).norm(), 1e-12);
  ASSERT_EQ(lm.features.size(), 2u);
  EXPECT_EQ(lm.features[0].name, "nose");
  EXPECT_EQ(lm.features[0].vertex, 10);
  EXPECT_EQ(lm.features[1].name, "tail");
  EXPECT_EQ(lm.features[1].vertex, m.mesh.faces[3][0]);
  // Every resolved point lies on its face.
  for (const auto* g : {&lm.seeds, &lm.features})
    for (const auto& l : *g)
      EXPECT_LT((qs::landmarks::position_of(m.mesh, l.where) - l.position).norm(), 1e-12);
}

TEST(Landmarks, FeaturesOnlyMeansAutomaticSeeds) {
  const auto lm = parse_json(R"({"features": {"a": 3}})");
  EXPECT_TRUE(lm.seeds.empty());
  EXPECT_EQ(lm.features.size(), 1u);
}

TEST(Landmarks, Errors) {
  EXPECT_THAT(error_of([] { parse_json(R"({"seeds": [0, 1, 2, 100000]})"); }),
              HasSubstr("vertex 100000 is out of range"));
  EXPECT_THAT(error_of([] { parse_json(R"({"seeds": [0, 1, 2, 1]})"); }), HasSubstr("same point"));
  EXPECT_THAT(error_of([] { parse_json(R"({"seeds": [0, 1, 2]})"); }), HasSubstr("exactly 4"));
  EXPECT_THAT(error_of([] { parse_json(R"({"seeds": [0, 1, 2, {"point": [5, 5, 5]}]})"); }),
              HasSubstr("from the surface"));
  EXPECT_THAT(error_of([] { parse_json(R"({"seeds": [0, 1, 2, {"face": 99999, "bary": [1, 0, 0]}]})"); }),
              HasSubstr("face 99999 is out of range"));
  EXPECT_THAT(error_of([] { parse_json(R"({"seeds": [0, 1, 2, {"face": 1, "bary": [0.5, 0.2, 0.2]}]})"); }),
              HasSubstr("sum to"));
  EXPECT_THAT(error_of([] { parse_json(R"({"seed": [0, 1, 2, 3]})"); }), HasSubstr("unknown key \"seed\""));
  EXPECT_THAT(error_of([] { parse_json(R"({"seeds": [0, 1, 2, 3],)"); }), HasSubstr("not valid JSON"));
  EXPECT_THAT(error_of([] { parse_json(R"({"features": {"a": "x"}})"); }), HasSubstr("landmark 'a'"));
}

TEST(Landmarks, PickedPoints) {
  const auto& m = sphere();
  auto pt = [&](int v, const char* name, int active = 1) {
    const qs::Vec3& p = m.mesh.positions[v];
    return "  <point x=\"" + std::to_string(p.x()) + "\" y=\"" + std::to_string(p.y()) + "\" z=\"" +
           std::to_string(p.z()) + "\" active=\"" + std::to_string(active) + "\" name=\"" + name + "\"/>\n";
  };
  const std::string pp = "<!DOCTYPE PickedPoints>\n<PickedPoints>\n <DocumentData>\n"
                         "  <DataFileName name=\"sphere.ply\"/>\n </DocumentData>\n" +
                         pt(3, "seed2") + pt(0, "seed0") + pt(1, "seed1") + pt(2, "seed3") + pt(9, "ear") +
                         pt(11, "hidden", 0) + "</PickedPoints>\n";
  const auto lm = qs::landmarks::parse_landmarks(pp, LandmarkFormat::PickedPoints, "a.pp", m);
  ASSERT_EQ(lm.seeds.size(), 4u);
  EXPECT_EQ(lm.seeds[0].vertex, 0);
  EXPECT_EQ(lm.seeds[2].vertex, 3);
  EXPECT_EQ(lm.seeds[3].vertex, 2);
  ASSERT_EQ(lm.features.size(), 1u);
  EXPECT_EQ(lm.features[0].name, "ear");

  const std::string three = "<PickedPoints>\n" + pt(0, "seed0") + pt(1, "seed1") + pt(2, "seed3") + "</PickedPoints>";
  EXPECT_THAT(error_of([&] { qs::landmarks::parse_landmarks(three, LandmarkFormat::PickedPoints, "b.pp", m); }),
              HasSubstr("missing seed2"));
  EXPECT_THAT(error_of([&] {
                qs::landmarks::parse_landmarks("<PickedPoints>\n<point x=\"a\" y=\"0\" z=\"0\" name=\"n\"/>",
                                               LandmarkFormat::PickedPoints, "c.pp", m);
              }),
              HasSubstr("c.pp:2"));
  EXPECT_THAT(error_of([&] { qs::landmarks::parse_landmarks("hello", LandmarkFormat::PickedPoints, "d.pp", m); }),
              HasSubstr("not a MeshLab PickedPoints"));
}

TEST(Landmarks, FileNumberingSurvivesCleaning) {
  // Vertex 0 is unreferenced, so it is dropped; the file's vertex 1 becomes vertex 0.
  qs::TriMesh raw = qs::shapes::icosphere(1);
  raw.positions.insert(raw.positions.begin(), qs::Vec3(9, 9, 9));
  for (auto& f : raw.faces)
    for (int& i : f) ++i;
  const auto valid = qs::mesh::validate(raw);
  ASSERT_TRUE(valid.report.accepted);
  const auto lm = qs::landmarks::parse_landmarks(R"({"features": {"a": 1}})", LandmarkFormat::Json, "x", valid);
  EXPECT_EQ(lm.features[0].vertex, 0);
  EXPECT_THAT(error_of([&] {
                qs::landmarks::parse_landmarks(R"({"features": {"a": 0}})", LandmarkFormat::Json, "x", valid);
              }),
              HasSubstr("used by no face"));
}

TEST(Landmarks, FoundBesideTheMesh) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "qs_lm_beside";
  fs::remove_all(dir);
  fs::create_directories(dir);
  EXPECT_FALSE(qs::landmarks::find_landmarks_beside(dir / "cow.obj"));
  std::ofstream(dir / "cow.pp") << "<PickedPoints/>";
  EXPECT_EQ(*qs::landmarks::find_landmarks_beside(dir / "cow.obj"), dir / "cow.pp");
  std::ofstream(dir / "cow.landmarks.json") << "{}";
  EXPECT_EQ(*qs::landmarks::find_landmarks_beside(dir / "cow.obj"), dir / "cow.landmarks.json");
  fs::remove_all(dir);
}
