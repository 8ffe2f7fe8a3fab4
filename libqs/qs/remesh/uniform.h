#pragma once
// Uniform semi-regular remeshing (paper 4.1): (2^n + 1)^2 samples per patch on the regular grid
// u = i / 2^n, v = j / 2^n, shared along patch sides and at corners (no duplicates), two
// triangles per grid cell. Vertex order: see semi_regular.h.
//
// Diagonal rule (depends only on the cell's place in its patch, so all meshes of a set agree):
//  - level n >= 1, N = 2^n: cell (i, j) (its corners (i,j), (i+1,j), (i+1,j+1), (i,j+1)) is cut
//    along the diagonal that points to the patch corner of its quadrant: cells with i < N/2 and
//    j < N/2 (near corner 0) or i >= N/2 and j >= N/2 (near corner 2) by (i,j)-(i+1,j+1), the two
//    other quadrants by (i+1,j)-(i,j+1). Every patch gets the same symmetric pattern (diagonals
//    along the patch's own two diagonals, a vertex of valence 8 at the patch centre), and every
//    corner cell is cut by the diagonal THROUGH the corner: a corner is never isolated, so a
//    valence-2 base vertex (two patches along two consecutive sides) never gets the same
//    triangle from both patches (which would make the output non-manifold).
//  - level 0 (one cell per patch): BaseTopology::level0_diagonal02 (corner 0 - corner 2 unless
//    that pair is already joined and corner 1 - corner 3 is not). The two seed patches then form
//    a tetrahedron. Level 0 is closed and manifold when every patch's diagonal joins two base
//    vertices that nothing else joins, which the greedy choice ensures whenever one of its two
//    diagonals is free (a quinary split only joins new corners, so in practice it always is;
//    levels >= 1 need no such condition).
//
// Result size: V = Vb + Eb (N-1) + P (N-1)^2, F = 2 P N^2 (Vb, Eb, P: base vertices, edges,
// patches). For a closed base domain V - E + F = Vb - Eb + P.

#include <array>
#include <cstdint>
#include <vector>

#include "qs/core/context.h"
#include "qs/dissect/dissection.h"
#include "qs/remesh/base_topology.h"
#include "qs/remesh/semi_regular.h"

namespace qs::remesh {

/// Largest uniform level accepted (4^12 = 16.8M cells per patch; a further check limits the
/// vertex and face counts to 2^31 - 1). At least kMaxAdaptiveLevel.
inline constexpr int kMaxUniformLevel = 12;

/// How each grid cell is cut into two triangles.
enum class DiagonalRule {
  /// The fixed symmetric pattern above: the connectivity depends on the patch list and the level
  /// only.
  Pattern,
  /// Per cell, the diagonal whose two triangles have the larger smallest angle, taking the worst
  /// mesh of the set (the max-min angle choice, like a Delaunay flip), so that one choice serves
  /// every mesh and the set still shares one face list. Ties keep the pattern's diagonal. A corner
  /// cell of a patch whose corner is a base vertex of valence 2 keeps the pattern's diagonal
  /// (through the corner, which is then never isolated); at a corner of valence >= 3 the other
  /// diagonal joins two side samples that no other patch joins, and a cell that is no corner cell
  /// touches at most one patch side, so a chosen diagonal is an edge of no other cell. The
  /// connectivity then depends on the geometry too (identical for the meshes of one set, not
  /// across separately remeshed sets).
  BestAngle,
};

struct UniformOptions {
  bool quads = false;  ///< also fill SemiRegularConnectivity::quads with the grid cells
  DiagonalRule diagonals = DiagonalRule::Pattern;  ///< how cells are cut (quads are not affected)
  /// Grid relaxation, in [0, kMaxGridRelax]; 0 keeps the regular grid u = i / N.
  /// The connectivity does not change, only the (u, v) in vertex_uv and the positions: every
  /// base edge gets a 1D map of its N + 1 samples, a property of the EDGE (both its patches use
  /// it, so shared side samples stay identical), and an interior grid point (i, j) blends the
  /// two opposite sides' maps: u = (1 - j/N) a_i + (j/N) c_i, v = (1 - i/N) d_j + (i/N) b_j
  /// (a/c the bottom/top side's u samples, d/b the left/right side's v samples), so rows and
  /// columns stay monotone in the square. The maps: each patch's map is probed on a 16 x 16 grid
  /// in every mesh of the set; the separable reparameterization u = U(s), v = V(t) that makes the
  /// probe cells closest to squares (least squares on log(|X_v| / |X_u|)) gives the patch's
  /// preferred sample density along u and v; `relax` scales its log (1: the full fit), clamped to
  /// a factor 4 either way of the regular spacing; an edge takes the mean of its two patches'
  /// preferences along it. Corners stay at the patch corners.
  double relax = 0.0;
};

/// Largest UniformOptions::relax accepted (over-relaxation up to 2x the least-squares fit).
inline constexpr double kMaxGridRelax = 2.0;

/// Vertex numbering of the uniform level-n grid of a base topology (semi_regular.h's order),
/// as 64-bit ids so that fine levels of big base domains can be numbered too.
class UniformNumbering {
 public:
  /// \throws InvalidInput when level is outside [0, kMaxUniformLevel].
  UniformNumbering(const BaseTopology& topology, int level);
  int level() const { return level_; }
  int cells() const { return n_; }  ///< N = 2^level cells along a side
  std::int64_t num_vertices() const { return interior_first_ + static_cast<std::int64_t>(topology_->num_patches()) * (n_ - 1) * (n_ - 1); }
  /// The id of grid point (i, j) of `patch`, 0 <= i, j <= N.
  std::int64_t vertex(int patch, int i, int j) const;
  /// Where vertex `id` is recorded: (patch, i, j) in the lowest-index patch holding it.
  void site(std::int64_t id, int& patch, int& i, int& j) const;

 private:
  const BaseTopology* topology_;
  int level_, n_;
  std::int64_t edge_first_, interior_first_;
};

/// The connectivity of faces whose corners are `num` ids (the adaptive and anisotropic remeshes):
/// the ids used, in increasing order, become vertices 0, 1, ...; each gets its recorded (patch,
/// uv) site; `level` is the numbering's. With `used_bits`, the OR of every vertex's grid i and j.
/// \throws InvalidInput (naming `what`) for more than 2^31 - 1 vertices or faces.
SemiRegularConnectivity compact_connectivity(const BaseTopology& topology, const UniformNumbering& num,
                                             const std::vector<std::array<std::int64_t, 3>>& faces,
                                             const std::string& what, int* used_bits = nullptr);

/// The connectivity of the uniform level-`level` remesh of a patch list (no geometry needed):
/// meshes whose patch lists have the same structure get identical results.
/// \throws InvalidInput for a bad patch list (see build_base_topology), a level outside
///         [0, kMaxUniformLevel], or more than 2^31 - 1 vertices or faces.
SemiRegularConnectivity uniform_connectivity(const BaseTopology& topology, int level,
                                             const UniformOptions& options = {});
SemiRegularConnectivity uniform_connectivity(const std::vector<dissect::PatchInfo>& patches, int level,
                                             const UniformOptions& options = {});

/// Uniform remesh of one chart. \throws InvalidInput (see ChartSampler and uniform_connectivity).
SemiRegular remesh_uniform(const dissect::Chart& chart, int level, const UniformOptions& options = {},
                           const Context& context = {});

/// Uniform remesh of a set with one connectivity. \pre the charts' patch lists have the same
/// structure (same count, names and base-domain quads), as dissect_set produces.
/// \throws InvalidInput naming the first chart that differs from chart 0, and as above.
SemiRegularSet remesh_uniform(const std::vector<const dissect::Chart*>& charts, int level,
                              const UniformOptions& options = {}, const Context& context = {});
SemiRegularSet remesh_uniform(const std::vector<dissect::Chart>& charts, int level,
                              const UniformOptions& options = {}, const Context& context = {});

/// Appends the two triangles of the quad cell c[0..3] (counter-clockwise) in the remeshes' pattern:
/// (c0, c1, c2), (c0, c2, c3) when diag02 (the cut runs c0-c2), else (c0, c1, c3), (c1, c2, c3).
inline void push_cell(std::vector<std::array<std::int64_t, 3>>& faces, const std::array<std::int64_t, 4>& c,
                      bool diag02) {
  if (diag02) {
    faces.push_back({c[0], c[1], c[2]});
    faces.push_back({c[0], c[2], c[3]});
  } else {
    faces.push_back({c[0], c[1], c[3]});
    faces.push_back({c[1], c[2], c[3]});
  }
}

/// Re-cuts one quad cell, given as its two triangles in the remeshes' pattern (f0 starts with the
/// cell's corners v00, v10; diag02: the cut runs v00-v11), along the other diagonal when that
/// raises the smallest angle, taken over every mesh of the set (`positions`: one array per mesh).
void recut_cell_best_angle(Tri& f0, Tri& f1, bool diag02, const std::vector<std::vector<Vec3>>& positions);

/// One sampler per chart of a set, checked to share sampler 0's structure (patch count, names,
/// base-domain quads). Used by the set remeshers.
/// \throws InvalidInput for no charts or charts of different dissections (naming what differs).
class ChartSampler;
std::vector<ChartSampler> set_samplers(const std::vector<const dissect::Chart*>& charts, const Context& context = {});

}  // namespace qs::remesh
