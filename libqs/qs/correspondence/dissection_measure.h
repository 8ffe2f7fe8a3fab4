#pragma once
// A saved dissection measured against its ground truth, as qs-metro --correspondence does it:
// where the dissected meshes and their map files are, the truth loaded from them, and the first
// mesh measured against every other (measure_pair). The tool and the Python module call these.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "qs/core/context.h"
#include "qs/correspondence/correspondence.h"
#include "qs/dissect/dissection_json.h"

namespace qs::correspondence {

/// The files a dissection's ground truth is read from, one per mesh in the dissection's order.
struct TruthFiles {
  std::vector<std::filesystem::path> meshes;
  std::vector<std::optional<std::filesystem::path>> maps;  ///< nullopt: the mesh's own face list
};

/// The mesh named `file` in dissection.json: as written (relative to the working folder), else
/// relative to the dissection `folder` or its parent, else its file name in either.
/// \throws IoError naming the mesh and the folder when none exists.
std::filesystem::path find_dissected_mesh(const std::string& file, const std::filesystem::path& folder);

/// The meshes of `dissection` (read from `folder`; find_dissected_mesh) and their map files:
/// `maps` one per mesh ("-" for none), or empty for <stem>.map.json beside each mesh when present.
/// \throws UsageError when `maps` is neither empty nor one per mesh, IoError for a missing mesh.
TruthFiles find_truth_files(const dissect::LoadedDissection& dissection, const std::filesystem::path& folder,
                            const std::vector<std::string>& maps);

/// load_truth_mesh for every mesh of `files`, as one GroundTruth. \throws IoError, InvalidInput.
GroundTruth load_ground_truth(const TruthFiles& files);

/// The first mesh of `dissection` against every other: measure_pair(truth, inputs, 0, b) for
/// b = 1 .. n-1, the inputs being the dissection's charts and landmarks (dissection_landmarks).
/// \throws InvalidInput for fewer than 2 meshes, a truth of another size or meshes that are not
/// the ones dissected; Error(Internal "cancelled").
std::vector<PairMeasure> measure_dissection(const GroundTruth& truth, const dissect::LoadedDissection& dissection,
                                            const MeasureOptions& options = {}, const Context& context = {});

}  // namespace qs::correspondence
