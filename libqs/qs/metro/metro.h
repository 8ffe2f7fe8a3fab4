#pragma once
// Metro-style two-sided distance between two triangle surfaces (Cignoni, Rocchini, Scopigno:
// "Metro: measuring error on simplified surfaces", 1998), by sampling.
//
// One direction, A -> B: points are sampled on A and each one's exact Euclidean distance to the
// surface of B (the nearest point of any triangle of B, not the nearest vertex) is measured.
//   - Surface samples: `face_samples` points spread over A in proportion to area (systematic
//     sampling along the faces in file order, so a face gets floor or ceil of its share; the point
//     inside the face is uniformly random). They estimate the area-weighted mean and RMS distance,
//     (1/|A|) integral_A d and sqrt((1/|A|) integral_A d^2), and take part in the maximum.
//   - Vertex samples: every vertex used by a face of A. They count towards the maximum only (a
//     vertex stands for no area): Metro samples vertices because the largest distances of
//     simplified or remeshed surfaces are often at vertices. Edges are not sampled separately.
// The two-sided values take both directions together: the maximum of the two maxima (the
// sampled Hausdorff distance) and the mean and RMS over the surface samples of both directions.
// Both directions use the same number of surface samples, so the two-sided mean is the average
// of the two one-sided means and the two-sided RMS is sqrt((rms_ab^2 + rms_ba^2) / 2).
//
// Deterministic: the random numbers come from our own splitmix64 generator (not <random>'s
// distributions, which differ across standard libraries), seeded per sample from `seed`, and the
// work is cut into fixed chunks whose sums are added in order, so the results are bitwise the
// same for every thread count and run (and across machines that round doubles alike).

#include <cstdint>
#include <memory>

#include "qs/core/context.h"
#include "qs/core/mesh.h"

namespace qs::metro {

struct MetroOptions {
  /// Surface samples per direction; 0 chooses max(min_samples, samples_per_face * max(#F of A,
  /// #F of B)). \pre >= 0.
  long face_samples = 0;
  double samples_per_face = 2.0;  ///< for the automatic count. \pre finite and >= 0
  long min_samples = 100000;      ///< for the automatic count. \pre >= 1
  bool sample_vertices = true;    ///< also measure at every used vertex (maximum only)
  /// With sample_vertices: B's vertices too. Turn off when they lie on A's surface by
  /// construction (a remesh sampled on A: their distances are 0 up to rounding), which saves
  /// one query per vertex of B; B -> A then reports vertex_samples = 0.
  bool sample_vertices_b = true;
  std::uint64_t seed = 1;         ///< same seed, same samples, same numbers
  /// Worker threads; 0 = Context::threads. Does not change the results.
  int threads = 0;
};

/// One direction, from the samples of one mesh to the surface of the other. Absolute distances,
/// in the meshes' units.
struct OneSided {
  double mean = 0;  ///< area-weighted mean over the surface samples
  double rms = 0;   ///< area-weighted root mean square over the surface samples
  double max = 0;   ///< over the surface and vertex samples
  Vec3 max_at = Vec3::Zero();  ///< a sample point (on the sampled mesh) where `max` is reached
  long samples = 0;         ///< surface samples (those behind mean and rms)
  long vertex_samples = 0;  ///< vertices measured (0 when sample_vertices is off)
};

struct MetroResult {
  OneSided a_to_b;  ///< samples on A, distances to B
  OneSided b_to_a;  ///< samples on B, distances to A
  double max = 0;   ///< two-sided (sampled Hausdorff): max(a_to_b.max, b_to_a.max)
  double mean = 0;  ///< over the surface samples of both directions
  double rms = 0;   ///< over the surface samples of both directions
  /// Bounding-box diagonal of mesh A (of the vertices its faces use): the length that
  /// percentages are taken of, e.g. 100 * max / diagonal. Always A's, never B's or the union's.
  double diagonal = 0;
  double area_a = 0, area_b = 0;  ///< surface areas
};

/// Samples both meshes and measures the distance from each to the other.
/// Meshes need not be closed, manifold, oriented or connected; degenerate (zero-area) faces are
/// measured as their edges and get no surface samples; unreferenced vertices are ignored.
/// \pre each mesh has at least one face, every face index is in [0, #V), the vertices used by
///      faces have finite coordinates, and the total area is positive and finite.
/// \throws InvalidInput naming the mesh ("A" or "B") and the first offending faces or vertices
///         when a precondition fails, or for an option out of range; Error (Internal,
///         "cancelled") when ctx.cancel is raised. Progress: stages "metro A -> B", "metro B -> A".
MetroResult metro(const TriMesh& a, const TriMesh& b, const MetroOptions& options = {},
                  const Context& ctx = {});

/// Exact closest-point queries to a fixed triangle surface (a bounding-volume hierarchy over its
/// faces). Built once, then const and safe to query from several threads.
/// \pre as for metro(): at least one face, indices in range, finite coordinates of used vertices.
/// \throws InvalidInput when a precondition fails (messages name the mesh as `name`).
class SurfaceDistance {
 public:
  /// `threads`: the build's for a large mesh (0: all hardware threads); the same tree on any count.
  explicit SurfaceDistance(const TriMesh& mesh, const char* name = "mesh", int threads = 1);
  ~SurfaceDistance();
  SurfaceDistance(SurfaceDistance&&) noexcept;
  SurfaceDistance& operator=(SurfaceDistance&&) noexcept;

  struct Closest {
    double distance = 0;  ///< Euclidean distance from the query to the surface
    Vec3 point = Vec3::Zero();  ///< the nearest surface point
    int face = -1;        ///< a face the nearest point lies on
  };
  Closest closest(const Vec3& query) const;
  /// The nearest point among the faces whose unit normal n has dot(n, facing / |facing|) >=
  /// min_cos (degenerate faces never count): a nearest point that keeps to the query's side of a
  /// thin part (two fingers, a lip) when `facing` is the query's own normal. face -1 and an
  /// infinite distance when no face qualifies or `facing` is zero.
  Closest closest_facing(const Vec3& query, const Vec3& facing, double min_cos) const;
  /// The same, with the last query's answer tried first (`hint`: -1 at first, then kept from
  /// call to call; the same point, faster for a query near the last one's).
  Closest closest_facing(const Vec3& query, const Vec3& facing, double min_cos, int& hint) const;
  double distance(const Vec3& query) const { return closest(query).distance; }
  /// The same faces moved to the positions of `mesh` (a deforming surface): the boxes are refit,
  /// the tree kept, so queries stay exact (slower when the surface has moved far) and hints stay
  /// valid. \throws InvalidInput for another face count or a bad position.
  void refit(const TriMesh& mesh);

  struct Impl;  ///< implementation detail (metro() shares it)

 private:
  std::unique_ptr<Impl> impl_;
};

/// Two surfaces' distance measured at their vertices: each vertex of one (with its area share, a
/// third of its faces' areas) at its distance to the other, both ways, each way weighing half.
struct VertexDistance {
  double mean = 0;      ///< the area-weighted mean
  double quantile = 0;  ///< the distance that `fraction` of the weight lies within
};
/// `to_a` and `to_b` are a's and b's trees. Parallel on the context's threads; the same result on
/// any thread count. Zero for a surface without area.
VertexDistance vertex_distance(const TriMesh& a, const SurfaceDistance& to_a, const TriMesh& b,
                               const SurfaceDistance& to_b, double fraction, const Context& ctx = {});

}  // namespace qs::metro
