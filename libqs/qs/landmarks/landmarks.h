#pragma once
// Landmarks of one mesh: 4 seeds (the corners of the seed loop) and named feature points.
//
// Two file formats:
//  - JSON: {"seeds": [r0, r1, r2, r3], "features": {"name": r, ...}}, both keys optional, where a
//    reference r is a vertex index (number), {"vertex": i}, {"point": [x, y, z]} (placed at the
//    closest surface point; the distance is reported) or {"face": f, "bary": [a, b, c]}.
//    Vertex and face ids are 0-based and refer to the mesh file as written.
//  - MeshLab PickedPoints (.pp): <point x= y= z= name=/> elements; points named seed0..seed3 are
//    the seeds, every other name is a feature; points with active="0" are skipped.

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "qs/core/mesh.h"
#include "qs/mesh/validate.h"

namespace qs::landmarks {

/// A point on the surface: a face and barycentric coordinates (non-negative, summing to 1)
/// with respect to that face's corners in the validated mesh.
struct SurfacePoint {
  int face = -1;
  std::array<double, 3> bary{1.0, 0.0, 0.0};
};

struct Landmark {
  std::string name;          ///< "seed0".."seed3" or the feature's name
  SurfacePoint where;
  int vertex = -1;           ///< the validated mesh's vertex, when the point is exactly on one
  Vec3 position = Vec3::Zero();
  double snap_distance = 0;  ///< distance from a given 3D point to the surface (0 otherwise)
};

struct Landmarks {
  std::vector<Landmark> seeds;     ///< empty (choose automatically) or exactly 4, in loop order
  std::vector<Landmark> features;  ///< sorted by name
  std::string source;              ///< the file they came from, for messages
};

struct LandmarkOptions {
  /// A {"point"} or .pp point farther than this fraction of the bounding-box diagonal from the
  /// surface is an error (it was probably picked on another mesh or in other units).
  double max_snap_fraction = 0.01;
};

enum class LandmarkFormat { Json, PickedPoints };

/// Reads a landmark file (.json or .pp by extension) for a validated mesh.
/// \throws IoError if the file cannot be read; InvalidInput naming the file and the landmark for
/// malformed files, out-of-range ids, duplicate seeds, a point too far from the surface, a seed
/// count other than 4, duplicate feature names.
Landmarks read_landmarks(const std::filesystem::path& path, const mesh::ValidationResult& mesh,
                         const LandmarkOptions& options = {});

/// The same from text; `name` is used in messages.
Landmarks parse_landmarks(std::string_view text, LandmarkFormat format, const std::string& name,
                          const mesh::ValidationResult& mesh, const LandmarkOptions& options = {});

/// `<stem>.landmarks.json` or `<stem>.pp` beside the mesh, if one exists (JSON first).
std::optional<std::filesystem::path> find_landmarks_beside(const std::filesystem::path& mesh_path);

/// The point of triangle abc closest to p, as barycentric coordinates (Ericson, Real-Time
/// Collision Detection, 5.1.5). A degenerate triangle gives its first corner.
std::array<double, 3> closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

/// The closest point of the surface to p, by a scan over the faces (landmark counts are small).
SurfacePoint closest_surface_point(const TriMesh& mesh, const Vec3& p, double* distance = nullptr);

/// The 3D position of a surface point.
Vec3 position_of(const TriMesh& mesh, const SurfacePoint& sp);

}  // namespace qs::landmarks
