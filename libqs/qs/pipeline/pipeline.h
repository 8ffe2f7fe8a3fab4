#pragma once
// The qs pipeline: read meshes with their landmarks, dissect them together, refine the maps
// between them, write a dissection folder; read it back and write semi-regular remeshes. Its
// defaults are the defaults: qs-dissect and qs-remesh are thin command-line mains over these
// calls, and a program that calls them with default configurations writes byte-identical
// folders. Options and their measurements: docs/tools/qs-dissect.md.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/output_folder.h"
#include "qs/dissect/dissection.h"
#include "qs/dissect/dissection_json.h"
#include "qs/io/read_mesh.h"
#include "qs/landmarks/landmarks.h"
#include "qs/maprefine/map_refine.h"
#include "qs/mesh/validate.h"
#include "qs/remesh/semi_regular.h"

namespace qs::pipeline {

// ---------------------------------------------------------------------------------------------
// Input

/// A mesh read, validated and with its landmarks (if any).
struct Input {
  std::string file;                               ///< as given
  io::ReadResult read;
  mesh::ValidationResult valid;                   ///< valid.mesh is what is dissected
  std::optional<landmarks::Landmarks> landmarks;  ///< nullopt: none found
  std::string landmark_file;                      ///< empty when none
};

/// Reads and validates a mesh; landmarks from `landmark_file`, else <stem>.landmarks.json or
/// <stem>.pp beside the mesh, else none. \throws IoError for an unreadable file, InvalidInput
/// with the validation report for a rejected mesh or for bad landmarks.
Input load_input(const std::string& mesh_file, const std::optional<std::string>& landmark_file = std::nullopt);

// ---------------------------------------------------------------------------------------------
// Dissection

/// Every option of a dissection. The defaults are qs-dissect's. Its JSON form (config_to_json)
/// is the "options" object of dissection.json, so that a run replays from its own output.
struct DissectConfig {
  /// The dissection proper (tau, depth, split rules, same-pose detection, ...). Its hooks
  /// (refine_before_split, same_pose_untangle) are ignored: dissect() sets them from the flags below.
  dissect::DissectOptions dissect;
  /// Before a node is split, refine every mesh's map of it against the first mesh's (the
  /// composed map as the metric), so that the split points correspond better.
  bool refine_before_split = true;
  /// For two or more meshes, refine every mesh's chart against the first's after the
  /// dissection (maprefine::refine_maps with `refine`).
  bool refine_maps = true;
  /// The refinement's options. Its pose_pull and border_iterations are replaced by pose_pull and
  /// pose_border_iterations below when the meshes are in one pose (told or detected); through a
  /// registration those are scaled and border_sweeps raised (maprefine::kRegisteredPullScale).
  maprefine::RefineOptions refine;
  /// Meshes in one pose: weight of the refinement's pull toward the first mesh's nearest points
  /// (0: off), and the Newton steps per glued pair of patches with it. \pre >= 0
  double pose_pull = maprefine::kDefaultPosePull;
  int pose_border_iterations = maprefine::kPoseBorderIterations;
};

/// The configuration as the "options" object of dissection.json (deterministic, ordered keys).
std::string config_to_json(const DissectConfig& config);
/// Reads a configuration: either a whole dissection.json (its "options" object is used) or just
/// such an object. Keys left out keep their defaults. `name` names the source in messages.
/// \throws UsageError for malformed JSON, an unknown key (naming it) or a value of the wrong
/// type or out of range (saying what is expected).
DissectConfig config_from_json(const std::string& json, const std::string& name = "the configuration");
/// The same from a file. \throws IoError when it cannot be read; UsageError as config_from_json.
DissectConfig read_config(const std::filesystem::path& file);
/// Checks every value of a configuration. \throws UsageError naming the option and what it expects.
void validate_config(const DissectConfig& config);

/// One line per option for --help-all: key, default, what it does.
std::string describe_config();

/// What dissect() computes for meshes already in memory: dissect_set with the map hooks, then
/// refine_maps for two or more meshes; no report, no files (benchmarks, studio).
struct SetResult {
  dissect::DissectionSet set;              ///< the refined charts when refine_maps ran
  maprefine::RefineReport refine;          ///< empty when the maps were not refined
  maprefine::RefineOptions refine_options; ///< as run (the pose pull and its border iterations set)
  bool one_pose = false;                   ///< same_pose told or detected
  double dissect_seconds = 0, refine_seconds = 0;
};
/// \throws as dissect().
SetResult dissect_meshes(const std::vector<dissect::MeshToDissect>& meshes, const DissectConfig& config = {},
                         const Context& ctx = {});

/// A dissected set, ready to be written.
struct DissectResult {
  DissectConfig config;                        ///< as asked (written as dissection.json's "options")
  std::vector<dissect::DissectedMesh> meshes;  ///< per input, in order, with their chart file names
  std::vector<std::filesystem::path> inputs;   ///< the mesh and landmark files read (never overwritten)
  std::string maps;          ///< the maps used ("geodesic+cotan", with the fallback's reason if any)
  std::string report;        ///< the text report (deterministic: no times)
  std::string patch_report;  ///< one line per patch of every mesh (faces, stretch, flipped faces)
  double dissect_seconds = 0, refine_seconds = 0;
  /// Flipped or zero-area uv faces left in the leaves, and the error message for them (empty
  /// when 0): the folder is still written, then check_bijective throws.
  int folded_faces = 0;
  std::string folded_message;
};

/// Checks that the inputs can be dissected together and returns the warnings a user should see
/// (a set without seeds). \throws InvalidInput when some meshes have seeds and others not.
std::vector<std::string> check_inputs(const std::vector<Input>& inputs);

/// Dissects the meshes together (one union quinary tree, the same patches on every mesh),
/// refines the maps between them and writes the report. Seeds come from the landmarks (every
/// mesh or none), features by name. Stages: "dissect", "refine maps" (Context::progress).
/// \throws UsageError for a bad configuration, InvalidInput for inconsistent landmarks or
/// meshes that cannot be dissected, SolverError when a map fails, InternalError for a result
/// that breaks the dissection's invariants.
DissectResult dissect(const std::vector<Input>& inputs, const DissectConfig& config = {}, const Context& ctx = {});

/// Writes `result` into an output folder: <stem>.chart.ply per mesh (-2, -3 ... for repeated
/// stems) and dissection.json, all-or-nothing. \throws UsageError when a file would replace an
/// input, IoError when the folder cannot be written.
void write_dissection(const DissectResult& result, const std::filesystem::path& folder);
/// The same into the staging folder of an OutputFolder the caller commits.
void write_dissection(const DissectResult& result, OutputFolder& folder);

/// \throws SolverError with result.folded_message when result.folded_faces > 0.
void check_bijective(const DissectResult& result);

/// The default output folder of a set: <stem>.dissection, <stem1>_<stem2>.dissection, ...
/// (the first three stems, then "_etc").
std::string default_dissection_folder(const std::vector<std::string>& mesh_files);

/// A dissection folder read back (dissection.json and its charts). \throws as
/// dissect::read_dissection.
dissect::LoadedDissection read_dissection(const std::filesystem::path& folder);

// ---------------------------------------------------------------------------------------------
// Remesh

/// qs-remesh's options. Exactly one of level >= 0 or adaptive > 0.
struct RemeshConfig {
  enum class Mode { Even, Uniform, Adaptive };
  Mode mode = Mode::Even;
  int level = 4;             ///< Even and Uniform
  bool square_cells = false; ///< Even: square quadtree cells instead of anisotropic ones
  double adaptive = 0;       ///< Adaptive: the error bound (fraction of the diagonal). > 0
  int max_level = 6;         ///< Adaptive: finest level
  bool quads = false;        ///< Uniform: write the grid cells as quads (OBJ only)
  bool pattern_diagonals = false;  ///< Uniform: the fixed diagonal pattern instead of the best angle
  double grid_relax = 0;     ///< Uniform: grid relaxation, in [0, remesh::kMaxGridRelax]
  std::string format = "obj";  ///< "obj" or "ply"
  bool error = false;        ///< measure every output against its original (Metro)
  long metro_samples = 20000;  ///< with error: samples per direction (0: qs-metro's full count)
};

/// \throws UsageError naming what does not fit (modes, levels, quads without OBJ, ...).
void validate_config(const RemeshConfig& config);

/// The remeshes of a dissected set, ready to be written.
struct RemeshResult {
  RemeshConfig config;
  std::filesystem::path dissection_folder;  ///< where the dissection was read (remesh.json names it)
  std::vector<std::filesystem::path> inputs;  ///< its dissection.json and charts (never overwritten)
  remesh::SemiRegularSet set;
  std::vector<std::string> outputs;  ///< file names, per mesh
  std::string report;                ///< the text report (deterministic: no times)
  double metro_seconds = 0, quality_seconds = 0;
  /// remesh.json's per-mesh and mode objects (JSON text), assembled by write_remesh.
  std::vector<std::string> mesh_json;
  std::string mode_json;
};

/// Remeshes a dissected set (read from `dissection_folder`) with one face list for all its
/// meshes, and measures the results (smallest angles, vertex density; the Metro error with
/// config.error). \throws UsageError for a bad configuration or a level the mode does not reach
/// (the even remesh with anisotropic cells goes to remesh::kMaxAnisotropicLevel).
RemeshResult remesh(const dissect::LoadedDissection& dissection, const std::filesystem::path& dissection_folder,
                    const RemeshConfig& config = {}, const Context& ctx = {});

/// Writes <stem>.obj|.ply per mesh and remesh.json into `folder`, all-or-nothing.
/// \throws UsageError when a file would replace one of the dissection's files, IoError when the
/// folder cannot be written.
void write_remesh(const RemeshResult& result, const std::filesystem::path& folder);
/// The same into the staging folder of an OutputFolder the caller commits (`folder.target()`
/// is the folder remesh.json is relative to).
void write_remesh(const RemeshResult& result, OutputFolder& folder);

/// The default output folder: <dissection>/remesh-L<n>, remesh-L<n>-uniform, remesh-L<n>-square
/// or remesh-adaptive.
std::filesystem::path default_remesh_folder(const std::filesystem::path& dissection_folder, const RemeshConfig& config);

}  // namespace qs::pipeline
