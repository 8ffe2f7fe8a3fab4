// The frame-sequence GLB (see sequence.h); tinygltf stays in this file.

#include "qs/gltf/sequence.h"

#include <tiny_gltf.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"

namespace qs::gltf {
namespace {

class Buffer {
 public:
  explicit Buffer(tinygltf::Model& model) : model_(model) { model_.buffers.resize(1); }

  int view(const void* data, size_t bytes, int target) {
    auto& bin = model_.buffers[0].data;
    tinygltf::BufferView v;
    v.buffer = 0;
    v.byteOffset = bin.size();
    v.byteLength = bytes;
    v.target = target;
    const auto* p = static_cast<const unsigned char*>(data);
    bin.insert(bin.end(), p, p + bytes);
    bin.resize((bin.size() + 3) / 4 * 4, 0);
    model_.bufferViews.push_back(v);
    return static_cast<int>(model_.bufferViews.size()) - 1;
  }

  int floats(const std::vector<float>& values, int components, int target, bool min_max) {
    tinygltf::Accessor a;
    a.bufferView = view(values.data(), values.size() * sizeof(float), target);
    a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    a.count = values.size() / components;
    a.type = components == 1 ? TINYGLTF_TYPE_SCALAR : TINYGLTF_TYPE_VEC3;
    if (min_max) {
      a.minValues.assign(components, std::numeric_limits<double>::infinity());
      a.maxValues.assign(components, -std::numeric_limits<double>::infinity());
      for (size_t i = 0; i < values.size(); ++i) {
        a.minValues[i % components] = std::min<double>(a.minValues[i % components], values[i]);
        a.maxValues[i % components] = std::max<double>(a.maxValues[i % components], values[i]);
      }
    }
    model_.accessors.push_back(a);
    return static_cast<int>(model_.accessors.size()) - 1;
  }

  int indices(const std::vector<Tri>& faces) {
    std::vector<uint32_t> idx;
    idx.reserve(faces.size() * 3);
    for (const Tri& t : faces)
      for (int v : t) idx.push_back(static_cast<uint32_t>(v));
    tinygltf::Accessor a;
    a.bufferView = view(idx.data(), idx.size() * 4, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    a.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    a.count = idx.size();
    a.type = TINYGLTF_TYPE_SCALAR;
    model_.accessors.push_back(a);
    return static_cast<int>(model_.accessors.size()) - 1;
  }

 private:
  tinygltf::Model& model_;
};

void check(const std::vector<SequenceFrame>& frames, const SequenceOptions& options) {
  if (frames.empty()) throw InvalidInput("sequence GLB: no frames");
  if (!(options.seconds_per_frame > 0) || !std::isfinite(options.seconds_per_frame))
    throw InvalidInput("sequence GLB: seconds_per_frame must be positive and finite");
  for (size_t k = 0; k < frames.size(); ++k) {
    const SequenceFrame& f = frames[k];
    const std::string name = "sequence GLB: frame " + std::to_string(k) + " '" + f.name + "'";
    if (f.faces.empty()) throw InvalidInput(name + ": no faces");
    for (const Vec3& p : f.positions)
      if (!p.allFinite()) throw InvalidInput(name + ": a position is not finite");
    for (size_t i = 0; i < f.faces.size(); ++i)
      for (int v : f.faces[i])
        if (v < 0 || v >= static_cast<int>(f.positions.size()))
          throw InvalidInput(name + ": face " + std::to_string(i) + " has vertex " + std::to_string(v) + " out of range");
  }
}

tinygltf::Model build(const std::vector<SequenceFrame>& frames, const SequenceOptions& options) {
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = options.generator;
  Buffer b(model);
  tinygltf::Material mat;
  mat.name = options.name;
  mat.pbrMetallicRoughness.baseColorFactor.assign(options.base_color.begin(), options.base_color.end());
  mat.pbrMetallicRoughness.metallicFactor = 0.0;
  mat.pbrMetallicRoughness.roughnessFactor = 0.6;
  model.materials.push_back(mat);

  tinygltf::Node root;
  root.name = options.name;
  model.nodes.push_back(root);
  const int n = static_cast<int>(frames.size());
  for (int k = 0; k < n; ++k) {
    const SequenceFrame& f = frames[k];
    std::vector<Vec3> normals(f.positions.size(), Vec3::Zero());
    for (const Tri& t : f.faces) {
      const Vec3 nrm = (f.positions[t[1]] - f.positions[t[0]]).cross(f.positions[t[2]] - f.positions[t[0]]);
      for (int v : t) normals[v] += nrm;
    }
    std::vector<float> pos, nor;
    pos.reserve(f.positions.size() * 3);
    nor.reserve(f.positions.size() * 3);
    for (size_t i = 0; i < f.positions.size(); ++i) {
      Vec3 m = normals[i];
      m = m.norm() > 0 ? Vec3(m.normalized()) : Vec3(0, 0, 1);
      for (int c = 0; c < 3; ++c) {
        pos.push_back(static_cast<float>(f.positions[i][c]));
        nor.push_back(static_cast<float>(m[c]));
      }
    }
    tinygltf::Primitive prim;
    prim.mode = TINYGLTF_MODE_TRIANGLES;
    prim.indices = b.indices(f.faces);
    prim.attributes["POSITION"] = b.floats(pos, 3, TINYGLTF_TARGET_ARRAY_BUFFER, true);
    prim.attributes["NORMAL"] = b.floats(nor, 3, TINYGLTF_TARGET_ARRAY_BUFFER, false);
    prim.material = 0;
    tinygltf::Mesh mesh;
    mesh.name = f.name;
    mesh.primitives.push_back(prim);
    model.meshes.push_back(mesh);
    tinygltf::Node node;
    node.name = f.name;
    node.mesh = k;
    if (k > 0) node.scale = {0.0, 0.0, 0.0};  // a still viewer shows frame 0
    model.nodes.push_back(node);
    model.nodes[0].children.push_back(k + 1);
  }
  tinygltf::Scene scene;
  scene.name = options.name;
  scene.nodes.push_back(0);
  model.scenes.push_back(scene);
  model.defaultScene = 0;

  if (n > 1) {
    tinygltf::Animation anim;
    anim.name = options.name;
    const double dt = options.seconds_per_frame;
    for (int k = 0; k < n; ++k) {
      std::vector<float> times, scales;
      auto key = [&](double t, float s) {
        times.push_back(static_cast<float>(t));
        for (int c = 0; c < 3; ++c) scales.push_back(s);
      };
      if (k == 0) {
        key(0, 1);
        key(dt, 0);
      } else {
        key(0, 0);
        key(k * dt, 1);
        key((k + 1) * dt, k + 1 < n ? 0.0f : 1.0f);
      }
      tinygltf::AnimationSampler s;
      s.input = b.floats(times, 1, 0, true);
      s.output = b.floats(scales, 3, 0, false);
      s.interpolation = "STEP";
      anim.samplers.push_back(s);
      tinygltf::AnimationChannel c;
      c.sampler = k;
      c.target_node = k + 1;
      c.target_path = "scale";
      anim.channels.push_back(c);
    }
    model.animations.push_back(anim);
  }
  model.buffers[0].name = "data";
  return model;
}

}  // namespace

std::vector<unsigned char> sequence_glb_bytes(const std::vector<SequenceFrame>& frames, const SequenceOptions& options) {
  check(frames, options);
  const tinygltf::Model model = build(frames, options);
  tinygltf::TinyGLTF writer;
  std::ostringstream out(std::ios::binary);
  if (!writer.WriteGltfSceneToStream(&model, out, false, true))
    throw InternalError("tinygltf could not serialize the sequence GLB '" + options.name + "'");
  const std::string s = out.str();
  return std::vector<unsigned char>(s.begin(), s.end());
}

void write_sequence_glb(const std::filesystem::path& path, const std::vector<SequenceFrame>& frames,
                        const SequenceOptions& options) {
  const std::vector<unsigned char> bytes = sequence_glb_bytes(frames, options);
  AtomicFile file(path);
  file.stream().write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  file.commit();
}

}  // namespace qs::gltf
