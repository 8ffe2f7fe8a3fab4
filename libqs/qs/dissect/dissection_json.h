#pragma once
// dissection.json: format version, options, the quinary tree, the base domain, and per mesh per
// patch its face count, L2 stretch, flipped-face count and stop reason. Layout in the README.

#include <string>
#include <vector>

#include "qs/dissect/dissection.h"

namespace qs::dissect {

inline constexpr int kDissectionFormatVersion = 1;

/// One dissected mesh with what the report needs about where it came from.
struct DissectedMesh {
  std::string file;         ///< the input mesh as given
  std::string chart_file;   ///< file name of its chart PLY, relative to the output folder
  std::string seed_source;  ///< "automatic" or the landmark file
  int input_vertices = 0, input_faces = 0;
  double seconds = 0;
  Dissection dissection;
};

/// The whole document, pretty-printed, deterministic (no times unless include_times).
std::string dissection_to_json(const std::vector<DissectedMesh>& meshes, const DissectOptions& options,
                               bool include_times);

}  // namespace qs::dissect
