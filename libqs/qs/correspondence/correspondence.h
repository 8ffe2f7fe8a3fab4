#pragma once
// How good is a dissection's correspondence? Measured against ground truth.
//
// Ground truth: every mesh of a set maps exactly to one common domain (README "Correspondence"):
//  - "sphere" map files (qs-family generate): a point with weights b on face (p, q, r) has the
//    parameter normalize(b0 s_p + b1 s_q + b2 s_r); its image on another mesh is the point of that
//    mesh's parameter triangulation that the ray through the parameter crosses (a bijection);
//  - identical connectivity (no map file): a point (face, bary) is the same (face, bary) on the
//    other mesh;
//  - "surface" map files (qs-family retessellate): every vertex sits exactly on a point of a
//    reference mesh whose connectivity is the domain; a point between vertices maps to its closest
//    point of the reference (and back, a reference point to its closest point of the mesh). Exact
//    at the vertices; between them the error of this rule is at most the re-tessellation's chord
//    distance from the reference (reported as `truth_tolerance`).
//
// The measure, for a pair (A, B) of a dissected set: points sampled uniformly per unit area on A
// (its chart, which is A's surface), each mapped through the dissection (A's chart gives the patch
// and (u,v); B's chart gives the 3D point at the same (patch, u, v), by remesh::ChartSampler) and
// compared with its exact image on B. Errors in % of B's bounding-box diagonal; the share of A's
// area whose exact image lies in the same-numbered patch of B; and, beside it, a baseline: A moved
// onto B by the least-squares similarity of the landmarks (Umeyama; the dissection's seeds and
// features), then each point's nearest point of B.

#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"
#include "qs/dissect/dissection.h"
#include "qs/family/family.h"
#include "qs/family/surface_map.h"
#include "qs/landmarks/landmarks.h"

namespace qs::correspondence {

/// One mesh with its ground-truth map, ready to use: everything refers to the VALIDATED mesh.
struct TruthMesh {
  std::string name;                          ///< for messages (the mesh file)
  TriMesh mesh;                              ///< validated
  std::optional<family::SurfaceMap> map;     ///< per validated vertex; nullopt: identity
  TriMesh reference;                         ///< "surface" maps: the validated reference mesh
};

/// Reads a mesh (validated; a rejected mesh is an InvalidInput with the report) and, when
/// `map_file` is given, its map file ("surface": the reference is read too, relative to the map
/// file's folder). \throws IoError, InvalidInput (counts that disagree, naming both files).
TruthMesh load_truth_mesh(const std::filesystem::path& mesh_file,
                          const std::optional<std::filesystem::path>& map_file);

/// The exact correspondence between the meshes of a set.
class GroundTruth {
 public:
  /// \throws InvalidInput when the meshes do not share one domain: sphere maps mixed with
  /// connectivity domains, or connectivity domains (a mesh without map, a reference) whose face
  /// lists differ — naming the meshes.
  explicit GroundTruth(std::vector<TruthMesh> meshes);
  ~GroundTruth();
  GroundTruth(GroundTruth&&) noexcept;
  GroundTruth& operator=(GroundTruth&&) noexcept;

  int size() const;
  const TruthMesh& mesh(int i) const;
  /// The exact image on mesh b (validated) of the point p of mesh a. Thread-safe.
  landmarks::SurfacePoint map(int a, int b, const landmarks::SurfacePoint& p) const;
  /// Upper bound of the truth's own interpolation error between vertices, as a length: 0 for
  /// sphere maps and identical connectivity; for surface maps the largest Metro distance between
  /// a mapped mesh and its reference (sampled).
  double tolerance() const;
  /// The mean of that distance over the surface (sampled; 0 without surface maps).
  double tolerance_mean() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

struct MeasureOptions {
  long samples = 100000;     ///< points sampled on A, uniformly per unit area. \pre >= 1
  std::uint64_t seed = 1;    ///< same seed, same points, same numbers
  int threads = 0;           ///< 0: all cores; the results do not depend on it
  /// 0: the dissection's continuous map (B's chart at (patch, u, v)); n >= 1: through B's uniform
  /// level-n common remesh, the point of its grid triangle at (u, v) (qs-remesh's diagonal rule,
  /// grid vertices evaluated on B's chart), i.e. where that remesh puts the point. \pre 0..12
  int level = 0;
  /// Also measure at every vertex of A's (validated) mesh: PairMeasure::vertex_error,
  /// vertex_baseline_error, vertex_patch and vertex_exact_patch, for an error map (write_error_map)
  /// or a list of the worst vertices (worst_vertices).
  bool vertex_errors = false;
};

/// Distances in % of B's bounding-box diagonal.
struct ErrorStats {
  double mean = 0, median = 0, p95 = 0, max = 0;
};

struct PairMeasure {
  int a = 0, b = 0;               ///< mesh indices in the set
  int level = 0;                  ///< MeasureOptions::level
  long samples = 0;
  double diagonal = 0;            ///< of B's chart (the length the percentages refer to)
  ErrorStats dissection;          ///< the dissection's map A -> B vs the exact image
  ErrorStats baseline;            ///< similarity on the landmarks + nearest point of B
  /// At level n >= 1, the remesh's own share: each sample's exact image against the point of B's
  /// level-n remesh at that image's own (patch, u, v) on B's chart, i.e. the error an exact map
  /// would have through this remesh (zero at level 0).
  ErrorStats remesh;
  double same_patch_share = 0;    ///< share of A's area whose exact image is in the same patch of B
  /// Distance between corresponding patch corners: the exact image on B of each of A's patch
  /// corners (base-domain vertices) against B's corner of the same (patch, corner), in % of the
  /// diagonal; mean and max over the corners.
  double corner_mean = 0, corner_max = 0;
  int baseline_landmarks = 0;     ///< landmark pairs the similarity used
  double truth_tolerance = 0;     ///< GroundTruth::tolerance() in % of the diagonal
  double truth_tolerance_mean = 0;  ///< GroundTruth::tolerance_mean() in % of the diagonal
  /// Isometric distortion of the two maps A -> B, each seen on A's input faces (on B's, of the maps
  /// B -> A, when B's truth is a "surface" map onto A: exact at B's vertices, not at A's): the
  /// linear map of a face onto the triangle of its three vertices' images (the dissection's by the
  /// charts, at level 0 whatever `level`, and the exact one), scaled to equal areas: the
  /// area-weighted mean and median of symDirichlet / 4 (1: an isometry up to the meshes' size; the
  /// energy the map refinement lowers, without its per-patch scale). An image triangle that is
  /// degenerate or turned against the surface normals at its corners' images is counted in
  /// `*_folded` and left out. A truth less distorted than the dissection's map is one that an
  /// isometric refinement could move toward; a truth more distorted is not the least distorted
  /// map (README, "Correspondence").
  bool distortion_on_b = false;  ///< seen on B's faces (maps B -> A), see above
  double distortion = 0, distortion_median = 0, truth_distortion = 0, truth_distortion_median = 0;
  int distortion_folded = 0, truth_distortion_folded = 0;
  /// With MeasureOptions::vertex_errors, per vertex of A's validated mesh (else empty), in % of the
  /// diagonal: the dissection's map at the vertex (through A's chart wedge of the vertex's first
  /// chart face, as `level` says) against its exact image, and the baseline's error there.
  std::vector<double> vertex_error, vertex_baseline_error;
  /// With MeasureOptions::vertex_errors, per vertex of A's validated mesh (else empty; -1 for an
  /// unused vertex): the patch of the vertex's first chart face on A (the one its error is measured
  /// through), and the patch of B's chart face nearest to its exact image. Different patches mark a
  /// point that the patch layout itself puts on the wrong side of a patch border.
  std::vector<int> vertex_patch, vertex_exact_patch;
};

/// A's vertices with the largest dissection error, at most `count`, largest first (ties by vertex
/// id: deterministic). \pre measure.vertex_error is filled (MeasureOptions::vertex_errors); count >= 0.
std::vector<int> worst_vertices(const PairMeasure& measure, int count);

/// One dissected mesh as the measure needs it: its chart (whose first vertices are the validated
/// mesh's) and its landmark positions by name (seeds "seed0".."seed3", features by name).
struct DissectedInput {
  const dissect::Chart* chart = nullptr;
  std::vector<std::pair<std::string, Vec3>> landmarks;
};

/// Landmark positions of a dissected mesh: its seeds (chart vertices) and features.
std::vector<std::pair<std::string, Vec3>> dissection_landmarks(const dissect::Dissection& d);

/// Measures the pair (a, b). \pre truth.mesh(i).mesh has the positions of inputs[i].chart's first
/// vertices (checked: InvalidInput naming the mesh when a mesh is not the one dissected); the
/// charts have the same patches. \throws InvalidInput, Error(Internal "cancelled").
/// Progress stage: "correspondence".
PairMeasure measure_pair(const GroundTruth& truth, const std::vector<DissectedInput>& inputs, int a, int b,
                         const MeasureOptions& options = {}, const Context& context = {});

/// The colour of an error on the error map's ramp (blue 0, cyan, green, yellow, red at `scale` and
/// beyond). \pre scale > 0.
std::array<unsigned char, 3> error_colour(double error, double scale);

/// Writes A's mesh with the pair's per-vertex errors as a binary little-endian PLY (atomically):
/// per vertex x, y, z (double), `error` and `baseline_error` (float, % of B's diagonal) and the
/// error's colour (uchar red, green, blue, error_colour at `scale`); the faces as in `mesh`.
/// \pre measure.vertex_error and vertex_baseline_error have one value per vertex of `mesh`
/// (InvalidInput otherwise), scale > 0. \throws IoError when the file cannot be written.
void write_error_map(const std::filesystem::path& path, const TriMesh& mesh, const PairMeasure& measure,
                     double scale);

/// A generated shape as qs-dissect takes it: its seeds as surface points (inserted exactly) and its
/// limb tips as named features. The mesh is referred to, not copied.
dissect::MeshToDissect dissect_input(const family::FamilyShape& shape);

}  // namespace qs::correspondence
