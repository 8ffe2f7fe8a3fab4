#pragma once
// The plain indexed triangle mesh that travels between stages.

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products are used everywhere
#include <array>
#include <string>
#include <vector>

namespace qs {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Tri = std::array<int, 3>;

/// An indexed triangle mesh: #V positions and #F triangles of 0-based vertex ids.
/// Nothing about it is assumed (it may be open, non-manifold, inconsistently oriented);
/// qs::mesh::validate() says what it is.
struct TriMesh {
  std::vector<Vec3> positions;  ///< #V
  std::vector<Tri> faces;       ///< #F, counter-clockwise seen from outside once validated
  int num_vertices() const { return static_cast<int>(positions.size()); }
  int num_faces() const { return static_cast<int>(faces.size()); }
};

/// Axis-aligned bounding box of the positions (empty mesh: both corners zero).
struct Box3 {
  Vec3 min = Vec3::Zero();
  Vec3 max = Vec3::Zero();
  double diagonal() const { return (max - min).norm(); }
};
Box3 bounding_box(const std::vector<Vec3>& positions);

/// The area of face f (always >= 0).
double face_area(const TriMesh& mesh, int f);
/// The sum of the face areas (in face order: deterministic).
double surface_area(const TriMesh& mesh);

/// Area-weighted vertex normals (the sum of the faces' cross products, normalized). A vertex
/// whose sum vanishes (no faces, or only degenerate ones) gets (0, 0, 1).
/// \pre faces index into positions.
std::vector<Vec3> vertex_normals(const std::vector<Vec3>& positions, const std::vector<Tri>& faces);

/// The least-squares transform (Umeyama) taking the points `from` onto `to`, paired by index:
/// rotation and translation, and a uniform scale when `with_scale`; as a homogeneous 4x4 matrix.
/// \pre from.size() == to.size() (fewer than 3 points do not determine it).
Eigen::Matrix4d fit_similarity(const std::vector<Vec3>& from, const std::vector<Vec3>& to, bool with_scale = true);

}  // namespace qs
