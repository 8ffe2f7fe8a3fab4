#pragma once
// Relaxation of the seed loop's curves (paper 3.3, "patch boundary relaxation", figure 6).
//
// The shortest edge paths of trace_seed_loop zig-zag along mesh edges. Each curve is replaced by
// the preimage of a straight segment in the parameterization of the two patches beside it, cut
// into the mesh with new vertices where the segment crosses edges.
//
// Measured on the 24 meshes of ../shared/meshes (one pass): every step succeeded; the loop gets
// shorter on 19 of them (up to 9%) and much less zig-zag on fine meshes (total turning -60% to
// -70% at 20k-50k vertices), but the seed patches' stretch stays within about 5% either way, and
// the final dissection changes unpredictably (better on some meshes, worse on others), for 2-6x
// the time of the rest of the dissection. Hence an option, not a default.

#include <array>
#include <string>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"
#include "qs/dissect/seed_loop.h"

namespace qs::dissect {

struct RelaxOptions {
  /// Passes over the four curves (each pass relaxes curve 0, 1, 2, 3 in turn, each against the
  /// current other three). 0 returns the input unchanged. \pre 0 <= rounds <= 16.
  int rounds = 1;
  /// A crossing within this fraction of an edge's length from one of its ends passes through that
  /// end vertex instead of splitting the edge (fewer slivers, at the price of small kinks),
  /// unless the vertex lies on another curve or is to be avoided; such a crossing is then moved
  /// to min(snap, 0.01) from the end. \pre 0 <= snap < 0.5.
  double snap = 0.05;
  /// Input vertex ids the new curves must not pass through (feature points that must stay inside
  /// a seed patch): a crossing near one splits the edge instead. \pre ids in [0, #V).
  std::vector<int> avoid;
  /// A step whose new curve would leave a vertex of `avoid` on the other side of the loop than
  /// the input loop does is not taken (the curve is kept; the step says why): features must stay
  /// in the seed patch the set's consistent loops put them in. false: a curve may move across
  /// them (measured: the human pair with --relax 1 then exits 2, its nose changing sides).
  bool keep_sides = true;
};

/// What happened to one curve in one pass.
struct CurveRelaxation {
  int round = 0;
  int curve = 0;               ///< i: the curve from seeds[i] to seeds[(i+1)%4]
  bool relaxed = false;        ///< false: the curve was kept as it was
  std::string why;             ///< when not relaxed: a sentence saying why
  double length_before = 0;    ///< 3D length of the curve before this step
  double length_after = 0;     ///< after it (equal to length_before when not relaxed)
  int inserted_vertices = 0;   ///< this step's new vertices (degeneracy splits included)
};

struct RelaxedLoop {
  /// The refined mesh: the input's vertices 0..V-1 keep their ids and positions, new vertices are
  /// appended, each on the input surface (on an edge of the mesh current when it was inserted,
  /// so inside or on the border of an input face); faces are re-split and renumbered.
  TriMesh mesh;
  SeedLoop loop;               ///< same seeds; paths are vertex ids of `mesh`
  int inserted_vertices = 0;   ///< mesh.num_vertices() minus the input's
  std::array<double, 4> length_before{}, length_after{};  ///< 3D curve lengths, input and result
  std::vector<CurveRelaxation> steps;  ///< rounds * 4 entries, in the order performed
};

/// Relaxes the four curves of a seed loop, one after another (rounds passes), the seeds staying
/// where they are. For curve i, the closed mesh is cut along the other three curves (a simple
/// path s[i+1] -> s[i+2] -> s[i+3] -> s[i]): a disk whose border walks them on both sides, their
/// inner vertices (s[i+2], s[i+3] included) appearing twice, s[i] and s[i+1] once. That disk is
/// the union of the two seed patches glued along curve i, and, as in the paper, all the corners
/// except the curve's own ends become the square's corners: s[i+2] and s[i+3] on patch 0's side
/// at (0,0) and (1,0), their copies on patch 1's side at (1,1) and (0,1). Border arc length then
/// puts s[i] exactly at (1, 1/2) and s[i+1] at (0, 1/2) (each in the middle of a side made of one
/// curve walked out and back), and the new curve is the preimage of the segment between them:
/// symmetric in the two seed patches, and the curve a reflection symmetry would fix when the
/// shape has one. Faces that would lose their UV area are split first (border_degeneracies), the
/// disk is parameterized (parameterize_square), and the segment is walked face by face through
/// the UV triangulation; each crossed edge is split at the crossing (linear interpolation: the
/// new vertex lies on the surface), or the crossing passes through an edge end within
/// options.snap of it when that vertex is not on the other curves.
///
/// A step that cannot complete (the solve fails, the segment leaves the disk or meets a folded
/// UV triangle, the result does not cut the mesh in two) keeps that curve as it was and says why
/// in `steps`; relax_seed_loop never throws for that. The result satisfies everything
/// trace_seed_loop guarantees: simple paths that share only their seeds, and
/// seed_patch_of_faces(result.mesh, result.loop) gives exactly two parts.
/// Cost: one whole-mesh sparse solve per curve and pass: ~0.2 s per curve at 20k vertices, ~0.8 s
/// at 50k (2-core machine, Release), i.e. often several times the rest of the dissection.
/// \pre mesh is closed, manifold and consistently oriented (a validated mesh), and loop is a seed
/// loop of it (as seed_patch_of_faces checks). \throws InvalidInput when it is not, or for options
/// out of range.
RelaxedLoop relax_seed_loop(const TriMesh& mesh, const SeedLoop& loop, const RelaxOptions& options = {},
                            const Context& context = {});

/// 3D length of an edge path (sum of its edges' lengths).
double curve_length(const TriMesh& mesh, const std::vector<int>& path);

}  // namespace qs::dissect
