// The GLB writer: tinygltf reads back what was written, the Khronos validator accepts it, and bad
// meshes are refused with a message naming the field.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <tiny_gltf.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "qs/core/error.h"
#include "qs/gltf/glb.h"
#include "../common/gltf_test_support.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

namespace {

using qs::testing::make_png;

unsigned char flat_normal(int, int, int c) { return c == 2 ? 255 : 128; }
unsigned char gradient(int x, int y, int c) { return static_cast<unsigned char>(c == 0 ? x * 16 : c == 1 ? y * 16 : 90); }

// An octahedron with normals, texcoords, tangents (6 vertices, 8 faces).
qs::gltf::Mesh octahedron() {
  qs::gltf::Mesh m;
  m.name = "octa";
  m.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  m.faces = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (const auto& p : m.positions) {
    m.normals.push_back(p.normalized());
    m.texcoords.emplace_back(0.5 + 0.4 * p.x(), 0.5 - 0.4 * p.y());
    const qs::Vec3 axis = std::abs(p.z()) < 0.9 ? qs::Vec3(0, 0, 1) : qs::Vec3(1, 0, 0);
    const qs::Vec3 t = axis.cross(p).normalized();
    m.tangents.push_back({t.x(), t.y(), t.z(), 1.0});
  }
  return m;
}

qs::gltf::MorphTarget scaled_target(const qs::gltf::Mesh& m, const std::string& name, double sx, double sy, double sz) {
  qs::gltf::MorphTarget t;
  t.name = name;
  for (size_t i = 0; i < m.positions.size(); ++i) {
    const qs::Vec3 p = m.positions[i];
    const qs::Vec3 q(p.x() * sx, p.y() * sy, p.z() * sz);
    t.position_deltas.push_back(q - p);
    const qs::Vec3 n(p.x() / sx, p.y() / sy, p.z() / sz);
    t.normal_deltas.push_back(n.normalized() - m.normals[i]);
    const qs::Vec3 tb(m.tangents[i][0], m.tangents[i][1], m.tangents[i][2]);
    t.tangent_deltas.push_back((tb - tb.dot(n.normalized()) * n.normalized()).normalized() - tb);
  }
  return t;
}

// The full-featured mesh: targets, default weights, an animation, normal and colour textures.
qs::gltf::Mesh full_mesh(int targets) {
  qs::gltf::Mesh m = octahedron();
  for (int k = 0; k < targets; ++k)
    m.targets.push_back(scaled_target(m, "shape" + std::to_string(k), 1 + 0.1 * k, 1.5 - 0.05 * k, 0.7 + 0.03 * k));
  m.default_weights.assign(targets, 0.0);
  if (targets > 0) m.default_weights[0] = 0.25;
  qs::gltf::WeightsAnimation a;
  a.name = "path";
  for (int k = 0; k <= targets; ++k) {
    a.times.push_back(static_cast<float>(k));
    std::vector<float> w(targets, 0.0f);
    if (k > 0) w[k - 1] = 1.0f;
    a.weights.push_back(w);
  }
  if (targets > 0) m.animations.push_back(a);
  qs::gltf::Material mat;
  mat.name = "skin";
  mat.normal_texture = qs::gltf::Image{"normal", "image/png", make_png(16, 16, flat_normal)};
  mat.base_color_texture = qs::gltf::Image{"colour", "image/png", make_png(16, 8, gradient)};
  mat.normal_scale = 0.8;
  m.material = mat;
  return m;
}

tinygltf::Model load(const std::vector<unsigned char>& bytes) {
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  std::string err, warn;
  const bool ok = loader.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(), static_cast<unsigned>(bytes.size()));
  EXPECT_TRUE(ok) << err;
  return model;
}

std::vector<float> accessor_floats(const tinygltf::Model& model, int index) {
  const auto& a = model.accessors.at(index);
  const auto& v = model.bufferViews.at(a.bufferView);
  EXPECT_EQ(a.componentType, TINYGLTF_COMPONENT_TYPE_FLOAT);
  const size_t n = a.count * tinygltf::GetNumComponentsInType(a.type);
  std::vector<float> out(n);
  std::memcpy(out.data(), model.buffers.at(v.buffer).data.data() + v.byteOffset + a.byteOffset, n * sizeof(float));
  return out;
}

uint32_t le32(const std::vector<unsigned char>& b, size_t at) {
  return b[at] | (b[at + 1] << 8) | (b[at + 2] << 16) | (uint32_t(b[at + 3]) << 24);
}

class GlbFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("qs_glb_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  // The Khronos validator's exit code (3: not installed) and output.
  int validate(const fs::path& file, std::string* out) { return qs::testing::run_gltf_validator(file, out); }
  fs::path dir_;
};

}  // namespace

TEST(Glb, RoundTripThroughTinygltf) {
  const qs::gltf::Mesh m = full_mesh(2);
  const std::vector<unsigned char> bytes = qs::gltf::glb_bytes(m);
  // GLB container: magic, version 2, total length, JSON then BIN chunk, everything 4-byte aligned.
  ASSERT_GE(bytes.size(), 28u);
  EXPECT_EQ(std::string(bytes.begin(), bytes.begin() + 4), "glTF");
  EXPECT_EQ(le32(bytes, 4), 2u);
  EXPECT_EQ(le32(bytes, 8), bytes.size());
  EXPECT_EQ(bytes.size() % 4, 0u);
  EXPECT_EQ(le32(bytes, 12) % 4, 0u);
  EXPECT_EQ(le32(bytes, 16), 0x4E4F534Au);  // "JSON"

  const tinygltf::Model model = load(bytes);
  ASSERT_EQ(model.meshes.size(), 1u);
  ASSERT_EQ(model.nodes.size(), 1u);
  EXPECT_EQ(model.nodes[0].mesh, 0);
  EXPECT_EQ(model.asset.generator, "qs");
  for (const auto& v : model.bufferViews) EXPECT_EQ(v.byteOffset % 4, 0u);
  const auto& gm = model.meshes[0];
  EXPECT_EQ(gm.name, "octa");
  ASSERT_EQ(gm.primitives.size(), 1u);
  const auto& prim = gm.primitives[0];
  EXPECT_EQ(prim.mode, TINYGLTF_MODE_TRIANGLES);

  const auto& ia = model.accessors.at(prim.indices);
  EXPECT_EQ(ia.count, m.faces.size() * 3);
  EXPECT_EQ(ia.componentType, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);
  const auto& iv = model.bufferViews.at(ia.bufferView);
  std::vector<uint16_t> idx(ia.count);
  std::memcpy(idx.data(), model.buffers[0].data.data() + iv.byteOffset, idx.size() * 2);
  for (size_t f = 0; f < m.faces.size(); ++f)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(idx[3 * f + c], m.faces[f][c]);

  const std::vector<float> pos = accessor_floats(model, prim.attributes.at("POSITION"));
  ASSERT_EQ(pos.size(), m.positions.size() * 3);
  for (size_t i = 0; i < m.positions.size(); ++i)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(pos[3 * i + c], static_cast<float>(m.positions[i][c]));
  const auto& pa = model.accessors.at(prim.attributes.at("POSITION"));
  EXPECT_EQ(pa.minValues, (std::vector<double>{-1, -1, -1}));
  EXPECT_EQ(pa.maxValues, (std::vector<double>{1, 1, 1}));
  EXPECT_EQ(accessor_floats(model, prim.attributes.at("NORMAL")).size(), m.positions.size() * 3);
  const std::vector<float> uv = accessor_floats(model, prim.attributes.at("TEXCOORD_0"));
  EXPECT_FLOAT_EQ(uv[1], static_cast<float>(m.texcoords[0].y()));
  const auto& ta = model.accessors.at(prim.attributes.at("TANGENT"));
  EXPECT_EQ(ta.type, TINYGLTF_TYPE_VEC4);
  EXPECT_EQ(accessor_floats(model, prim.attributes.at("TANGENT"))[3], 1.0f);

  ASSERT_EQ(prim.targets.size(), 2u);
  for (size_t k = 0; k < 2; ++k) {
    const int acc = prim.targets[k].at("POSITION");
    const std::vector<float> d = accessor_floats(model, acc);
    float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
    for (size_t i = 0; i < m.positions.size(); ++i)
      for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(d[3 * i + c], static_cast<float>(m.targets[k].position_deltas[i][c]));
        lo[c] = std::min(lo[c], d[3 * i + c]);
        hi[c] = std::max(hi[c], d[3 * i + c]);
      }
    const auto& a = model.accessors.at(acc);
    ASSERT_EQ(a.minValues.size(), 3u) << "min/max on every morph-target POSITION accessor";
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(a.minValues[c], lo[c]);
      EXPECT_EQ(a.maxValues[c], hi[c]);
    }
    EXPECT_TRUE(prim.targets[k].count("NORMAL"));
    ASSERT_TRUE(prim.targets[k].count("TANGENT"));
    const auto& tan = model.accessors.at(prim.targets[k].at("TANGENT"));
    EXPECT_EQ(tan.type, TINYGLTF_TYPE_VEC3) << "morph-target tangents are xyz deltas";
    EXPECT_EQ(accessor_floats(model, prim.targets[k].at("TANGENT"))[4],
              static_cast<float>(m.targets[k].tangent_deltas[1].y()));
  }
  ASSERT_TRUE(gm.extras.Has("targetNames"));
  const auto& names = gm.extras.Get("targetNames");
  ASSERT_EQ(names.ArrayLen(), 2u);
  EXPECT_EQ(names.Get(0).Get<std::string>(), "shape0");
  EXPECT_EQ(names.Get(1).Get<std::string>(), "shape1");
  EXPECT_EQ(gm.weights, (std::vector<double>{0.25, 0.0}));

  ASSERT_EQ(model.animations.size(), 1u);
  const auto& an = model.animations[0];
  EXPECT_EQ(an.name, "path");
  ASSERT_EQ(an.channels.size(), 1u);
  EXPECT_EQ(an.channels[0].target_path, "weights");
  EXPECT_EQ(an.channels[0].target_node, 0);
  EXPECT_EQ(an.samplers.at(0).interpolation, "LINEAR");
  EXPECT_EQ(accessor_floats(model, an.samplers[0].input), (std::vector<float>{0, 1, 2}));
  EXPECT_EQ(accessor_floats(model, an.samplers[0].output), (std::vector<float>{0, 0, 1, 0, 0, 1}));

  ASSERT_EQ(model.materials.size(), 1u);
  const auto& mat = model.materials[0];
  EXPECT_EQ(mat.name, "skin");
  EXPECT_DOUBLE_EQ(mat.normalTexture.scale, 0.8);
  ASSERT_GE(mat.normalTexture.index, 0);
  const auto& img = model.images.at(model.textures.at(mat.normalTexture.index).source);
  EXPECT_EQ(img.mimeType, "image/png");
  EXPECT_EQ(img.width, 16);  // tinygltf decoded the PNG we embedded
  ASSERT_GE(mat.pbrMetallicRoughness.baseColorTexture.index, 0);
  EXPECT_EQ(model.images.at(model.textures.at(mat.pbrMetallicRoughness.baseColorTexture.index).source).height, 8);
}

TEST(Glb, BytesAreDeterministic) {
  EXPECT_EQ(qs::gltf::glb_bytes(full_mesh(3)), qs::gltf::glb_bytes(full_mesh(3)));
  EXPECT_NE(qs::gltf::glb_bytes(full_mesh(3)), qs::gltf::glb_bytes(full_mesh(2)));
}

TEST(Glb, PlainMeshHasNoTargetsOrMaterial) {
  qs::gltf::Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.faces = {{0, 1, 2}};
  const tinygltf::Model model = load(qs::gltf::glb_bytes(m));
  ASSERT_EQ(model.meshes.size(), 1u);
  EXPECT_TRUE(model.meshes[0].primitives[0].targets.empty());
  EXPECT_FALSE(model.meshes[0].extras.Has("targetNames"));
  EXPECT_TRUE(model.materials.empty());
  EXPECT_EQ(model.meshes[0].primitives[0].material, -1);
  EXPECT_EQ(model.meshes[0].primitives[0].attributes.size(), 1u);
}

TEST(Glb, LargeMeshUsesUint32Indices) {
  qs::gltf::Mesh m;
  const int n = 70000;
  for (int i = 0; i < n; ++i) m.positions.emplace_back(i * 1e-3, (i % 7) * 0.1, (i % 3) * 0.2);
  for (int i = 0; i + 2 < n; i += 3) m.faces.push_back({i, i + 1, i + 2});
  m.faces.push_back({0, n - 1, n / 2});
  const tinygltf::Model model = load(qs::gltf::glb_bytes(m));
  const auto& a = model.accessors.at(model.meshes[0].primitives[0].indices);
  EXPECT_EQ(a.componentType, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);
  const auto& v = model.bufferViews.at(a.bufferView);
  uint32_t last[3];
  std::memcpy(last, model.buffers[0].data.data() + v.byteOffset + (a.count - 3) * 4, 12);
  EXPECT_EQ(last[1], static_cast<uint32_t>(n - 1));
}

TEST_F(GlbFiles, WriteThenReadBack) {
  const qs::gltf::Mesh m = full_mesh(2);
  const fs::path file = dir_ / "m.glb";
  qs::gltf::write_glb(file, m);
  const qs::gltf::Mesh r = qs::gltf::read_glb(file);
  EXPECT_EQ(r.name, m.name);
  EXPECT_EQ(r.faces, m.faces);
  ASSERT_EQ(r.positions.size(), m.positions.size());
  ASSERT_EQ(r.texcoords.size(), m.texcoords.size());
  ASSERT_EQ(r.tangents.size(), m.tangents.size());
  for (size_t i = 0; i < m.positions.size(); ++i) {
    EXPECT_LT((r.positions[i] - m.positions[i]).norm(), 1e-6);
    EXPECT_LT((r.normals[i] - m.normals[i]).norm(), 1e-6);
    EXPECT_LT((r.texcoords[i] - m.texcoords[i]).norm(), 1e-6);
    for (int c = 0; c < 4; ++c) EXPECT_NEAR(r.tangents[i][c], m.tangents[i][c], 1e-6);
  }
  ASSERT_EQ(r.targets.size(), 2u);
  EXPECT_EQ(r.targets[1].name, "shape1");
  EXPECT_LT((r.targets[1].position_deltas[2] - m.targets[1].position_deltas[2]).norm(), 1e-6);
  EXPECT_EQ(r.targets[1].normal_deltas.size(), m.positions.size());
  ASSERT_EQ(r.targets[1].tangent_deltas.size(), m.positions.size());
  EXPECT_LT((r.targets[1].tangent_deltas[3] - m.targets[1].tangent_deltas[3]).norm(), 1e-6);
  EXPECT_EQ(r.default_weights, m.default_weights);
  ASSERT_TRUE(r.material && r.material->normal_texture && r.material->base_color_texture);
  EXPECT_EQ(r.material->normal_texture->bytes, m.material->normal_texture->bytes);
  EXPECT_EQ(r.material->base_color_texture->bytes, m.material->base_color_texture->bytes);
  EXPECT_EQ(r.material->normal_texture->mime_type, "image/png");
  EXPECT_NEAR(r.material->normal_scale, 0.8, 1e-12);
  // What was read writes again to the same bytes except for the animation it does not read.
  qs::gltf::Mesh again = m;
  again.animations.clear();
  qs::gltf::Mesh r2 = r;
  r2.normals = again.normals;  // float rounding aside
  EXPECT_NO_THROW(qs::gltf::check_mesh(r2));
}

TEST_F(GlbFiles, ReadGlbErrors) {
  EXPECT_THROW(qs::gltf::read_glb(dir_ / "missing.glb"), qs::IoError);
  std::ofstream(dir_ / "junk.glb") << "this is not glTF";
  try {
    qs::gltf::read_glb(dir_ / "junk.glb");
    FAIL() << "junk was read";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("junk.glb"));
  }
}

TEST_F(GlbFiles, ValidatorAcceptsTargetsAnimationAndTextures) {
  for (int targets : {0, 2, 8}) {
    const fs::path file = dir_ / ("t" + std::to_string(targets) + ".glb");
    qs::gltf::write_glb(file, full_mesh(targets));
    std::string out;
    const int rc = validate(file, &out);
    if (rc == 3) GTEST_SKIP() << "glTF validator not installed (scripts/setup.sh): " << out;
    EXPECT_EQ(rc, 0) << out;
    EXPECT_THAT(out, HasSubstr(": 0 errors, 0 warnings")) << out;
    if (std::getenv("QS_SHOW_VALIDATOR")) std::cout << out;
  }
}

TEST_F(GlbFiles, WriteIsAtomic) {
  qs::gltf::Mesh bad = octahedron();
  bad.faces[0][0] = 99;
  EXPECT_THROW(qs::gltf::write_glb(dir_ / "bad.glb", bad), qs::InvalidInput);
  EXPECT_FALSE(fs::exists(dir_ / "bad.glb"));
  EXPECT_TRUE(fs::is_empty(dir_)) << "no temporary file left behind";
  EXPECT_THROW(qs::gltf::write_glb(dir_ / "no" / "such" / "dir.glb", octahedron()), qs::IoError);
}

// One test per documented precondition of check_mesh: InvalidInput naming the field.
TEST(Glb, BadMeshesAreRefused) {
  struct Case {
    const char* what;
    void (*edit)(qs::gltf::Mesh&);
  };
  const Case cases[] = {
      {"positions: empty", [](qs::gltf::Mesh& m) { m.positions.clear(); m.faces.clear(); m.normals.clear(); m.texcoords.clear(); m.tangents.clear(); m.targets.clear(); m.animations.clear(); m.default_weights.clear(); m.material.reset(); }},
      {"positions: not finite at vertex: 3", [](qs::gltf::Mesh& m) { m.positions[3].x() = NAN; }},
      {"out of range", [](qs::gltf::Mesh& m) { m.faces[2][1] = 6; }},
      {"out of range", [](qs::gltf::Mesh& m) { m.faces[2][1] = -1; }},
      {"normals: 5 entries, expected 0 or 6", [](qs::gltf::Mesh& m) { m.normals.pop_back(); }},
      {"normals: not unit length", [](qs::gltf::Mesh& m) { m.normals[1] *= 1.01; }},
      {"texcoords: 7 entries", [](qs::gltf::Mesh& m) { m.texcoords.emplace_back(0, 0); }},
      {"tangents: xyz not unit length", [](qs::gltf::Mesh& m) { m.tangents[0][3] = 0.5; }},
      {"tangents: xyz not unit length", [](qs::gltf::Mesh& m) { m.tangents[4][0] = 3; }},
      {"tangents: given without normals", [](qs::gltf::Mesh& m) { m.normals.clear(); for (auto& t : m.targets) t.normal_deltas.clear(); }},
      {"position deltas, expected 6", [](qs::gltf::Mesh& m) { m.targets[1].position_deltas.pop_back(); }},
      {"position delta is not finite", [](qs::gltf::Mesh& m) { m.targets[0].position_deltas[0].y() = INFINITY; }},
      {"normal deltas on some targets but not on all", [](qs::gltf::Mesh& m) { m.targets[0].normal_deltas.clear(); }},
      {"tangent deltas on some targets but not on all", [](qs::gltf::Mesh& m) { m.targets[1].tangent_deltas.clear(); }},
      {"5 tangent deltas, expected 6", [](qs::gltf::Mesh& m) { m.targets[1].tangent_deltas.pop_back(); }},
      {"tangent deltas given but the mesh has no tangents", [](qs::gltf::Mesh& m) { m.tangents.clear(); }},
      {"default_weights: 1 weights for 2 targets", [](qs::gltf::Mesh& m) { m.default_weights = {1}; }},
      {"not strictly increasing", [](qs::gltf::Mesh& m) { m.animations[0].times[2] = 1; }},
      {"negative", [](qs::gltf::Mesh& m) { m.animations[0].times[0] = -1; }},
      {"2 weight rows for 3 key times", [](qs::gltf::Mesh& m) { m.animations[0].weights.pop_back(); }},
      {"key 1 has 1 weights for 2 targets", [](qs::gltf::Mesh& m) { m.animations[0].weights[1] = {1}; }},
      {"needs morph targets", [](qs::gltf::Mesh& m) { m.targets.clear(); m.default_weights.clear(); }},
      {"a texture needs texcoords", [](qs::gltf::Mesh& m) { m.texcoords.clear(); m.tangents.clear(); }},
      {"not a image/png file", [](qs::gltf::Mesh& m) { m.material->normal_texture->bytes = {1, 2, 3, 4, 5, 6, 7, 8}; }},
      {"mime_type 'image/bmp'", [](qs::gltf::Mesh& m) { m.material->base_color_texture->mime_type = "image/bmp"; }},
      {"material.roughness", [](qs::gltf::Mesh& m) { m.material->roughness = 2; }},
  };
  EXPECT_NO_THROW(qs::gltf::check_mesh(full_mesh(2)));
  for (const Case& c : cases) {
    qs::gltf::Mesh m = full_mesh(2);
    c.edit(m);
    try {
      qs::gltf::glb_bytes(m);
      ADD_FAILURE() << "accepted a mesh that should fail with: " << c.what;
    } catch (const qs::InvalidInput& e) {
      EXPECT_THAT(e.what(), HasSubstr(c.what));
      EXPECT_THAT(e.what(), HasSubstr("glTF mesh 'octa'"));
    }
  }
}

TEST(Glb, EveryProblemIsReported) {
  qs::gltf::Mesh m = full_mesh(2);
  m.faces[0][0] = 40;
  m.normals[2] *= 2;
  m.default_weights = {1, 2, 3};
  try {
    qs::gltf::check_mesh(m);
    FAIL();
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("out of range [0, 6): face 0 (vertex 40)"));
    EXPECT_THAT(e.what(), HasSubstr("normals: not unit length (within 1e-3) at vertex: 2"));
    EXPECT_THAT(e.what(), HasSubstr("default_weights: 3 weights for 2 targets"));
  }
}
