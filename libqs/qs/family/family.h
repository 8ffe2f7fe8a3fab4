#pragma once
// A family of smooth genus-0 shapes with limbs and an exact map between any two of them, for the
// set-dissection tests and the correspondence benchmark.
//
// Every shape is the image of the unit sphere under its own smooth map S_i: S^2 -> R^3,
//   S_i(d) = G_i( r_i(d) d + sum_k bend_ik(d) ),
// where r_i is a radial function (an ellipsoidal body, one Gaussian spike per limb along a limb
// direction a_k that is COMMON to the family, bulges), bend_ik pushes limb k sideways in
// proportion to the square of its extension, and G_i is a global smooth deformation (anisotropic
// scale, a twist about the body axis, a small sine wave). The parameter d is the correspondence:
// the point S_i(d) of shape i corresponds to S_j(d) of shape j, and the limb tips sit at d = a_k
// in every shape.
//
// Each shape has its own tessellation: points on the parameter sphere, sampled with a density
// proportional to the area element of S_i (so thin limbs get as many points per unit area as the
// body) with a minimum spacing (dart throwing), triangulated as their convex hull (the spherical
// Delaunay triangulation), each vertex then placed at S_i(d). The exact piecewise map of a mesh
// to the sphere is: a point with barycentric weights b on face (p, q, r) has the parameter
// normalize(b0 d_p + b1 d_q + b2 d_r) (central projection of the flat parameter triangle, a
// bijection since the parameter mesh is a convex polyhedron around the origin). See
// correspondence/ground_truth.h for its inverse.
//
// Everything is deterministic from (seed, options): the same arguments give the same bytes.

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"
#include "qs/landmarks/landmarks.h"

namespace qs::family {

struct FamilyOptions {
  int shapes = 4;            ///< N shapes. \pre 1 <= shapes <= 256
  std::uint64_t seed = 1;    ///< the family's random seed: limbs, their directions and every warp
  int faces = 8000;          ///< faces per shape (exactly; V = faces / 2 + 2). \pre even, 200..2000000
  /// Limbs: 4 legs, 5 adds a head, 6 adds a tail; 0 = chosen by the seed in 4..6. \pre 0 or 4..6
  int limbs = 0;
  /// Scales every per-shape deviation from the common base (limb lengths and thickness, bends,
  /// bulges, global deformation): 0 gives N identical surfaces (still tessellated differently),
  /// 1 the default variety. \pre 0 <= variation <= 2
  double variation = 1.0;
};

/// One named point on a shape: a face of its mesh and barycentric weights of the face's corners
/// (never exactly at a vertex unless the parameter falls on one), and its parameter.
struct FamilyLandmark {
  std::string name;
  landmarks::SurfacePoint where;
  Vec3 parameter = Vec3::Zero();  ///< on the unit sphere (common to the family)
};

struct FamilyShape {
  std::string name;                   ///< "shape00", "shape01", ...
  TriMesh mesh;                       ///< closed, manifold, genus 0, outward-oriented
  std::vector<Vec3> parameters;       ///< #V: each vertex's point on the unit sphere
  std::vector<FamilyLandmark> seeds;  ///< 4, in loop order: a belt around the body's middle
  std::vector<FamilyLandmark> features;  ///< the limb tips, sorted by name
};

struct Family {
  FamilyOptions options;
  int limbs = 0;                      ///< the limb count used
  std::vector<std::string> limb_names;  ///< feature names, in limb order
  std::vector<FamilyShape> shapes;
};

/// Generates the family. Shapes are made in parallel (Context::threads); the result does not depend on
/// the thread count. \throws InvalidInput for an option out of range (naming it), InternalError if
/// a generated mesh fails its own checks (a bug). Progress stage: "family".
Family generate_family(const FamilyOptions& options = {}, const Context& context = {});

/// The same shapes, for families too large to hold at once: made in batches of the thread count,
/// each handed to `sink` in index order (and dropped) before the next batch starts, so that at
/// most one batch is in memory. Returns the family without its shapes. \throws as above, and
/// whatever `sink` throws (the shapes after it are not made).
Family generate_family(const FamilyOptions& options, const Context& context,
                       const std::function<void(FamilyShape&&)>& sink);

/// The smooth surface of shape `index` of the family at the unit parameter d (the map S_i above).
/// \pre 0 <= index < options.shapes.
Vec3 family_surface_point(const FamilyOptions& options, int index, const Vec3& d);

/// `<stem>.landmarks.json` text for a shape (the format qs-dissect reads): the seeds and features
/// as {"face": f, "bary": [a, b, c]}, numbers written so that they read back exactly.
std::string landmarks_json(const FamilyShape& shape);

}  // namespace qs::family
