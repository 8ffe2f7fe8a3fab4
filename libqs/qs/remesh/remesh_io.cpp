#include "qs/remesh/remesh_io.h"

#include <fstream>
#include <nlohmann/json.hpp>

#include "qs/core/error.h"
#include "qs/core/finite.h"
#include "qs/core/json_strict.h"
#include "qs/io/read_mesh.h"

namespace qs::remesh {

namespace fs = std::filesystem;

namespace {

const nlohmann::json& field(const nlohmann::json& doc, const char* name, const fs::path& path) {
  if (!doc.contains(name)) throw InvalidInput(path.string() + ": missing field \"" + name + "\"");
  return doc[name];
}

int int_field(const nlohmann::json& doc, const char* name, const fs::path& path) {
  const auto& f = field(doc, name, path);
  long long x = 0;
  if (!json_strict::integer_in(f, 0, (1LL << 31) - 1, x))
    throw InvalidInput(path.string() + ": \"" + name + "\" must be a non-negative integer below 2^31, found " +
                       json_strict::describe(f));
  return static_cast<int>(x);
}

std::string string_field(const nlohmann::json& doc, const char* name, const fs::path& path) {
  const auto& f = field(doc, name, path);
  if (!f.is_string() || !json_strict::is_clean_text(f.get_ref<const std::string&>()))
    throw InvalidInput(path.string() + ": \"" + name + "\" must be a UTF-8 string, found " + json_strict::describe(f));
  return f.get<std::string>();
}

}  // namespace

LoadedRemesh read_remesh(const fs::path& folder) {
  const fs::path path = folder / "remesh.json";
  if (!fs::is_directory(folder))
    throw IoError(json_strict::printable(folder.string()) + ": no such folder (expected a qs-remesh output folder with remesh.json)");
  const nlohmann::json doc = json_strict::parse(
      json_strict::read_text_file(path, "remesh.json (is " + json_strict::printable(folder.string()) +
                                            " a qs-remesh output folder?)"),
      json_strict::printable(path.string()));
  const auto format = doc.is_object() ? doc.find("format") : doc.end();
  if (!doc.is_object() || format == doc.end() || *format != "qs-remesh")
    throw InvalidInput(path.string() + ": not a qs-remesh file (\"format\" must be \"qs-remesh\")");
  const auto version = doc.find("version");
  if (version == doc.end() || *version != 1)
    throw InvalidInput(path.string() + ": format version " +
                       (version == doc.end() ? std::string("missing") : json_strict::describe(*version)) +
                       ", this qs reads version 1");

  LoadedRemesh r;
  r.folder = folder;
  r.dissection_folder = doc.contains("dissection_path") ? folder / string_field(doc, "dissection_path", path)
                                                        : folder.parent_path();
  r.mode = string_field(doc, "mode", path);
  if (r.mode != "uniform" && r.mode != "adaptive" && r.mode != "even" && r.mode != "merge")
    throw InvalidInput(path.string() + ": \"mode\" must be \"uniform\", \"adaptive\", \"even\" or \"merge\", not \"" + r.mode +
                       "\"");
  if (doc.contains("quads") && !doc["quads"].is_boolean())
    throw InvalidInput(path.string() + ": \"quads\" must be true or false");
  r.quads = doc.contains("quads") && doc["quads"].get<bool>();
  auto& c = r.set.connectivity;
  c.level = int_field(doc, "level", path);
  c.num_base_vertices = int_field(doc, "base_vertices", path);
  c.num_base_edges = int_field(doc, "base_edges", path);
  c.num_patches = int_field(doc, "patches", path);
  const int nv = int_field(doc, "vertices", path);
  const int nf = int_field(doc, "faces", path);

  const auto& patch = field(doc, "vertex_patch", path);
  const auto& uv = field(doc, "vertex_uv", path);
  if (!patch.is_array() || static_cast<int>(patch.size()) != nv)
    throw InvalidInput(path.string() + ": \"vertex_patch\" must be an array of " + std::to_string(nv) + " patch indices");
  if (!uv.is_array() || uv.size() != 2 * static_cast<size_t>(nv))
    throw InvalidInput(path.string() + ": \"vertex_uv\" must be an array of " + std::to_string(2 * size_t(nv)) +
                       " numbers (u, v per vertex)");
  c.vertex_patch.resize(nv);
  c.vertex_uv.resize(nv);
  for (int v = 0; v < nv; ++v) {
    const auto& p = patch[v];
    const auto& a = uv[2 * v];
    const auto& b = uv[2 * v + 1];
    long long pid = 0;
    if (!json_strict::integer_in(p, 0, static_cast<long long>(c.num_patches) - 1, pid))
      throw InvalidInput(path.string() + ": vertex_patch[" + std::to_string(v) + "] must be a patch index in [0, " +
                         std::to_string(c.num_patches) + ")");
    double ua = 0, ub = 0;
    if (!json_strict::finite_number(a, ua) || !json_strict::finite_number(b, ub) || ua < 0 || ua > 1 || ub < 0 ||
        ub > 1)
      throw InvalidInput(path.string() + ": vertex_uv of vertex " + std::to_string(v) + " must be two numbers in [0, 1]");
    c.vertex_patch[v] = static_cast<int>(pid);
    c.vertex_uv[v] = Vec2(ua, ub);
  }

  const auto& meshes = field(doc, "meshes", path);
  if (!meshes.is_array() || meshes.empty())
    throw InvalidInput(path.string() + ": \"meshes\" must be a non-empty array");
  for (size_t i = 0; i < meshes.size(); ++i) {
    const auto& m = meshes[i];
    if (!m.is_object()) throw InvalidInput(path.string() + ": meshes[" + std::to_string(i) + "] must be an object");
    const std::string out = string_field(m, "output", path);
    if (out.empty() || out == "." || out == ".." || fs::path(out).filename() != fs::path(out))
      throw InvalidInput(path.string() + ": meshes[" + std::to_string(i) + "].output must be a plain file name, not \"" +
                         out + "\"");
    r.outputs.push_back(out);
    r.stems.push_back(fs::path(out).stem().string());
    if (m.contains("file") && !(m["file"].is_string() && json_strict::is_clean_text(m["file"].get_ref<const std::string&>())))
      throw InvalidInput(path.string() + ": meshes[" + std::to_string(i) + "].file must be a UTF-8 string");
    r.sources.push_back(m.contains("file") ? m["file"].get<std::string>() : std::string());
    io::ReadResult read = io::read_mesh(folder / out);
    const fs::path file = folder / out;
    if (read.mesh.num_vertices() != nv)
      throw InvalidInput(file.string() + ": " + std::to_string(read.mesh.num_vertices()) + " vertices, remesh.json says " +
                         std::to_string(nv) + " (was the file changed after qs-remesh wrote it?)");
    if (i == 0) {
      c.faces = std::move(read.mesh.faces);
      if (!r.quads && c.num_faces() != nf)
        throw InvalidInput(file.string() + ": " + std::to_string(c.num_faces()) + " faces, remesh.json says " +
                           std::to_string(nf));
    } else if (read.mesh.faces != c.faces) {
      size_t k = 0;
      while (k < read.mesh.faces.size() && k < c.faces.size() && read.mesh.faces[k] == c.faces[k]) ++k;
      throw InvalidInput(file.string() + ": its faces differ from " + (folder / r.outputs[0]).string() + "'s (first at face " +
                         std::to_string(k) + "): the meshes of a remesh must share one connectivity");
    }
    // No NaN in, no NaN out: a remesh vertex that is not a usable point would spread into frames.
    for (size_t v = 0; v < read.mesh.positions.size(); ++v)
      if (!usable_position(read.mesh.positions[v]))
        throw InvalidInput(file.string() + ": vertex " + std::to_string(v) +
                           " has a NaN, infinite or too large coordinate (expected finite, |x| <= 1e100)");
    r.set.positions.push_back(std::move(read.mesh.positions));
  }
  return r;
}

}  // namespace qs::remesh
