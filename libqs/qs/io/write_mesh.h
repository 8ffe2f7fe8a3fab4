#pragma once
// Mesh writers. Every writer goes through qs::AtomicFile: a failure leaves no partial file.
// Numbers are written with the shortest representation that reads back bit-exact, so the
// same mesh always gives the same bytes.

#include <filesystem>
#include <string>

#include "qs/core/mesh.h"
#include "qs/io/read_mesh.h"

namespace qs::io {

/// Writes OBJ, OFF or ASCII PLY by extension (.obj .off .ply). \throws IoError, InvalidInput.
void write_mesh(const std::filesystem::path& path, const TriMesh& mesh);

/// The same text in memory.
std::string mesh_to_string(const TriMesh& mesh, MeshFormat format);

}  // namespace qs::io
