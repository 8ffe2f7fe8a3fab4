#include "qs/bake/export_glb.h"

namespace qs::bake {

gltf::Mesh to_gltf_mesh(const BakeResult& result, const std::vector<unsigned char>& normal_png, const std::string& name) {
  const SplitMesh& m = result.mesh;
  gltf::Mesh g;
  g.name = name;
  g.positions = m.positions;
  g.faces = m.faces;
  g.normals = m.normals;
  g.tangents = m.tangents;
  g.texcoords.reserve(m.num_vertices());
  for (int i = 0; i < m.num_vertices(); ++i) g.texcoords.push_back(result.layout.texcoord(m.vertex_patch[i], m.vertex_uv[i]));
  gltf::Material mat;
  mat.name = name + "_baked";
  if (result.options.space == NormalSpace::Tangent) {
    gltf::Image img;
    img.name = name + "_normal";
    img.mime_type = "image/png";
    img.bytes = normal_png;
    mat.normal_texture = std::move(img);
  }
  g.material = std::move(mat);
  g.generator = "qs-bake";
  return g;
}

}  // namespace qs::bake
