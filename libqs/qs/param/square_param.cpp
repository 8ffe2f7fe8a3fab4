// Floater mean-value parameterization of a quad patch onto the unit square (paper 3.1).

#include "qs/param/square_param.h"

#include <Eigen/Geometry>
#include <Eigen/OrderingMethods>
#include <Eigen/SparseCore>
#include <Eigen/SparseLU>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <future>
#include <limits>
#include <sstream>
#include <string>
#include <utility>

#include "qs/core/error.h"
#include "qs/core/parallel.h"
#include "qs/core/problem_list.h"
#include "qs/param/sparse_cholesky.h"

namespace qs::param {
// Internal: a named namespace because HeldSolver::Impl holds some of its types.
namespace square_detail {

/// tan(a/2) is clamped here: a corner angle within ~2e-8 rad of pi (a vertex on its opposite
/// edge) would otherwise give an infinite weight.
constexpr double kMaxTanHalfAngle = 1e8;
/// In a row of the system, an edge whose mean-value weight is below this fraction of the row's
/// largest weight (only edges all of whose corners at the row vertex are degenerate) gets this
/// fraction: every edge keeps a positive weight, so the matrix stays an irreducibly diagonally
/// dominant M-matrix (nonsingular) however degenerate the geometry.
constexpr double kRelativeWeightFloor = 1e-8;
/// SparseLU takes the diagonal as pivot when it is at least this fraction of its column's largest
/// entry (symmetric-AMD path only).
constexpr double kDiagonalPivotThreshold = 1e-3;
/// Stretch minimization stops when a round lowers the patch stretch by less than this fraction.
constexpr double kMinGain = 0.01;

/// tan(a/2) for the angle a between u and v, computed without cancellation on both sides of
/// pi/2: sin a / (1 + cos a) for acute angles, (1 - cos a) / sin a for obtuse ones. 0 when u or v
/// is a zero vector (no angle); never NaN for finite input.
double tan_half_angle(const Vec3& u, const Vec3& v) {
  const double nn = u.norm() * v.norm();
  if (!(nn > 0)) return 0;
  const double cr = u.cross(v).norm();
  const double d = u.dot(v);
  if (d >= 0) return cr / (nn + d);
  const double num = nn - d;  // >= nn > 0
  if (cr * kMaxTanHalfAngle <= num) return kMaxTanHalfAngle;
  return num / cr;
}


[[noreturn]] void throw_problems(const std::vector<std::string>& problems) {
  std::ostringstream s;
  s << "parameterize_square: invalid patch: ";
  for (std::size_t i = 0; i < problems.size(); ++i) s << (i ? "; " : "") << problems[i];
  throw InvalidInput(s.str());
}

std::string pair_str(int a, int b) {
  std::string s(1, '(');  // not "(" + ...: GCC 12 warns falsely (-Wrestrict) on that form
  s += std::to_string(a);
  s += ',';
  s += std::to_string(b);
  s += ')';
  return s;
}

/// Half-edge h = 3 f + c runs from faces[f][c] to faces[f][(c+1)%3]. Out-going half-edges are
/// bucketed per vertex (CSR), and every half-edge knows its opposite (-1 on the border; twin and
/// by_target are left empty by out_half_edges).
struct HalfEdges {
  std::vector<int> out_offset;  ///< #V + 1
  std::vector<int> out;         ///< half-edge ids grouped by source vertex
  std::vector<int> twin;        ///< #H
  /// Per source vertex (same offsets as `out`): (target vertex, half-edge id) sorted, so that a
  /// look-up costs O(log valence), not O(valence): fans of 100k faces around one vertex occur.
  std::vector<std::pair<int, int>> by_target;
};

int he_from(const std::vector<Tri>& faces, int h) { return faces[h / 3][h % 3]; }
int he_to(const std::vector<Tri>& faces, int h) { return faces[h / 3][(h % 3 + 1) % 3]; }

/// Finds the half-edge a->b among a's out-going ones (the lowest id if there are several), or -1.
int find_half_edge(const HalfEdges& he, const std::vector<Tri>&, int a, int b) {
  const auto first = he.by_target.begin() + he.out_offset[a], last = he.by_target.begin() + he.out_offset[a + 1];
  const auto it = std::lower_bound(first, last, std::pair<int, int>(b, std::numeric_limits<int>::min()));
  return it != last && it->first == b ? it->second : -1;
}

/// The out-going half-edges only (out_offset, out), for a triangulation whose twins are known.
/// \pre face ids are in range.
HalfEdges out_half_edges(int num_vertices, const std::vector<Tri>& faces) {
  HalfEdges he;
  const int nh = 3 * static_cast<int>(faces.size());
  he.out_offset.assign(num_vertices + 1, 0);
  for (const Tri& t : faces)
    for (int v : t) ++he.out_offset[v + 1];
  for (int v = 0; v < num_vertices; ++v) he.out_offset[v + 1] += he.out_offset[v];
  he.out.resize(nh);
  std::vector<int> fill(he.out_offset.begin(), he.out_offset.end() - 1);
  for (int h = 0; h < nh; ++h) he.out[fill[he_from(faces, h)]++] = h;
  return he;
}

/// \pre face ids are in range.
HalfEdges build_half_edges(int num_vertices, const std::vector<Tri>& faces) {
  HalfEdges he = out_half_edges(num_vertices, faces);
  const int nh = 3 * static_cast<int>(faces.size());
  he.by_target.resize(nh);
  for (int k = 0; k < nh; ++k) he.by_target[k] = {he_to(faces, he.out[k]), he.out[k]};
  for (int v = 0; v < num_vertices; ++v)
    std::sort(he.by_target.begin() + he.out_offset[v], he.by_target.begin() + he.out_offset[v + 1]);
  he.twin.assign(nh, -1);
  for (int h = 0; h < nh; ++h) he.twin[h] = find_half_edge(he, faces, he_to(faces, h), he_from(faces, h));
  return he;
}

/// Checks every documented precondition, collecting all problems; returns the half-edges.
HalfEdges validate_patch(const PatchMesh& patch, const SquareParamOptions& options) {
  std::vector<std::string> problems;
  const int nv = static_cast<int>(patch.positions.size());
  const int nf = static_cast<int>(patch.faces.size());
  const int nb = static_cast<int>(patch.boundary.size());

  if (!(options.min_edge_length > 0) || !std::isfinite(options.min_edge_length))
    problems.push_back("options.min_edge_length must be positive and finite (got " +
                       std::to_string(options.min_edge_length) + ")");
  if (!(options.min_border_spacing >= 0 && options.min_border_spacing < 1))
    problems.push_back("options.min_border_spacing must be in [0, 1) (got " +
                       std::to_string(options.min_border_spacing) + ")");
  if (nf == 0) problems.push_back("the patch has no faces");

  ProblemList non_finite("vertices with a non-finite position");
  for (int v = 0; v < nv; ++v)
    if (!patch.positions[v].allFinite()) non_finite.add(std::to_string(v));
  non_finite.append_to(problems);

  ProblemList bad_face("faces with a vertex id outside [0, " + std::to_string(nv) + ")");
  ProblemList repeated("faces that repeat a vertex");
  std::vector<char> used(nv, 0);
  for (int f = 0; f < nf; ++f) {
    const Tri& t = patch.faces[f];
    bool ok = true;
    for (int v : t)
      if (v < 0 || v >= nv) ok = false;
    if (!ok) {
      bad_face.add(std::to_string(f) + " (" + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " +
                   std::to_string(t[2]) + ")");
      continue;
    }
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) repeated.add(std::to_string(f));
    for (int v : t) used[v] = 1;
  }
  bad_face.append_to(problems);
  repeated.append_to(problems);
  if (bad_face.empty()) {
    ProblemList unused("vertices used by no face (remove them from the patch)");
    for (int v = 0; v < nv; ++v)
      if (!used[v]) unused.add(std::to_string(v));
    unused.append_to(problems);
  }

  if (nb < 4)
    problems.push_back("the boundary loop has " + std::to_string(nb) +
                       " vertices; a square patch needs at least 4 (one per corner)");
  ProblemList bad_boundary("boundary loop entries outside [0, " + std::to_string(nv) + ") (position: id)");
  ProblemList twice("vertices that appear more than once in the boundary loop (the patch must be a disk)");
  std::vector<int> position_in_loop(nv, -1);
  for (int i = 0; i < nb; ++i) {
    const int v = patch.boundary[i];
    if (v < 0 || v >= nv) {
      bad_boundary.add(std::to_string(i) + ": " + std::to_string(v));
    } else if (position_in_loop[v] >= 0) {
      twice.add(std::to_string(v) + " (positions " + std::to_string(position_in_loop[v]) + " and " +
                std::to_string(i) + ")");
    } else {
      position_in_loop[v] = i;
    }
  }
  bad_boundary.append_to(problems);
  twice.append_to(problems);

  const auto& c = patch.corner_index;
  const std::string corners = "(got " + std::to_string(c[0]) + " " + std::to_string(c[1]) + " " +
                              std::to_string(c[2]) + " " + std::to_string(c[3]) + ")";
  if (c[0] != 0)
    problems.push_back("corner_index[0] must be 0: the boundary loop starts at corner 0 " + corners);
  for (int k = 0; k < 4; ++k)
    if (c[k] < 0 || c[k] >= nb)
      problems.push_back("corner_index[" + std::to_string(k) + "] = " + std::to_string(c[k]) +
                         " is out of range: the boundary loop has " + std::to_string(nb) + " vertices " +
                         corners);
  for (int k = 0; k + 1 < 4; ++k)
    if (c[k] >= c[k + 1])
      problems.push_back("corner indices must strictly increase (4 distinct corners in loop order): corner_index[" +
                         std::to_string(k) + "] >= corner_index[" + std::to_string(k + 1) + "] " + corners);

  if (!problems.empty()) throw_problems(problems);

  // Connectivity: ids are all valid from here on.
  HalfEdges he = build_half_edges(nv, patch.faces);
  const int nh = 3 * nf;
  ProblemList duplicate("edges used twice in the same direction (faces inconsistently oriented or "
                        "the patch is not manifold)");
  {
    // Every a->b but the lowest id (find_half_edge's) is a duplicate: the later ones of a run of
    // equal targets in a's sorted row. Reported in half-edge order.
    std::vector<char> again(nh, 0);
    for (int a = 0; a < nv; ++a)
      for (int k = he.out_offset[a] + 1; k < he.out_offset[a + 1]; ++k)
        if (he.by_target[k].first == he.by_target[k - 1].first) again[he.by_target[k].second] = 1;
    for (int h = 0; h < nh; ++h)
      if (again[h]) duplicate.add(pair_str(he_from(patch.faces, h), he_to(patch.faces, h)));
  }
  duplicate.append_to(problems);

  ProblemList reversed("boundary edges reversed: the face holding the edge runs it the other way; the loop "
                       "must run counter-clockwise with the patch on its left (reverse the loop)");
  ProblemList not_edge("consecutive boundary loop entries that are not an edge of any face");
  ProblemList inner("consecutive boundary loop entries joined by an interior edge (faces on both sides)");
  for (int i = 0; i < nb; ++i) {
    const int a = patch.boundary[i], b = patch.boundary[(i + 1) % nb];
    const bool forward = find_half_edge(he, patch.faces, a, b) >= 0;
    const bool backward = find_half_edge(he, patch.faces, b, a) >= 0;
    if (forward && backward) inner.add(pair_str(a, b));
    else if (backward) reversed.add(pair_str(a, b));
    else if (!forward) not_edge.add(pair_str(a, b));
  }
  reversed.append_to(problems);
  not_edge.append_to(problems);
  inner.append_to(problems);

  if (problems.empty()) {
    // Connected components over the face edges (union-find).
    std::vector<int> parent(nv);
    for (int v = 0; v < nv; ++v) parent[v] = v;
    auto root = [&](int v) {
      while (parent[v] != v) v = parent[v] = parent[parent[v]];
      return v;
    };
    for (const Tri& t : patch.faces)
      for (int c = 0; c < 2; ++c) parent[root(t[c])] = root(t[c + 1]);
    int components = 0;
    for (int v = 0; v < nv; ++v)
      if (root(v) == v) ++components;
    if (components != 1)
      problems.push_back("the patch has " + std::to_string(components) +
                         " connected components; it must be one disk");
  }
  if (problems.empty()) {
    int border_edges = 0;
    for (int h = 0; h < nh; ++h)
      if (he.twin[h] < 0) ++border_edges;
    if (border_edges != nb) {
      problems.push_back("the patch has " + std::to_string(border_edges) +
                         " border edges but its boundary loop has " + std::to_string(nb) +
                         ": it has holes or more than one boundary loop; a patch must be a disk");
    } else {
      const int num_edges = (nh + border_edges) / 2;
      const int euler = nv - num_edges + nf;
      if (euler != 1)
        problems.push_back("the patch is not a disk: V - E + F = " + std::to_string(euler) + " (expected 1)");
    }
  }
  if (!problems.empty()) throw_problems(problems);
  return he;
}

/// The sides (bit s for side s) each vertex lies on; 0 for interior vertices. A corner lies on
/// both of its sides. \pre the boundary loop and corners are valid.
std::vector<unsigned> side_masks(const PatchMesh& patch) {
  std::vector<unsigned> mask(patch.positions.size(), 0u);
  const int nb = static_cast<int>(patch.boundary.size());
  for (int s = 0; s < 4; ++s) {
    const int begin = patch.corner_index[s];
    const int end = s < 3 ? patch.corner_index[s + 1] : nb;
    for (int i = begin; i <= end; ++i) mask[patch.boundary[i % nb]] |= 1u << s;
  }
  return mask;
}

[[noreturn]] void throw_factorization(Eigen::Index n, const std::string& why) {
  throw SolverError("parameterize_square: sparse LU factorization of the " + std::to_string(n) + "x" +
                    std::to_string(n) + " mean-value system failed: " + why);
}

/// Eigen SparseLU with its own column ordering (COLAMD on the columns only).
Eigen::MatrixX2d solve_colamd(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixX2d& rhs,
                              const Context& context) {
  Eigen::SparseLU<Eigen::SparseMatrix<double>, Eigen::COLAMDOrdering<int>> lu;
  lu.analyzePattern(A);
  lu.factorize(A);
  if (lu.info() != Eigen::Success) throw_factorization(A.rows(), lu.lastErrorMessage());
  context.report("parameterize: solve", 0.9);
  Eigen::MatrixX2d x = lu.solve(rhs);
  if (lu.info() != Eigen::Success) throw_factorization(A.rows(), "the solve failed");
  return x;
}

/// What a repeated solve with the same pattern (stretch minimization) keeps: the AMD ordering
/// and the LU's symbolic analysis.
struct SymbolicCache {
  bool ready = false;
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> perm;
  Eigen::SparseLU<Eigen::SparseMatrix<double>, Eigen::NaturalOrdering<int>> lu;
};

/// The matrix is structurally symmetric and row diagonally dominant: order rows and columns
/// together by AMD on its pattern (P^T A P), then factor with SparseLU in symmetric mode and a
/// low diagonal-pivot threshold so that the diagonal pivots (and the symmetric fill) are kept.
/// Gaussian elimination needs no pivoting on a row diagonally dominant matrix (growth <= 2).
Eigen::MatrixX2d solve_symmetric_amd(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixX2d& rhs,
                                     const Context& context, SymbolicCache& cache) {
  if (!cache.ready) {
    Eigen::AMDOrdering<int> amd;
    amd(A, cache.perm);
  }
  Eigen::SparseMatrix<double> B = cache.perm.transpose() * A * cache.perm;
  B.makeCompressed();
  auto& lu = cache.lu;
  if (!cache.ready) {
    lu.isSymmetric(true);
    lu.setPivotThreshold(kDiagonalPivotThreshold);
    lu.analyzePattern(B);
    cache.ready = true;
  }
  lu.factorize(B);
  if (lu.info() != Eigen::Success) throw_factorization(A.rows(), lu.lastErrorMessage());
  context.report("parameterize: solve", 0.9);
  const Eigen::MatrixX2d y = lu.solve(cache.perm.transpose() * rhs);
  if (lu.info() != Eigen::Success) throw_factorization(A.rows(), "the solve failed");
  return cache.perm * y;
}

/// What a repeated symmetric solve keeps: the Cholesky factor's ordering and supernodes.
struct CholeskyCache {
  bool ready = false;
  SupernodalCholesky llt;
  std::future<void> pending;                 // llt.analyze() running on another thread
  const std::vector<int>* ordering = nullptr;  // given by the caller: no ordering to find
};

/// Large cotangent systems are ordered (the analysis depends on the pattern only) on another
/// thread while the weights are computed and the matrix assembled.
constexpr int kEarlyAnalysisRows = 20000;

/// A symmetric positive definite system (cotangent weights, every weight positive, the border
/// fixed; A holds its lower triangle): sparse Cholesky, without pivoting. False when a pivot is
/// not positive in floating point (weights many orders of magnitude apart): the caller solves by
/// LU instead.
bool solve_cholesky(const Eigen::SparseMatrix<double>& A, const Eigen::MatrixX2d& rhs, const Context& context,
                    CholeskyCache& cache, Eigen::MatrixX2d& x) {
  auto& llt = cache.llt;
  if (cache.pending.valid()) {
    cache.pending.get();
    cache.ready = true;
  }
  if (!cache.ready) {
    if (cache.ordering) llt.analyze(A, *cache.ordering);
    else llt.analyze(A);
    cache.ready = true;
  }
  if (!llt.factorize(A, context.threads)) return false;
  context.report("parameterize: solve", 0.9);
  x = llt.solve(rhs, context.threads);
  return x.allFinite();
}

/// A triangulation of the patch's vertices given by edge lengths only (Fisher, Springborn, Schroeder,
/// Bobenko 2007): it starts as the patch itself and is flipped to the intrinsic Delaunay
/// triangulation of the same surface. Half-edge h = 3 f + c runs from faces[f][c] to
/// faces[f][(c+1)%3], has length len[h] and opposite twin[h] (-1 on the border).
struct IntrinsicMesh {
  std::vector<Tri> faces;
  std::vector<double> len;
  std::vector<int> twin;
  std::vector<double> cot;  ///< per half-edge: cot of the corner opposite it in its face (cot_at)
  int flips = 0;
  bool complete = true;  ///< every interior edge is Delaunay
};

/// Flip budget of the intrinsic Delaunay triangulation, per face (plus kMinFlipBudget). Lawson's
/// flips are quadratic in the worst case (a thin band between two chains of vertices, as a cut
/// leaves across a fan of slivers); patches of ordinary meshes need under one flip per face.
constexpr long kMaxFlipsPerFace = 4;
constexpr long kMinFlipBudget = 1000;

/// cot of the angle opposite side a in the triangle with sides a, b, c; +-kMaxCot when the
/// triangle has no area (the sign of the cosine decides).
constexpr double kMaxCot = 1e12;
double cot_opposite(double a, double b, double c) {
  const double num = b * b + c * c - a * a;  // 2bc cos
  // 16 A^2 by Heron's formula in its stable form (sides sorted).
  double x = a, y = b, z = c;
  if (x < y) std::swap(x, y);
  if (x < z) std::swap(x, z);
  if (y < z) std::swap(y, z);
  const double h16 = (x + (y + z)) * (z - (x - y)) * (z + (x - y)) * (x + (y - z));
  const double den = h16 > 0 ? std::sqrt(h16) : 0.0;  // 4 A
  if (!(den > 0)) return num < 0 ? -kMaxCot : kMaxCot;
  return std::clamp(num / den, -kMaxCot, kMaxCot);  // (2bc cos) / (4A) * 2 / 2 = cos / sin
}

/// cot of the corner opposite half-edge h in its face.
double cot_at(const IntrinsicMesh& m, int h) {
  const int f = h / 3, c = h % 3;
  return cot_opposite(m.len[h], m.len[3 * f + (c + 1) % 3], m.len[3 * f + (c + 2) % 3]);
}

/// Flips the patch to its intrinsic Delaunay triangulation (border edges stay). Every interior
/// edge ends with cot a + cot b >= -1e-12, unless the flips reach kMaxFlipsPerFace per face (then
/// `complete` is false and the triangulation is left part-flipped).
IntrinsicMesh intrinsic_delaunay(const PatchMesh& patch, const HalfEdges& he, double min_len) {
  IntrinsicMesh m;
  m.faces = patch.faces;
  m.twin = he.twin;
  const int nh = 3 * static_cast<int>(m.faces.size());
  m.len.resize(nh);
  for (int h = 0; h < nh; ++h)
    m.len[h] = std::max(min_len, (patch.positions[he_to(m.faces, h)] - patch.positions[he_from(m.faces, h)]).norm());
  // Symmetric lengths: both half-edges of an edge get the same value.
  for (int h = 0; h < nh; ++h)
    if (m.twin[h] > h) m.len[m.twin[h]] = m.len[h];
  m.cot.resize(nh);
  for (int h = 0; h < nh; ++h) m.cot[h] = cot_at(m, h);
  std::vector<int> stack;
  std::vector<char> queued(nh, 0);
  for (int h = 0; h < nh; ++h)
    if (m.twin[h] > h) {
      stack.push_back(h);
      queued[h] = 1;
    }
  const long max_flips = kMaxFlipsPerFace * static_cast<long>(m.faces.size()) + kMinFlipBudget;
  auto push = [&](int h) {
    if (h < 0 || m.twin[h] < 0) return;
    const int e = std::min(h, m.twin[h]);
    if (!queued[e]) {
      queued[e] = 1;
      stack.push_back(e);
    }
  };
  while (!stack.empty() && m.flips < max_flips) {
    const int h = stack.back();
    stack.pop_back();
    queued[h] = 0;
    const int t = m.twin[h];
    if (t < 0) continue;
    if (m.cot[h] + m.cot[t] >= -1e-12) continue;
    const int f = h / 3, c = h % 3, g = t / 3, d = t % 3;
    const int i = m.faces[f][c], j = m.faces[f][(c + 1) % 3], k = m.faces[f][(c + 2) % 3];
    const int l = m.faces[g][(d + 2) % 3];
    if (k == l) continue;
    const double l_ij = m.len[h], l_jk = m.len[3 * f + (c + 1) % 3], l_ki = m.len[3 * f + (c + 2) % 3];
    const double l_il = m.len[3 * g + (d + 1) % 3], l_lj = m.len[3 * g + (d + 2) % 3];
    const int o_jk = m.twin[3 * f + (c + 1) % 3], o_ki = m.twin[3 * f + (c + 2) % 3];
    const int o_il = m.twin[3 * g + (d + 1) % 3], o_lj = m.twin[3 * g + (d + 2) % 3];
    // The new diagonal k-l: unfold the two triangles about i.
    auto angle = [](double opp, double b, double c2) {
      const double cs = (b * b + c2 * c2 - opp * opp) / (2 * b * c2);
      return std::acos(std::clamp(cs, -1.0, 1.0));
    };
    const double th = angle(l_jk, l_ij, l_ki) + angle(l_lj, l_ij, l_il);
    const double kl = std::max(min_len, std::sqrt(std::max(0.0, l_ki * l_ki + l_il * l_il - 2 * l_ki * l_il * std::cos(th))));
    // f = (k, i, l), g = (l, j, k).
    m.faces[f] = {k, i, l};
    m.faces[g] = {l, j, k};
    const int nf_ki = 3 * f, nf_il = 3 * f + 1, nf_lk = 3 * f + 2;
    const int ng_lj = 3 * g, ng_jk = 3 * g + 1, ng_kl = 3 * g + 2;
    m.len[nf_ki] = l_ki;
    m.len[nf_il] = l_il;
    m.len[nf_lk] = kl;
    m.len[ng_lj] = l_lj;
    m.len[ng_jk] = l_jk;
    m.len[ng_kl] = kl;
    auto link = [&](int a, int b) {
      m.twin[a] = b;
      if (b >= 0) m.twin[b] = a;
    };
    link(nf_ki, o_ki);
    link(nf_il, o_il);
    link(ng_lj, o_lj);
    link(ng_jk, o_jk);
    link(nf_lk, ng_kl);
    for (int x = 0; x < 3; ++x) {  // the two faces' corners changed
      m.cot[3 * f + x] = cot_at(m, 3 * f + x);
      m.cot[3 * g + x] = cot_at(m, 3 * g + x);
    }
    ++m.flips;
    for (int x : {nf_ki, nf_il, ng_lj, ng_jk}) push(x);
  }
  m.complete = stack.empty();
  return m;
}

}  // namespace square_detail
using namespace square_detail;  // NOLINT(google-build-using-namespace): this file's own internals

std::vector<std::array<int, 2>> border_degeneracies(const PatchMesh& patch) {
  const HalfEdges he = validate_patch(patch, {});
  std::vector<char> interior(he.twin.size());
  for (size_t h = 0; h < he.twin.size(); ++h) interior[h] = he.twin[h] >= 0;
  return border_degeneracies(patch, interior);
}

std::vector<std::array<int, 2>> border_degeneracies(const PatchMesh& patch, const std::vector<char>& interior) {
  const std::vector<unsigned> mask = side_masks(patch);
  const auto& faces = patch.faces;
  std::vector<std::array<int, 2>> result;
  // Interior edges (both half-edges present: each visited once, from the lower id) joining two
  // vertices of one side.
  for (int h = 0; h < 3 * static_cast<int>(faces.size()); ++h) {
    if (!interior[h]) continue;
    const int a = he_from(faces, h), b = he_to(faces, h);
    if (a < b && (mask[a] & mask[b]) != 0) result.push_back({a, b});
  }
  // A face with all three vertices on one side has at least one edge that is not a border edge
  // (a 3-vertex border is rejected above), and that edge joins two same-side vertices, so it is
  // already listed; adding it again is harmless (deduplicated below) and keeps this explicit.
  for (int f = 0; f < static_cast<int>(faces.size()); ++f) {
    const Tri& t = faces[f];
    if ((mask[t[0]] & mask[t[1]] & mask[t[2]]) == 0) continue;
    for (int c = 0; c < 3; ++c) {
      if (!interior[3 * f + c]) continue;
      const int a = t[c], b = t[(c + 1) % 3];
      result.push_back({std::min(a, b), std::max(a, b)});
      break;
    }
  }
  std::sort(result.begin(), result.end());
  result.erase(std::unique(result.begin(), result.end()), result.end());
  return result;
}

namespace square_detail {

/// The border's (u, v): arc length on each side, each edge at least min_border_spacing times its
/// side's mean.
void place_border(const PatchMesh& patch, double min_border_spacing, std::vector<Vec2>& uv) {
  const auto& pos = patch.positions;
  const int nb = static_cast<int>(patch.boundary.size());
  const Vec2 corner_uv[4] = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};
  for (int s = 0; s < 4; ++s) {
    const int begin = patch.corner_index[s];
    const int end = s < 3 ? patch.corner_index[s + 1] : nb;
    const int m = end - begin;
    std::vector<double> len(m);
    double total = 0;
    for (int k = 0; k < m; ++k) {
      len[k] = (pos[patch.boundary[(begin + k + 1) % nb]] - pos[patch.boundary[begin + k]]).norm();
      total += len[k];
    }
    const double floor_len = min_border_spacing * total / m;
    double sum = 0;
    for (int k = 0; k < m; ++k) {
      if (!(total > 0)) len[k] = 1;  // a side of zero length: spread its vertices evenly
      len[k] = std::max(len[k], floor_len);
      sum += len[k];
    }
    const Vec2 a = corner_uv[s], b = corner_uv[(s + 1) % 4];
    double run = 0;
    uv[patch.boundary[begin]] = a;
    for (int k = 1; k < m; ++k) {
      run += len[k - 1];
      const double t = run / sum;
      uv[patch.boundary[begin + k]] = a + t * (b - a);  // exact 0 or 1 across the side
    }
  }
}

/// A patch's Laplacian: the triangulation it is built on (the patch itself, or its intrinsic
/// Delaunay triangulation for cotangent weights) and one weight per half-edge of it, for row
/// he_from. Not copyable: `faces` and `he` may point into it.
struct Laplacian {
  InteriorWeights weights = InteriorWeights::MeanValue;  ///< as built (cotangent may fall back)
  IntrinsicMesh idt;
  HalfEdges idt_he;
  const std::vector<Tri>* faces = nullptr;
  const HalfEdges* he = nullptr;
  std::vector<double> w;
  Laplacian() = default;
  Laplacian(const Laplacian&) = delete;
  Laplacian& operator=(const Laplacian&) = delete;
};

/// The triangulation of `lap` for `weights`: the intrinsic Delaunay triangulation for cotangent
/// weights (mean-value weights when its flips do not finish), else the patch's own.
void laplacian_triangulation(const PatchMesh& patch, const HalfEdges& he, InteriorWeights weights,
                             double min_edge_length, Laplacian& lap) {
  lap.weights = weights;
  lap.faces = &patch.faces;
  lap.he = &he;
  if (weights != InteriorWeights::IntrinsicCotan) return;
  lap.idt = intrinsic_delaunay(patch, he, min_edge_length);
  if (!lap.idt.complete) {
    lap.weights = InteriorWeights::MeanValue;
    return;
  }
  lap.idt_he = out_half_edges(static_cast<int>(patch.positions.size()), lap.idt.faces);  // twins: idt.twin
  lap.faces = &lap.idt.faces;
  lap.he = &lap.idt_he;
}

/// The weights of `lap` (after laplacian_triangulation), for every row without skip_row.
void laplacian_weights(const PatchMesh& patch, const HalfEdges& he, const std::vector<char>& skip_row,
                       double min_edge_length, Laplacian& lap) {
  const auto& pos = patch.positions;
  const auto& faces = patch.faces;
  const int nf = static_cast<int>(faces.size());
  lap.w.assign(3 * nf, 0.0);
  if (lap.weights == InteriorWeights::IntrinsicCotan) {
    // Cotangent weight of edge ij: (cot a + cot b) / 2 over the two corners opposite it in the
    // intrinsic Delaunay triangulation, where both sum to at most pi: non-negative.
    const IntrinsicMesh& idt = lap.idt;
    for (int h = 0; h < 3 * nf; ++h)
      lap.w[h] = std::max(0.0, 0.5 * (idt.twin[h] >= 0 ? idt.cot[h] + idt.cot[idt.twin[h]] : idt.cot[h]));
    return;
  }
  // Mean-value weight of half-edge i->j, for row i: (tan(a/2) + tan(b/2)) / |ij| over the two
  // corners at i next to the edge. Corner c of face f adds to its two out-going half-edge slots:
  // i->j is half-edge 3f+c itself, i->k is the twin of k->i (3f+(c+2)%3).
  for (int f = 0; f < nf; ++f) {
    const Tri& t = faces[f];
    for (int c = 0; c < 3; ++c) {
      const int i = t[c], j = t[(c + 1) % 3], k = t[(c + 2) % 3];
      if (skip_row[i]) continue;
      const Vec3 eij = pos[j] - pos[i], eik = pos[k] - pos[i];
      const double th = tan_half_angle(eij, eik);
      lap.w[3 * f + c] += th / std::max(eij.norm(), min_edge_length);
      lap.w[he.twin[3 * f + (c + 2) % 3]] += th / std::max(eik.norm(), min_edge_length);
    }
  }
}

/// One solve of the rows with interior_index >= 0 (ni of them) under half-edge weights ww, every
/// other vertex held at uv; their solution written to uv. By Cholesky when `spd` and the weights
/// allow it; false when the Cholesky factorization failed (nothing is changed then).
/// \throws SolverError when the LU factorization fails or the solution is not finite.
bool solve_rows(const Laplacian& lap, const std::vector<double>& ww, const std::vector<int>& interior_index,
                int ni, bool spd, LuOrdering ordering, const Context& context, CholeskyCache& cholesky,
                SymbolicCache& symbolic, std::vector<int>* cholesky_ordering, std::vector<Vec2>& uv) {
  const int nv = static_cast<int>(uv.size());
  const HalfEdges& he = *lap.he;
  // Symmetric assembly: the floor of edge ij is the larger of its two rows' floors, so the
  // matrix stays symmetric; a row without a usable weight falls back to the general path.
  std::vector<double> row_max_w;  // per vertex, the largest weight of its row (symmetric floor)
  if (spd) {
    row_max_w.assign(nv, 0.0);
    for (int i = 0; i < nv && spd; ++i) {
      for (int k = he.out_offset[i]; k < he.out_offset[i + 1]; ++k) {
        const double x = ww[he.out[k]];
        if (!std::isfinite(x)) spd = false;
        row_max_w[i] = std::max(row_max_w[i], x);
      }
      if (interior_index[i] >= 0 && !(row_max_w[i] > 0)) spd = false;
    }
  }
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(he.out.size() + ni);
  Eigen::MatrixX2d rhs = Eigen::MatrixX2d::Zero(ni, 2);
  for (int i = 0; i < nv; ++i) {
    const int r = interior_index[i];
    if (r < 0) continue;
    const int begin = he.out_offset[i], end = he.out_offset[i + 1];
    double wmax = 0;
    bool finite = true;
    for (int k = begin; k < end; ++k) {
      const double x = ww[he.out[k]];
      finite = finite && std::isfinite(x);
      wmax = std::max(wmax, x);
    }
    // No usable angle at all around i (every face degenerate), or overflow: uniform weights.
    const bool uniform = !finite || !(wmax > 0);
    const double floor_w = kRelativeWeightFloor * wmax;
    double diag = 0;
    for (int k = begin; k < end; ++k) {
      const int h = he.out[k];
      const int j = he_to(*lap.faces, h);
      const double x = spd ? std::max(ww[h], kRelativeWeightFloor * std::max(wmax, row_max_w[j]))
                           : uniform ? 1.0
                                     : std::max(ww[h], floor_w);
      diag += x;
      if (interior_index[j] >= 0) {
        if (!spd || interior_index[j] <= r) triplets.emplace_back(r, interior_index[j], -x);
      } else {
        rhs.row(r) += x * uv[j].transpose();
      }
    }
    triplets.emplace_back(r, r, diag);
  }
  Eigen::SparseMatrix<double> A(ni, ni);
  A.setFromTriplets(triplets.begin(), triplets.end());  // spd: the lower triangle only
  triplets = {};
  context.report("parameterize: factorize", 0.2);
  context.check_cancel();

  Eigen::MatrixX2d x;
  if (spd) {
    if (!solve_cholesky(A, rhs, context, cholesky, x)) return false;
    if (cholesky_ordering && cholesky_ordering->empty()) *cholesky_ordering = cholesky.llt.ordering();
  } else {
    x = ordering == LuOrdering::SymmetricAmd ? solve_symmetric_amd(A, rhs, context, symbolic)
                                             : solve_colamd(A, rhs, context);
  }
  if (!x.allFinite())
    throw SolverError("parameterize_square: the " + std::string(spd ? "cotangent" : "mean-value") + " solve (" +
                      std::to_string(ni) + " interior vertices) gave no finite solution");
  for (int v = 0; v < nv; ++v)
    if (interior_index[v] >= 0) uv[v] = x.row(interior_index[v]).transpose();
  return true;
}

}  // namespace square_detail

SquareParam parameterize_square(const PatchMesh& patch, const SquareParamOptions& options,
                                const Context& context) {
  const HalfEdges he = validate_patch(patch, options);
  context.check_cancel();
  const auto& pos = patch.positions;
  const auto& faces = patch.faces;
  const int nv = static_cast<int>(pos.size());
  const int nf = static_cast<int>(faces.size());

  SquareParam result;
  result.uv.assign(nv, Vec2::Zero());
  place_border(patch, options.min_border_spacing, result.uv);
  std::vector<int> interior_index(nv, -1);
  std::vector<char> on_border(nv, 0);
  for (int v : patch.boundary) on_border[v] = 1;

  for (const auto& [v, q] : options.pinned) {
    if (v < 0 || v >= nv || on_border[v] || !q.allFinite() || q.minCoeff() < 0 || q.maxCoeff() > 1)
      throw InvalidInput("parameterize_square: pinned vertex " + std::to_string(v) +
                         " is out of range, on the border, pinned twice or pinned outside the square");
    on_border[v] = 1;  // a fixed row, like the border
    result.uv[v] = q;
  }
  int ni = 0;
  for (int v = 0; v < nv; ++v)
    if (!on_border[v]) interior_index[v] = ni++;
  context.report("parameterize: weights", 0.0);

  result.weights = options.weights;
  const bool plain_uv_given = options.plain && options.plain->uv.size() == pos.size() && options.pinned.empty();
  if (ni > 0) {
    Laplacian lap;
    laplacian_triangulation(patch, he, options.weights, options.min_edge_length, lap);
    if (options.weights == InteriorWeights::IntrinsicCotan) result.intrinsic_flips = lap.idt.flips;
    result.weights = lap.weights;
    CholeskyCache cholesky;
    if (result.weights == InteriorWeights::IntrinsicCotan) {
      const bool solves = !plain_uv_given || options.stretch_iterations > 0;
      if (options.plain && is_permutation_of(options.plain->cholesky_ordering, ni))
        cholesky.ordering = &options.plain->cholesky_ordering;
      if (solves && !cholesky.ordering && ni >= kEarlyAnalysisRows && !inside_parallel_loop() &&
          thread_count(0, context) > 1) {
        // The lower triangle's pattern as the assembly makes it (same entries, same order).
        cholesky.pending = std::async(std::launch::async, [&] {
          std::vector<Eigen::Triplet<double>> pattern;
          pattern.reserve(lap.idt_he.out.size() / 2 + ni);
          for (int i = 0; i < nv; ++i) {
            const int r = interior_index[i];
            if (r < 0) continue;
            for (int k = lap.idt_he.out_offset[i]; k < lap.idt_he.out_offset[i + 1]; ++k) {
              const int j = interior_index[he_to(lap.idt.faces, lap.idt_he.out[k])];
              if (j >= 0 && j <= r) pattern.emplace_back(r, j, 1.0);
            }
            pattern.emplace_back(r, r, 1.0);
          }
          Eigen::SparseMatrix<double> lower(ni, ni);
          lower.setFromTriplets(pattern.begin(), pattern.end());
          cholesky.llt.analyze(lower);
        });
      }
    }
    laplacian_weights(patch, he, on_border, options.min_edge_length, lap);
    std::vector<double>& w = lap.w;
    const std::vector<Tri>* lap_faces = lap.faces;

    // Cotangent weights are symmetric (w_ij = w_ji), so with the border fixed the system is
    // symmetric positive definite and is solved by Cholesky; mean-value weights are not (LU).
    const bool symmetric = result.weights == InteriorWeights::IntrinsicCotan;
    SymbolicCache symbolic;
    bool use_cholesky = symmetric;  // false once a Cholesky factorization failed
    auto solve_with = [&](const std::vector<double>& ww) {
      if (use_cholesky && solve_rows(lap, ww, interior_index, ni, true, options.ordering, context, cholesky, symbolic,
                                     &result.cholesky_ordering, result.uv))
        return;
      use_cholesky = false;
      solve_rows(lap, ww, interior_index, ni, false, options.ordering, context, cholesky, symbolic,
                 &result.cholesky_ordering, result.uv);
    };
    if (plain_uv_given)
      result.uv = options.plain->uv;
    else
      solve_with(w);

    // Stretch minimization (Yoshizawa, Belyaev, Seidel 2004): divide every weight w_ij by the
    // stretch at j (area-weighted RMS of the face stretches around j) and solve again; keep the
    // lowest-stretch map. Weights stay positive, so with the convex border alone the map stays
    // bijective (counted all the same); the border never moves.
    if (options.stretch_iterations > 0) {
      // Faces without UV area have no finite stretch: they count as 10x the largest finite one,
      // so that a map squeezed to zero area in floating point is pushed apart too.
      std::vector<double> area3(nf);
      for (int f = 0; f < nf; ++f) {
        const Tri& t = faces[f];
        area3[f] = 0.5 * (pos[t[1]] - pos[t[0]]).cross(pos[t[2]] - pos[t[0]]).norm();
      }
      count_uv_faces(faces, result);
      Stretch st = l2_stretch(pos, faces, result.uv);  // of the current map
      std::vector<Vec2> best_uv = result.uv;
      int best_bad = result.flipped_faces + result.zero_area_faces;
      double best = best_bad == 0 ? st.patch : INFINITY;
      std::vector<double> sum(nv), area(nv), sigma(nv), row_max(nv);
      for (int it = 0; it < options.stretch_iterations; ++it) {
        context.check_cancel();
        double cap = 0;
        for (double x : st.face)
          if (std::isfinite(x)) cap = std::max(cap, x);
        cap = cap > 0 ? 10 * cap : 1e6;
        std::fill(sum.begin(), sum.end(), 0.0);
        std::fill(area.begin(), area.end(), 0.0);
        for (int f = 0; f < nf; ++f) {
          const double x = std::isfinite(st.face[f]) ? st.face[f] : cap;
          for (int v : faces[f]) {
            sum[v] += area3[f] * x * x;
            area[v] += area3[f];
          }
        }
        for (int v = 0; v < nv; ++v)
          sigma[v] = area[v] > 0 && sum[v] > 0 && std::isfinite(sum[v]) ? std::sqrt(sum[v] / area[v]) : 1.0;
        if (symmetric) {
          // Row i of the system with w_ij / sigma_j, multiplied by the product of 1 / sigma_i
          // over the rounds so far (the map does not change), has the symmetric weights
          // w_ij / (sigma_i sigma_j) round after round: still a Cholesky system. All weights are
          // rescaled to a largest of 1, so that repeated divisions do not underflow.
          double wmax = 0;
          for (int f = 0; f < nf; ++f)
            for (int c = 0; c < 3; ++c) {
              double& x = w[3 * f + c];
              x /= sigma[(*lap_faces)[f][c]] * sigma[(*lap_faces)[f][(c + 1) % 3]];
              wmax = std::max(wmax, x);
            }
          if (wmax > 0)
            for (double& x : w) x /= wmax;
        } else {
          std::fill(row_max.begin(), row_max.end(), 0.0);
          for (int f = 0; f < nf; ++f)
            for (int c = 0; c < 3; ++c) {
              double& x = w[3 * f + c];
              x /= sigma[(*lap_faces)[f][(c + 1) % 3]];
              row_max[(*lap_faces)[f][c]] = std::max(row_max[(*lap_faces)[f][c]], x);
            }
          // Rows rescaled to a largest weight of 1 (the map does not change): repeated divisions
          // would otherwise underflow.
          for (int f = 0; f < nf; ++f)
            for (int c = 0; c < 3; ++c)
              if (row_max[(*lap_faces)[f][c]] > 0) w[3 * f + c] /= row_max[(*lap_faces)[f][c]];
        }
        try {
          solve_with(w);
        } catch (const SolverError&) {
          break;  // keep the best map so far
        }
        count_uv_faces(faces, result);
        st = l2_stretch(pos, faces, result.uv);
        const int bad = result.flipped_faces + result.zero_area_faces;
        const double now = bad == 0 ? st.patch : INFINITY;
        if (bad < best_bad || (bad == 0 && now < best * (1 - kMinGain))) {
          best_bad = bad;
          best = now;
          best_uv = result.uv;
        } else if (best_bad == 0) {
          break;  // bijective and no longer improving
        }
      }
      result.uv = std::move(best_uv);
    }
  }

  count_uv_faces(faces, result);
  context.report("parameterize: done", 1.0);
  if (!result.bijective())
    context.warn("parameterize_square: " + std::to_string(result.flipped_faces) + " flipped and " +
                 std::to_string(result.zero_area_faces) + " zero-area UV faces of " + std::to_string(nf));
  return result;
}

struct HeldSolver::Impl {
  HalfEdges he;
  Laplacian lap;  ///< may point into the caller's patch (mean-value weights)
  std::vector<Vec2> border_uv;
  std::vector<char> on_border;
  Context context;
  Impl(const PatchMesh& p, const Context& c) : he(validate_patch(p, {})), context(c) {}
};

HeldSolver::HeldSolver(const PatchMesh& patch, InteriorWeights weights, const Context& context)
    : impl_(std::make_unique<Impl>(patch, context)) {
  Impl& m = *impl_;
  const int nv = static_cast<int>(patch.positions.size());
  const SquareParamOptions defaults;
  m.border_uv.assign(nv, Vec2::Zero());
  place_border(patch, defaults.min_border_spacing, m.border_uv);
  m.on_border.assign(nv, 0);
  for (int v : patch.boundary) m.on_border[v] = 1;
  laplacian_triangulation(patch, m.he, weights, defaults.min_edge_length, m.lap);
  laplacian_weights(patch, m.he, m.on_border, defaults.min_edge_length, m.lap);
}

HeldSolver::~HeldSolver() = default;

void HeldSolver::solve(const std::vector<char>& free, std::vector<Vec2>& uv) const {
  const Impl& m = *impl_;
  const int nv = static_cast<int>(m.on_border.size());
  if (static_cast<int>(free.size()) != nv || static_cast<int>(uv.size()) != nv)
    throw InvalidInput("HeldSolver::solve: " + std::to_string(free.size()) + " free flags and " +
                       std::to_string(uv.size()) + " (u, v) for a patch of " + std::to_string(nv) + " vertices");
  std::vector<Vec2> full = uv;
  std::vector<int> interior_index(nv, -1);
  int ni = 0;
  for (int v = 0; v < nv; ++v) {
    if (m.on_border[v]) {
      full[v] = m.border_uv[v];
    } else if (free[v]) {
      interior_index[v] = ni++;
    } else if (!uv[v].allFinite() || uv[v].minCoeff() < 0 || uv[v].maxCoeff() > 1) {
      throw InvalidInput("HeldSolver::solve: held vertex " + std::to_string(v) + " is outside the square");
    }
  }
  if (ni == 0) return;
  CholeskyCache cholesky;
  SymbolicCache symbolic;
  const SquareParamOptions defaults;
  if (m.lap.weights != InteriorWeights::IntrinsicCotan ||
      !solve_rows(m.lap, m.lap.w, interior_index, ni, true, defaults.ordering, m.context, cholesky, symbolic, nullptr,
                  full))
    solve_rows(m.lap, m.lap.w, interior_index, ni, false, defaults.ordering, m.context, cholesky, symbolic, nullptr,
               full);
  for (int v = 0; v < nv; ++v)
    if (interior_index[v] >= 0) uv[v] = full[v];
}

void count_uv_faces(const std::vector<Tri>& faces, SquareParam& sp) {
  sp.flipped_faces = sp.zero_area_faces = 0;
  sp.uv_area_sum = 0;
  for (const Tri& t : faces) {
    if (std::max({t[0], t[1], t[2]}) >= static_cast<int>(sp.uv.size()) || std::min({t[0], t[1], t[2]}) < 0)
      throw InvalidInput("count_uv_faces: a face refers to a vertex without uv");
    const Vec2 &a = sp.uv[t[0]], &b = sp.uv[t[1]], &c = sp.uv[t[2]];
    const double area = 0.5 * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
    sp.uv_area_sum += area;
    if (std::abs(area) <= kZeroUvArea) ++sp.zero_area_faces;
    else if (area < 0) ++sp.flipped_faces;
  }
}

}  // namespace qs::param
