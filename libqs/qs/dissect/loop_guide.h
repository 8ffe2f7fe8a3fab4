#pragma once
// One seed loop for the set: every mesh's loop routed to follow the first mesh's by intrinsic
// coordinates (distances along the surface to the landmarks), which a change of pose keeps.

#include <array>
#include <utility>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"
#include "qs/dissect/seed_loop.h"

namespace qs::dissect {

/// Per vertex, its edge-path distances to the landmark vertices, divided by the square root of
/// the surface area: #V rows of `landmarks` numbers (row-major). Unreachable: +infinity.
struct GeodesicCoordinates {
  int dims = 0;
  std::vector<double> values;
  const double* at(int v) const { return values.data() + static_cast<size_t>(v) * dims; }
};

/// \pre landmarks index into mesh.positions. The landmarks in parallel on the context's threads
/// (the same values on any thread count).
GeodesicCoordinates geodesic_coordinates(const TriMesh& mesh, const std::vector<int>& landmarks,
                                         const Context& context = {});

/// How far two meshes are from one shape in two poses: their landmarks' geodesic distances to each
/// other (a and b: coordinates of the landmark vertices la and lb, in the same order) differ by
/// this fraction of their sum; +infinity when unmeasurable.
double landmark_discrepancy(const GeodesicCoordinates& a, const std::vector<int>& la, const GeodesicCoordinates& b,
                            const std::vector<int>& lb);

/// The coordinates of the vertices of each path of `loop` (at most `samples` per path, evenly
/// spaced along the path's vertices, both ends included).
std::array<std::vector<std::vector<double>>, 4> loop_coordinates(const GeodesicCoordinates& coords,
                                                                 const SeedLoop& loop, int samples = 128);

/// The seed loop through `seeds` whose path i follows reference[i] (another mesh's loop in
/// intrinsic coordinates of the same landmarks, in the same order): edge v-w of path i costs
/// length x (1 + (c / sigma)^2), c the mean over v and w of the coordinate distance to the nearest
/// point of reference[i]. Paths avoid `avoid`. \throws InvalidInput as trace_weighted_loop.
/// \pre sigma > 0, coords.dims equal to the reference's dimension, references not empty.
SeedLoop trace_intrinsic_loop(const TriMesh& mesh, const std::array<int, 4>& seeds, const GeodesicCoordinates& coords,
                              const std::array<std::vector<std::vector<double>>, 4>& reference, double sigma,
                              const std::vector<int>& avoid);

/// Points at the ends of A's protrusions matched to B's vertices by their geodesic coordinates,
/// for a shape in two poses whose landmarks leave limbs free. A's points are farthest-point
/// samples of the edge-path distance to its landmarks (and to the points already taken), at most
/// `count`, none nearer than a quarter of the first's distance. A point p of A goes to the vertex
/// q of B whose coordinates differ least from p's (relative root-mean-square difference, at most
/// `tolerance`) when the match is unambiguous: every vertex of B farther than half p's distance
/// to the landmarks from q differs at least 1.5 times as much and at least a fifth of
/// `tolerance` (the other of two symmetric limbs), and p is the best match of q's coordinates on
/// A up to that distance. (a vertex, b vertex) pairs.
/// \pre ca and cb have the same landmarks, in the same order, as coordinates of a and b.
std::vector<std::pair<int, int>> matched_extremities(const TriMesh& a, const GeodesicCoordinates& ca, const TriMesh& b,
                                                     const GeodesicCoordinates& cb, int count, double tolerance);

}  // namespace qs::dissect
