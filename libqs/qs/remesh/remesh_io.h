#pragma once
// A qs-remesh output folder read back (remesh.json + the meshes it names): the input of qs-bake
// and qs-morph. remesh.json's layout is in the README.

#include <filesystem>
#include <string>
#include <vector>

#include "qs/remesh/semi_regular.h"

namespace qs::remesh {

struct LoadedRemesh {
  std::filesystem::path folder;
  /// The dissection it was made from: remesh.json's "dissection_path" (relative to `folder`),
  /// or `folder`'s parent for files written before that field existed. Not checked to exist.
  std::filesystem::path dissection_folder;
  std::string mode;                    ///< "uniform", "adaptive" or "merge" (qs-merge's output)
  bool quads = false;                  ///< the files hold the grid cells as quads (fan-split on read)
  std::vector<std::string> outputs;    ///< per mesh: its remesh file name in `folder`
  std::vector<std::string> stems;      ///< per mesh: that name without its extension
  std::vector<std::string> sources;    ///< per mesh: the original mesh file as qs-dissect was given it
  /// One connectivity (faces from the files, vertex_patch / vertex_uv and counts from
  /// remesh.json) and per mesh the positions read from its file.
  SemiRegularSet set;
};

/// Reads OUTDIR/remesh.json and every mesh file it names, and checks that they agree: the same
/// vertex count as remesh.json, the identical face list in every file, patch indices and (u,v) in
/// range. \throws IoError for a missing or unreadable file; InvalidInput for a malformed
/// remesh.json or files that do not share one connectivity (naming the file and what differs).
LoadedRemesh read_remesh(const std::filesystem::path& folder);

}  // namespace qs::remesh
