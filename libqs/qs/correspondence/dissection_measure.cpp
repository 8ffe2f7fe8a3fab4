#include "qs/correspondence/dissection_measure.h"

#include "qs/core/error.h"
#include "qs/core/json_strict.h"

namespace qs::correspondence {

namespace fs = std::filesystem;

fs::path find_dissected_mesh(const std::string& file, const fs::path& folder) {
  const std::vector<fs::path> found = dissect::dissected_mesh_candidates(file, folder);
  if (!found.empty()) return found.front();
  const bool lossy = file.find("\xEF\xBF\xBD") != std::string::npos;  // U+FFFD
  throw IoError(json_strict::printable(file) + ": mesh of the dissection " + json_strict::printable(folder.string()) +
                " not found (looked as written, in the folder and beside it; run from where qs-dissect ran)" +
                (lossy ? "; its path was not UTF-8, which dissection.json (JSON) cannot hold, so it holds U+FFFD "
                         "in place of those bytes: put the mesh in or beside the dissection folder, or give it a "
                         "UTF-8 path and dissect it again"
                       : ""));
}

TruthFiles find_truth_files(const dissect::LoadedDissection& dissection, const fs::path& folder,
                            const std::vector<std::string>& maps) {
  const size_t n = dissection.meshes.size();
  if (!maps.empty() && maps.size() != n)
    throw UsageError("maps: " + std::to_string(maps.size()) + " given for " + std::to_string(n) +
                     " meshes (one per mesh in the dissection's order, '-' for a mesh without a map)");
  TruthFiles files;
  for (size_t i = 0; i < n; ++i) {
    files.meshes.push_back(find_dissected_mesh(dissection.meshes[i].file, folder));
    std::optional<fs::path> map;
    if (!maps.empty()) {
      if (maps[i] != "-") map = maps[i];
    } else {
      const fs::path& mesh = files.meshes.back();
      const fs::path beside = mesh.parent_path() / (mesh.stem().string() + ".map.json");
      if (fs::exists(beside)) map = beside;
    }
    files.maps.push_back(map);
  }
  return files;
}

GroundTruth load_ground_truth(const TruthFiles& files) {
  std::vector<TruthMesh> meshes;
  for (size_t i = 0; i < files.meshes.size(); ++i)
    meshes.push_back(load_truth_mesh(files.meshes[i], i < files.maps.size() ? files.maps[i] : std::nullopt));
  return GroundTruth(std::move(meshes));
}

std::vector<PairMeasure> measure_dissection(const GroundTruth& truth, const dissect::LoadedDissection& dissection,
                                            const MeasureOptions& options, const Context& context) {
  const int n = static_cast<int>(dissection.meshes.size());
  if (n < 2)
    throw InvalidInput("the dissection holds " + std::to_string(n) + " mesh" + (n == 1 ? "" : "es") +
                       "; a correspondence needs 2 or more");
  if (truth.size() != n)
    throw InvalidInput("the ground truth has " + std::to_string(truth.size()) + " meshes, the dissection " +
                       std::to_string(n));
  std::vector<DissectedInput> inputs(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    inputs[i].chart = &dissection.meshes[i].dissection.chart;
    inputs[i].landmarks = dissection_landmarks(dissection.meshes[i].dissection);
  }
  std::vector<PairMeasure> pairs;
  for (int b = 1; b < n; ++b) pairs.push_back(measure_pair(truth, inputs, 0, b, options, context));
  return pairs;
}

}  // namespace qs::correspondence
