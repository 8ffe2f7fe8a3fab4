// GLB writing and reading with tinygltf (kept out of the header).

#include "qs/gltf/glb.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/core/problem_list.h"

namespace qs::gltf {
namespace {

constexpr double kUnitTolerance = 1e-3;

bool finite3(const Vec3& v) { return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z()); }

std::string join(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += (s.empty() ? "" : "; ") + l;
  return s;
}

// Image bytes must match their MIME type: the validator decodes the header.
bool image_matches_mime(const Image& image) {
  const auto& b = image.bytes;
  if (image.mime_type == "image/png")
    return b.size() >= 8 && b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G';
  if (image.mime_type == "image/jpeg") return b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF;
  return false;
}

void check_image(const std::optional<Image>& image, const std::string& what, std::vector<std::string>& problems) {
  if (!image) return;
  if (image->mime_type != "image/png" && image->mime_type != "image/jpeg")
    problems.push_back(what + ": mime_type '" + image->mime_type + "' is not image/png or image/jpeg");
  else if (image->bytes.empty())
    problems.push_back(what + ": no bytes");
  else if (!image_matches_mime(*image))
    problems.push_back(what + ": bytes are not a " + image->mime_type + " file (wrong signature)");
}

// --- writing ----------------------------------------------------------------------------------

// Appends views and accessors to one buffer; every view starts on a 4-byte boundary.
class Builder {
 public:
  explicit Builder(tinygltf::Model& model) : model_(model) { model_.buffers.resize(1); }

  int add_view(const void* data, size_t bytes, int target) {
    auto& bin = model_.buffers[0].data;
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = bin.size();
    view.byteLength = bytes;
    view.target = target;
    const auto* p = static_cast<const unsigned char*>(data);
    bin.insert(bin.end(), p, p + bytes);
    bin.resize((bin.size() + 3) / 4 * 4, 0);
    model_.bufferViews.push_back(view);
    return static_cast<int>(model_.bufferViews.size()) - 1;
  }

  // A dense float accessor of `components` floats per element; min/max when asked.
  int add_floats(const std::vector<float>& values, int components, int target, bool min_max) {
    const int view = add_view(values.data(), values.size() * sizeof(float), target);
    tinygltf::Accessor a;
    a.bufferView = view;
    a.byteOffset = 0;
    a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    a.count = values.size() / components;
    a.type = components == 1 ? TINYGLTF_TYPE_SCALAR
             : components == 2 ? TINYGLTF_TYPE_VEC2
             : components == 3 ? TINYGLTF_TYPE_VEC3
                                : TINYGLTF_TYPE_VEC4;
    if (min_max) {
      a.minValues.assign(components, std::numeric_limits<double>::infinity());
      a.maxValues.assign(components, -std::numeric_limits<double>::infinity());
      for (size_t i = 0; i < values.size(); ++i) {
        const int c = static_cast<int>(i % components);
        a.minValues[c] = std::min<double>(a.minValues[c], values[i]);
        a.maxValues[c] = std::max<double>(a.maxValues[c], values[i]);
      }
    }
    model_.accessors.push_back(a);
    return static_cast<int>(model_.accessors.size()) - 1;
  }

  int add_indices(const std::vector<Tri>& faces, int num_vertices) {
    tinygltf::Accessor a;
    a.byteOffset = 0;
    a.count = faces.size() * 3;
    a.type = TINYGLTF_TYPE_SCALAR;
    if (num_vertices <= 65535) {  // 65535 is the primitive-restart value of uint16
      std::vector<uint16_t> idx;
      idx.reserve(a.count);
      for (const Tri& t : faces)
        for (int v : t) idx.push_back(static_cast<uint16_t>(v));
      a.bufferView = add_view(idx.data(), idx.size() * 2, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
      a.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
    } else {
      std::vector<uint32_t> idx;
      idx.reserve(a.count);
      for (const Tri& t : faces)
        for (int v : t) idx.push_back(static_cast<uint32_t>(v));
      a.bufferView = add_view(idx.data(), idx.size() * 4, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
      a.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    }
    model_.accessors.push_back(a);
    return static_cast<int>(model_.accessors.size()) - 1;
  }

  // Image in the binary chunk + a texture with a linear, repeating sampler.
  int add_texture(const Image& image) {
    tinygltf::Image im;
    im.name = image.name;
    im.mimeType = image.mime_type;
    im.bufferView = add_view(image.bytes.data(), image.bytes.size(), 0);
    model_.images.push_back(im);
    if (model_.samplers.empty()) {
      tinygltf::Sampler s;
      s.magFilter = TINYGLTF_TEXTURE_FILTER_LINEAR;
      s.minFilter = TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_LINEAR;
      model_.samplers.push_back(s);
    }
    tinygltf::Texture t;
    t.source = static_cast<int>(model_.images.size()) - 1;
    t.sampler = 0;
    model_.textures.push_back(t);
    return static_cast<int>(model_.textures.size()) - 1;
  }

 private:
  tinygltf::Model& model_;
};

std::vector<float> to_floats(const std::vector<Vec3>& v, bool normalize) {
  std::vector<float> f;
  f.reserve(v.size() * 3);
  for (const Vec3& p : v) {
    const Vec3 q = normalize ? p.normalized() : p;
    f.push_back(static_cast<float>(q.x()));
    f.push_back(static_cast<float>(q.y()));
    f.push_back(static_cast<float>(q.z()));
  }
  return f;
}

tinygltf::Model build_model(const Mesh& mesh) {
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = mesh.generator;
  Builder b(model);
  const int nv = static_cast<int>(mesh.positions.size());

  tinygltf::Primitive prim;
  prim.mode = TINYGLTF_MODE_TRIANGLES;
  prim.indices = b.add_indices(mesh.faces, nv);
  prim.attributes["POSITION"] = b.add_floats(to_floats(mesh.positions, false), 3, TINYGLTF_TARGET_ARRAY_BUFFER, true);
  if (!mesh.normals.empty())
    prim.attributes["NORMAL"] = b.add_floats(to_floats(mesh.normals, true), 3, TINYGLTF_TARGET_ARRAY_BUFFER, false);
  if (!mesh.texcoords.empty()) {
    std::vector<float> f;
    f.reserve(nv * 2);
    for (const Vec2& t : mesh.texcoords) {
      f.push_back(static_cast<float>(t.x()));
      f.push_back(static_cast<float>(t.y()));
    }
    prim.attributes["TEXCOORD_0"] = b.add_floats(f, 2, TINYGLTF_TARGET_ARRAY_BUFFER, false);
  }
  if (!mesh.tangents.empty()) {
    std::vector<float> f;
    f.reserve(nv * 4);
    for (const auto& t : mesh.tangents) {
      const Vec3 d = Vec3(t[0], t[1], t[2]).normalized();
      f.push_back(static_cast<float>(d.x()));
      f.push_back(static_cast<float>(d.y()));
      f.push_back(static_cast<float>(d.z()));
      f.push_back(t[3] < 0 ? -1.0f : 1.0f);
    }
    prim.attributes["TANGENT"] = b.add_floats(f, 4, TINYGLTF_TARGET_ARRAY_BUFFER, false);
  }
  for (const MorphTarget& t : mesh.targets) {
    std::map<std::string, int> attrs;
    attrs["POSITION"] = b.add_floats(to_floats(t.position_deltas, false), 3, TINYGLTF_TARGET_ARRAY_BUFFER, true);
    if (!t.normal_deltas.empty())
      attrs["NORMAL"] = b.add_floats(to_floats(t.normal_deltas, false), 3, TINYGLTF_TARGET_ARRAY_BUFFER, false);
    if (!t.tangent_deltas.empty())
      attrs["TANGENT"] = b.add_floats(to_floats(t.tangent_deltas, false), 3, TINYGLTF_TARGET_ARRAY_BUFFER, false);
    prim.targets.push_back(attrs);
  }

  if (mesh.material) {
    const Material& m = *mesh.material;
    tinygltf::Material mat;
    mat.name = m.name;
    mat.pbrMetallicRoughness.baseColorFactor.assign(m.base_color.begin(), m.base_color.end());
    mat.pbrMetallicRoughness.metallicFactor = m.metallic;
    mat.pbrMetallicRoughness.roughnessFactor = m.roughness;
    mat.doubleSided = m.double_sided;
    if (m.normal_texture) {
      mat.normalTexture.index = b.add_texture(*m.normal_texture);
      mat.normalTexture.texCoord = 0;
      mat.normalTexture.scale = m.normal_scale;
    }
    if (m.base_color_texture) {
      mat.pbrMetallicRoughness.baseColorTexture.index = b.add_texture(*m.base_color_texture);
      mat.pbrMetallicRoughness.baseColorTexture.texCoord = 0;
    }
    model.materials.push_back(mat);
    prim.material = 0;
  }

  tinygltf::Mesh gm;
  gm.name = mesh.name;
  gm.primitives.push_back(prim);
  if (!mesh.targets.empty()) {
    tinygltf::Value::Array names;
    for (const MorphTarget& t : mesh.targets) names.emplace_back(t.name);
    tinygltf::Value::Object extras;
    extras["targetNames"] = tinygltf::Value(names);
    gm.extras = tinygltf::Value(extras);
    gm.weights = mesh.default_weights.empty() ? std::vector<double>(mesh.targets.size(), 0.0) : mesh.default_weights;
  }
  model.meshes.push_back(gm);

  tinygltf::Node node;
  node.name = mesh.name;
  node.mesh = 0;
  model.nodes.push_back(node);
  tinygltf::Scene scene;
  scene.name = "scene";
  scene.nodes.push_back(0);
  model.scenes.push_back(scene);
  model.defaultScene = 0;

  for (const WeightsAnimation& anim : mesh.animations) {
    std::vector<float> out;
    out.reserve(anim.times.size() * mesh.targets.size());
    for (const auto& row : anim.weights)
      for (float w : row) out.push_back(w);
    tinygltf::AnimationSampler s;
    s.input = b.add_floats(anim.times, 1, 0, true);  // the spec wants min/max on sampler inputs
    s.output = b.add_floats(out, 1, 0, false);
    s.interpolation = "LINEAR";
    tinygltf::AnimationChannel c;
    c.sampler = 0;
    c.target_node = 0;
    c.target_path = "weights";
    tinygltf::Animation a;
    a.name = anim.name;
    a.samplers.push_back(s);
    a.channels.push_back(c);
    model.animations.push_back(a);
  }
  model.buffers[0].name = "data";
  return model;
}

// --- reading ----------------------------------------------------------------------------------

// Keeps the encoded bytes: qs never decodes images here.
bool keep_encoded(tinygltf::Image* image, const int, std::string*, std::string*, int, int, const unsigned char* bytes,
                  int size, void*) {
  image->image.assign(bytes, bytes + size);
  image->as_is = true;
  return true;
}

class Reader {
 public:
  Reader(const tinygltf::Model& model, std::string file) : model_(model), file_(std::move(file)) {}

  [[noreturn]] void fail(const std::string& what) const { throw InvalidInput(file_ + ": " + what); }

  // Reads accessor `index` as floats, `components` per element, expecting `count` elements.
  std::vector<float> floats(int index, int components, size_t count, const std::string& what) const {
    if (index < 0 || index >= static_cast<int>(model_.accessors.size())) fail(what + ": no accessor " + std::to_string(index));
    const tinygltf::Accessor& a = model_.accessors[index];
    if (a.sparse.isSparse) fail(what + ": sparse accessors are not supported");
    if (a.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT) fail(what + ": not float (only float attributes are supported)");
    if (tinygltf::GetNumComponentsInType(a.type) != components)
      fail(what + ": expected " + std::to_string(components) + " components per element");
    if (count != 0 && a.count != count)
      fail(what + ": " + std::to_string(a.count) + " elements, expected " + std::to_string(count));
    std::vector<float> out(a.count * components);
    const unsigned char* base = view_data(a, components * sizeof(float), what);
    const size_t stride = stride_of(a, components * sizeof(float));
    for (size_t i = 0; i < a.count; ++i) std::memcpy(&out[i * components], base + i * stride, components * sizeof(float));
    return out;
  }

  std::vector<Vec3> vec3s(int index, size_t count, const std::string& what) const {
    const std::vector<float> f = floats(index, 3, count, what);
    std::vector<Vec3> v(f.size() / 3);
    for (size_t i = 0; i < v.size(); ++i) v[i] = Vec3(f[3 * i], f[3 * i + 1], f[3 * i + 2]);
    return v;
  }

  std::vector<Tri> triangles(int index, size_t num_vertices) const {
    if (index < 0 || index >= static_cast<int>(model_.accessors.size())) fail("indices: no accessor");
    const tinygltf::Accessor& a = model_.accessors[index];
    if (a.count % 3 != 0) fail("indices: count " + std::to_string(a.count) + " is not a multiple of 3");
    const int size = tinygltf::GetComponentSizeInBytes(a.componentType);
    if (a.type != TINYGLTF_TYPE_SCALAR || (size != 1 && size != 2 && size != 4)) fail("indices: not unsigned scalars");
    const unsigned char* base = view_data(a, size, "indices");
    const size_t stride = stride_of(a, size);
    std::vector<Tri> faces(a.count / 3);
    for (size_t i = 0; i < a.count; ++i) {
      const unsigned char* p = base + i * stride;
      uint32_t v = 0;
      if (size == 1) v = *p;
      else if (size == 2) { uint16_t s; std::memcpy(&s, p, 2); v = s; }
      else std::memcpy(&v, p, 4);
      if (v >= num_vertices) fail("indices: vertex " + std::to_string(v) + " out of range (" + std::to_string(num_vertices) + " vertices)");
      faces[i / 3][i % 3] = static_cast<int>(v);
    }
    return faces;
  }

  std::optional<Image> image_of_texture(int texture) const {
    if (texture < 0) return std::nullopt;
    if (texture >= static_cast<int>(model_.textures.size())) fail("texture " + std::to_string(texture) + " does not exist");
    const int source = model_.textures[texture].source;
    if (source < 0 || source >= static_cast<int>(model_.images.size())) fail("texture " + std::to_string(texture) + " has no image");
    const tinygltf::Image& im = model_.images[source];
    Image out;
    out.name = im.name;
    out.bytes = im.image;
    out.mime_type = im.mimeType;
    if (out.mime_type.empty()) {  // an image file by URI: guess from its signature
      out.mime_type = "image/png";
      if (!image_matches_mime(out)) out.mime_type = "image/jpeg";
    }
    if (!image_matches_mime(out)) fail("image " + std::to_string(source) + " is neither PNG nor JPEG");
    return out;
  }

 private:
  size_t stride_of(const tinygltf::Accessor& a, size_t element) const {
    const int s = a.ByteStride(model_.bufferViews.at(a.bufferView));
    return s > 0 ? static_cast<size_t>(s) : element;
  }
  const unsigned char* view_data(const tinygltf::Accessor& a, size_t element, const std::string& what) const {
    if (a.bufferView < 0 || a.bufferView >= static_cast<int>(model_.bufferViews.size())) fail(what + ": no buffer view");
    const tinygltf::BufferView& v = model_.bufferViews[a.bufferView];
    if (v.buffer < 0 || v.buffer >= static_cast<int>(model_.buffers.size())) fail(what + ": no buffer");
    const auto& data = model_.buffers[v.buffer].data;
    const size_t stride = stride_of(a, element);
    const size_t begin = v.byteOffset + a.byteOffset;
    const size_t need = a.count == 0 ? 0 : (a.count - 1) * stride + element;
    if (a.byteOffset + need > v.byteLength || begin + need > data.size()) fail(what + ": accessor runs past its buffer");
    return data.data() + begin;
  }

  const tinygltf::Model& model_;
  std::string file_;
};

}  // namespace

void check_mesh(const Mesh& mesh) {
  std::vector<std::string> problems;
  const size_t nv = mesh.positions.size(), nt = mesh.targets.size();
  if (nv == 0) problems.push_back("positions: empty (a glTF mesh needs at least one vertex)");
  if (nv > static_cast<size_t>(std::numeric_limits<int>::max())) problems.push_back("positions: too many vertices");
  if (mesh.faces.empty()) problems.push_back("faces: empty (a glTF mesh needs at least one triangle)");
  auto sized = [&](size_t n, const char* field) {
    if (n != 0 && n != nv)
      problems.push_back(std::string(field) + ": " + std::to_string(n) + " entries, expected 0 or " + std::to_string(nv) +
                         " (one per vertex)");
    return n == nv;
  };
  {
    ProblemList bad("positions: not finite at vertex");
    for (size_t i = 0; i < nv; ++i)
      if (!finite3(mesh.positions[i])) bad.add(std::to_string(i));
    bad.append_to(problems);
  }
  {
    ProblemList bad("faces: vertex index out of range [0, " + std::to_string(nv) + ")");
    for (size_t f = 0; f < mesh.faces.size(); ++f)
      for (int v : mesh.faces[f])
        if (v < 0 || static_cast<size_t>(v) >= nv) {
          bad.add("face " + std::to_string(f) + " (vertex " + std::to_string(v) + ")");
          break;
        }
    bad.append_to(problems);
  }
  if (sized(mesh.normals.size(), "normals")) {
    ProblemList bad("normals: not unit length (within 1e-3) at vertex");
    for (size_t i = 0; i < nv; ++i)
      if (!finite3(mesh.normals[i]) || std::abs(mesh.normals[i].norm() - 1) > kUnitTolerance) bad.add(std::to_string(i));
    bad.append_to(problems);
  }
  if (sized(mesh.texcoords.size(), "texcoords")) {
    ProblemList bad("texcoords: not finite at vertex");
    for (size_t i = 0; i < nv; ++i)
      if (!std::isfinite(mesh.texcoords[i].x()) || !std::isfinite(mesh.texcoords[i].y())) bad.add(std::to_string(i));
    bad.append_to(problems);
  }
  if (sized(mesh.tangents.size(), "tangents")) {
    ProblemList bad("tangents: xyz not unit length (within 1e-3) or w not +-1 at vertex");
    for (size_t i = 0; i < nv; ++i) {
      const auto& t = mesh.tangents[i];
      const Vec3 d(t[0], t[1], t[2]);
      if (!finite3(d) || std::abs(d.norm() - 1) > kUnitTolerance || !(std::abs(std::abs(t[3]) - 1) <= kUnitTolerance))
        bad.add(std::to_string(i));
    }
    bad.append_to(problems);
  }
  if (!mesh.tangents.empty() && mesh.normals.empty())
    problems.push_back("tangents: given without normals (glTF needs NORMAL with TANGENT)");

  bool some_normal_deltas = false, all_normal_deltas = true, some_tangent_deltas = false, all_tangent_deltas = true;
  for (size_t k = 0; k < nt; ++k) {
    const MorphTarget& t = mesh.targets[k];
    const std::string name = "targets[" + std::to_string(k) + "] '" + t.name + "'";
    if (t.position_deltas.size() != nv)
      problems.push_back(name + ": " + std::to_string(t.position_deltas.size()) + " position deltas, expected " +
                         std::to_string(nv));
    else if (std::any_of(t.position_deltas.begin(), t.position_deltas.end(), [](const Vec3& d) { return !finite3(d); }))
      problems.push_back(name + ": a position delta is not finite");
    if (!t.normal_deltas.empty()) {
      some_normal_deltas = true;
      if (mesh.normals.empty()) problems.push_back(name + ": normal deltas given but the mesh has no normals");
      else if (t.normal_deltas.size() != nv)
        problems.push_back(name + ": " + std::to_string(t.normal_deltas.size()) + " normal deltas, expected " +
                           std::to_string(nv));
      else if (std::any_of(t.normal_deltas.begin(), t.normal_deltas.end(), [](const Vec3& d) { return !finite3(d); }))
        problems.push_back(name + ": a normal delta is not finite");
    } else {
      all_normal_deltas = false;
    }
    if (!t.tangent_deltas.empty()) {
      some_tangent_deltas = true;
      if (mesh.tangents.empty()) problems.push_back(name + ": tangent deltas given but the mesh has no tangents");
      else if (t.tangent_deltas.size() != nv)
        problems.push_back(name + ": " + std::to_string(t.tangent_deltas.size()) + " tangent deltas, expected " +
                           std::to_string(nv));
      else if (std::any_of(t.tangent_deltas.begin(), t.tangent_deltas.end(), [](const Vec3& d) { return !finite3(d); }))
        problems.push_back(name + ": a tangent delta is not finite");
    } else {
      all_tangent_deltas = false;
    }
  }
  if (some_normal_deltas && !all_normal_deltas)
    problems.push_back("targets: normal deltas on some targets but not on all (glTF wants the same attributes on every target)");
  if (some_tangent_deltas && !all_tangent_deltas)
    problems.push_back("targets: tangent deltas on some targets but not on all (glTF wants the same attributes on every target)");
  if (!mesh.default_weights.empty()) {
    if (mesh.default_weights.size() != nt)
      problems.push_back("default_weights: " + std::to_string(mesh.default_weights.size()) + " weights for " +
                         std::to_string(nt) + " targets");
    else if (std::any_of(mesh.default_weights.begin(), mesh.default_weights.end(), [](double w) { return !std::isfinite(w); }))
      problems.push_back("default_weights: a weight is not finite");
  }
  for (size_t a = 0; a < mesh.animations.size(); ++a) {
    const WeightsAnimation& anim = mesh.animations[a];
    const std::string name = "animations[" + std::to_string(a) + "] '" + anim.name + "'";
    if (nt == 0) problems.push_back(name + ": a weights animation needs morph targets");
    if (anim.times.empty()) problems.push_back(name + ": no key times");
    for (size_t k = 0; k < anim.times.size(); ++k) {
      const float t = anim.times[k];
      if (!std::isfinite(t) || t < 0) {
        problems.push_back(name + ": time " + std::to_string(k) + " is negative or not finite");
        break;
      }
      if (k > 0 && !(t > anim.times[k - 1])) {
        problems.push_back(name + ": times are not strictly increasing at key " + std::to_string(k));
        break;
      }
    }
    if (anim.weights.size() != anim.times.size())
      problems.push_back(name + ": " + std::to_string(anim.weights.size()) + " weight rows for " +
                         std::to_string(anim.times.size()) + " key times");
    for (size_t k = 0; k < anim.weights.size(); ++k) {
      if (anim.weights[k].size() != nt) {
        problems.push_back(name + ": key " + std::to_string(k) + " has " + std::to_string(anim.weights[k].size()) +
                           " weights for " + std::to_string(nt) + " targets");
        break;
      }
      if (std::any_of(anim.weights[k].begin(), anim.weights[k].end(), [](float w) { return !std::isfinite(w); })) {
        problems.push_back(name + ": key " + std::to_string(k) + " has a weight that is not finite");
        break;
      }
    }
  }
  if (mesh.material) {
    const Material& m = *mesh.material;
    for (double c : m.base_color)
      if (!(c >= 0 && c <= 1)) {
        problems.push_back("material.base_color: components must lie in [0, 1]");
        break;
      }
    if (!(m.metallic >= 0 && m.metallic <= 1)) problems.push_back("material.metallic: must lie in [0, 1]");
    if (!(m.roughness >= 0 && m.roughness <= 1)) problems.push_back("material.roughness: must lie in [0, 1]");
    if (!std::isfinite(m.normal_scale)) problems.push_back("material.normal_scale: not finite");
    check_image(m.normal_texture, "material.normal_texture", problems);
    check_image(m.base_color_texture, "material.base_color_texture", problems);
    if ((m.normal_texture || m.base_color_texture) && mesh.texcoords.empty())
      problems.push_back("material: a texture needs texcoords (TEXCOORD_0)");
  }
  if (!problems.empty()) throw InvalidInput("glTF mesh '" + mesh.name + "': " + join(problems));
}

std::vector<unsigned char> glb_bytes(const Mesh& mesh) {
  check_mesh(mesh);
  const tinygltf::Model model = build_model(mesh);
  tinygltf::TinyGLTF writer;
  std::ostringstream out(std::ios::binary);
  if (!writer.WriteGltfSceneToStream(&model, out, false, true))
    throw InternalError("tinygltf could not serialize glTF mesh '" + mesh.name + "'");
  const std::string s = out.str();
  return std::vector<unsigned char>(s.begin(), s.end());
}

void write_glb(const std::filesystem::path& path, const Mesh& mesh) {
  const std::vector<unsigned char> bytes = glb_bytes(mesh);
  AtomicFile file(path);
  file.stream().write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  file.commit();
}

Mesh read_glb(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(file + ": cannot open for reading");
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw IoError(file + ": read error");

  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(keep_encoded, nullptr);
  tinygltf::Model model;
  std::string err, warn;
  const bool binary = bytes.size() >= 4 && bytes.compare(0, 4, "glTF") == 0;
  const std::string base_dir = path.parent_path().string();
  const bool ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn,
                                                       reinterpret_cast<const unsigned char*>(bytes.data()),
                                                       static_cast<unsigned int>(bytes.size()), base_dir)
                         : loader.LoadASCIIFromString(&model, &err, &warn, bytes.c_str(),
                                                      static_cast<unsigned int>(bytes.size()), base_dir);
  if (!ok) throw InvalidInput(file + ": not a readable glTF file: " + err);

  Reader r(model, file);
  if (model.meshes.empty() || model.meshes[0].primitives.empty()) r.fail("no mesh");
  const tinygltf::Mesh& gm = model.meshes[0];
  const tinygltf::Primitive& prim = gm.primitives[0];
  if (prim.mode != TINYGLTF_MODE_TRIANGLES && prim.mode != -1) r.fail("the first primitive is not triangles");
  auto attr = [&](const char* name) {
    const auto it = prim.attributes.find(name);
    return it == prim.attributes.end() ? -1 : it->second;
  };
  Mesh mesh;
  mesh.name = gm.name;
  mesh.generator = model.asset.generator;
  if (attr("POSITION") < 0) r.fail("the first primitive has no POSITION");
  mesh.positions = r.vec3s(attr("POSITION"), 0, "POSITION");
  const size_t nv = mesh.positions.size();
  if (prim.indices >= 0) {
    mesh.faces = r.triangles(prim.indices, nv);
  } else {
    if (nv % 3 != 0) r.fail("non-indexed primitive with a vertex count that is not a multiple of 3");
    for (size_t i = 0; i < nv; i += 3) mesh.faces.push_back({int(i), int(i + 1), int(i + 2)});
  }
  if (attr("NORMAL") >= 0) mesh.normals = r.vec3s(attr("NORMAL"), nv, "NORMAL");
  if (attr("TEXCOORD_0") >= 0) {
    const std::vector<float> f = r.floats(attr("TEXCOORD_0"), 2, nv, "TEXCOORD_0");
    for (size_t i = 0; i < nv; ++i) mesh.texcoords.emplace_back(f[2 * i], f[2 * i + 1]);
  }
  if (attr("TANGENT") >= 0) {
    const std::vector<float> f = r.floats(attr("TANGENT"), 4, nv, "TANGENT");
    for (size_t i = 0; i < nv; ++i) mesh.tangents.push_back({f[4 * i], f[4 * i + 1], f[4 * i + 2], f[4 * i + 3]});
  }
  std::vector<std::string> names;
  if (gm.extras.IsObject() && gm.extras.Has("targetNames") && gm.extras.Get("targetNames").IsArray()) {
    const tinygltf::Value& a = gm.extras.Get("targetNames");
    for (size_t i = 0; i < a.ArrayLen(); ++i) names.push_back(a.Get(int(i)).IsString() ? a.Get(int(i)).Get<std::string>() : "");
  }
  for (size_t k = 0; k < prim.targets.size(); ++k) {
    MorphTarget t;
    t.name = k < names.size() ? names[k] : "target_" + std::to_string(k);
    const auto& ta = prim.targets[k];
    const std::string what = "target " + std::to_string(k) + " ";
    if (ta.count("POSITION")) t.position_deltas = r.vec3s(ta.at("POSITION"), nv, what + "POSITION");
    else t.position_deltas.assign(nv, Vec3::Zero());
    if (ta.count("NORMAL")) t.normal_deltas = r.vec3s(ta.at("NORMAL"), nv, what + "NORMAL");
    if (ta.count("TANGENT")) t.tangent_deltas = r.vec3s(ta.at("TANGENT"), nv, what + "TANGENT");
    mesh.targets.push_back(std::move(t));
  }
  mesh.default_weights = gm.weights;
  if (prim.material >= 0 && prim.material < static_cast<int>(model.materials.size())) {
    const tinygltf::Material& gmat = model.materials[prim.material];
    Material m;
    m.name = gmat.name;
    const auto& pbr = gmat.pbrMetallicRoughness;
    for (size_t i = 0; i < 4 && i < pbr.baseColorFactor.size(); ++i) m.base_color[i] = pbr.baseColorFactor[i];
    m.metallic = pbr.metallicFactor;
    m.roughness = pbr.roughnessFactor;
    m.double_sided = gmat.doubleSided;
    m.normal_scale = gmat.normalTexture.scale;
    m.normal_texture = r.image_of_texture(gmat.normalTexture.index);
    m.base_color_texture = r.image_of_texture(pbr.baseColorTexture.index);
    mesh.material = std::move(m);
  }
  return mesh;
}

}  // namespace qs::gltf
