#pragma once
// dissection.json: format version, options, the quinary tree, the base domain, and per mesh per
// patch its face count, L2 stretch, flipped-face count and stop reason. Layout in the README.

#include <filesystem>
#include <string>
#include <vector>

#include "qs/dissect/dissection.h"

namespace qs::dissect {

/// 2: base vertices numbered by first appearance (identical across a set), features, per-node
/// stretch and alignment figures.
inline constexpr int kDissectionFormatVersion = 2;

/// One dissected mesh with what the report needs about where it came from.
struct DissectedMesh {
  std::string file;         ///< the input mesh as given
  std::string chart_file;   ///< file name of its chart PLY, relative to the output folder
  std::string seed_source;  ///< "automatic" or the landmark file
  int input_vertices = 0, input_faces = 0;
  double seconds = 0;
  Dissection dissection;
};

/// The whole document, pretty-printed, deterministic (no times unless include_times). The tree
/// and base domain are taken from the first mesh (they are common to the set).
/// `maps`, when not empty, is written as the top-level "maps" field (which seed curves and patch
/// weights were used, and why, e.g. after the fallback of DissectOptions::fallback_maps).
std::string dissection_to_json(const std::vector<DissectedMesh>& meshes, const DissectOptions& options,
                               bool include_times, const std::string& maps = {});
/// The same with the "options" object given as JSON text (qs::pipeline::config_to_json: every
/// option of the run, so that it replays). \throws InvalidInput when it is not an object.
std::string dissection_to_json(const std::vector<DissectedMesh>& meshes, const std::string& options_json,
                               bool include_times, const std::string& maps = {});

}  // namespace qs::dissect

namespace qs::dissect {

/// A dissection folder read back: the options, the tree and per mesh its chart with the patch
/// list (names, corners, stretch, stop reasons) and feature placements from dissection.json.
struct LoadedDissection {
  DissectOptions options;
  std::vector<DissectedMesh> meshes;  ///< dissection.chart read from each chart PLY
};

/// Reads OUTDIR/dissection.json and the chart PLYs it names, and checks that they agree (face
/// counts, patch counts, corner ids in range, identical base domains across the set).
/// \throws IoError for missing or unreadable files, InvalidInput for a malformed or
/// inconsistent folder (naming the file and the field).
LoadedDissection read_dissection(const std::filesystem::path& folder);

/// The places where the mesh that dissection.json names `file` may be: as written (relative to
/// the working folder), relative to the dissection `folder` or its parent, or its file name in
/// either. Only those that exist, in that order.
std::vector<std::filesystem::path> dissected_mesh_candidates(const std::string& file,
                                                             const std::filesystem::path& folder);

}  // namespace qs::dissect
