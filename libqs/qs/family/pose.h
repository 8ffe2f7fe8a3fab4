#pragma once
// A mesh in another pose with the same connectivity, so that the map between the two is exact
// (vertex i <-> vertex i; a point (face, bary) <-> the same (face, bary)): for correspondence
// pairs with ground truth on real shapes (README "Correspondence", docs/pose-pairs.md).
//
// The extremities are found without knowing the shape: geodesic farthest points, each moved uphill
// on the geodesic distance from the set's geodesic median (the core) to a local maximum. An
// extremity is a limb when the vertices within a geodesic radius R of it (R = half its distance
// from the core, shrunk until it holds) form a disc whose border is under 0.45 * 2 pi r (r: the
// border's mean geodesic distance from the tip; a protrusion, not a patch of a flat side; 0.6 when
// fewer than 3 limbs are found so) and hold under 30% of the area. A pose rotates each limb's
// outer half (the vertices within R / 2 of the tip: the handle) rigidly about a pivot at the
// limb's root (the border's centroid), about an axis across the limb (a bent joint) or along it (a
// turned head); the rest of the limb (R / 2 .. R) is deformed as rigidly as possible (CGAL
// Surface_mesh_deformation, spokes and rims), everything beyond R stays in place. A limb whose
// result folds a face or makes the surface cross itself is tried with the other turn, then at
// smaller angles, and left out below the smallest.

#include <cstdint>
#include <string>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"

namespace qs::family {

enum class PoseKind {
  Mixed,  ///< per limb, seeded: a bend (3 in 4) or a turn about the limb's own axis
  Bend,   ///< every limb bent about an axis across it
  Twist,  ///< every limb turned about its own axis
};

struct PoseOptions {
  std::uint64_t seed = 1;           ///< the same seed and mesh give the same pose (bytes)
  PoseKind kind = PoseKind::Mixed;
  int limbs = 0;                    ///< how many limbs to pose (seeded choice); 0: all. \pre >= 0
  double min_angle_deg = 30;        ///< each limb's angle is drawn in [min, max]. \pre 5 <= min <= max <= 120
  double max_angle_deg = 60;
  double smallest_angle_deg = 15;   ///< a limb that cannot be posed at this angle is left out. \pre > 0, <= min
};

/// An extremity: a vertex at a local maximum of the geodesic distance from the core.
struct Extremity {
  int vertex = -1;
  double prominence = 0;   ///< its geodesic distance from the core
  double limb_radius = 0;  ///< R of its limb (geodesic); 0 when it is not a limb
};

/// The extremities: the limbs' tips, then the others, each most prominent first (ties by vertex
/// id), at most `max_count`. Deterministic.
/// \pre `mesh` is closed, manifold, genus 0 (validated); max_count >= 1.
std::vector<Extremity> find_extremities(const TriMesh& mesh, int max_count = 8);

/// Automatic landmarks at extremities (vertex ids): 4 seeds, the first 4 extremities (above) in
/// the cyclic order of their shortest loop (geodesic, most prominent first), and 2..6 features:
/// the next extremities, then geodesic farthest points from those chosen, named "tip4", "tip5"...
struct PoseLandmarks {
  std::vector<int> seeds;
  std::vector<std::pair<std::string, int>> features;
};
PoseLandmarks choose_landmarks(const TriMesh& mesh);

/// The cyclic order of four vertices whose closed geodesic loop through them is shortest,
/// starting at the first. \pre seeds.size() == 4.
std::vector<int> shortest_loop_order(const TriMesh& mesh, const std::vector<int>& seeds);

struct PosedLimb {
  int tip = -1;
  double radius = 0;          ///< R: vertices within it move, the others do not
  Vec3 pivot = Vec3::Zero();  ///< the rotation's centre, at the limb's root
  Vec3 axis = Vec3::Zero();   ///< unit
  double angle_deg = 0;       ///< as applied (signed, about `axis`)
  bool twist = false;         ///< turned about its own axis (else bent)
  std::vector<int> handle;    ///< vertices moved rigidly, ascending
  std::vector<int> region;    ///< vertices that move (handle included), ascending
};

struct Pose {
  TriMesh mesh;                  ///< the input's faces; positions posed
  std::vector<PosedLimb> limbs;  ///< the limbs posed (those left out are not listed)
  int limbs_found = 0;           ///< limbs found on the mesh
  int limbs_dropped = 0;         ///< limbs that could not be posed without folds or crossings
  int input_self_intersections = 0;  ///< intersecting face pairs of the input (their faces excused)
  double max_handle_error = 0;   ///< largest distance of a handle vertex from its rigid target
};

/// Poses `mesh` (see the file comment). Afterwards no face is folded against an edge neighbour
/// that it did not fold against before (normals turned more than 90 degrees apart where they were
/// within 60), no face shrinks to under 1e-3 of its area, and no two faces cross that did not
/// cross any face in the input (CGAL Polygon_mesh_processing::self_intersections).
/// \pre `mesh` is closed, manifold, genus 0, outward (validated). \throws InvalidInput for options
/// out of range, SolverError when the mesh has no limb or none can be posed. Progress stage: "pose".
Pose pose_mesh(const TriMesh& mesh, const PoseOptions& options = {}, const Context& context = {});

/// Faces of `posed` folded against an edge neighbour relative to `rest` (the test pose_mesh
/// applies) or shrunk under 1e-3 of their area. \pre the same faces.
std::vector<int> folded_faces(const TriMesh& rest, const TriMesh& posed);

}  // namespace qs::family
