#pragma once
// Internal to qs::maprefine: what the pieces of map refinement share (the patch problem and its
// Newton solver, the reference's metric, the pose pull, the glued charts of sides and corners).
// Included by the module's sources only; the contract is map_refine.h.

#include <Eigen/Core>
#include <array>
#include <functional>
#include <limits>
#include <optional>
#include <vector>

#include "qs/core/geometry2d.h"
#include "qs/maprefine/map_refine.h"
#include "qs/metro/metro.h"

namespace qs::maprefine::detail {

constexpr double kInf = std::numeric_limits<double>::infinity();
using Mat32 = Eigen::Matrix<double, 3, 2>;
using Mat46 = Eigen::Matrix<double, 4, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

// Point location among a patch's uv triangles: a uniform grid over the unit square (about one cell
// per triangle) holding the triangles marked positive; locate() tries the hint, then q's cell,
// then (when q lies in none of those: `scan_when_outside`, else only when the cell is empty) every
// positive triangle, and takes the one where q is least outside.
class UvLocator {
 public:
  UvLocator(std::vector<std::array<Vec2, 3>> tris, const std::vector<char>& positive, bool scan_when_outside)
      : tris_(std::move(tris)), positive_(positive), scan_when_outside_(scan_when_outside) {
    const size_t n = tris_.size();
    size_ = std::clamp(static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n)))), 1, 1024);
    offsets_.assign(static_cast<size_t>(size_) * size_ + 1, 0);
    auto cells = [&](size_t i, auto&& visit) {
      const auto& uv = tris_[i];
      const Vec2 lo = uv[0].cwiseMin(uv[1]).cwiseMin(uv[2]), hi = uv[0].cwiseMax(uv[1]).cwiseMax(uv[2]);
      for (int y = cell(lo.y()); y <= cell(hi.y()); ++y)
        for (int x = cell(lo.x()); x <= cell(hi.x()); ++x) visit(y * size_ + x);
    };
    for (size_t i = 0; i < n; ++i)
      if (positive_[i]) cells(i, [&](int c) { ++offsets_[c + 1]; });
    for (size_t c = 1; c < offsets_.size(); ++c) offsets_[c] += offsets_[c - 1];
    grid_.resize(offsets_.back());
    std::vector<int> fill(offsets_.begin(), offsets_.end() - 1);
    for (size_t i = 0; i < n; ++i)
      if (positive_[i]) cells(i, [&](int c) { grid_[fill[c]++] = static_cast<int>(i); });
  }

  // The triangle holding q (or where q is least outside, e.g. by rounding on an edge) and q's
  // barycentric coordinates in it, clamped to it; -1 when there is no positive triangle.
  // `hint`: a triangle to try first, updated.
  int locate(const Vec2& q, int& hint, Vec3& bary) const {
    double score = -kInf;
    int best = -1;
    if (hint >= 0) try_tri(hint, q, best, bary, score);
    if (score < 0) {
      const int c = cell(q.y()) * size_ + cell(q.x());
      for (int k = offsets_[c]; k < offsets_[c + 1] && score < 0; ++k) try_tri(grid_[k], q, best, bary, score);
    }
    if (scan_when_outside_ ? score < 0 : best < 0)
      for (size_t i = 0; i < tris_.size() && score < 0; ++i)
        if (positive_[i]) try_tri(static_cast<int>(i), q, best, bary, score);
    if (best < 0) return -1;
    hint = best;
    bary = bary.cwiseMax(0.0);
    bary /= bary.sum();
    return best;
  }

 private:
  int cell(double x) const { return std::clamp(static_cast<int>(std::floor(x * size_)), 0, size_ - 1); }
  void try_tri(int i, const Vec2& q, int& best, Vec3& bary, double& score) const {
    try_uv_triangle(tris_[i][0], tris_[i][1], tris_[i][2], q, i, best, bary, score);
  }

  std::vector<std::array<Vec2, 3>> tris_;
  std::vector<char> positive_;
  bool scan_when_outside_ = true;
  int size_ = 1;
  std::vector<int> offsets_, grid_;
};

// One patch of the reference mesh: its surface's metric in (u, v), constant on each face of
// positive uv area (neither smoothed nor clamped, so that a chart equal to the reference's is the
// energy's minimum), and a uniform grid over the unit square for point location (about one cell
// per face).
class ReferencePatch {
 public:
  ReferencePatch(const dissect::Chart& chart, std::vector<int> faces);
  double area() const { return area_; }

  // The metric at uv (clamped to the square); `hint`: a local face to try first, updated.
  Eigen::Matrix2d metric(const Vec2& q, int& hint) const {
    Vec3 bary;
    const int best = locator_->locate(q, hint, bary);
    if (best < 0) return Eigen::Matrix2d::Identity() * (area_ > 0 ? area_ : 1.0);
    return metric_[best];
  }

 private:
  std::vector<int> faces_;
  std::vector<Eigen::Matrix2d> metric_;
  double area_ = 0;
  std::optional<UvLocator> locator_;
};

// One patch of a mesh being refined, in local numbering.
// A set of chart faces whose wedge (u, v) are affine in a few unknowns. Local vertices are wedges
// of one chart vertex in one patch: a patch-interior vertex has 2 unknowns (u and v); a vertex
// sliding along a patch side has 1, shared by its wedges in the two patches of the side, each
// moving along its side (`basis`); a held vertex has none.
struct PatchProblem {
  std::vector<int> vertices;           // local -> chart vertex
  std::vector<int> faces;              // chart faces
  std::vector<int> face_patch;         // their patches (the reference patch of each face)
  std::vector<std::array<int, 3>> tri;  // local corner ids per face
  std::vector<Vec2> uv;                // per local vertex
  std::vector<int> var;                // per local vertex: index of its first unknown, -1 held
  std::vector<int> dims;               // per local vertex: 0 held, 1 sliding, 2 free
  std::vector<Vec2> basis;             // per local vertex with dims 1: d uv / d unknown
  std::vector<Eigen::Matrix2d> dm_inv;  // per face: inverse of the 3D edge matrix in a local frame
  std::vector<double> area;            // per face: 3D area (the energy's weight)
  // RefineOptions::pose_pull, per local vertex (empty: none): the energy (uv - target)^T pull
  // (uv - target), pull = weight * the reference's metric at the target (zero: no pull).
  std::vector<Eigen::Matrix2d> pull;
  std::vector<Vec2> target;
  int unknowns = 0;
  double total_area = 0;

  /// Appends chart face f of `chart` (patch `patch`) with local corners c: its 3D frame and area.
  void add_face(const dissect::Chart& chart, int f, int patch, const std::array<int, 3>& c);
  /// Gives every local vertex not held two unknowns (var, dims, basis appended in local order).
  void add_unknowns(const std::vector<char>& held);
};

// The 2D edge matrix of a 3D triangle in its own frame (first edge along x), with its height
// floored at 1e-3 of the longest edge so that a needle face still has a finite, positive inverse.
Eigen::Matrix2d local_edges(const Vec3& x0, const Vec3& x1, const Vec3& x2, double& area);

// vec(J) = A x for J = Q [x1 - x0, x2 - x0] P, x = (u0, v0, u1, v1, u2, v2), vec row-major.
Mat46 jacobian_matrix(const Eigen::Matrix2d& q, const Eigen::Matrix2d& p);

inline double tri_det(const Vec2& a, const Vec2& b, const Vec2& c) { return cross2(b - a, c - a); }

// The reference's metric seen by one face of a problem: (local face, uv point) -> 2x2 metric.
using MetricFn = std::function<Eigen::Matrix2d(size_t, const Vec2&)>;

// Instead of a metric: the Jacobian of local face t's map to the reference, linearized at the
// current uv, vec(J_t) = a x + b (x: the face's corner uv, as jacobian_matrix); refine_patch's
// composition.
using LinearizeFn = std::function<void(size_t, Mat46&, Eigen::Vector4d&)>;

// The metric of a problem whose faces lie in their own patches' unit squares: per patch, the
// reference patch and area_B(patch) / area_A(patch); one location hint per face.
MetricFn patch_metric(const PatchProblem& prob, const std::vector<ReferencePatch>& refs,
                      const std::vector<double>& scale);

// The map from local face t's corner uv to its Jacobian against `metric` taken at its uv centroid
// (vec(J) = a x, x the corner uv as corner_uv).
Mat46 metric_jacobian(const PatchProblem& prob, size_t t, const MetricFn& metric);

// Local face t's area * symDirichlet(J), vec(J) = a x + b at uv; +inf when it folds.
double face_energy(const PatchProblem& prob, size_t t, const Mat46& a, const Eigen::Vector4d& b,
                   const std::vector<Vec2>& uv);

struct PatchResult {
  bool changed = false;
  bool skipped = false;
  int steps = 0;
  double energy_before = 0, energy_after = 0, area = 0;  // unnormalized energies, total 3D area
  int free = 0, held = 0;
};

// Refines a problem's free (u, v) (all inside [lo, hi]) under `metric` (or `linearize`, when
// given): projected Newton, kept only if bijective, inside and lower in energy. With
// max_start_distortion > 0, a problem without area or whose start's normalized distortion
// (energy_before / area / 4) exceeds it is left as it is (skipped).
PatchResult solve_problem(PatchProblem& pr, const MetricFn& metric, const RefineOptions& options, bool optimize,
                          const Vec2& hi = Vec2(1, 1), const Vec2& lo = Vec2(0, 0),
                          const LinearizeFn* linearize = nullptr, double max_start_distortion = 0);

// The set's checks of refine_maps (see its \throws).
void check_set(const std::vector<dissect::Dissection>& meshes, const RefineOptions& options);

// ---- The same-pose pull (RefineOptions::pose_pull) -----------------------------------------------

// The reference's patches as nearest-point trees (patch-local vertices), built once per set.
struct PullPatch {
  std::vector<int> faces;  // tree face -> chart face
  std::optional<metro::SurfaceDistance> tree;
};

// The pull of one mesh B: B's frame moved into the reference's, the reference's patch trees, and
// the weight per unit area and squared length.
struct PosePull {
  const dissect::Chart* ref = nullptr;
  const std::vector<PullPatch>* patches = nullptr;
  registration::Pose pose;  ///< the reference's frame -> B's
  double weight = 0;
};

std::vector<PullPatch> build_pull_patches(const dissect::Chart& ref, const RefineOptions& options,
                                          const Context& context);

// The landmarks' similarity from mesh b to the reference (seeds, then features by name), as
// qs-dissect --same-pose fits it the other way.
Eigen::Matrix4d pose_to_reference(const dissect::Dissection& ref, const dissect::Dissection& b);

// Where the pull sends a vertex: (u, v) in a reference patch, the reference's 3D metric there and
// the distance from the vertex.
struct PullTarget {
  Vec2 uv;
  Eigen::Matrix2d metric;
  double distance = 0;
};

// The reference's point nearest to y (in the reference's frame) within reference patch p, on a
// face that faces as `normal` does (dissect::kSamePoseFacingCos); none when the patch has no such
// face or the nearest point's uv face has zero area.
std::optional<PullTarget> nearest_on_patch(const PosePull& pull, int p, const Vec3& y, const Vec3& normal);

// Where a vertex of a problem is pulled to: (the patch of its faces in the problem, its point and
// normal moved into the reference's frame) -> the target, (u, v) and metric in the problem's
// coordinates; none: no pull on it.
using PullTargetFn = std::function<std::optional<PullTarget>(int, const Vec3&, const Vec3&)>;

// Fills a problem's pull: every local vertex of B with unknowns (free, or sliding along a side)
// that `locate` places gets its target and as weight the pull's weight times a third of its faces'
// area times the metric.
void add_pull(PatchProblem& pr, const dissect::Chart& chart, const PosePull& pull, const PullTargetFn& locate);

// The nearest of several reference patches to y (patch i of n given by `patch(i)`), its target
// carried into the problem's glued coordinates by `carry(i, target)`; none when no patch places y.
template <class PatchOf, class Carry>
std::optional<PullTarget> nearest_of(const PosePull& pull, int n, const Vec3& y, const Vec3& normal, PatchOf&& patch,
                                     Carry&& carry) {
  std::optional<PullTarget> best;
  for (int i = 0; i < n; ++i) {
    const auto t = nearest_on_patch(pull, patch(i), y, normal);
    if (t && (!best || t->distance < best->distance)) best = carry(i, *t);
  }
  return best;
}

struct MeshResult {
  double energy_before = 0, energy_after = 0, area = 0;  // unnormalized energies, 3D area
  int free = 0, held = 0, steps = 0, refined = 0, skipped = 0;
};

// Recomputes the figures of the patches marked in `which` (faces, stretch, flipped and zero-area
// uv faces, uv area sum) from the chart, as the dissection computes them, and the mesh's maximum.
void update_figures(dissect::Dissection& b, const std::vector<char>& which);

// The reference's patches (metric and location grid), built once per reference.
std::vector<ReferencePatch> build_refs(const dissect::Chart& ref, const RefineOptions& options,
                                       const Context& context);

// Refines the interior of every patch of B (optimize: false only measures the energy).
MeshResult run_mesh(dissect::Dissection& b, const std::vector<ReferencePatch>& refs, const RefineOptions& options,
                    bool optimize, const Context& context, const PosePull* pull = nullptr);

// ---- Glued charts of sides and corners ----------------------------------------------------------

// The unit square turned by m quarter turns counter-clockwise about its centre (side k goes to
// side k + m), closed forms so that 0 and 1 stay exact.
inline Vec2 turn_square(const Vec2& q, int m) {
  switch (m & 3) {
    case 1: return Vec2(1 - q.y(), q.x());
    case 2: return Vec2(1 - q.x(), 1 - q.y());
    case 3: return Vec2(q.y(), 1 - q.x());
    default: return q;
  }
}

// A patch's place in the glued chart: g = turn(s, turns) + (shift, 0).
struct Glue {
  int patch = -1;
  int turns = 0;
  double shift = 0;
  Vec2 to_glued(const Vec2& s) const { return turn_square(s, turns) + Vec2(shift, 0); }
  Vec2 to_patch(const Vec2& g) const {
    return turn_square(Vec2(g.x() - shift, g.y()), 4 - turns).cwiseMax(0.0).cwiseMin(1.0);
  }
  // The linear part A of to_glued: a metric M in patch (u, v) is A M A^T in glued (u, v).
  Eigen::Matrix2d linear() const {
    Eigen::Matrix2d a = Eigen::Matrix2d::Identity(), r;
    r << 0, -1, 1, 0;
    for (int i = 0; i < (turns & 3); ++i) a = r * a;
    return a;
  }
};

// Faces per patch and per vertex of a chart, built once per group of sides or corners planned
// together (the chart does not change while they are planned), so that gathering the faces of
// two or k patches does not pass over the whole chart for every side or corner.
struct ChartIndex {
  std::vector<std::vector<int>> patch_faces;
  std::vector<int> vertex_offset, vertex_faces;  // vertex v's faces: [offset[v], offset[v + 1])

  explicit ChartIndex(const dissect::Chart& chart);

  /// The faces of `patches` (distinct), ascending; `outside` (#V, zero) gets 1 at their vertices
  /// that also lie on a face of another patch.
  std::vector<int> gather(const dissect::Chart& chart, const std::vector<int>& patches,
                          std::vector<char>& outside) const;
};

// Corners, seeds and features of a mesh (#V flags): what the side and corner moves never move.
std::vector<char> pinned_vertices(const dissect::Dissection& d);

enum class SideOutcome { Refined, Unchanged, Skipped };

// With the pose pull, a side's union moves only within this distance of the side in u (the rest
// held): in one pose the maps start near their place and a side moves little. Without the pull
// a side may move far, and a band loses accuracy (docs/algorithms.md, "Map refinement").
constexpr double kPoseSideBand = 0.25;

// A free vertex this close to the cut line (as a fraction of a crossing edge's extent across it)
// is moved onto the line instead of cutting the edge next to it.
constexpr double kCutSnap = 0.15;
// ... when its ring's energy grows by at most this fraction.
constexpr double kSnapEnergyGrowth = 0.01;

// A side's planned refinement: computed from the chart without changing it (sides of different
// patches can be planned at once), then committed.
struct SideCut {
  struct Piece {
    int face;                // original chart face
    std::array<int, 3> c;    // local vertex ids; ids >= vertices.size() are new_pos entries
  };
  SideOutcome outcome = SideOutcome::Unchanged;
  int steps = 0;
  std::vector<int> vertices;  // local -> chart vertex
  std::vector<Vec3> new_pos;
  std::vector<Piece> pieces;
  std::vector<int> piece_patch;
  std::vector<std::array<Vec2, 3>> piece_uv;
  SideCut& with(SideOutcome o) {
    outcome = o;
    return *this;
  }
};

// Writes a planned cut into the chart: new vertices appended, each face of the union replaced by
// its pieces (the first keeps the face id, the others appended).
void commit_side(dissect::Chart& chart, const SideCut& cut);

struct AcrossResult {
  int sides_refined = 0, sides_skipped = 0, added_vertices = 0, steps = 0;
};

// `border_sweeps` passes over the shared sides of B. The sides are grouped (in patch order, each
// into the first group that has neither of its patches), the sides of a group are planned in
// parallel (their unions share no face) and committed in order: the result does not depend on
// the thread count.
AcrossResult refine_across(dissect::Dissection& b, const std::vector<ReferencePatch>& refs,
                           const RefineOptions& options, const Context& context, const PosePull* pull);

struct CornerResult {
  int moved = 0, irregular = 0, skipped = 0, added_vertices = 0, steps = 0;
};

// `corner_sweeps` passes over B's corners (base-domain order: first met in patch order). The
// corners are grouped (in order, each into the first group whose stars share none of its
// patches), planned in parallel within a group and committed in order: the result does not depend
// on the thread count.
CornerResult move_corners(dissect::Dissection& b, const std::vector<ReferencePatch>& refs,
                          const RefineOptions& options, const Context& context, const PosePull* pull);

}  // namespace qs::maprefine::detail
