#include "qs/morph/morph_glb.h"

#include <cmath>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>

#include "qs/core/error.h"
#include "qs/core/json_strict.h"
#include "qs/morph/blend.h"

namespace fs = std::filesystem;

namespace qs::morph {
namespace {

std::vector<unsigned char> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string() + ": cannot open for reading");
  std::vector<unsigned char> b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw IoError(path.string() + ": read error");
  return b;
}

void check_bake_json(const fs::path& bake_dir) {
  const fs::path path = bake_dir / "bake.json";
  const nlohmann::json doc = json_strict::parse(
      json_strict::read_text_file(path, "bake.json (is " + json_strict::printable(bake_dir.string()) +
                                            " a qs-bake output folder? --bake wants the folder holding bake.json, "
                                            "<stem>.glb and <stem>_normal.png)"),
      json_strict::printable(path.string()));
  if (!doc.is_object()) throw InvalidInput(path.string() + ": not a JSON object");
  if (doc.contains("format") && doc["format"] != "qs-bake")
    throw InvalidInput(path.string() + ": not a qs-bake file (\"format\" is " + json_strict::describe(doc["format"]) + ")");
  // glTF normal textures are tangent-space with OpenGL's green (+Y up).
  const nlohmann::json options = doc.contains("options") ? doc["options"] : nlohmann::json::object();
  if (options.is_object() && options.contains("space") && options["space"] != "tangent")
    throw InvalidInput(path.string() + ": the maps are " + json_strict::describe(options["space"]) +
                       " space; a glTF normal texture must be tangent space (run qs-bake --space tangent)");
  if (options.is_object() && options.contains("green") && options["green"] == "directx")
    throw InvalidInput(path.string() + ": the maps use DirectX's green channel; glTF wants OpenGL's "
                       "(run qs-bake --green opengl)");
}

}  // namespace

BakedShape read_baked_shape(const fs::path& bake_dir, const std::string& stem, const std::vector<Tri>& faces,
                            const std::vector<Vec3>& positions) {
  check_bake_json(bake_dir);
  BakedShape out;
  out.glb = bake_dir / (stem + ".glb");
  if (!fs::exists(out.glb))
    throw IoError(out.glb.string() + ": no such file (the bake of shape '" + stem + "' should be there)");
  gltf::Mesh g = gltf::read_glb(out.glb);
  const std::string file = out.glb.string();
  if (g.faces.size() != faces.size())
    throw InvalidInput(file + ": " + std::to_string(g.faces.size()) + " faces, the remesh has " +
                       std::to_string(faces.size()) + " (was it baked from this remesh?)");
  out.vertex_source.assign(g.positions.size(), -1);
  for (size_t f = 0; f < faces.size(); ++f)
    for (int k = 0; k < 3; ++k) {
      int& src = out.vertex_source[g.faces[f][k]];
      if (src == -1) src = faces[f][k];
      else if (src != faces[f][k])
        throw InvalidInput(file + ": bake vertex " + std::to_string(g.faces[f][k]) + " is remesh vertex " +
                           std::to_string(src) + " in one face and " + std::to_string(faces[f][k]) + " in face " +
                           std::to_string(f) + " (the bake's faces must follow the remesh's)");
    }
  const double tol = 1e-5 * std::max(bounding_box(positions).diagonal(), 1e-30);
  for (size_t v = 0; v < g.positions.size(); ++v) {
    const int src = out.vertex_source[v];
    if (src < 0)
      throw InvalidInput(file + ": bake vertex " + std::to_string(v) + " is in no face");
    if ((g.positions[v] - positions[src]).norm() > tol)
      throw InvalidInput(file + ": bake vertex " + std::to_string(v) + " is not at remesh vertex " + std::to_string(src) +
                         " of shape '" + stem + "' (was it baked from this remesh?)");
  }
  if (g.texcoords.empty()) throw InvalidInput(file + ": no TEXCOORD_0 (the atlas UVs qs-morph needs)");
  out.faces = std::move(g.faces);
  out.texcoords = std::move(g.texcoords);
  out.tangents = std::move(g.tangents);
  out.normals = std::move(g.normals);
  for (Vec3& n : out.normals) n.normalize();
  if (g.material && g.material->normal_texture) {
    out.normal_map = *g.material->normal_texture;
    out.normal_scale = g.material->normal_scale;
  } else {
    const fs::path png = bake_dir / (stem + "_normal.png");
    if (!fs::exists(png))
      throw InvalidInput(file + ": no normal texture in the GLB and no " + png.string());
    out.normal_map.name = stem + "_normal";
    out.normal_map.mime_type = "image/png";
    out.normal_map.bytes = read_bytes(png);
  }
  if (out.normal_map.name.empty()) out.normal_map.name = stem + "_normal";
  if (!out.tangents.empty() && out.normals.empty())
    throw InvalidInput(file + ": TANGENT without NORMAL");
  return out;
}

gltf::Mesh morph_glb_mesh(const remesh::SemiRegularSet& set, const std::vector<std::string>& names,
                          const MorphGlbOptions& options, const BakedShape* baked) {
  const int n = static_cast<int>(set.positions.size());
  if (n < 2) throw InvalidInput("a morph needs at least 2 shapes (the set has " + std::to_string(n) + ")");
  if (static_cast<int>(names.size()) != n)
    throw InvalidInput("morph GLB: " + std::to_string(names.size()) + " names for " + std::to_string(n) + " shapes");
  if (options.base < 0 || options.base >= n)
    throw InvalidInput("morph GLB: base shape " + std::to_string(options.base) + " is not in [0, " + std::to_string(n) + ")");
  if (!options.weights.empty()) check_weights(options.weights, n);
  for (int s : options.path)
    if (s < 0 || s >= n) throw InvalidInput("morph GLB: path stop " + std::to_string(s) + " is not a shape");
  if (!(options.seconds_per_leg > 0) || !std::isfinite(options.seconds_per_leg))
    throw InvalidInput("morph GLB: seconds_per_leg must be > 0");
  const auto& faces = set.connectivity.faces;
  const size_t nv = set.positions[0].size();

  // Remesh vertex of each output vertex (identity without a bake).
  std::vector<int> source;
  if (baked) {
    source = baked->vertex_source;
    for (int s : source)
      if (s < 0 || static_cast<size_t>(s) >= nv) throw InvalidInput("morph GLB: bake vertex map out of range");
    if (baked->faces.size() != faces.size()) throw InvalidInput("morph GLB: the bake's face count differs from the remesh's");
  } else {
    source.resize(nv);
    for (size_t v = 0; v < nv; ++v) source[v] = static_cast<int>(v);
  }
  auto expand = [&](const std::vector<Vec3>& a) {
    std::vector<Vec3> out(source.size());
    for (size_t v = 0; v < source.size(); ++v) out[v] = a[source[v]];
    return out;
  };

  gltf::Mesh m;
  m.name = options.name;
  m.positions = expand(set.positions[options.base]);
  m.faces = baked ? baked->faces : faces;
  const std::vector<Vec3> base_normals = expand(vertex_normals(set.positions[options.base], faces));
  m.normals = baked && !baked->normals.empty() ? baked->normals : base_normals;
  if (baked) {
    m.texcoords = baked->texcoords;
    m.tangents = baked->tangents;
    gltf::Material mat;
    mat.name = "qs-morph";
    mat.normal_texture = baked->normal_map;
    mat.normal_scale = baked->normal_scale;
    m.material = mat;
  }
  std::vector<int> target_shape;
  for (int i = 0; i < n; ++i) {
    if (i == options.base) continue;
    gltf::MorphTarget t;
    t.name = names[i];
    const std::vector<Vec3> p = expand(set.positions[i]);
    const std::vector<Vec3> nn = expand(vertex_normals(set.positions[i], faces));
    t.position_deltas.resize(p.size());
    t.normal_deltas.resize(p.size());
    for (size_t v = 0; v < p.size(); ++v) {
      t.position_deltas[v] = p[v] - m.positions[v];
      t.normal_deltas[v] = nn[v] - m.normals[v];
    }
    if (!m.tangents.empty()) {
      // The base tangent made perpendicular to this shape's normal (Gram-Schmidt), as a delta.
      t.tangent_deltas.resize(p.size());
      for (size_t v = 0; v < p.size(); ++v) {
        const Vec3 tb(m.tangents[v][0], m.tangents[v][1], m.tangents[v][2]);
        const Vec3 ortho = tb - tb.dot(nn[v]) * nn[v];
        const double len = ortho.norm();
        t.tangent_deltas[v] = len > 1e-6 ? Vec3(ortho / len - tb) : Vec3::Zero();
      }
    }
    m.targets.push_back(std::move(t));
    target_shape.push_back(i);
  }
  if (!options.weights.empty())
    for (int s : target_shape) m.default_weights.push_back(options.weights[s]);
  if (options.path.size() >= 2) {
    gltf::WeightsAnimation a;
    a.name = options.animation_name;
    for (size_t k = 0; k < options.path.size(); ++k) {
      a.times.push_back(static_cast<float>(k * options.seconds_per_leg));
      std::vector<float> w(target_shape.size(), 0.0f);
      for (size_t j = 0; j < target_shape.size(); ++j)
        if (target_shape[j] == options.path[k]) w[j] = 1.0f;
      a.weights.push_back(std::move(w));
    }
    m.animations.push_back(std::move(a));
  }
  m.generator = "qs-morph";
  return m;
}

gltf::Mesh write_morph_glb(const fs::path& path, const remesh::SemiRegularSet& set, const std::vector<std::string>& names,
                           const MorphGlbOptions& options, const BakedShape* baked) {
  gltf::Mesh mesh = morph_glb_mesh(set, names, options, baked);
  const fs::path dir = path.parent_path();
  if (!dir.empty()) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) throw IoError(dir.string() + ": cannot create the folder (" + ec.message() + ")");
  }
  gltf::write_glb(path, mesh);
  return mesh;
}

}  // namespace qs::morph
