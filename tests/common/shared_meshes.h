#pragma once
// The shared test meshes (../shared/meshes beside the repository, with their licences): tests that
// read them are skipped when the folder is absent.

#include <cstdlib>
#include <filesystem>

namespace qs::testing {

/// $QS_SHARED_MESHES, or <repo>/../shared/meshes.
inline std::filesystem::path shared_meshes_dir() {
  if (const char* env = std::getenv("QS_SHARED_MESHES"); env && *env) return env;
  return std::filesystem::path(QS_SOURCE_DIR) / ".." / "shared" / "meshes";
}

}  // namespace qs::testing
