#pragma once
// Geodesic seed curves: the four edge paths of a seed loop straightened into locally
// shortest curves on the surface and cut into the mesh, so that the seed loop is (nearly) the
// same curve for any tessellation of a surface, not a zig-zag along whichever edges it has.

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"
#include "qs/dissect/cut_mesh.h"
#include "qs/dissect/seed_loop.h"

namespace qs::dissect {

struct GeodesicLoopOptions {
  /// A crossing within this fraction of an edge's length from one of its ends passes through
  /// that end vertex instead of splitting the edge (no sliver faces; the curve moves by at most
  /// this fraction of one edge), unless the vertex must be avoided. \pre 0 <= snap < 0.5.
  double snap = 0.02;
  /// Input vertex ids the curves must not pass through or cross over (features that must stay on
  /// their side of the loop). \pre ids in [0, #V).
  std::vector<int> avoid;
  /// Bound on the vertex flips per curve: max_rounds times the edges of its edge path.
  int max_rounds = 64;
};

struct GeodesicLoop {
  /// The refined mesh: the input's vertices keep their ids and positions, new vertices (where a
  /// curve crosses an edge) are appended, each on an input edge; faces are re-split.
  TriMesh mesh;
  SeedLoop loop;                         ///< same seeds; paths are vertex ids of `mesh`
  std::array<bool, 4> straightened{};    ///< false: curve i kept as the input's edge path
  std::array<std::string, 4> why;        ///< when not straightened: a sentence saying why
  std::array<double, 4> length_before{}, length_after{};  ///< 3D lengths
  int inserted_vertices = 0;
  /// seed_patch_of_faces(mesh, loop) where a curve was straightened (empty otherwise).
  std::vector<int> face_patches;
  /// `mesh` as CutMesh(mesh) builds it, where a curve was straightened (empty otherwise).
  std::optional<CutMesh> cut;
  /// Whether any curve was straightened (else `mesh` and `loop` are the input's).
  bool any_straightened() const { return straightened[0] || straightened[1] || straightened[2] || straightened[3]; }
};

/// Straightens each curve of `loop` in turn (0, 1, 2, 3) into the shortest curve on the surface
/// that is homotopic to it among the obstacles (the seeds other than its ends, the other three
/// curves as they are at that moment, and options.avoid): Martinez, Velho, Carvalho 2005 ("Computing
/// geodesics on triangular meshes"): the faces left of the edge path form a strip; the shortest
/// path in the unfolded strip is found by the funnel algorithm; wherever it bends around a strip
/// vertex whose angle on the other side is below pi, the strip is moved to the other side of that
/// vertex (a flip) when that shortens the curve; repeated until no flip shortens it. The result is
/// a geodesic (straight in every unfolding, through vertices only at saddles or obstacles), then cut
/// into the mesh: every crossed edge is split at the crossing (or snapped, options.snap).
/// A curve that cannot be straightened safely (it would touch an obstacle, revisit a face, or the
/// loop would no longer cut the mesh in two with every `avoid` vertex on its side) stays the edge
/// path and `why` says so; this function does not throw for that.
/// \pre mesh is a validated closed manifold mesh and loop is a seed loop of it (seed_patch_of_faces
/// accepts it). \throws InvalidInput when it is not, or for options out of range.
/// Cost: O(strip size x flips) per curve, plus the cut mesh's build.
GeodesicLoop straighten_seed_loop(const TriMesh& mesh, const SeedLoop& loop, const GeodesicLoopOptions& options = {},
                                  const Context& context = {});
/// The same on a mesh held as a cut mesh already (its patch labels are ignored): copied instead of
/// built again, and the loop checked on its half-edges.
GeodesicLoop straighten_seed_loop(const CutMesh& mesh, const SeedLoop& loop, const GeodesicLoopOptions& options = {},
                                  const Context& context = {});

}  // namespace qs::dissect
