#pragma once
// Validation of a triangle soup as qs's input: closed, manifold, one component, genus 0.
// Every problem is collected (not just the first), each with a count and the first element ids.
//
// The problem kinds, in the order they appear in ValidationReport::problems. Ids always refer to
// the INPUT mesh (input face ids, input vertex ids), never to the renumbered output. For the edge
// kinds an id is a vertex pair (lower id first), stored flattened: first_ids = {a0, b0, a1, ...}.
//
//   Fatal
//   empty                    no faces at all, or none left to check once faces with an invalid or
//                            repeated index are skipped. count: 1; ids: none
//   invalid_vertex_index     faces with an index < 0 or >= #V. ids: faces. Those faces are dropped
//                            from all further checks and from the output mesh.
//   non_finite_coordinates   vertices used by a face with a NaN or infinite coordinate, or one of
//                            magnitude above kMaxCoordinate = 1e100 (qs/core/finite.h: lengths,
//                            areas and volumes must stay finite). ids: vertices. Faces touching
//                            them skip the geometric checks; bbox_diagonal is then always finite.
//   repeated_index_faces     faces that use one vertex twice, e.g. (4, 4, 9). ids: faces. Skipped
//                            by the checks below (they stay in the output mesh).
//   duplicate_faces          faces with the same vertex set as an earlier face, in any order and
//                            either orientation. ids: the later copies. The copies are skipped by
//                            the checks below (they stay in the output mesh).
//   non_manifold_edges       edges with more than two faces. ids: vertex pairs.
//   non_manifold_vertices    vertices whose faces form more than one fan (a "bowtie": two surfaces
//                            meeting at one point; faces around a non-manifold edge count as one
//                            fan). ids: vertices.
//   inconsistent_orientation edges whose two faces both run a->b: a mis-oriented neighbour or a
//                            non-orientable surface. ids: vertex pairs.
//   boundary_edges           edges with a single face: the mesh is open. ids: vertex pairs;
//                            report.boundary_loop_sizes has the edge count of each hole.
//   multiple_components      more than one connected part (connected through shared vertices).
//                            count: the number of parts; ids: the smallest face id of each part.
//   genus                    closed, manifold, oriented, but not a sphere: count = genus (one
//                            part), or the number of parts with a non-zero genus. ids: none.
//                            A Note instead when ValidateOptions::allow_any_genus is set.
//   Note (fixed in the output)
//   unreferenced_vertices    vertices used by no face (faces with an invalid index aside);
//                            dropped and the rest renumbered in order (see vertex_map).
//                            ids: vertices.
//   orientation_flipped      the closed mesh had a negative signed volume: every face was flipped.
//                            count: faces flipped. ids: none.
//   Warning (accepted anyway)
//   zero_area_faces          faces with area <= zero_area_relative * bbox_diagonal^2. ids: faces.
//   tiny_angles              non-zero-area faces whose smallest corner angle is below
//                            tiny_angle_degrees. ids: faces.

#include <string>
#include <string_view>
#include <vector>

#include "qs/core/mesh.h"

namespace qs::mesh {

enum class Severity {
  Note,   ///< fixed automatically (unreferenced vertices dropped, orientation flipped)
  Warning,///< accepted, but worth knowing (tiny angles, zero-area faces)
  Fatal,  ///< the mesh is rejected
};

/// One kind of problem, e.g. kind = "non_manifold_edges".
struct Problem {
  std::string kind;        ///< stable snake_case identifier (used in --json output)
  Severity severity = Severity::Fatal;
  long long count = 0;     ///< how many elements have it
  std::vector<long long> first_ids;  ///< the first (lowest) up to 10 elements: vertex or face
                                     ///< ids, or for edge kinds 10 vertex pairs flattened (20 ids)
  std::string message;     ///< one human sentence with the count and first ids
};

struct ValidationReport {
  int input_vertices = 0, input_faces = 0;
  int vertices = 0, faces = 0, edges = 0;  ///< of the output mesh; edges (and V-E+F) leave out
                                           ///< repeated-index and duplicate faces
  int components = 0;
  std::vector<int> boundary_loop_sizes;    ///< edge count of each boundary loop (loops through a
                                           ///< non-manifold vertex are cut where they revisit it)
  int euler_characteristic = 0;            ///< V - E + F
  int genus = -1;                          ///< -1 if undefined (non-manifold, open, several parts)
  bool orientation_flipped = false;        ///< the mesh was inward and was flipped
  double min_angle_degrees = 0;            ///< smallest corner angle over non-zero-area faces with
                                           ///< finite coordinates (0 when there are none)
  double bbox_diagonal = 0;                ///< of the finite positions of the output mesh
  double signed_volume = 0;                ///< after any flip; 0 unless closed, manifold, oriented
                                           ///< and finite
  std::vector<Problem> problems;
  bool accepted = false;                   ///< closed, manifold, one component, genus 0 (any genus
                                           ///< with allow_any_genus), finite
};

struct ValidateOptions {
  double tiny_angle_degrees = 1.0;  ///< below this, a Warning is reported (never a rejection)
  double zero_area_relative = 1e-12;  ///< area <= this * bbox_diagonal^2 counts as zero (Warning)
  /// When true, a closed surface of genus > 0 is accepted: "genus" becomes a Note (still reported,
  /// with the genus in report.genus) instead of Fatal. Only qs-dfi sets it; the default keeps
  /// every other tool's genus-0 requirement.
  bool allow_any_genus = false;
};

struct ValidationResult {
  TriMesh mesh;             ///< cleaned: unreferenced vertices dropped, outward orientation
  ValidationReport report;
  /// #input V: input vertex id -> output vertex id, -1 for a dropped (unreferenced) vertex.
  /// Kept vertices keep their relative order. Faces keep their ids; when the orientation is
  /// flipped, every face has its corners 1 and 2 swapped. (The one exception: faces with an
  /// invalid_vertex_index, a Fatal problem, are left out of the output and later faces move up.
  /// Repeated-index and duplicate faces stay in the output, but are skipped by the checks.)
  std::vector<int> vertex_map;
};

/// Checks a triangle soup. Never throws for a bad mesh: the verdict is in report.accepted.
/// O(F) apart from small per-vertex sorts, no maps or sets: a 100k-face mesh takes ~15 ms.
ValidationResult validate(const TriMesh& input, const ValidateOptions& options = {});

/// A multi-line human summary of the report (what `qs-inspect` prints): counts, components,
/// genus, boundary loops, min angle, one line per problem, and a last line that is either
/// "accepted" or "rejected: <the Fatal kinds, comma separated>".
std::string format_report(const std::string& name, const ValidationReport& report);

/// The problem of the given kind in the report, or null.
const Problem* find_problem(const ValidationReport& report, std::string_view kind);

/// Signed volume enclosed by the faces, positive when a closed mesh faces outward (computed about
/// the bounding-box centre for accuracy). \pre every index is in range.
double signed_volume(const TriMesh& mesh);

}  // namespace qs::mesh
