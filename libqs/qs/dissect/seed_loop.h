#pragma once
// The seed loop (paper 3.3): four seeds joined by shortest edge paths s0->s1->s2->s3->s0 that
// cut a closed genus-0 mesh into two quad patches. The rules in full: docs/algorithms.md.

#include <array>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"

namespace qs::dissect {

struct SeedLoop {
  std::array<int, 4> seeds{};
  /// paths[i] runs from seeds[i] to seeds[(i+1)%4], both included, along mesh edges (3D lengths).
  /// The four paths are simple and share no vertex except the seeds they meet at.
  std::array<std::vector<int>, 4> paths;
};

/// Traces the four paths. \pre mesh is a validated closed genus-0 mesh; seeds are 4 distinct
/// vertices. \throws InvalidInput naming the seeds when a path cannot be routed without
/// crossing or touching the others.
///
/// Shortest paths on the vertex graph with 3D edge lengths (A*, exact; ties broken by vertex id:
/// deterministic), one path at a time; a path avoids the seeds other than its ends and the
/// vertices of the paths already routed. Orders tried: the four paths by increasing unobstructed
/// length first (so the shortest pair gets a true shortest path), then the other 23 orders. A result is accepted only
/// when the faces flooded across non-loop edges form exactly two parts and every loop edge has
/// one part on each side (an edge joining two loop vertices off the loop, a chord, is allowed).
/// Also \throws InvalidInput for a seed out of range, two equal seeds, or an edge with one face
/// or more than two. O(F log F) per path.
SeedLoop trace_seed_loop(const TriMesh& mesh, const std::array<int, 4>& seeds, const Context& context = {});
/// The same, with paths that also avoid the vertices in `avoid` (feature points, which must lie
/// inside a seed patch). Loops found by the unobstructed search are kept when they avoid them.
SeedLoop trace_seed_loop(const TriMesh& mesh, const std::array<int, 4>& seeds, const std::vector<int>& avoid,
                         const Context& context = {});

/// A vertex that must end on a given side of the seed loop (0: left of s0->s1->s2->s3, patch 0).
struct SideConstraint {
  int vertex = -1;
  int side = 0;
};

/// Re-routes `loop` so that every constrained vertex lies on its side, when the shortest loop
/// puts some on the other (for example a head between two hands: the shortest hand-to-hand path
/// may pass in front of the neck on one mesh and behind it on another). One vertex at a time, the
/// path of the loop nearest it is routed through a waypoint across the vertex (on the far side
/// of it, at 1, 1.5 or 2.5 times its distance to the path, and at 2, 3 or 5 mean edge lengths when
/// the path passes within two); among the loops that cut the mesh in
/// two and leave fewer vertices on the wrong side, the shortest is kept. Every path still avoids
/// `avoid`. Returns the loop unchanged when all sides already hold.
/// \throws InvalidInput naming the vertices whose side cannot be met.
SeedLoop reroute_for_sides(const TriMesh& mesh, const SeedLoop& loop, const std::vector<int>& avoid,
                           const std::vector<SideConstraint>& sides, const Context& context = {});

/// A seed loop that follows four guide curves (DissectOptions::same_pose: another mesh's loop,
/// moved into this mesh's pose): path i runs from seeds[i] to seeds[(i+1)%4] along mesh edges,
/// the shortest under edge costs length x (1 + (d / sigma)^2), d the distance from the edge's
/// midpoint to guides[i] (a polyline); paths in order 0..3, each avoiding the other seeds, the
/// vertices in `avoid` and the paths already routed. \throws InvalidInput when a path does not
/// route or the loop does not cut the mesh into two patches. \pre sigma > 0, guides not empty.
SeedLoop trace_guided_loop(const TriMesh& mesh, const std::array<int, 4>& seeds,
                           const std::array<std::vector<Vec3>, 4>& guides, double sigma,
                           const std::vector<int>& avoid);

/// Cost factor of the edge v-w for path i (>= 1 keeps the paths' lengths meaningful).
using EdgeFactor = std::function<double(int path, int v, int w)>;

/// Path i from seeds[i] to seeds[(i+1)%4] along mesh edges, the shortest under edge costs
/// length x factor(i, v, w); paths in order 0..3, each avoiding the other seeds, the vertices in
/// `avoid` and the paths already routed. \throws InvalidInput when a path does not route or the
/// loop does not cut the mesh into two patches.
SeedLoop trace_weighted_loop(const TriMesh& mesh, const std::array<int, 4>& seeds, const EdgeFactor& factor,
                             const std::vector<int>& avoid);

/// The side of the loop each vertex in `vertices` lies on (0 or 1); -1 for a vertex on the loop.
std::vector<int> sides_of_vertices(const TriMesh& mesh, const SeedLoop& loop, const std::vector<int>& vertices);
/// The same from the faces' seed patches (seed_patch_of_faces() of the loop).
std::vector<int> sides_of_vertices(const TriMesh& mesh, const std::vector<int>& face_patches,
                                   const std::vector<int>& vertices);

/// Which seed patch each face lies in: #F labels, 0 for the faces left of the loop
/// s0 -> s1 -> s2 -> s3 -> s0 (the loop runs counter-clockwise around patch 0 seen from outside,
/// faces being counter-clockwise seen from outside as validate() leaves them), 1 for the others.
/// With choose_seeds' seeds, patch 0 is the +e3 side. \throws InvalidInput when the paths are
/// not joined edge paths between the seeds or do not cut the mesh into exactly two parts.
std::vector<int> seed_patch_of_faces(const TriMesh& mesh, const SeedLoop& loop);

/// Four seeds chosen automatically (the rule in full: docs/algorithms.md): with e1, e2, e3 the principal
/// axes of the area-weighted vertices, the candidates are the ray seeds (where rays from the
/// centroid first meet the surface, 4 rays 90 degrees apart) in each principal plane, also turned
/// by 45 degrees, then the axis-extreme and the geodesically farthest vertices, then two slab
/// candidates (the extremes in the plane through the centroid normal to e1). Among the loops
/// that route and enclose at least 5% of the area, the largest (smaller side's area fraction) /
/// (loop length / sqrt(area)) wins (else the most even loop; a slab candidate must score 1.5
/// times the best of the others): a short belt cutting the shape into two sizable parts.
/// Deterministic (the candidates route on the context's threads; the result does not depend on them).
/// \throws InvalidInput when the mesh has fewer than 4 used vertices, or no candidate routes.
std::array<int, 4> choose_seeds(const TriMesh& mesh, const Context& context = {});

/// The first candidate (name, seeds) whose loop routes. \throws InvalidInput naming every rule
/// and why it failed, asking for seeds by hand, when none routes.
std::array<int, 4> first_routable_seeds(const TriMesh& mesh,
                                        const std::vector<std::pair<std::string, std::array<int, 4>>>& candidates);

/// The fallback rule of choose_seeds: geodesic (edge-path) farthest points. s0 = the vertex
/// farthest from the vertex nearest the area-weighted centroid, s2 = farthest from s0, s1 =
/// farthest from both s0 and s2 (max of the smaller distance), s3 = farthest from s0, s1 and s2;
/// s1 and s3 are swapped if needed so the loop runs counter-clockwise around +e3 (signed area of
/// the quadrilateral projected on the e1-e2 plane). Not checked for routability.
std::array<int, 4> choose_seeds_farthest(const TriMesh& mesh);

}  // namespace qs::dissect
