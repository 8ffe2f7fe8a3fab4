#include "qs/io/write_mesh.h"

#include <charconv>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"

namespace qs::io {

namespace {

/// Appends the shortest text that reads back as exactly `v`.
void append_number(std::string& out, double v) {
  char buf[32];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, ptr);
}

void append_number(std::string& out, long long v) {
  char buf[24];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, v);
  out.append(buf, ptr);
}

void append_xyz(std::string& out, const Vec3& p) {
  append_number(out, p.x());
  out += ' ';
  append_number(out, p.y());
  out += ' ';
  append_number(out, p.z());
  out += '\n';
}

void append_tri(std::string& out, const Tri& t, long long offset) {
  append_number(out, t[0] + offset);
  out += ' ';
  append_number(out, t[1] + offset);
  out += ' ';
  append_number(out, t[2] + offset);
  out += '\n';
}

void check_faces(const TriMesh& mesh) {
  const int nv = mesh.num_vertices();
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int id : mesh.faces[static_cast<std::size_t>(f)])
      if (id < 0 || id >= nv)
        throw InvalidInput("cannot write the mesh: face " + std::to_string(f) + " references vertex " +
                           std::to_string(id) + " but the mesh has " + std::to_string(nv) +
                           " vertices");
}

}  // namespace

std::string mesh_to_string(const TriMesh& mesh, MeshFormat format) {
  check_faces(mesh);
  std::string out;
  out.reserve(mesh.positions.size() * 64 + mesh.faces.size() * 24 + 256);
  const std::string nv = std::to_string(mesh.num_vertices());
  const std::string nf = std::to_string(mesh.num_faces());
  switch (format) {
    case MeshFormat::Obj:
      out += "# qs: " + nv + " vertices, " + nf + " triangles\n";
      for (const Vec3& p : mesh.positions) {
        out += "v ";
        append_xyz(out, p);
      }
      for (const Tri& t : mesh.faces) {
        out += "f ";
        append_tri(out, t, 1);
      }
      break;
    case MeshFormat::Off:
      out += "OFF\n" + nv + " " + nf + " 0\n";
      for (const Vec3& p : mesh.positions) append_xyz(out, p);
      for (const Tri& t : mesh.faces) {
        out += "3 ";
        append_tri(out, t, 0);
      }
      break;
    case MeshFormat::Ply:
      out += "ply\nformat ascii 1.0\ncomment written by qs\nelement vertex " + nv +
             "\nproperty double x\nproperty double y\nproperty double z\nelement face " + nf +
             "\nproperty list uchar int vertex_indices\nend_header\n";
      for (const Vec3& p : mesh.positions) append_xyz(out, p);
      for (const Tri& t : mesh.faces) {
        out += "3 ";
        append_tri(out, t, 0);
      }
      break;
    case MeshFormat::Stl:
      throw InvalidInput("writing STL is not supported; write .obj, .off or .ply");
  }
  return out;
}

void write_mesh(const std::filesystem::path& path, const TriMesh& mesh) {
  const MeshFormat format = format_from_path(path);
  if (format == MeshFormat::Stl)
    throw InvalidInput(path.string() + ": writing STL is not supported; write .obj, .off or .ply");
  write_file_atomically(path, mesh_to_string(mesh, format));
}

}  // namespace qs::io
