// The frame-sequence GLB: structure read back with tinygltf, the Khronos validator, determinism.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <tiny_gltf.h>
#include <unistd.h>

#include <filesystem>

#include "../common/gltf_test_support.h"
#include "qs/core/error.h"
#include "qs/gltf/sequence.h"

namespace fs = std::filesystem;
using namespace qs;

namespace {

gltf::SequenceFrame tetra(const std::string& name, double s, int extra_vertices) {
  gltf::SequenceFrame f;
  f.name = name;
  f.positions = {Vec3(0, 0, 0), Vec3(s, 0, 0), Vec3(0, s, 0), Vec3(0, 0, s)};
  for (int i = 0; i < extra_vertices; ++i) f.positions.push_back(Vec3(0.1 * s, 0.1 * s, 0.1 * s));  // unused
  f.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return f;
}

}  // namespace

TEST(SequenceGlb, OneNodePerFrameWithSteppedScaleAndValid) {
  std::vector<gltf::SequenceFrame> frames{tetra("f0", 1, 0), tetra("f1", 2, 1), tetra("f2", 3, 2)};
  const std::vector<unsigned char> bytes = gltf::sequence_glb_bytes(frames);
  EXPECT_EQ(bytes, gltf::sequence_glb_bytes(frames));  // deterministic

  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  ASSERT_TRUE(loader.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(), static_cast<unsigned>(bytes.size())))
      << err;
  ASSERT_EQ(model.meshes.size(), 3u);
  ASSERT_EQ(model.nodes.size(), 4u);  // root + one per frame
  EXPECT_EQ(model.nodes[0].children, (std::vector<int>{1, 2, 3}));
  EXPECT_TRUE(model.nodes[1].scale.empty());                       // frame 0 shown by default
  EXPECT_EQ(model.nodes[2].scale, (std::vector<double>{0, 0, 0}));  // the others hidden
  ASSERT_EQ(model.animations.size(), 1u);
  EXPECT_EQ(model.animations[0].channels.size(), 3u);
  for (const auto& s : model.animations[0].samplers) EXPECT_EQ(s.interpolation, "STEP");
  EXPECT_EQ(model.accessors[model.meshes[1].primitives[0].attributes.at("POSITION")].count, 5u);

  const fs::path file = fs::temp_directory_path() / ("qs_sequence_" + std::to_string(::getpid()) + ".glb");
  gltf::write_sequence_glb(file, frames);
  std::string out;
  const int rc = qs::testing::run_gltf_validator(file, &out);
  fs::remove(file);
  if (rc == 3) GTEST_SKIP() << "glTF validator not installed (scripts/setup.sh): " << out;
  EXPECT_EQ(rc, 0) << out;
}

TEST(SequenceGlb, RejectsBadFrames) {
  EXPECT_THROW(gltf::sequence_glb_bytes({}), InvalidInput);
  auto f = tetra("bad", 1, 0);
  f.faces[2][1] = 9;
  EXPECT_THAT([&] { gltf::sequence_glb_bytes({f}); },
              ::testing::ThrowsMessage<InvalidInput>(::testing::HasSubstr("out of range")));
}
