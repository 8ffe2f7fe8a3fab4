#pragma once
// Validation of a triangle soup as qs's input: closed, manifold, one component, genus 0.
// Every problem is collected (not just the first), each with a count and the first element ids.

#include <string>
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
  std::vector<long long> first_ids;  ///< up to 10 ids (vertex, face or edge-vertex pairs as documented per kind)
  std::string message;     ///< one human sentence with the count and first ids
};

struct ValidationReport {
  int input_vertices = 0, input_faces = 0;
  int vertices = 0, faces = 0, edges = 0;  ///< after dropping unreferenced vertices
  int components = 0;
  std::vector<int> boundary_loop_sizes;    ///< edge count of each boundary loop
  int euler_characteristic = 0;            ///< V - E + F
  int genus = -1;                          ///< -1 when undefined (non-manifold / open / several parts)
  bool orientation_flipped = false;        ///< the mesh was inward and was flipped
  double min_angle_degrees = 0;            ///< smallest corner angle over non-degenerate faces
  double bbox_diagonal = 0;
  std::vector<Problem> problems;
  bool accepted = false;                   ///< closed, manifold, one component, genus 0, finite
};

struct ValidateOptions {
  double tiny_angle_degrees = 1.0;  ///< below this, a Warning is reported (never a rejection)
};

struct ValidationResult {
  TriMesh mesh;             ///< cleaned: unreferenced vertices dropped, outward orientation
  ValidationReport report;
};

/// Checks a triangle soup. Never throws for a bad mesh: the verdict is in report.accepted.
ValidationResult validate(const TriMesh& input, const ValidateOptions& options = {});

/// A multi-line human summary of the report (what `qs-inspect` prints).
std::string format_report(const std::string& name, const ValidationReport& report);

}  // namespace qs::mesh
