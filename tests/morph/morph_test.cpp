// Linear blending, path frames, frame files and the morph GLB, on sets made in code (icosphere
// variants share one connectivity, as a remesh set does).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>

#include "qs/core/error.h"
#include "qs/gltf/glb.h"
#include "qs/io/read_mesh.h"
#include "qs/io/write_mesh.h"
#include "../common/gltf_test_support.h"
#include "../common/image_test_support.h"
#include "qs/morph/blend.h"
#include "qs/morph/frame_maps.h"
#include "qs/morph/frames.h"
#include "qs/morph/morph_glb.h"
#include "qs/shapes/shapes.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

namespace {

// A set of `n` shapes on the icosphere's connectivity: an ellipsoid, bumpy spheres, ...
qs::remesh::SemiRegularSet make_set(int n, int subdivisions = 2) {
  qs::remesh::SemiRegularSet set;
  for (int i = 0; i < n; ++i) {
    const qs::TriMesh m = i == 0   ? qs::shapes::ellipsoid(1.4, 1, 0.8, subdivisions)
                          : i == 1 ? qs::shapes::bumpy_sphere(0.1, 3, subdivisions)
                                   : qs::shapes::displaced_sphere(
                                         [i](const qs::Vec3& d) { return 1 + 0.05 * i * d.x() * d.x() + 0.02 * d.z(); },
                                         subdivisions);
    if (i == 0) set.connectivity.faces = m.faces;
    EXPECT_EQ(m.faces, set.connectivity.faces);
    set.positions.push_back(m.positions);
  }
  return set;
}

std::vector<std::string> names_of(int n) {
  std::vector<std::string> names;
  for (int i = 0; i < n; ++i) names.push_back("shape" + std::to_string(i));
  return names;
}

template <class F>
std::string message_of(F&& f) {
  try {
    f();
  } catch (const qs::Error& e) {
    return e.what();
  }
  return "(nothing thrown)";
}

// A w x h flat normal map (128, 128, 255).
std::vector<unsigned char> flat_normal_png(int w, int h) {
  return qs::testing::make_png(w, h, [](int, int, int c) -> unsigned char { return c == 2 ? 255 : 128; });
}

int run_validator(const fs::path& file, std::string* out) { return qs::testing::run_gltf_validator(file, out); }

class MorphFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("qs_morph_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

// A bake of shape `base` as qs-bake might write it: vertices split along a seam (every vertex of
// faces [0, F/2) duplicated), a spherical atlas UV, tangents, the normal map in the material.
void write_fake_bake(const fs::path& dir, const std::string& stem, const qs::remesh::SemiRegularSet& set, int base,
                     bool with_texture = true, bool with_json = true) {
  fs::create_directories(dir);
  if (with_json) std::ofstream(dir / "bake.json") << R"({"format": "qs-bake", "version": 1})";
  const auto& p = set.positions[base];
  const auto normals = qs::vertex_normals(p, set.connectivity.faces);
  qs::gltf::Mesh g;
  g.name = stem;
  std::vector<int> src;
  for (size_t v = 0; v < p.size(); ++v) src.push_back(static_cast<int>(v));
  g.faces = set.connectivity.faces;
  const size_t half = g.faces.size() / 2;
  std::vector<bool> kept(p.size(), false);  // used by the second half: its copy there stays in use
  for (size_t f = half; f < g.faces.size(); ++f)
    for (int v : g.faces[f]) kept[v] = true;
  for (size_t f = 0; f < half; ++f)
    for (int& v : g.faces[f])
      if (kept[v]) {
        src.push_back(v);
        v = static_cast<int>(src.size()) - 1;
      }
  for (int s : src) {
    g.positions.push_back(p[s]);
    g.normals.push_back(normals[s]);
    const qs::Vec3 d = p[s].normalized();
    g.texcoords.emplace_back(0.5 + 0.5 * std::atan2(d.y(), d.x()) / M_PI, 0.5 - 0.5 * d.z());
    const qs::Vec3 axis = std::abs(normals[s].z()) < 0.9 ? qs::Vec3(0, 0, 1) : qs::Vec3(1, 0, 0);
    const qs::Vec3 t = axis.cross(normals[s]).normalized();
    g.tangents.push_back({t.x(), t.y(), t.z(), -1.0});
  }
  if (with_texture) {
    qs::gltf::Material m;
    m.normal_texture = qs::gltf::Image{stem + "_normal", "image/png", flat_normal_png(8, 8)};
    g.material = m;
  }
  qs::gltf::write_glb(dir / (stem + ".glb"), g);
  std::ofstream(dir / (stem + "_normal.png"), std::ios::binary)
      .write(reinterpret_cast<const char*>(flat_normal_png(4, 4).data()), flat_normal_png(4, 4).size());
}

}  // namespace

TEST(PathFrames, EndsAreTheShapesExactly) {
  const auto set = make_set(3);
  for (int frames : {2, 7, 10}) {
    const auto pf = qs::morph::path_frames(3, {0, 1, 2}, frames);
    ASSERT_EQ(pf.size(), static_cast<size_t>(frames));
    EXPECT_EQ(qs::morph::blend(set, pf.front().weights), set.positions[0]);  // bit-exact
    EXPECT_EQ(qs::morph::blend(set, pf.back().weights), set.positions[2]);
    EXPECT_EQ(pf.back().s, 2.0);
    for (const auto& f : pf) {
      double sum = 0;
      for (double w : f.weights) {
        EXPECT_GE(w, 0);
        sum += w;
      }
      EXPECT_NEAR(sum, 1, 1e-15);
    }
  }
  // A stop in the middle is a frame when (frames - 1) is a multiple of the leg count.
  const auto pf = qs::morph::path_frames(3, {0, 1, 2}, 5);
  EXPECT_EQ(pf[2].s, 1.0);
  EXPECT_EQ(qs::morph::blend(set, pf[2].weights), set.positions[1]);
  EXPECT_EQ(pf[1].leg, 0);
  EXPECT_EQ(pf[3].leg, 1);
  EXPECT_DOUBLE_EQ(pf[3].t, 0.5);
}

TEST(PathFrames, MidpointOfTwoShapesIsTheAverage) {
  const auto set = make_set(2);
  const auto pf = qs::morph::path_frames(2, {0, 1}, 9);
  EXPECT_EQ(pf[4].weights, (std::vector<double>{0.5, 0.5}));
  const auto mid = qs::morph::blend(set, pf[4].weights);
  for (size_t v = 0; v < mid.size(); ++v) {
    const qs::Vec3 avg = (set.positions[0][v] + set.positions[1][v]) / 2;
    EXPECT_LE((mid[v] - avg).cwiseAbs().maxCoeff(), 4e-16 * std::max(1.0, avg.cwiseAbs().maxCoeff())) << v;
  }
  // Uniform in the path parameter: frame f at s = f / 8.
  for (int f = 0; f < 9; ++f) EXPECT_DOUBLE_EQ(pf[f].weights[1], f / 8.0);
}

TEST(PathFrames, RepeatedStopsAndBackAndForth) {
  const auto set = make_set(2);
  const auto pf = qs::morph::path_frames(2, {0, 1, 0}, 5);
  EXPECT_EQ(qs::morph::blend(set, pf[2].weights), set.positions[1]);
  EXPECT_EQ(qs::morph::blend(set, pf[4].weights), set.positions[0]);
  const auto still = qs::morph::path_frames(2, {1, 1}, 3);
  EXPECT_EQ(still[1].weights, (std::vector<double>{0, 1}));  // a leg from a shape to itself sums weights
}

TEST(PathFrames, BadArgumentsAreRefused) {
  EXPECT_THAT(message_of([] { qs::morph::path_frames(2, {0, 1}, 1); }), HasSubstr("at least 2 frames"));
  EXPECT_THAT(message_of([] { qs::morph::path_frames(2, {0}, 5); }), HasSubstr("at least 2 stops"));
  EXPECT_THAT(message_of([] { qs::morph::path_frames(2, {0, 2}, 5); }), HasSubstr("path stop 1 is shape 2, not in [0, 2)"));
  EXPECT_THROW(qs::morph::path_frames(2, {-1, 0}, 5), qs::InvalidInput);
}

TEST(Align, SimilarityUndoesARotationScaleAndShift) {
  const qs::TriMesh m = qs::shapes::bumpy_sphere(0.1, 3, 3);
  const Eigen::AngleAxisd r(1.1, qs::Vec3(0.3, -0.5, 0.8).normalized());
  std::vector<qs::Vec3> moved;
  for (const auto& p : m.positions) moved.push_back(2.5 * (r * p) + qs::Vec3(3, -1, 7));
  const auto back = qs::morph::align_to(moved, m.positions, qs::morph::Align::Similarity);
  for (size_t i = 0; i < back.size(); ++i) EXPECT_LT((back[i] - m.positions[i]).norm(), 1e-9) << i;
  // Rigid keeps the size: the aligned copy is still 2.5 times larger, turned back and centred on
  // the base's centroid c: c + 2.5 (p - c).
  qs::Vec3 c = qs::Vec3::Zero();
  for (const auto& p : m.positions) c += p / static_cast<double>(m.positions.size());
  const auto rigid = qs::morph::align_to(moved, m.positions, qs::morph::Align::Rigid);
  for (size_t i = 0; i < rigid.size(); ++i) EXPECT_LT((rigid[i] - (c + 2.5 * (m.positions[i] - c))).norm(), 1e-9) << i;
  EXPECT_EQ(qs::morph::align_to(moved, m.positions, qs::morph::Align::None), moved);
  EXPECT_THROW(qs::morph::align_to(moved, {}, qs::morph::Align::Rigid), qs::InvalidInput);
  EXPECT_THROW(qs::morph::align_from_name("affine"), qs::InvalidInput);
}

TEST(Blend, WeightsAreChecked) {
  const auto set = make_set(3, 1);
  EXPECT_THAT(message_of([&] { qs::morph::blend(set, {0.5, 0.5}); }), HasSubstr("2 given, expected one per shape (3)"));
  EXPECT_THAT(message_of([&] { qs::morph::blend(set, {-0.5, 1, 0.5}); }), HasSubstr("weight 1 is -0.5; every weight must be >= 0"));
  EXPECT_THAT(message_of([&] { qs::morph::blend(set, {0.5, 0.5, 0.5}); }), HasSubstr("sum to 1.5, expected 1"));
  EXPECT_THAT(message_of([&] { qs::morph::blend(set, {NAN, 0.5, 0.5}); }), HasSubstr("weight 1 is nan"));
  EXPECT_THROW(qs::morph::blend(set, {0.2, 0.3, 0.5 + 2e-6}), qs::InvalidInput);
  EXPECT_NO_THROW(qs::morph::blend(set, {0.2, 0.3, 0.5 + 5e-7}));
  const auto b = qs::morph::blend(set, {0.2, 0.3, 0.5});
  for (size_t v = 0; v < b.size(); ++v) {
    const qs::Vec3 e = 0.2 * set.positions[0][v] + 0.3 * set.positions[1][v] + 0.5 * set.positions[2][v];
    EXPECT_LT((b[v] - e).norm(), 1e-15);
  }
  auto bad = set;
  bad.positions[2].pop_back();
  EXPECT_THAT(message_of([&] { qs::morph::blend(bad, {0.2, 0.3, 0.5}); }), HasSubstr("shape 2 has"));
}

TEST(Blend, ShapeIndexListsTheKnownNames) {
  EXPECT_EQ(qs::morph::shape_index({"horse", "camel"}, "camel"), 1);
  EXPECT_THAT(message_of([] { qs::morph::shape_index({"horse", "camel"}, "cow"); }),
              HasSubstr("unknown shape 'cow'; the shapes are: horse, camel"));
}

TEST(VertexNormals, AreaWeightedAndUnit) {
  // Vertex 0 is shared by a big face in z = 0 and a small face in x = 0.
  const std::vector<qs::Vec3> p = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0, 0.1, 0}, {0, 0, 0.1}};
  const std::vector<qs::Tri> f = {{0, 1, 2}, {0, 3, 4}};
  const auto n = qs::vertex_normals(p, f);
  const qs::Vec3 expected = (qs::Vec3(0, 0, 4) + qs::Vec3(0.01, 0, 0)).normalized();
  EXPECT_LT((n[0] - expected).norm(), 1e-12);
  EXPECT_LT((n[1] - qs::Vec3(0, 0, 1)).norm(), 1e-12);
  EXPECT_LT((n[3] - qs::Vec3(1, 0, 0)).norm(), 1e-12);
  const auto sphere = qs::shapes::icosphere(3);
  const auto ns = qs::vertex_normals(sphere.positions, sphere.faces);
  for (size_t v = 0; v < ns.size(); ++v) {
    EXPECT_NEAR(ns[v].norm(), 1, 1e-12);
    EXPECT_GT(ns[v].dot(sphere.positions[v].normalized()), 0.999);
  }
  EXPECT_EQ(qs::vertex_normals({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {{0, 1, 2}})[0], qs::Vec3(0, 0, 1));
}

TEST_F(MorphFiles, FramesReadBackExactlyInBothFormats) {
  const auto set = make_set(2);
  const qs::TriMesh a = set.mesh(0);
  // OBJ frames are byte for byte what qs::io::write_mesh writes.
  EXPECT_EQ(qs::morph::FrameWriter(a.faces, qs::morph::FrameFormat::Obj).bytes(a.positions),
            qs::io::mesh_to_string(a, qs::io::MeshFormat::Obj));
  const auto pf = qs::morph::path_frames(2, {0, 1}, 4);
  for (auto fmt : {qs::morph::FrameFormat::Obj, qs::morph::FrameFormat::Ply}) {
    const std::string ext = qs::morph::extension(fmt);
    std::vector<std::string> files;
    for (int f = 0; f < 4; ++f) files.push_back("f" + std::to_string(f) + "." + ext);
    qs::morph::write_frames(dir_ / "one", {}, set.positions, a.faces, {}, fmt, 1);  // nothing to do
    fs::create_directories(dir_ / ext / "t1");
    fs::create_directories(dir_ / ext / "t3");
    qs::morph::write_frames(dir_ / ext / "t1", files, set.positions, a.faces, pf, fmt, 1);
    qs::morph::write_frames(dir_ / ext / "t3", files, set.positions, a.faces, pf, fmt, 3);
    for (int f = 0; f < 4; ++f) {
      const auto r = qs::io::read_mesh(dir_ / ext / "t1" / files[f]);
      EXPECT_EQ(r.mesh.faces, a.faces);
      EXPECT_EQ(r.mesh.positions, qs::morph::blend(set, pf[f].weights)) << ext << " frame " << f;
      std::ifstream x(dir_ / ext / "t1" / files[f], std::ios::binary), y(dir_ / ext / "t3" / files[f], std::ios::binary);
      EXPECT_EQ(std::string(std::istreambuf_iterator<char>(x), {}), std::string(std::istreambuf_iterator<char>(y), {}))
          << "thread count changed the bytes";
    }
    if (fmt == qs::morph::FrameFormat::Ply) {
      EXPECT_EQ(qs::io::read_mesh(dir_ / ext / "t1" / files[0]).report.variant, "binary_little_endian");
    }
  }
  EXPECT_THAT(message_of([&] { qs::morph::FrameWriter(a.faces, qs::morph::FrameFormat::Obj).bytes({{0, 0, 0}}); }),
              HasSubstr("1 vertices, but the faces use vertex"));
  EXPECT_THROW(qs::morph::frame_format("stl"), qs::UsageError);
}

TEST_F(MorphFiles, FailedFrameWritingLeavesNoFiles) {
  const auto set = make_set(2, 1);
  const auto pf = qs::morph::path_frames(2, {0, 1}, 3);
  EXPECT_THROW(qs::morph::write_frames(dir_ / "missing", {"a.obj", "b.obj", "c.obj"}, set.positions,
                                       set.connectivity.faces, pf, qs::morph::FrameFormat::Obj, 2),
               qs::IoError);
  EXPECT_FALSE(fs::exists(dir_ / "missing"));
  EXPECT_THROW(qs::morph::write_frames(dir_, {"a.obj"}, set.positions, set.connectivity.faces, pf,
                                       qs::morph::FrameFormat::Obj, 2),
               qs::InvalidInput);
  EXPECT_TRUE(fs::is_empty(dir_));
}

TEST_F(MorphFiles, GlbHasOneTargetPerOtherShapeAndValidates) {
  const int n = 9;  // 8 morph targets
  const auto set = make_set(n);
  qs::morph::MorphGlbOptions o;
  o.base = 2;
  o.path = {2, 0, 5, 2};
  o.weights.assign(n, 0.0);
  o.weights[2] = 0.5;
  o.weights[7] = 0.5;
  const qs::gltf::Mesh m = qs::morph::morph_glb_mesh(set, names_of(n), o);
  EXPECT_EQ(m.positions, set.positions[2]);
  ASSERT_EQ(m.targets.size(), 8u);
  EXPECT_EQ(m.targets[0].name, "shape0");
  EXPECT_EQ(m.targets[2].name, "shape3");  // the base (shape2) is skipped
  const auto normals7 = qs::vertex_normals(set.positions[7], set.connectivity.faces);
  for (size_t v = 0; v < m.positions.size(); v += 17) {
    EXPECT_LT((m.positions[v] + m.targets[6].position_deltas[v] - set.positions[7][v]).norm(), 1e-15);
    EXPECT_LT((m.normals[v] + m.targets[6].normal_deltas[v] - normals7[v]).norm(), 1e-15);
  }
  EXPECT_EQ(m.default_weights, (std::vector<double>{0, 0, 0, 0, 0, 0, 0.5, 0}));  // shape7 is target 6
  ASSERT_EQ(m.default_weights.size(), 8u);
  ASSERT_EQ(m.animations.size(), 1u);
  EXPECT_EQ(m.animations[0].times, (std::vector<float>{0, 1, 2, 3}));
  EXPECT_EQ(m.animations[0].weights[0], std::vector<float>(8, 0.0f));
  EXPECT_EQ(m.animations[0].weights[1][0], 1.0f);  // shape0
  EXPECT_EQ(m.animations[0].weights[2][4], 1.0f);  // shape5
  EXPECT_EQ(m.animations[0].weights[3], std::vector<float>(8, 0.0f));
  EXPECT_FALSE(m.material.has_value());

  const fs::path file = dir_ / "nine.glb";
  qs::gltf::write_glb(file, m);
  std::string out;
  const int rc = run_validator(file, &out);
  if (rc == 3) GTEST_SKIP() << "glTF validator not installed (scripts/setup.sh): " << out;
  EXPECT_EQ(rc, 0) << out;
  EXPECT_THAT(out, HasSubstr(": 0 errors, 0 warnings")) << out;
}

TEST(MorphGlb, BadOptionsAreRefused) {
  const auto set = make_set(3, 1);
  qs::morph::MorphGlbOptions o;
  EXPECT_THAT(message_of([&] { qs::morph::morph_glb_mesh(set, names_of(2), o); }), HasSubstr("2 names for 3 shapes"));
  o.base = 3;
  EXPECT_THAT(message_of([&] { qs::morph::morph_glb_mesh(set, names_of(3), o); }), HasSubstr("base shape 3"));
  o.base = 0;
  o.weights = {1, 1, -1};
  EXPECT_THAT(message_of([&] { qs::morph::morph_glb_mesh(set, names_of(3), o); }), HasSubstr("must be >= 0"));
  o.weights.clear();
  o.path = {0, 4};
  EXPECT_THAT(message_of([&] { qs::morph::morph_glb_mesh(set, names_of(3), o); }), HasSubstr("path stop 4"));
  auto one = set;
  one.positions.resize(1);
  EXPECT_THAT(message_of([&] { qs::morph::morph_glb_mesh(one, names_of(1), {}); }), HasSubstr("at least 2 shapes"));
}

TEST_F(MorphFiles, BakeGivesTheMaterialUvsAndTangentsOnTheBakesVertexLayout) {
  const auto set = make_set(3);
  write_fake_bake(dir_ / "bake", "shape1", set, 1);
  const auto baked = qs::morph::read_baked_shape(dir_ / "bake", "shape1", set.connectivity.faces, set.positions[1]);
  const size_t nv = set.positions[1].size(), split = baked.vertex_source.size();
  ASSERT_GT(split, nv + 100) << "the fake bake splits vertices";
  for (size_t v = 0; v < nv; ++v) EXPECT_EQ(baked.vertex_source[v], static_cast<int>(v));
  for (size_t v = nv; v < split; ++v) EXPECT_LT(baked.vertex_source[v], static_cast<int>(nv));
  EXPECT_EQ(baked.texcoords.size(), split);
  EXPECT_EQ(baked.tangents.size(), split);
  EXPECT_EQ(baked.normal_map.bytes, flat_normal_png(8, 8));

  qs::morph::MorphGlbOptions o;
  o.base = 1;
  o.path = {1, 0, 2};
  const qs::gltf::Mesh m = qs::morph::morph_glb_mesh(set, names_of(3), o, &baked);
  ASSERT_EQ(m.positions.size(), split);
  ASSERT_TRUE(m.material && m.material->normal_texture);
  EXPECT_EQ(m.texcoords.size(), split);
  EXPECT_EQ(m.tangents.size(), split);
  const auto normals2 = qs::vertex_normals(set.positions[2], set.connectivity.faces);
  ASSERT_EQ(m.targets[1].tangent_deltas.size(), split);
  for (size_t v = 0; v < split; v += 7) {
    const int s = baked.vertex_source[v];
    EXPECT_LT((m.positions[v] + m.targets[1].position_deltas[v] - set.positions[2][s]).norm(), 1e-15);
    // At weight 1 the tangent is a unit vector perpendicular to shape 2's normal.
    const qs::Vec3 t = qs::Vec3(m.tangents[v][0], m.tangents[v][1], m.tangents[v][2]) + m.targets[1].tangent_deltas[v];
    EXPECT_NEAR(t.norm(), 1, 1e-12);
    EXPECT_NEAR(t.dot(normals2[s]), 0, 1e-12);
  }
  const fs::path file = dir_ / "baked.glb";
  qs::gltf::write_glb(file, m);
  std::string out;
  const int rc = run_validator(file, &out);
  if (rc == 3) GTEST_SKIP() << "glTF validator not installed (scripts/setup.sh): " << out;
  EXPECT_EQ(rc, 0) << out;
  EXPECT_THAT(out, HasSubstr(": 0 errors, 0 warnings")) << out;
}

TEST_F(MorphFiles, BakeFallsBackToThePngAndRefusesForeignBakes) {
  const auto set = make_set(2);
  write_fake_bake(dir_ / "nomat", "shape0", set, 0, /*with_texture=*/false);
  const auto baked = qs::morph::read_baked_shape(dir_ / "nomat", "shape0", set.connectivity.faces, set.positions[0]);
  EXPECT_EQ(baked.normal_map.bytes, flat_normal_png(4, 4));  // <stem>_normal.png
  fs::remove(dir_ / "nomat" / "shape0_normal.png");
  EXPECT_THAT(message_of([&] { qs::morph::read_baked_shape(dir_ / "nomat", "shape0", set.connectivity.faces, set.positions[0]); }),
              HasSubstr("no normal texture in the GLB and no"));

  write_fake_bake(dir_ / "nojson", "shape0", set, 0, true, /*with_json=*/false);
  EXPECT_THROW(qs::morph::read_baked_shape(dir_ / "nojson", "shape0", set.connectivity.faces, set.positions[0]), qs::IoError);
  EXPECT_THAT(message_of([&] { qs::morph::read_baked_shape(dir_ / "nojson", "shape0", set.connectivity.faces, set.positions[0]); }),
              HasSubstr("bake.json: cannot open"));
  std::ofstream(dir_ / "nojson" / "bake.json") << R"({"format": "qs-remesh"})";
  EXPECT_THAT(message_of([&] { qs::morph::read_baked_shape(dir_ / "nojson", "shape0", set.connectivity.faces, set.positions[0]); }),
              HasSubstr("not a qs-bake file"));

  std::ofstream(dir_ / "nojson" / "bake.json") << R"({"format": "qs-bake", "options": {"space": "object"}})";
  EXPECT_THAT(message_of([&] { qs::morph::read_baked_shape(dir_ / "nojson", "shape0", set.connectivity.faces, set.positions[0]); }),
              HasSubstr("must be tangent space"));
  std::ofstream(dir_ / "nojson" / "bake.json") << R"({"format": "qs-bake", "options": {"space": "tangent", "green": "directx"}})";
  EXPECT_THAT(message_of([&] { qs::morph::read_baked_shape(dir_ / "nojson", "shape0", set.connectivity.faces, set.positions[0]); }),
              HasSubstr("DirectX's green"));
  std::ofstream(dir_ / "nojson" / "bake.json") << R"({"format": "qs-bake", "options": {"space": "tangent", "green": "opengl"}})";
  EXPECT_NO_THROW(qs::morph::read_baked_shape(dir_ / "nojson", "shape0", set.connectivity.faces, set.positions[0]));
  std::ofstream(dir_ / "nojson" / "bake.json") << "[1, 2]";
  EXPECT_THAT(message_of([&] { qs::morph::read_baked_shape(dir_ / "nojson", "shape0", set.connectivity.faces, set.positions[0]); }),
              HasSubstr("not a JSON object"));
  std::ofstream(dir_ / "nojson" / "bake.json") << "{ not json";
  EXPECT_THAT(message_of([&] { qs::morph::read_baked_shape(dir_ / "nojson", "shape0", set.connectivity.faces, set.positions[0]); }),
              HasSubstr("not valid JSON"));

  write_fake_bake(dir_ / "ok", "shape0", set, 0);
  EXPECT_THROW(qs::morph::read_baked_shape(dir_ / "ok", "shape1", set.connectivity.faces, set.positions[1]), qs::IoError);
  // The bake of shape 0 is not at shape 1's positions.
  EXPECT_THAT(message_of([&] { qs::morph::read_baked_shape(dir_ / "ok", "shape0", set.connectivity.faces, set.positions[1]); }),
              HasSubstr("was it baked from this remesh?"));
  // Another connectivity: a face less.
  auto faces = set.connectivity.faces;
  faces.pop_back();
  EXPECT_THAT(message_of([&] { qs::morph::read_baked_shape(dir_ / "ok", "shape0", faces, set.positions[0]); }),
              HasSubstr("faces, the remesh has"));
  // The same count but corners that do not follow the remesh's faces.
  faces = set.connectivity.faces;
  std::swap(faces[0], faces[1]);
  EXPECT_THROW(qs::morph::read_baked_shape(dir_ / "ok", "shape0", faces, set.positions[0]), qs::InvalidInput);
}

// ---- normal maps that morph with the frames (--frame-maps) -----------------------------------

TEST_F(MorphFiles, NormalMapsBlendTexelByTexel) {
  qs::morph::NormalAtlases a;
  a.width = 2;
  a.height = 1;
  a.rgb = {{128, 128, 255, 255, 128, 128}, {255, 128, 128, 0, 128, 128}};  // +z, +x | +x, -x
  EXPECT_EQ(qs::morph::blend_normal_maps(a, {1, 0}), a.rgb[0]);
  EXPECT_EQ(qs::morph::blend_normal_maps(a, {0, 1}), a.rgb[1]);
  const auto mid = qs::morph::blend_normal_maps(a, {0.5, 0.5});
  // Texel 0: normalize(+z + +x) = (0.707, 0, 0.707) -> (218, 128, 218) (up to the 8-bit decode).
  EXPECT_NEAR(mid[0], 218, 1);
  EXPECT_NEAR(mid[1], 128, 1);
  EXPECT_NEAR(mid[2], 218, 1);
  // Texel 1: +x and -x cancel but for 8-bit "zero" (128), which decodes to +1/255: (0, 1, 1) / sqrt 2.
  EXPECT_EQ(mid[3], 128);
  EXPECT_NEAR(mid[4], 218, 1);
  EXPECT_NEAR(mid[5], 218, 1);
  EXPECT_THROW(qs::morph::blend_normal_maps(a, {0.5, 0.6}), qs::InvalidInput);

  // PNG round trip, and maps of different sizes refused.
  std::vector<unsigned char> rgb(5 * 3 * 3);
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<unsigned char>(i * 5);
  const auto png = qs::morph::encode_png_rgb8(5, 3, rgb);
  std::ofstream(dir_ / "x_normal.png", std::ios::binary).write(reinterpret_cast<const char*>(png.data()), png.size());
  const auto flat = flat_normal_png(4, 4);
  std::ofstream(dir_ / "y_normal.png", std::ios::binary).write(reinterpret_cast<const char*>(flat.data()), flat.size());
  const auto back = qs::morph::read_normal_atlases(dir_, {"x"});
  EXPECT_EQ(back.width, 5);
  EXPECT_EQ(back.height, 3);
  EXPECT_EQ(back.rgb[0], rgb);
  EXPECT_EQ(back.png[0], png);
  EXPECT_THAT(message_of([&] { qs::morph::read_normal_atlases(dir_, {"x", "y"}); }), HasSubstr("4 x 4, the other maps are 5 x 3"));
  EXPECT_THROW(qs::morph::read_normal_atlases(dir_, {"x", "z"}), qs::IoError);
  EXPECT_THROW(qs::morph::encode_png_rgb8(5, 4, rgb), qs::InvalidInput);

  // Damaged maps: the file, what is wrong, what was expected (the shape, the other maps' size);
  // none of libpng's text.
  const std::string png_text(png.begin(), png.end());
  std::string bad_crc = png_text;
  bad_crc[30] ^= 1;
  const struct {
    std::string bytes, what;
  } damaged[] = {{png_text.substr(0, png_text.size() - 20), "the PNG ends early"},
                 {bad_crc, "damaged PNG"},
                 {"P6\n5 3\n255\n", "not a PNG file"},
                 {qs::test::make_png(5, 3, 8, 6), "not an RGB image"}};
  for (const auto& d : damaged) {
    std::ofstream(dir_ / "w_normal.png", std::ios::binary) << d.bytes;
    const std::string m = message_of([&] { qs::morph::read_normal_atlases(dir_, {"x", "w"}); });
    EXPECT_EQ(m.rfind((dir_ / "w_normal.png").string() + ": " + d.what, 0), 0u) << m;
    EXPECT_THAT(m, HasSubstr("expected the 8-bit RGB normal map of shape 'w' written by qs-bake, 5 x 3 as the other maps"));
    EXPECT_EQ(qs::test::quoted_library_phrase(m), "") << m;
    EXPECT_THROW(qs::morph::read_normal_atlases(dir_, {"w"}), qs::InvalidInput);
  }
}

TEST_F(MorphFiles, TexturedFramesCarryUvsAndTheirOwnMap) {
  const auto set = make_set(2);
  write_fake_bake(dir_ / "bake", "shape0", set, 0);
  write_fake_bake(dir_ / "bake1", "shape1", set, 1);
  fs::copy_file(dir_ / "bake1" / "shape1_normal.png", dir_ / "bake" / "shape1_normal.png");
  // Make shape1's map differ from shape0's: a tilted normal everywhere.
  std::vector<unsigned char> tilted(4 * 4 * 3);
  for (size_t i = 0; i < tilted.size(); i += 3) {
    tilted[i] = 218;
    tilted[i + 1] = 128;
    tilted[i + 2] = 218;
  }
  const auto tilted_png = qs::morph::encode_png_rgb8(4, 4, tilted);
  std::ofstream(dir_ / "bake" / "shape1_normal.png", std::ios::binary)
      .write(reinterpret_cast<const char*>(tilted_png.data()), tilted_png.size());
  const auto baked = qs::morph::read_baked_shape(dir_ / "bake", "shape0", set.connectivity.faces, set.positions[0]);
  const auto atlases = qs::morph::read_normal_atlases(dir_ / "bake", {"shape0", "shape1"});
  const auto pf = qs::morph::path_frames(2, {0, 1}, 3);
  fs::create_directories(dir_ / "out");
  qs::morph::write_textured_frames(dir_ / "out", {"f0", "f1", "f2"}, set.positions, set.connectivity.faces, baked,
                                   atlases, pf, 2);
  for (int f = 0; f < 3; ++f) {
    const std::string name = "f" + std::to_string(f);
    const auto r = qs::io::read_mesh(dir_ / "out" / (name + ".obj"));
    EXPECT_EQ(r.mesh.positions, qs::morph::blend(set, pf[f].weights));
    EXPECT_EQ(r.mesh.faces, set.connectivity.faces);
    std::ifstream mtl(dir_ / "out" / (name + ".mtl"));
    EXPECT_THAT(std::string(std::istreambuf_iterator<char>(mtl), {}), HasSubstr("norm " + name + "_normal.png"));
  }
  std::ifstream obj(dir_ / "out" / "f1.obj");
  const std::string text(std::istreambuf_iterator<char>(obj), {});
  EXPECT_THAT(text, HasSubstr("mtllib f1.mtl\n"));
  size_t vt = 0;
  for (size_t at = text.find("\nvt "); at != std::string::npos; at = text.find("\nvt ", at + 1)) ++vt;
  EXPECT_EQ(vt, baked.texcoords.size()) << "one vt line per bake vertex";
  const auto f0 = qs::morph::read_normal_atlases(dir_ / "out", {"f0"});
  EXPECT_EQ(f0.png[0], atlases.png[0]) << "a frame that is one shape keeps its map's bytes";
  const auto f1 = qs::morph::read_normal_atlases(dir_ / "out", {"f1"});
  EXPECT_EQ(f1.rgb[0], qs::morph::blend_normal_maps(atlases, {0.5, 0.5}));
  EXPECT_NE(f1.rgb[0], atlases.rgb[0]);
  EXPECT_NE(f1.rgb[0], atlases.rgb[1]);
}
