#pragma once
// The body shared by the mesh-reader fuzz targets: parse the bytes as one format, and validate what
// was read (validation walks every face and vertex the reader produced). Only qs::Error may leave
// the library; any other exception, crash, hang or sanitizer report is a finding.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "qs/core/error.h"
#include "qs/io/read_mesh.h"
#include "qs/mesh/validate.h"

inline int fuzz_mesh(const std::uint8_t* data, std::size_t size, qs::io::MeshFormat format) {
  try {
    const qs::io::ReadResult r =
        qs::io::read_mesh_from_memory(std::string_view(reinterpret_cast<const char*>(data), size), format, "fuzz");
    (void)qs::mesh::validate(r.mesh);
  } catch (const qs::Error&) {
  }
  return 0;
}
