#pragma once
// Floater mean-value parameterization of a quad patch onto the unit square (paper 3.1), and
// Sander et al. 2001 L2 stretch (paper 3.2).

#include <array>
#include <memory>
#include <utility>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"

namespace qs::param {

/// One patch as its own small mesh. A topological disk, faces CCW seen from outside.
struct PatchMesh {
  std::vector<Vec3> positions;  ///< #V local vertices
  std::vector<Tri> faces;       ///< #F, local ids
  /// The boundary loop in CCW order (the patch on the left when walking it), starting at
  /// corner 0; each consecutive pair is a boundary edge, and the last joins back to the first.
  std::vector<int> boundary;
  /// Indices into `boundary` of corners 0..3: corner_index[0] == 0 < [1] < [2] < [3].
  std::array<int, 4> corner_index{};
};

/// How the sparse LU orders the mean-value system before factorizing it.
enum class LuOrdering {
  /// AMD on the (structurally symmetric) pattern, applied to rows and columns alike, diagonal
  /// pivots preferred: less fill, about 2x faster than Colamd on patches of 20k+ vertices.
  SymmetricAmd,
  /// Eigen's COLAMD column ordering with ordinary partial pivoting.
  Colamd,
};

/// The interior weights of the parameterization's Laplacian.
enum class InteriorWeights {
  /// Floater's mean-value weights on the patch's own triangles: positive, but they depend on how
  /// the surface is triangulated, not only on its shape.
  MeanValue,
  /// Cotangent (harmonic) weights on the intrinsic Delaunay triangulation of the patch (its edges
  /// flipped by lengths alone until every interior edge is Delaunay; Fisher et al. 2007,
  /// Bobenko-Springborn 2007): non-negative, so Tutte's guarantee holds for that triangulation,
  /// and a discretization of the harmonic map of the surface that converges under refinement.
  /// The original triangles' images are counted all the same (they may fold where the intrinsic
  /// triangulation differs). A patch whose Delaunay flips pass 4 per face (plus 1000) gets
  /// mean-value weights instead (SquareParam::weights says which), so that the cost stays linear.
  IntrinsicCotan,
};

/// What a plain solve of a patch (no pins, no stretch rounds) leaves for a later call on the same
/// patch with the same weights (SquareParamOptions::plain).
struct PlainSolve {
  /// Its map: taken as the first solve (stretch minimization starts from it) when it has one uv
  /// per vertex and there are no pins; otherwise ignored.
  std::vector<Vec2> uv;
  /// Its Cholesky ordering (SquareParam::cholesky_ordering; cotangent weights): the analysis takes
  /// it instead of ordering the system again (the same factor). Ignored unless it is a permutation
  /// of the interior vertices.
  std::vector<int> cholesky_ordering;
};

struct SquareParamOptions {
  double min_edge_length = 1e-12;  ///< shorter 3D edges get this length in the weights (> 0)
  /// Border spacing floor, relative: on each side, every border edge counts as at least this
  /// fraction of the side's mean edge length, so coincident border vertices stay apart in UV.
  /// In [0, 1); 0 gives pure arc length.
  double min_border_spacing = 1e-4;
  LuOrdering ordering = LuOrdering::SymmetricAmd;  ///< both give the same map (to rounding)
  /// Interior vertices held at given (u,v) like the border (feature alignment): (local id, uv),
  /// ids distinct, not on the boundary loop, uv inside the square. With pins the map may fold
  /// (Tutte's guarantee needs every fixed vertex on the convex border): count the flips.
  std::vector<std::pair<int, Vec2>> pinned;
  /// Rounds of stretch minimization after the mean-value solve (Yoshizawa, Belyaev, Seidel
  /// 2004): each round divides every weight w_ij by the L2 stretch around j and solves again;
  /// it stops early when the patch stretch falls by less than 1%, and the lowest-stretch
  /// bijective map is kept. 0: the plain mean-value map.
  int stretch_iterations = 0;
  InteriorWeights weights = InteriorWeights::MeanValue;
  /// A previous plain solve of the same patch with the same weights, when the caller has one:
  /// its map is taken instead of solving again and its ordering instead of ordering again.
  const PlainSolve* plain = nullptr;
};

/// A UV face with |signed area| <= this counts as zero-area (and neither as flipped).
inline constexpr double kZeroUvArea = 1e-14;

/// A parameterization: corners at (0,0) (1,0) (1,1) (0,1), CCW.
struct SquareParam {
  std::vector<Vec2> uv;     ///< #V
  int flipped_faces = 0;    ///< UV faces with signed area < -kZeroUvArea (computed, never assumed)
  int zero_area_faces = 0;  ///< UV faces with |signed area| <= kZeroUvArea
  double uv_area_sum = 0;   ///< sum of signed UV areas; 1 for a valid map
  int intrinsic_flips = 0;  ///< edge flips to the intrinsic Delaunay triangulation (IntrinsicCotan)
  InteriorWeights weights = InteriorWeights::MeanValue;  ///< the weights the map was solved with
  /// The ordering of the Cholesky factorizations (cotangent weights), for a later call on the
  /// same patch (PlainSolve::cholesky_ordering); empty when none ran.
  std::vector<int> cholesky_ordering;
  bool bijective() const { return flipped_faces == 0 && zero_area_faces == 0; }
};

/// Interior edges joining two boundary vertices of the same square side (a corner counts on both
/// of its sides): the region they cut off lands on one straight side of the square, so its faces
/// get zero UV area (Floater's "dividing edges"). A face with all three vertices on one side (an
/// ear) always has such an edge, so it is covered by the same list.
/// Returns the local vertex pairs (a, b), a < b, sorted and unique; empty when the patch is clean.
/// The caller must split every returned edge at its 3D midpoint before solving: add a vertex m
/// (a new interior vertex, not on the boundary loop) and replace each of the two faces (a, b, x)
/// by (a, m, x) and (m, b, x), keeping the orientation. Splitting never removes another listed
/// edge, so the edges may be split one after another by their vertex pairs; afterwards no interior
/// edge joins two same-side vertices and the mean-value map is bijective in exact arithmetic.
/// \pre the same as parameterize_square (checked: InvalidInput).
std::vector<std::array<int, 2>> border_degeneracies(const PatchMesh& patch);
/// The same for a patch the caller knows to be valid, which also knows its interior half-edges:
/// interior[3 f + c] (half-edge faces[f][c] -> faces[f][c + 1]) is nonzero where the opposite
/// half-edge is in the patch too. Nothing is checked.
std::vector<std::array<int, 2>> border_degeneracies(const PatchMesh& patch, const std::vector<char>& interior);

/// Counts flipped and zero-area UV faces and sums the signed UV areas of `faces` under sp.uv into
/// sp (the counts parameterize_square reports), e.g. after the map was changed by a warp.
void count_uv_faces(const std::vector<Tri>& faces, SquareParam& sp);

/// Border by arc length on each side (3D edge lengths), interior by Floater mean-value weights
/// w_ij = (tan(a/2) + tan(b/2)) / |p_i - p_j| from the 3D one-ring angles, one sparse LU solve
/// (Eigen SparseLU, ordering per options.ordering) for u and v together. Cotangent weights are
/// symmetric: that system (and each stretch-minimization round's, its rows rescaled) is solved by
/// sparse Cholesky (SupernodalCholesky) instead, and a weight's floor is the larger of its two
/// rows'; should a pivot not be positive in floating point, the patch falls back to LU.
/// Degenerate geometry never yields NaN: edge lengths are floored at options.min_edge_length;
/// a corner without an angle (zero-length edge) contributes 0, an angle within ~2e-8 rad of pi is
/// clamped; in each row, edges left with a weight below 1e-8 times the row's largest get that
/// floor (the system stays nonsingular), and a vertex with no usable angle at all gets uniform
/// weights. Flipped and zero-area UV faces are counted, never assumed away: call
/// border_degeneracies() first and split what it returns.
/// \pre patch is a disk (V - E + F = 1, manifold, consistently oriented) whose boundary loop is
/// its only border, listed CCW (each b[i] -> b[i+1] is a half-edge of a face), vertices distinct;
/// corner_index[0] == 0 < [1] < [2] < [3] < boundary.size(); every vertex used by a face;
/// positions finite. All checked: InvalidInput naming the offending local ids.
/// \throws SolverError if the factorization fails or the solution is not finite.
SquareParam parameterize_square(const PatchMesh& patch, const SquareParamOptions& options = {},
                                const Context& context = {});

/// Solves of a few interior vertices of a patch at a time, every other vertex held (a local repair
/// of a map): the weights are built once, and each solve assembles and factors only its own rows.
/// A solve gives those vertices what parameterize_square gives them with the same weights and
/// every other interior vertex pinned where it is held. The patch must outlive the solver.
class HeldSolver {
 public:
  /// \pre as parameterize_square (checked: InvalidInput).
  HeldSolver(const PatchMesh& patch, InteriorWeights weights, const Context& context = {});
  ~HeldSolver();
  HeldSolver(const HeldSolver&) = delete;
  HeldSolver& operator=(const HeldSolver&) = delete;
  /// uv[v] solved for every interior vertex v with free[v] (border vertices are skipped; the
  /// border is where parameterize_square puts it), the other interior vertices held at uv[v].
  /// \throws InvalidInput when a held (u, v) is not finite or outside the unit square;
  /// SolverError as parameterize_square.
  void solve(const std::vector<char>& free, std::vector<Vec2>& uv) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// L2 stretch (Sander, Snyder, Gortler, Hoppe 2001). Per face, with S_s, S_t the partial
/// derivatives of the (linear) UV-to-3D map, L2_f = sqrt((|S_s|^2 + |S_t|^2) / 2); per patch
/// sqrt(sum L2_f^2 A3D_f / sum A3D_f). Normalization: every value (faces and patch) is multiplied
/// by sqrt(total UV area / total 3D area), which makes it invariant under scaling the surface or
/// the UV domain: an isometry up to uniform scale scores exactly 1, and the patch value is >= 1
/// for every map (e.g. > 1 for a conformal map with non-uniform scale; single faces may be < 1).
/// A face with UV signed area <= 0 scores infinity, and so does the patch. Faces of zero 3D area
/// weigh nothing (a patch of zero 3D area scores 0).
/// \throws InvalidInput if uv.size() != positions.size() or a face id is out of range.
struct Stretch {
  std::vector<double> face;  ///< #F per-face normalized L2 stretch (infinity for UV area <= 0)
  double patch = 0;          ///< area-weighted RMS over the faces (3D area weights), normalized
  double area3d = 0;         ///< total 3D area of the patch
};
Stretch l2_stretch(const std::vector<Vec3>& positions, const std::vector<Tri>& faces,
                   const std::vector<Vec2>& uv);

}  // namespace qs::param
