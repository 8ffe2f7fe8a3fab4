#pragma once
// Non-rigid registration of one surface onto another in another pose: A is moved onto B by the
// landmarks' similarity, then deformed as rigidly as possible (cotangent ARAP, Sorkine and Alexa
// 2007) while its landmarks are held at B's and every vertex is pulled toward its nearest point of
// B facing as it does, the pull growing from stage to stage (annealed non-rigid ICP, Amberg et al.
// 2007); in the stronger stages B's points also pull their nearest points of A, so that A covers
// B's protruding parts instead of sliding off them. Each stage's local/global rounds are
// Anderson-accelerated (Peng et al. 2018). A large A
// runs the early stages on a coarser tessellation of itself, then the last on A. The registered A
// lies on B; its vertices' nearest points of B are a map A -> B that a pose change
// keeps (docs/pose-pairs.md). Pose maps through the registration: Pose.

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"

namespace qs::registration {

struct RegisterOptions {
  /// Weight of the pull toward B per stage, relative to the rigidity (a vertex's cotangent
  /// weights): small first (the limbs bend as rigid parts), then growing (the surface settles on B).
  std::vector<double> stages{1e-4, 1e-3, 1e-2, 1e-1, 1};
  int iterations = 24;  ///< local/global rounds per stage (Anderson-accelerated). \pre >= 1
  /// An A of more than twice this many faces runs every stage but the last on a tessellation of
  /// about this many faces (qs::mesh::simplify), and the last, on A, with half the rounds; a B of
  /// more than twice this many faces is pulled toward such a tessellation of it in every stage
  /// but the last two. 0: every stage on A and toward B.
  int coarse_faces = 30000;
  int threads = 0;      ///< 0: the context's; the result does not depend on it
};

/// A landmark of A and its place on B.
struct LandmarkPair {
  Vec3 on_a = Vec3::Zero();
  Vec3 on_b = Vec3::Zero();
};

/// A's surface registered onto B.
struct Registration {
  std::vector<Vec3> positions;          ///< A's vertices in B's frame, on B's surface
  std::vector<Eigen::Matrix3d> turn;    ///< per vertex of A: the rotation taking A's frame to B's there
  /// How far the registered A lies from B, both ways (qs::metro::vertex_distance: over each
  /// surface's vertices by area, each way weighing half), as fractions of B's bounding-box
  /// diagonal: mean and the 99th percentile.
  double mean_distance = 0, p99_distance = 0;
  /// The registration's isometric distortion: area-weighted mean over A's faces of the symmetric
  /// Dirichlet energy / 4 of A's face onto its registered face, scale of the similarity removed
  /// (1: isometric).
  double distortion = 1;
};

/// Registers A onto B. \pre a and b valid triangle meshes (qs::mesh::validate), at least 3
/// landmark pairs not on one line. \throws InvalidInput for fewer than 3 landmarks or
/// iterations < 1 or no stage; InternalError when the deformation's system is not positive
/// definite or a position diverges; Error(Internal "cancelled") on cancel. Deterministic on any
/// thread count.
Registration register_surface(const TriMesh& a, const TriMesh& b, const std::vector<LandmarkPair>& landmarks,
                              const RegisterOptions& options = {}, const Context& context = {});

/// A map between two frames, the frame of a first mesh (A) and the frame of another (B): the
/// landmarks' similarity, or a registration of A onto B. Points of A's surface go to B's frame
/// (forward), points on or near B's surface to A's (inverse); normals turn with them. Copies share
/// their data; const and safe to use from several threads.
class Pose {
 public:
  /// The identity.
  Pose();
  /// A similarity (a homogeneous 4x4 matrix, A -> B).
  explicit Pose(const Eigen::Matrix4d& similarity);
  /// The similarity whose inverse (B -> A) is given.
  static Pose from_inverse(const Eigen::Matrix4d& inverse);
  /// A registration of `a` onto a mesh (register_surface); `threads` build its trees (0: all
  /// hardware threads).
  Pose(const TriMesh& a, Registration registration, int threads = 1);

  bool registered() const;
  Vec3 forward(const Vec3& x) const;
  Vec3 inverse(const Vec3& y) const;
  /// A point and a normal there, moved together (one lookup); the normal turned by the local
  /// rotation (by the similarity's linear part: not unit length).
  struct Moved {
    Vec3 point, normal;
  };
  Moved forward(const Vec3& x, const Vec3& n) const;
  Moved inverse(const Vec3& y, const Vec3& n) const;

  struct Impl;

 private:
  std::shared_ptr<const Impl> impl_;
};

}  // namespace qs::registration
