#pragma once
// Mesh readers: OBJ, OFF (COFF/NOFF), PLY (ASCII, binary little/big endian), STL (ASCII, binary).
// Our own parsers: they keep non-manifold and duplicate faces as written (OpenMesh's readers drop
// them while building the half-edge mesh, which would hide them from validation), never weld
// vertices by position, and check every count in a header against the file size before
// allocating anything.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "qs/core/mesh.h"

namespace qs::io {

enum class MeshFormat { Obj, Off, Ply, Stl };

/// Format from a file name's extension (case-insensitive). \throws InvalidInput naming the
/// supported extensions when it is none of .obj .off .ply .stl.
MeshFormat format_from_path(const std::filesystem::path& path);
const char* format_name(MeshFormat format);

/// What the reader did besides producing the mesh.
struct ReadReport {
  MeshFormat format = MeshFormat::Obj;
  std::string variant;             ///< e.g. "ascii", "binary_little_endian", "COFF"
  int polygons_triangulated = 0;   ///< faces with more than 3 corners, fan-triangulated
  int degenerate_polygons_dropped = 0;  ///< faces with fewer than 3 corners (OBJ/PLY only)
  std::vector<std::string> notes;  ///< anything else worth telling the user
};

struct ReadResult {
  TriMesh mesh;
  ReadReport report;
};

/// Reads a mesh file; format by extension.
/// \throws IoError if the file cannot be opened or read; InvalidInput naming the file and the
/// line (text) or byte offset (binary) of a parse error.
ReadResult read_mesh(const std::filesystem::path& path);

/// Reads from memory; `name` is used in messages (tests, stdin).
ReadResult read_mesh_from_memory(std::string_view data, MeshFormat format, const std::string& name);

}  // namespace qs::io
