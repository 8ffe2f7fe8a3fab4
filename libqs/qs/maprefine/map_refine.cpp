#include "qs/maprefine/map_refine.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <functional>
#include <memory>
#include <limits>
#include <map>
#include <tuple>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <unordered_map>

#include "qs/core/error.h"
#include "qs/core/geometry2d.h"
#include "qs/core/parallel.h"
#include "qs/landmarks/landmarks.h"
#include "qs/metro/metro.h"
#include "qs/param/square_param.h"

namespace qs::maprefine {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
using Mat32 = Eigen::Matrix<double, 3, 2>;
using Mat46 = Eigen::Matrix<double, 4, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

// Eigenvalues of a symmetric 2x2 matrix clamped into [lo, hi] (closed form).
Eigen::Matrix2d clamp_metric(const Eigen::Matrix2d& m, double lo, double hi) {
  const double a = m(0, 0), b = 0.5 * (m(0, 1) + m(1, 0)), c = m(1, 1);
  const double mean = 0.5 * (a + c), r = std::hypot(0.5 * (a - c), b);
  const double l1 = mean + r, l2 = mean - r;
  const double c1 = std::clamp(l1, lo, hi), c2 = std::clamp(l2, lo, hi);
  if (c1 == l1 && c2 == l2) return m;
  if (r <= 1e-300) return 0.5 * (c1 + c2) * Eigen::Matrix2d::Identity();
  // Eigenvector of l1: (b, l1 - a) or (l1 - c, b), whichever is longer.
  Vec2 e1 = std::abs(l1 - a) > std::abs(l1 - c) ? Vec2(b, l1 - a) : Vec2(l1 - c, b);
  e1.normalize();
  return c1 * e1 * e1.transpose() + c2 * (Eigen::Matrix2d::Identity() - e1 * e1.transpose());
}

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

// One patch of the reference mesh: its surface's metric in (u, v) per face corner (the uv-area
// weighted mean of the metrics of the patch's faces around the vertex, each with its eigenvalues
// clamped to [1e-6, 1e6] times the patch's mean, so that uv slivers do not dominate), and a
// uniform grid over the unit square for point location (about one cell per face).
class ReferencePatch {
 public:
  ReferencePatch(const dissect::Chart& chart, std::vector<int> faces) : faces_(std::move(faces)) {
    const size_t nf = faces_.size();
    wedge_.resize(nf);
    std::vector<Eigen::Matrix2d> metric(nf, Eigen::Matrix2d::Zero());
    std::vector<double> uv_area(nf, 0.0);
    double total_uv = 0;
    for (size_t i = 0; i < nf; ++i) {
      const int f = faces_[i];
      const auto& t = chart.mesh.faces[f];
      const auto& uv = chart.face_uv[f];
      const Vec3& x0 = chart.mesh.positions[t[0]];
      Mat32 e;
      e.col(0) = chart.mesh.positions[t[1]] - x0;
      e.col(1) = chart.mesh.positions[t[2]] - x0;
      Eigen::Matrix2d ds;
      ds.col(0) = uv[1] - uv[0];
      ds.col(1) = uv[2] - uv[0];
      area_ += 0.5 * e.col(0).cross(e.col(1)).norm();
      const double auv = 0.5 * ds.determinant();
      if (auv > param::kZeroUvArea) {
        const Mat32 g = e * ds.inverse();
        metric[i] = g.transpose() * g;
        uv_area[i] = auv;
        total_uv += auv;
      }
    }
    const double mean = total_uv > 0 && area_ > 0 ? area_ / total_uv : 1.0;
    std::unordered_map<int, std::pair<Eigen::Matrix2d, double>> acc;
    acc.reserve(nf);
    for (size_t i = 0; i < nf; ++i) {
      if (uv_area[i] <= 0) continue;
      const Eigen::Matrix2d m = clamp_metric(metric[i], 1e-6 * mean, 1e6 * mean);
      for (int v : chart.mesh.faces[faces_[i]]) {
        auto& a = acc.try_emplace(v, Eigen::Matrix2d::Zero(), 0.0).first->second;
        a.first += uv_area[i] * m;
        a.second += uv_area[i];
      }
    }
    for (size_t i = 0; i < nf; ++i)
      for (int k = 0; k < 3; ++k) {
        const auto it = acc.find(chart.mesh.faces[faces_[i]][k]);
        wedge_[i][k] = it != acc.end() && it->second.second > 0 ? Eigen::Matrix2d(it->second.first / it->second.second)
                                                                 : Eigen::Matrix2d(mean * Eigen::Matrix2d::Identity());
      }
    // Location (faces with a positive uv area only; a point outside every face of its cell takes
    // the least outside of them).
    std::vector<std::array<Vec2, 3>> tris(nf);
    std::vector<char> positive(nf, 0);
    for (size_t i = 0; i < nf; ++i) {
      tris[i] = chart.face_uv[faces_[i]];
      positive[i] = uv_area[i] > 0;
    }
    locator_.emplace(std::move(tris), positive, false);
  }

  double area() const { return area_; }

  // The metric at uv (clamped to the square); `hint`: a local face to try first, updated.
  Eigen::Matrix2d metric(const Vec2& q, int& hint) const {
    Vec3 bary;
    const int best = locator_->locate(q, hint, bary);
    if (best < 0) return Eigen::Matrix2d::Identity() * (area_ > 0 ? area_ : 1.0);
    return bary[0] * wedge_[best][0] + bary[1] * wedge_[best][1] + bary[2] * wedge_[best][2];
  }

 private:
  std::vector<int> faces_;
  std::vector<std::array<Eigen::Matrix2d, 3>> wedge_;
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
Eigen::Matrix2d local_edges(const Vec3& x0, const Vec3& x1, const Vec3& x2, double& area) {
  const Vec3 e1 = x1 - x0, e2 = x2 - x0;
  area = 0.5 * e1.cross(e2).norm();
  const double l1 = e1.norm();
  const double longest = std::max({l1, e2.norm(), (x2 - x1).norm(), 1e-300});
  Eigen::Matrix2d dm;
  if (l1 <= 1e-12 * longest) {
    dm << longest, 0, 0, 1e-3 * longest;
    return dm;
  }
  const double a = e1.dot(e2) / l1;
  const double h = std::max(2.0 * area / l1, 1e-3 * longest);
  dm << l1, a, 0, h;
  return dm;
}

void PatchProblem::add_face(const dissect::Chart& chart, int f, int patch, const std::array<int, 3>& c) {
  tri.push_back(c);
  faces.push_back(f);
  face_patch.push_back(patch);
  double a = 0;
  const auto& t = chart.mesh.faces[f];
  const Eigen::Matrix2d dm = local_edges(chart.mesh.positions[t[0]], chart.mesh.positions[t[1]], chart.mesh.positions[t[2]], a);
  dm_inv.push_back(dm.inverse());
  area.push_back(a);
  total_area += a;
}

void PatchProblem::add_unknowns(const std::vector<char>& held) {
  for (size_t l = 0; l < held.size(); ++l) {
    const bool free = !held[l];
    var.push_back(free ? unknowns : -1);
    dims.push_back(free ? 2 : 0);
    basis.push_back(Vec2::Zero());
    if (free) unknowns += 2;
  }
}

// vec(J) = A x for J = Q [x1 - x0, x2 - x0] P, x = (u0, v0, u1, v1, u2, v2), vec row-major.
Mat46 jacobian_matrix(const Eigen::Matrix2d& q, const Eigen::Matrix2d& p) {
  Mat46 a = Mat46::Zero();
  for (int r = 0; r < 2; ++r)
    for (int b = 0; b < 2; ++b)
      for (int c = 0; c < 2; ++c)
        for (int d = 0; d < 2; ++d) {
          const double w = q(r, c) * p(d, b);
          a(2 * r + b, 2 * (d + 1) + c) += w;
          a(2 * r + b, c) -= w;
        }
  return a;
}

double tri_det(const Vec2& a, const Vec2& b, const Vec2& c) { return cross2(b - a, c - a); }

// Smallest alpha > 0 at which det(Ds + alpha dDs) = 0, or +inf.
double flip_step(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& da, const Vec2& db, const Vec2& dc) {
  const Vec2 e1 = b - a, e2 = c - a, d1 = db - da, d2 = dc - da;
  const double c0 = cross2(e1, e2);
  const double c1 = cross2(e1, d2) + cross2(d1, e2);
  const double c2 = cross2(d1, d2);
  double best = kInf;
  auto consider = [&](double t) {
    if (t > 0 && t < best) best = t;
  };
  const double scale = std::abs(c0) + std::abs(c1) + std::abs(c2);
  if (scale == 0) return kInf;
  if (std::abs(c2) <= 1e-14 * scale) {
    if (c1 != 0) consider(-c0 / c1);
    return best;
  }
  const double disc = c1 * c1 - 4 * c2 * c0;
  if (disc < 0) return best;
  const double s = std::sqrt(disc);
  const double qq = -0.5 * (c1 + (c1 >= 0 ? s : -s));
  if (qq != 0) {
    consider(qq / c2);
    consider(c0 / qq);
  }
  return best;
}

}  // namespace

Eigen::Matrix4d projected_hessian(const Eigen::Matrix2d& J) {
  // J = C + A, C = [E -H; H E] conformal, A = [F G; G -F] anticonformal; the singular values are
  // Q + R and Q - R with Q = |(E, H)|, R = |(F, G)| (positive when det J = Q^2 - R^2 > 0). The
  // Hessian of an isotropic energy is diagonal in the basis U M V^T (J = U S V^T) with M the two
  // scalings e1 e1^T, e2 e2^T, the twist and the flip (e1 e2^T -+ e2 e1^T) / sqrt(2) (Smith, Goes,
  // Kim 2019); in terms of C and A those are (C^ +- A^) / 2, the conformal direction turned by 90
  // degrees and the anticonformal one turned, ^ meaning divided by Q or R. With
  // psi = s1^2 + s2^2 + s1^-2 + s2^-2: scalings 2 + 6 / si^4, twist (psi_1 + psi_2) / (s1 + s2) =
  // 2 - 2 (s1^2 - s1 s2 + s2^2) / (s1 s2)^3, flip (psi_1 - psi_2) / (s1 - s2) =
  // 2 + 2 (s1^2 + s1 s2 + s2^2) / (s1 s2)^3. Only the twist can be negative; it is clamped at 0.
  const double e = 0.5 * (J(0, 0) + J(1, 1)), f = 0.5 * (J(0, 0) - J(1, 1));
  const double g = 0.5 * (J(1, 0) + J(0, 1)), h = 0.5 * (J(1, 0) - J(0, 1));
  const double q = std::sqrt(e * e + h * h), r = std::sqrt(f * f + g * g);
  const double s1 = q + r, s2 = q - r;
  // Unit conformal and anticonformal directions as vec (J00, J01, J10, J11); for R = 0 (s1 = s2)
  // the two anticonformal eigenvalues equal the scalings' and any unit A will do.
  const Eigen::Vector4d c = Eigen::Vector4d(e, -h, h, e) / q;
  const Eigen::Vector4d ct = Eigen::Vector4d(-h, -e, e, -h) / q;
  Eigen::Vector4d a(1, 0, 0, -1), at(0, 1, 1, 0);
  if (r > 0) {
    a = Eigen::Vector4d(f, g, g, -f) / r;
    at = Eigen::Vector4d(g, -f, -f, -g) / r;
  }
  const double p = s1 * s2, p3 = p * p * p;
  const double l1 = 2 + 6 / (s1 * s1 * s1 * s1), l2 = 2 + 6 / (s2 * s2 * s2 * s2);
  const double twist = 2 - 2 * (s1 * s1 - p + s2 * s2) / p3, flip = 2 + 2 * (s1 * s1 + p + s2 * s2) / p3;
  // Modes of unit Frobenius norm: (c + a) / 2, (c - a) / 2, ct / sqrt(2), at / sqrt(2).
  const Eigen::Vector4d m1 = 0.5 * (c + a), m2 = 0.5 * (c - a);
  Eigen::Matrix4d out = l1 * m1 * m1.transpose() + l2 * m2 * m2.transpose() + 0.5 * flip * at * at.transpose();
  if (twist > 0) out += 0.5 * twist * ct * ct.transpose();
  return out;
}

namespace {

// The reference's metric seen by one face of a problem: (local face, uv point) -> 2x2 metric.
using MetricFn = std::function<Eigen::Matrix2d(size_t, const Vec2&)>;

// Instead of a metric: the Jacobian of local face t's map to the reference, linearized at the
// current uv, vec(J_t) = a x + b (x: the face's corner uv, as jacobian_matrix); refine_patch's
// composition.
using LinearizeFn = std::function<void(size_t, Mat46&, Eigen::Vector4d&)>;

// The metric of a problem whose faces lie in their own patches' unit squares: per patch, the
// reference patch and area_B(patch) / area_A(patch); one location hint per face.
MetricFn patch_metric(const PatchProblem& prob, const std::vector<ReferencePatch>& refs,
                      const std::vector<double>& scale) {
  auto hints = std::make_shared<std::vector<int>>(prob.faces.size(), -1);
  return [&prob, &refs, &scale, hints](size_t t, const Vec2& q) {
    const int p = prob.face_patch[t];
    return Eigen::Matrix2d(scale[p] * refs[p].metric(q.cwiseMax(0.0).cwiseMin(1.0), (*hints)[t]));
  };
}

// The map from local face t's corner uv to its Jacobian against `metric` taken at its uv centroid
// (vec(J) = a x, x the corner uv as corner_uv).
Mat46 metric_jacobian(const PatchProblem& prob, size_t t, const MetricFn& metric) {
  const auto& c = prob.tri[t];
  const Vec2 centroid = (prob.uv[c[0]] + prob.uv[c[1]] + prob.uv[c[2]]) / 3.0;
  const Eigen::Matrix2d m = metric(t, centroid);
  Eigen::LLT<Eigen::Matrix2d> llt(m);
  const Eigen::Matrix2d l = llt.info() == Eigen::Success
                                ? Eigen::Matrix2d(llt.matrixL())
                                : Eigen::Matrix2d(std::sqrt(std::max(m.trace() / 2, 1e-300)) * Eigen::Matrix2d::Identity());
  return jacobian_matrix(l.transpose(), prob.dm_inv[t]);
}

// Local face t's corner uv as one vector (u0, v0, u1, v1, u2, v2).
Vec6 corner_uv(const PatchProblem& prob, size_t t, const std::vector<Vec2>& uv) {
  const auto& c = prob.tri[t];
  Vec6 x;
  x << uv[c[0]], uv[c[1]], uv[c[2]];
  return x;
}

// Local face t's area * symDirichlet(J), vec(J) = a x + b at uv; +inf when it folds.
double face_energy(const PatchProblem& prob, size_t t, const Mat46& a, const Eigen::Vector4d& b,
                   const std::vector<Vec2>& uv) {
  const auto& c = prob.tri[t];
  if (tri_det(uv[c[0]], uv[c[1]], uv[c[2]]) <= 2 * param::kZeroUvArea) return kInf;
  const Eigen::Vector4d j = a * corner_uv(prob, t, uv) + b;
  Eigen::Matrix2d jm;
  jm << j[0], j[1], j[2], j[3];
  const double f = sym_dirichlet(jm);
  return std::isfinite(f) ? prob.area[t] * f : kInf;
}

class PatchSolver {
 public:
  // `metric`: the reference's (scaled) metric for local face t at uv point q of the problem;
  // `linearize`, when given, replaces it (the per-face Jacobian's affine model at the current uv).
  PatchSolver(PatchProblem& prob, const MetricFn& metric, const LinearizeFn* linearize = nullptr)
      : prob_(prob), metric_(metric), linearize_(linearize) {
    a_.resize(prob.faces.size());
    b_.assign(prob.faces.size(), Eigen::Vector4d::Zero());
  }

  // Re-evaluates the reference metric at the faces' uv centroids and the per-face Jacobian maps.
  void update_metric() {
    if (linearize_) {
      for (size_t t = 0; t < prob_.faces.size(); ++t) (*linearize_)(t, a_[t], b_[t]);
      return;
    }
    for (size_t t = 0; t < prob_.faces.size(); ++t) a_[t] = metric_jacobian(prob_, t, metric_);
  }

  // Distortion energy (sum of area * symDirichlet) at uv under the current metric; +inf when a
  // face folds.
  double distortion(const std::vector<Vec2>& uv) const {
    double e = 0;
    for (size_t t = 0; t < prob_.faces.size(); ++t) {
      const double f = face_energy(prob_, t, a_[t], b_[t], uv);
      if (!std::isfinite(f)) return kInf;
      e += f;
    }
    return e;
  }

  // The pose pull's energy at uv (0 without one).
  double pull(const std::vector<Vec2>& uv) const {
    double e = 0;
    for (size_t v = 0; v < prob_.pull.size(); ++v) {
      const Vec2 d = uv[v] - prob_.target[v];
      e += d.dot(prob_.pull[v] * d);
    }
    return e;
  }

  // What the solver minimizes: the distortion and the pose pull.
  double energy(const std::vector<Vec2>& uv) const {
    const double e = distortion(uv);
    return std::isfinite(e) ? e + pull(uv) : kInf;
  }

  // One projected Newton step; returns false when no progress was made.
  bool step(double& e_now, double tolerance) {
    const int n = prob_.unknowns;
    if (n == 0) return false;
    // The Hessian's entries come in the same order at every step (assemble): the first step
    // collects them as triplets, which fix the pattern (analyze); the later ones add each straight
    // into the value where it landed (slot_).
    double diag = 0;  // the largest single diagonal contribution (scales the regularization)
    Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
    if (!analyzed_) {
      std::vector<Eigen::Triplet<double>> trip;
      trip.reserve(prob_.faces.size() * 36 + prob_.pull.size() * 4 + n);
      if (!assemble(g, [&](int row, int col, double x) {
            trip.emplace_back(row, col, x);
            if (row == col) diag = std::max(diag, x);
          }))
        return false;
      analyze(trip);
    } else {
      double* const value = h_.valuePtr();
      std::fill(value, value + h_.nonZeros(), 0.0);
      const std::ptrdiff_t* slot = slot_.data();
      if (!assemble(g, [&](int row, int col, double x) {
            value[*slot++] += x;
            if (row == col) diag = std::max(diag, x);
          }))
        return false;
    }
    std::vector<double> plain(n);
    for (int i = 0; i < n; ++i) plain[i] = h_.valuePtr()[diag_slot_[i]];
    Eigen::VectorXd d;
    double mu = 1e-10 * std::max(diag, 1e-300);
    for (int attempt = 0; attempt < 6; ++attempt, mu *= 100) {
      for (int i = 0; i < n; ++i) h_.valuePtr()[diag_slot_[i]] = plain[i] + mu;
      ldlt_.factorize(h_);
      if (ldlt_.info() != Eigen::Success) continue;
      d = ldlt_.solve(-g);
      if (ldlt_.info() == Eigen::Success && d.allFinite() && g.dot(d) < 0) break;
      d.resize(0);
    }
    if (d.size() == 0) return false;
    // Direction per local vertex; cap the step below the first fold.
    std::vector<Vec2> dir(prob_.uv.size(), Vec2::Zero());
    for (size_t v = 0; v < prob_.uv.size(); ++v)
      if (prob_.dims[v] == 2) dir[v] = Vec2(d[prob_.var[v]], d[prob_.var[v] + 1]);
      else if (prob_.dims[v] == 1) dir[v] = d[prob_.var[v]] * prob_.basis[v];
    double alpha_max = kInf;
    for (const auto& c : prob_.tri)
      alpha_max = std::min(alpha_max, flip_step(prob_.uv[c[0]], prob_.uv[c[1]], prob_.uv[c[2]], dir[c[0]], dir[c[1]],
                                                dir[c[2]]));
    double alpha = std::min(1.0, 0.8 * alpha_max);
    const double slope = g.dot(d);
    std::vector<Vec2> trial(prob_.uv.size());
    for (int k = 0; k < 40; ++k, alpha *= 0.5) {
      for (size_t v = 0; v < trial.size(); ++v) trial[v] = prob_.uv[v] + alpha * dir[v];
      const double e = energy(trial);
      if (e <= e_now + 1e-4 * alpha * slope) {
        const double gain = e_now - e;
        prob_.uv.swap(trial);
        e_now = e;
        return gain > tolerance * e;
      }
    }
    return false;
  }

 private:
  PatchProblem& prob_;
  const MetricFn& metric_;
  const LinearizeFn* linearize_;
  // The gradient into g and every Hessian entry to add(row, col, value), faces then the pose pull,
  // in the same order at every call; false when a face's energy is not finite.
  template <class Add>
  bool assemble(Eigen::VectorXd& g, Add&& add) const {
    for (size_t t = 0; t < prob_.faces.size(); ++t) {
      const Eigen::Vector4d j = a_[t] * corner_uv(prob_, t, prob_.uv) + b_[t];
      Eigen::Matrix2d jm;
      jm << j[0], j[1], j[2], j[3];
      Eigen::Vector4d gj;
      if (!std::isfinite(sym_dirichlet(jm, &gj))) return false;
      const Eigen::Matrix4d hp = projected_hessian(jm);
      const Vec6 gx = prob_.area[t] * a_[t].transpose() * gj;
      const Mat6 hx = prob_.area[t] * a_[t].transpose() * hp * a_[t];
      std::array<std::pair<int, Vec2>, 6> cols;
      std::array<int, 6> col_corner{};
      const int ncols = face_columns(t, cols, col_corner);
      for (int r = 0; r < ncols; ++r) {
        const int kr = col_corner[r];
        g[cols[r].first] += cols[r].second.dot(gx.segment<2>(2 * kr));
        for (int q = 0; q < ncols; ++q) {
          const int kq = col_corner[q];
          add(cols[r].first, cols[q].first, cols[r].second.dot(hx.block<2, 2>(2 * kr, 2 * kq) * cols[q].second));
        }
      }
    }
    // The pose pull: gradient 2 P (uv - target), Hessian 2 P per free vertex.
    for (size_t v = 0; v < prob_.pull.size(); ++v) {
      if (prob_.dims[v] == 0) continue;
      const Vec2 gv = 2 * prob_.pull[v] * (prob_.uv[v] - prob_.target[v]);
      const Eigen::Matrix2d hv = 2 * prob_.pull[v];
      const int i = prob_.var[v];
      if (prob_.dims[v] == 2) {
        g.segment<2>(i) += gv;
        for (int r = 0; r < 2; ++r)
          for (int q = 0; q < 2; ++q) add(i + r, i + q, hv(r, q));
      } else {
        g[i] += prob_.basis[v].dot(gv);
        add(i, i, prob_.basis[v].dot(hv * prob_.basis[v]));
      }
    }
    return true;
  }

  // Face t's unknown columns among its 6 corner coordinates: (unknown, d corner uv / d unknown),
  // and the corner of each; returns their count.
  int face_columns(size_t t, std::array<std::pair<int, Vec2>, 6>& cols, std::array<int, 6>& col_corner) const {
    int ncols = 0;
    const auto& c = prob_.tri[t];
    for (int k = 0; k < 3; ++k) {
      const int lv = c[k];
      if (prob_.dims[lv] == 2) {
        col_corner[ncols] = k;
        cols[ncols++] = {prob_.var[lv], Vec2(1, 0)};
        col_corner[ncols] = k;
        cols[ncols++] = {prob_.var[lv] + 1, Vec2(0, 1)};
      } else if (prob_.dims[lv] == 1) {
        col_corner[ncols] = k;
        cols[ncols++] = {prob_.var[lv], prob_.basis[lv]};
      }
    }
    return ncols;
  }

  // The Hessian's pattern, the same at every step: the first step's entries `trip` (summed where
  // they repeat) and the whole diagonal, which takes the regularization; ordered once. slot_ is
  // where each entry lands in the value array, diag_slot_ each diagonal entry.
  void analyze(std::vector<Eigen::Triplet<double>>& trip) {
    const int n = prob_.unknowns;
    const size_t visited = trip.size();
    for (int i = 0; i < n; ++i) trip.emplace_back(i, i, 0.0);
    h_.resize(n, n);
    h_.setFromTriplets(trip.begin(), trip.end());
    h_.makeCompressed();
    const double* base = h_.valuePtr();
    slot_.resize(visited);
    for (size_t k = 0; k < visited; ++k) slot_[k] = &h_.coeffRef(trip[k].row(), trip[k].col()) - base;
    diag_slot_.resize(n);
    for (int i = 0; i < n; ++i) diag_slot_[i] = &h_.coeffRef(i, i) - base;
    ldlt_.analyzePattern(h_);
    analyzed_ = true;
  }

  std::vector<Mat46> a_;
  std::vector<Eigen::Vector4d> b_;
  Eigen::SparseMatrix<double> h_;
  std::vector<std::ptrdiff_t> slot_, diag_slot_;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt_;
  bool analyzed_ = false;
};

struct PatchResult {
  bool changed = false;
  bool skipped = false;
  int steps = 0;
  double energy_before = 0, energy_after = 0, area = 0;  // unnormalized energies, total 3D area
  int free = 0, held = 0;
};

void check_set(const std::vector<dissect::Dissection>& meshes, const RefineOptions& options) {
  if (meshes.empty()) throw InvalidInput("refine_maps: the set is empty; give the meshes of one dissection");
  if (options.reference < 0 || options.reference >= static_cast<int>(meshes.size()))
    throw InvalidInput("refine_maps: reference mesh " + std::to_string(options.reference) + " is not in the set of " +
                       std::to_string(meshes.size()) + " meshes (expected 0.." + std::to_string(meshes.size() - 1) +
                       ")");
  if (options.iterations < 0 || !(options.tolerance >= 0) || options.border_sweeps < 0 ||
      options.border_iterations < 0 || options.corner_sweeps < 0 || options.corner_iterations < 0)
    throw InvalidInput("refine_maps: iterations (" + std::to_string(options.iterations) + "), tolerance (" +
                       std::to_string(options.tolerance) + "), border sweeps (" +
                       std::to_string(options.border_sweeps) + "), border iterations (" +
                       std::to_string(options.border_iterations) + "), corner sweeps (" +
                       std::to_string(options.corner_sweeps) + ") and corner iterations (" +
                       std::to_string(options.corner_iterations) + ") must be >= 0");
  if (!(options.pose_pull >= 0 && std::isfinite(options.pose_pull)))
    throw InvalidInput("refine_maps: pose pull " + std::to_string(options.pose_pull) +
                       " must be a finite weight >= 0 (0: off)");
  const size_t np = meshes[0].chart.patches.size();
  for (size_t i = 0; i < meshes.size(); ++i) {
    const auto& c = meshes[i].chart;
    const size_t nf = c.mesh.faces.size();
    if (c.patches.size() != np)
      throw InvalidInput("refine_maps: mesh " + std::to_string(i) + " has " + std::to_string(c.patches.size()) +
                         " patches, mesh 0 has " + std::to_string(np) + "; the meshes must come from one dissection");
    if (c.face_patch.size() != nf || c.face_uv.size() != nf)
      throw InvalidInput("refine_maps: mesh " + std::to_string(i) + " has " + std::to_string(nf) + " faces but " +
                         std::to_string(c.face_patch.size()) + " patch labels and " + std::to_string(c.face_uv.size()) +
                         " uv triples");
    for (size_t f = 0; f < nf; ++f) {
      if (c.face_patch[f] < 0 || c.face_patch[f] >= static_cast<int>(np))
        throw InvalidInput("refine_maps: face " + std::to_string(f) + " of mesh " + std::to_string(i) +
                           " has patch " + std::to_string(c.face_patch[f]) + ", expected 0.." +
                           std::to_string(np - 1));
      for (int v : c.mesh.faces[f])
        if (v < 0 || v >= c.mesh.num_vertices())
          throw InvalidInput("refine_maps: face " + std::to_string(f) + " of mesh " + std::to_string(i) +
                             " uses vertex " + std::to_string(v) + " out of range");
    }
  }
}

// The patch problems of one mesh (free = patch-interior, not a seed/feature, consistent wedges).
std::vector<PatchProblem> build_problems(const dissect::Dissection& d) {
  const auto& chart = d.chart;
  const int nv = chart.mesh.num_vertices();
  const int np = static_cast<int>(chart.patches.size());
  std::vector<int> first_patch(nv, -1);
  std::vector<char> held(nv, 0);
  for (int f = 0; f < chart.mesh.num_faces(); ++f)
    for (int v : chart.mesh.faces[f]) {
      if (first_patch[v] < 0) first_patch[v] = chart.face_patch[f];
      else if (first_patch[v] != chart.face_patch[f]) held[v] = 1;  // on a patch border
    }
  for (int s : d.seeds)
    if (s >= 0 && s < nv) held[s] = 1;
  for (const auto& f : d.features)
    if (f.vertex >= 0 && f.vertex < nv) held[f.vertex] = 1;
  for (const auto& p : chart.patches)
    for (int c : p.corners)
      if (c >= 0 && c < nv) held[c] = 1;

  std::vector<PatchProblem> probs(np);
  std::vector<std::vector<int>> patch_faces(np);
  for (int f = 0; f < chart.mesh.num_faces(); ++f) patch_faces[chart.face_patch[f]].push_back(f);
  std::vector<int> local(nv, -1);
  for (int p = 0; p < np; ++p) {
    auto& pr = probs[p];
    for (int f : patch_faces[p]) {
      std::array<int, 3> c{};
      for (int k = 0; k < 3; ++k) {
        const int v = chart.mesh.faces[f][k];
        if (local[v] < 0) {
          local[v] = static_cast<int>(pr.vertices.size());
          pr.vertices.push_back(v);
          pr.uv.push_back(chart.face_uv[f][k]);
          pr.var.push_back(held[v] ? -1 : 0);
          pr.dims.push_back(0);
          pr.basis.push_back(Vec2::Zero());
        } else if (pr.uv[local[v]] != chart.face_uv[f][k]) {
          pr.var[local[v]] = -1;  // wedges disagree: hold it
        }
        c[k] = local[v];
      }
      pr.add_face(chart, f, p, c);
    }
    for (size_t v = 0; v < pr.var.size(); ++v)
      if (pr.var[v] == 0) {
        pr.var[v] = pr.unknowns;
        pr.dims[v] = 2;
        pr.unknowns += 2;
      }
    for (int v : pr.vertices) local[v] = -1;
  }
  return probs;
}

// Refines a problem's free (u, v) (all inside [0, hi.x] x [0, hi.y]) under `metric`.
PatchResult solve_problem(PatchProblem& pr, const MetricFn& metric, const RefineOptions& options, bool optimize,
                          const Vec2& hi = Vec2(1, 1), const Vec2& lo = Vec2(0, 0),
                          const LinearizeFn* linearize = nullptr) {
  PatchResult res;
  res.area = pr.total_area;
  for (int v : pr.var) (v >= 0 ? res.free : res.held) += 1;
  if (pr.faces.empty()) return res;
  PatchSolver solver(pr, metric, linearize);
  solver.update_metric();
  const std::vector<Vec2> start = pr.uv;
  double e = solver.energy(pr.uv);
  const double e_start = e;
  res.energy_before = solver.distortion(pr.uv);
  res.energy_after = res.energy_before;
  if (!std::isfinite(e)) {
    res.skipped = true;  // folded to start with: left alone, and left out of the energies
    res.energy_before = res.energy_after = res.area = 0;
    return res;
  }
  if (!optimize || pr.unknowns == 0 || options.iterations == 0) return res;
  for (int it = 0; it < options.iterations; ++it) {
    const bool more = solver.step(e, options.tolerance);
    ++res.steps;
    solver.update_metric();
    e = solver.energy(pr.uv);
    if (!more || !std::isfinite(e)) break;
  }
  // Keep the result only if it is bijective, inside the square and better.
  bool ok = std::isfinite(e) && e < e_start;
  for (const auto& c : pr.tri)
    if (!(0.5 * tri_det(pr.uv[c[0]], pr.uv[c[1]], pr.uv[c[2]]) > param::kZeroUvArea)) ok = false;
  for (const auto& q : pr.uv)
    if (!(q.x() >= lo.x() && q.x() <= hi.x() && q.y() >= lo.y() && q.y() <= hi.y())) ok = false;
  if (!ok) {
    pr.uv = start;
    res.skipped = true;
    res.energy_after = res.energy_before;
    return res;
  }
  res.energy_after = solver.distortion(pr.uv);
  res.changed = pr.uv != start;
  return res;
}

// Writes a solved problem's (u, v) into the chart's wedges.
void write_back(const PatchProblem& pr, dissect::Chart& chart) {
  for (size_t t = 0; t < pr.faces.size(); ++t)
    for (int k = 0; k < 3; ++k) chart.face_uv[pr.faces[t]][k] = pr.uv[pr.tri[t][k]];
}

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
  Eigen::Matrix4d to_ref = Eigen::Matrix4d::Identity();
  double weight = 0;
};

std::vector<PullPatch> build_pull_patches(const dissect::Chart& ref, const RefineOptions& options,
                                          const Context& context) {
  const int np = static_cast<int>(ref.patches.size());
  std::vector<PullPatch> out(np);
  for (int f = 0; f < ref.mesh.num_faces(); ++f) out[ref.face_patch[f]].faces.push_back(f);
  parallel_for(np, options.threads, context, [&](int p) {
    TriMesh m;
    std::unordered_map<int, int> local;
    for (int f : out[p].faces) {
      Tri t{};
      for (int k = 0; k < 3; ++k) {
        const int v = ref.mesh.faces[f][k];
        auto [it, added] = local.try_emplace(v, static_cast<int>(m.positions.size()));
        if (added) m.positions.push_back(ref.mesh.positions[v]);
        t[k] = it->second;
      }
      m.faces.push_back(t);
    }
    if (!m.faces.empty()) out[p].tree.emplace(m, "reference patch");
  });
  return out;
}

// The landmarks' similarity from mesh b to the reference (seeds, then features by name), as
// qs-dissect --same-pose fits it the other way.
Eigen::Matrix4d pose_to_reference(const dissect::Dissection& ref, const dissect::Dissection& b) {
  std::vector<Vec3> from, to;
  for (int k = 0; k < 4; ++k) {
    from.push_back(b.chart.mesh.positions[b.seeds[k]]);
    to.push_back(ref.chart.mesh.positions[ref.seeds[k]]);
  }
  for (const auto& fb : b.features)
    for (const auto& fr : ref.features)
      if (fr.name == fb.name && fb.vertex >= 0 && fr.vertex >= 0) {
        from.push_back(b.chart.mesh.positions[fb.vertex]);
        to.push_back(ref.chart.mesh.positions[fr.vertex]);
      }
  return fit_similarity(from, to);
}

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
std::optional<PullTarget> nearest_on_patch(const PosePull& pull, int p, const Vec3& y, const Vec3& normal) {
  const PullPatch& pp = (*pull.patches)[p];
  if (!pp.tree) return std::nullopt;
  const auto hit = pp.tree->closest_facing(y, normal, dissect::kSamePoseFacingCos);
  if (hit.face < 0) return std::nullopt;
  const dissect::Chart& ref = *pull.ref;
  const int f = pp.faces[hit.face];
  const auto& t = ref.mesh.faces[f];
  const auto& fuv = ref.face_uv[f];
  const Vec3& x0 = ref.mesh.positions[t[0]];
  Eigen::Matrix2d ds;
  ds.col(0) = fuv[1] - fuv[0];
  ds.col(1) = fuv[2] - fuv[0];
  if (!(0.5 * ds.determinant() > param::kZeroUvArea)) return std::nullopt;
  const auto b = landmarks::closest_on_triangle(y, x0, ref.mesh.positions[t[1]], ref.mesh.positions[t[2]]);
  Mat32 e;
  e.col(0) = ref.mesh.positions[t[1]] - x0;
  e.col(1) = ref.mesh.positions[t[2]] - x0;
  const Mat32 g = e * ds.inverse();
  return PullTarget{b[0] * fuv[0] + b[1] * fuv[1] + b[2] * fuv[2], g.transpose() * g, hit.distance};
}

// Where a vertex of a problem is pulled to: (the patch of its faces in the problem, its point and
// normal moved into the reference's frame) -> the target, (u, v) and metric in the problem's
// coordinates; none: no pull on it.
using PullTargetFn = std::function<std::optional<PullTarget>(int, const Vec3&, const Vec3&)>;

// Fills a problem's pull: every local vertex of B with unknowns (free, or sliding along a side)
// that `locate` places gets its target and as weight the pull's weight times a third of its faces'
// area times the metric.
void add_pull(PatchProblem& pr, const dissect::Chart& chart, const PosePull& pull, const PullTargetFn& locate) {
  pr.pull.assign(pr.uv.size(), Eigen::Matrix2d::Zero());
  pr.target.assign(pr.uv.size(), Vec2::Zero());
  std::vector<double> area(pr.uv.size(), 0.0);
  // A free vertex has all its faces here; a sliding wedge those of its own patch.
  std::vector<Vec3> normal(pr.uv.size(), Vec3::Zero());
  std::vector<int> patch(pr.uv.size(), -1);
  for (size_t t = 0; t < pr.tri.size(); ++t) {
    const auto& c = chart.mesh.faces[pr.faces[t]];
    const Vec3 n = (chart.mesh.positions[c[1]] - chart.mesh.positions[c[0]])
                       .cross(chart.mesh.positions[c[2]] - chart.mesh.positions[c[0]]);
    for (int l : pr.tri[t]) area[l] += pr.area[t] / 3, normal[l] += n, patch[l] = pr.face_patch[t];
  }
  const Eigen::Matrix3d turn = pull.to_ref.topLeftCorner<3, 3>();
  for (size_t l = 0; l < pr.uv.size(); ++l) {
    if (pr.dims[l] == 0) continue;
    const Vec3 y = (pull.to_ref * chart.mesh.positions[pr.vertices[l]].homogeneous()).head<3>();
    if (const auto t = locate(patch[l], y, turn * normal[l])) {
      pr.target[l] = t->uv;
      pr.pull[l] = pull.weight * area[l] * t->metric;
    }
  }
}

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

// add_pull for a problem of one patch's interior: the target in the vertex's own patch.
void add_patch_pull(PatchProblem& pr, const dissect::Chart& chart, const PosePull& pull) {
  if (pr.face_patch.empty()) return;
  const int p = pr.face_patch.front();
  add_pull(pr, chart, pull, [&](int, const Vec3& y, const Vec3& n) { return nearest_on_patch(pull, p, y, n); });
}

struct MeshResult {
  double energy_before = 0, energy_after = 0, area = 0;  // unnormalized energies, 3D area
  int free = 0, held = 0, steps = 0, refined = 0, skipped = 0;
};

// Interior pass: every patch on its own (parallel); returns per patch results.
std::vector<PatchResult> interior_pass(dissect::Dissection& b, const std::vector<ReferencePatch>& refs,
                                       const std::vector<double>& scale, const RefineOptions& options,
                                       bool optimize, const Context& context, const PosePull* pull) {
  std::vector<PatchProblem> probs = build_problems(b);
  std::vector<PatchResult> results(probs.size());
  // Largest patches first: better balance; the result does not depend on the order.
  std::vector<int> order(probs.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(),
                   [&](int x, int y) { return probs[x].faces.size() > probs[y].faces.size(); });
  parallel_for(static_cast<int>(order.size()), options.threads, context, [&](int i) {
    const int p = order[i];
    if (pull && optimize) add_patch_pull(probs[p], b.chart, *pull);
    results[p] = solve_problem(probs[p], patch_metric(probs[p], refs, scale), options, optimize);
  });
  for (size_t p = 0; p < probs.size(); ++p)
    if (results[p].changed) write_back(probs[p], b.chart);
  return results;
}

// Recomputes the figures of the patches marked in `which` (faces, stretch, flipped and zero-area
// uv faces, uv area sum) from the chart, as the dissection computes them, and the mesh's maximum.
void update_figures(dissect::Dissection& b, const std::vector<char>& which) {
  auto& chart = b.chart;
  const int np = static_cast<int>(chart.patches.size());
  std::vector<std::vector<int>> faces_of(np);
  for (int f = 0; f < chart.mesh.num_faces(); ++f) faces_of[chart.face_patch[f]].push_back(f);
  for (int p = 0; p < np; ++p) {
    if (!which[p]) continue;
    std::unordered_map<int, int> local;
    std::vector<Vec3> pos;
    std::vector<Vec2> uv;
    std::vector<Tri> tris;
    for (int f : faces_of[p]) {
      Tri t{};
      for (int k = 0; k < 3; ++k) {
        const int v = chart.mesh.faces[f][k];
        auto [it, added] = local.try_emplace(v, static_cast<int>(pos.size()));
        if (added) {
          pos.push_back(chart.mesh.positions[v]);
          uv.push_back(chart.face_uv[f][k]);
        }
        t[k] = it->second;
      }
      tris.push_back(t);
    }
    param::SquareParam sp;
    sp.uv = uv;
    param::count_uv_faces(tris, sp);
    auto& info = chart.patches[p];
    info.faces = static_cast<int>(tris.size());
    info.stretch = param::l2_stretch(pos, tris, uv).patch;
    info.flipped_faces = sp.flipped_faces;
    info.zero_area_faces = sp.zero_area_faces;
    info.uv_area_sum = sp.uv_area_sum;
  }
  b.max_stretch = 0;
  for (const auto& p : chart.patches) b.max_stretch = std::max(b.max_stretch, p.stretch);
}

// The reference's patches (metric and location grid), built once per reference.
std::vector<ReferencePatch> build_refs(const dissect::Chart& ref, const RefineOptions& options,
                                       const Context& context) {
  const int np = static_cast<int>(ref.patches.size());
  std::vector<std::vector<int>> ref_faces(np);
  for (int f = 0; f < ref.mesh.num_faces(); ++f) ref_faces[ref.face_patch[f]].push_back(f);
  std::vector<std::optional<ReferencePatch>> built(np);
  parallel_for(np, options.threads, context, [&](int p) { built[p].emplace(ref, ref_faces[p]); });
  std::vector<ReferencePatch> refs;
  refs.reserve(np);
  for (auto& r : built) refs.push_back(std::move(*r));
  return refs;
}

MeshResult run_mesh(dissect::Dissection& b, const std::vector<ReferencePatch>& refs, const RefineOptions& options,
                    bool optimize, const Context& context, const PosePull* pull = nullptr) {
  const int np = static_cast<int>(b.chart.patches.size());
  std::vector<double> area_b(np, 0.0), scale(np, 1.0);
  for (int f = 0; f < b.chart.mesh.num_faces(); ++f) area_b[b.chart.face_patch[f]] += face_area(b.chart.mesh, f);
  for (int p = 0; p < np; ++p)
    if (refs[p].area() > 0) scale[p] = area_b[p] / refs[p].area();

  MeshResult out;
  std::vector<char> changed(np, 0);
  auto note = [&](const std::vector<PatchResult>& rs, bool first) {
    double e = 0, area = 0;
    for (size_t p = 0; p < rs.size(); ++p) {
      e += rs[p].energy_after;
      area += rs[p].area;
      out.steps += rs[p].steps;
      if (rs[p].changed) changed[p] = 1;
      if (first) {
        out.energy_before += rs[p].energy_before;
        out.free += rs[p].free;
        out.held += rs[p].held;
        out.skipped += rs[p].skipped && !rs[p].changed ? 1 : 0;
      }
    }
    out.energy_after = e;
    out.area = area;
  };
  note(interior_pass(b, refs, scale, options, optimize, context, pull), true);
  if (!optimize) return out;
  for (int p = 0; p < np; ++p) out.refined += changed[p];
  update_figures(b, changed);
  return out;
}

// ---- Refinement across patch borders ----------------------------------------------------------
//
// Two patches P and Q that share exactly one side are glued into one chart on [0,2] x [0,1]: P's
// square turned so that the shared side is its side 1 (u = 1), Q's turned so that the side is its
// side 3 (u = 0) and shifted by 1 in u. B's (u, v) is refined on the union against the reference's
// metric glued the same way, with the shared side's vertices free; then B's union is cut along
// u = 1 into the new P (u <= 1) and Q (u >= 1).

// The unit square turned by m quarter turns counter-clockwise about its centre (side k goes to
// side k + m), closed forms so that 0 and 1 stay exact.
Vec2 turn_square(const Vec2& q, int m) {
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

struct SharedSide {
  int p = -1, side_p = -1, q = -1, side_q = -1;  // side_p of p runs opposite to side_q of q; p < q
};

// The patch sides shared by two patches that share no other side, in patch order.
std::vector<SharedSide> shared_sides(const dissect::Chart& chart) {
  std::map<std::pair<int, int>, std::pair<int, int>> directed;  // (corner a, corner b) -> (patch, side)
  std::map<std::pair<int, int>, int> twice;
  const int np = static_cast<int>(chart.patches.size());
  for (int p = 0; p < np; ++p)
    for (int k = 0; k < 4; ++k) {
      const auto& c = chart.patches[p].corners;
      const auto key = std::make_pair(c[k], c[(k + 1) % 4]);
      if (!directed.emplace(key, std::make_pair(p, k)).second) ++twice[key];
    }
  std::vector<SharedSide> sides;
  std::map<std::pair<int, int>, int> pair_count;
  for (int p = 0; p < np; ++p)
    for (int k = 0; k < 4; ++k) {
      const auto& c = chart.patches[p].corners;
      const auto key = std::make_pair(c[(k + 1) % 4], c[k]);
      const auto it = directed.find(key);
      if (it == directed.end() || twice.count(key) || twice.count({c[k], c[(k + 1) % 4]})) continue;
      const int q = it->second.first;
      if (q == p) continue;
      if (q < p) continue;
      ++pair_count[{p, q}];
      sides.push_back({p, k, q, it->second.second});
    }
  std::vector<SharedSide> out;
  for (const auto& s : sides)
    if (pair_count[{s.p, s.q}] == 1) out.push_back(s);
  return out;
}

// Faces per patch and per vertex of a chart, built once per group of sides or corners planned
// together (the chart does not change while they are planned), so that gathering the faces of
// two or k patches does not pass over the whole chart for every side or corner.
struct ChartIndex {
  std::vector<std::vector<int>> patch_faces;
  std::vector<int> vertex_offset, vertex_faces;  // vertex v's faces: [offset[v], offset[v + 1])

  explicit ChartIndex(const dissect::Chart& chart) : patch_faces(chart.patches.size()) {
    const int nf = chart.mesh.num_faces();
    vertex_offset.assign(chart.mesh.num_vertices() + 1, 0);
    for (int f = 0; f < nf; ++f) {
      patch_faces[chart.face_patch[f]].push_back(f);
      for (int v : chart.mesh.faces[f]) ++vertex_offset[v + 1];
    }
    for (size_t v = 1; v < vertex_offset.size(); ++v) vertex_offset[v] += vertex_offset[v - 1];
    vertex_faces.resize(vertex_offset.back());
    std::vector<int> fill(vertex_offset.begin(), vertex_offset.end() - 1);
    for (int f = 0; f < nf; ++f)
      for (int v : chart.mesh.faces[f]) vertex_faces[fill[v]++] = f;
  }

  /// The faces of `patches` (distinct), ascending; `outside` (#V, zero) gets 1 at their vertices
  /// that also lie on a face of another patch.
  std::vector<int> gather(const dissect::Chart& chart, const std::vector<int>& patches,
                          std::vector<char>& outside) const {
    std::vector<int> faces;
    for (int p : patches) faces.insert(faces.end(), patch_faces[p].begin(), patch_faces[p].end());
    std::sort(faces.begin(), faces.end());
    for (int f : faces)
      for (int v : chart.mesh.faces[f])
        for (int i = vertex_offset[v]; i < vertex_offset[v + 1] && !outside[v]; ++i)
          if (std::find(patches.begin(), patches.end(), chart.face_patch[vertex_faces[i]]) == patches.end())
            outside[v] = 1;
    return faces;
  }
};

// Corners, seeds and features of a mesh (#V flags): what the side and corner moves never move.
std::vector<char> pinned_vertices(const dissect::Dissection& d) {
  std::vector<char> pinned(d.chart.mesh.num_vertices(), 0);
  auto pin = [&](int v) {
    if (v >= 0 && v < static_cast<int>(pinned.size())) pinned[v] = 1;
  };
  for (const auto& p : d.chart.patches)
    for (int c : p.corners) pin(c);
  for (int v : d.seeds) pin(v);
  for (const auto& f : d.features) pin(f.vertex);
  return pinned;
}

enum class SideOutcome { Refined, Unchanged, Skipped };

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

// Refines B's map on the union of the two patches of `side` and plans the cut along the glued line
// u = 1. `pinned`: corners, seeds and features of B (never moved). Only an outcome Refined has a
// cut to commit: the refined union was bijective, lower in energy, and every piece is a positive
// uv triangle inside its square.
SideCut plan_side(const dissect::Chart& chart, const ChartIndex& index, const std::vector<ReferencePatch>& refs,
                  const SharedSide& side, const std::vector<char>& pinned, const RefineOptions& options,
                  const PosePull* pull) {
  SideCut out;
  const int nv = chart.mesh.num_vertices();
  const std::array<Glue, 2> glue = {Glue{side.p, (1 - side.side_p + 4) % 4, 0.0},
                                    Glue{side.q, (3 - side.side_q + 4) % 4, 1.0}};
  std::vector<char> outside(nv, 0);
  const std::vector<int> faces = index.gather(chart, {side.p, side.q}, outside);
  // Local vertices (one per chart vertex, glued (u, v)), with their original wedges per patch.
  PatchProblem pr;
  std::unordered_map<int, int> local;
  std::vector<std::array<char, 2>> in_patch;
  std::vector<std::array<Vec2, 2>> wedge;
  std::vector<char> held;
  for (int f : faces) {
    const int w = chart.face_patch[f] == side.p ? 0 : 1;
    std::array<int, 3> c{};
    for (int k = 0; k < 3; ++k) {
      const int v = chart.mesh.faces[f][k];
      const Vec2& s = chart.face_uv[f][k];
      const Vec2 g = glue[w].to_glued(s);
      auto [it, added] = local.try_emplace(v, static_cast<int>(pr.vertices.size()));
      const int l = it->second;
      if (added) {
        pr.vertices.push_back(v);
        pr.uv.push_back(g);
        in_patch.push_back({0, 0});
        wedge.emplace_back();
        held.push_back(outside[v] || pinned[v]);
      }
      if (!in_patch[l][w]) {
        in_patch[l][w] = 1;
        wedge[l][w] = s;
        if (in_patch[l][1 - w]) {
          // On both patches: must be on the shared side, at the same glued point.
          if (std::abs(g.x() - 1) > 1e-9 || std::abs(pr.uv[l].x() - 1) > 1e-9 || std::abs(g.y() - pr.uv[l].y()) > 1e-9)
            return out.with(SideOutcome::Skipped);  // the patches meet elsewhere too, or disagree along the side
          pr.uv[l] = Vec2(1, glue[0].to_glued(wedge[l][0]).y());
        }
      } else if (wedge[l][w] != s) {
        held[l] = 1;  // wedges of one patch disagree: hold it
      }
      c[k] = l;
    }
    pr.add_face(chart, f, chart.face_patch[f], c);
  }
  // A vertex of both patches off the shared side (checked above) cannot occur; the side's own
  // vertices become interior unknowns unless pinned.
  pr.add_unknowns(held);
  const int nl = static_cast<int>(pr.vertices.size());
  if (pr.unknowns == 0) return out.with(SideOutcome::Unchanged);
  // The reference's metric on the same union, scaled by area_B(union) / area_A(union).
  const double area_a = refs[side.p].area() + refs[side.q].area();
  const double scale = area_a > 0 ? pr.total_area / area_a : 1.0;
  const std::array<Eigen::Matrix2d, 2> lin = {glue[0].linear(), glue[1].linear()};
  auto hints = std::make_shared<std::vector<std::array<int, 2>>>(pr.faces.size(), std::array<int, 2>{-1, -1});
  const MetricFn metric = [&, hints](size_t t, const Vec2& g) {
    const int w = g.x() <= 1 ? 0 : 1;
    const Vec2 s = glue[w].to_patch(g);
    return Eigen::Matrix2d(scale * lin[w] * refs[glue[w].patch].metric(s, (*hints)[t][w]) * lin[w].transpose());
  };
  if (pull) {
    // The pose pull toward the nearer of the reference's two patches, in glued (u, v).
    add_pull(pr, chart, *pull, [&](int, const Vec3& y, const Vec3& n) {
      return nearest_of(
          *pull, 2, y, n, [&](int w) { return glue[w].patch; },
          [&](int w, const PullTarget& t) {
            return PullTarget{glue[w].to_glued(t.uv), lin[w] * t.metric * lin[w].transpose(), t.distance};
          });
    });
  }
  const std::vector<Vec2> start = pr.uv;
  RefineOptions side_options = options;
  side_options.iterations = std::min(options.iterations, options.border_iterations);
  const PatchResult res = solve_problem(pr, metric, side_options, true, Vec2(2, 1));
  out.steps = res.steps;
  if (res.skipped) return out.with(SideOutcome::Skipped);
  if (!res.changed) return out.with(SideOutcome::Unchanged);
  std::vector<Vec2> uv = pr.uv;
  for (int l = 0; l < nl; ++l)
    if (held[l]) uv[l] = start[l];  // exactly as they were

  // Snap free vertices within kCutSnap of a crossing edge's u-extent onto the cut line (when
  // their faces stay positive and their ring's energy grows by at most kSnapEnergyGrowth), so
  // that the cut makes fewer slivers. (Without the energy bound a snap could flatten a ring:
  // gen-s3's distortion to mesh 0 went 1.051 -> 2.418 instead of -> 1.023.)
  std::vector<std::vector<int>> vertex_faces(nl);
  for (size_t t = 0; t < pr.tri.size(); ++t)
    for (int l : pr.tri[t]) vertex_faces[l].push_back(static_cast<int>(t));
  std::vector<Mat46> ring_a(pr.tri.size());
  std::vector<char> ring_have(pr.tri.size(), 0);
  auto ring = [&](int l) {
    double e = 0;
    for (int t : vertex_faces[l]) {
      if (!ring_have[t]) ring_a[t] = metric_jacobian(pr, t, metric), ring_have[t] = 1;
      e += face_energy(pr, t, ring_a[t], Eigen::Vector4d::Zero(), uv);
    }
    return e;
  };
  auto faces_positive = [&](int l) {
    for (int t : vertex_faces[l]) {
      const auto& c = pr.tri[t];
      if (!(0.5 * tri_det(uv[c[0]], uv[c[1]], uv[c[2]]) > 4 * param::kZeroUvArea)) return false;
    }
    return true;
  };
  std::vector<int> snap;
  for (const auto& c : pr.tri)
    for (int k = 0; k < 3; ++k) {
      const int a = c[k], bb = c[(k + 1) % 3];
      const double ua = uv[a].x() - 1, ub = uv[bb].x() - 1;
      if (!(ua * ub < 0)) continue;
      const double t = ua / (ua - ub);
      if (t < kCutSnap && !held[a]) snap.push_back(a);
      if (t > 1 - kCutSnap && !held[bb]) snap.push_back(bb);
    }
  std::sort(snap.begin(), snap.end());
  snap.erase(std::unique(snap.begin(), snap.end()), snap.end());
  for (int l : snap) {
    const Vec2 was = uv[l];
    const double before = ring(l);
    uv[l].x() = 1;
    if (!faces_positive(l) || !(ring(l) <= (1 + kSnapEnergyGrowth) * before)) uv[l] = was;
  }

  // Cut points: one per crossing edge, computed from its lower chart vertex.
  std::map<std::pair<int, int>, int> cut;  // (local a, local b), a < b -> new local id
  std::vector<Vec3> new_pos;
  std::vector<Vec2> all_uv = uv;
  auto cut_point = [&](int a, int bb) {
    if (pr.vertices[a] > pr.vertices[bb]) std::swap(a, bb);
    const auto key = std::make_pair(a, bb);
    const auto it = cut.find(key);
    if (it != cut.end()) return it->second;
    const double ua = uv[a].x() - 1, ub = uv[bb].x() - 1;
    const double t = ua / (ua - ub);
    const int id = static_cast<int>(all_uv.size());
    all_uv.emplace_back(1.0, (1 - t) * uv[a].y() + t * uv[bb].y());
    new_pos.push_back((1 - t) * chart.mesh.positions[pr.vertices[a]] + t * chart.mesh.positions[pr.vertices[bb]]);
    cut.emplace(key, id);
    return id;
  };
  auto sign = [&](int l) { return all_uv[l].x() < 1 ? -1 : all_uv[l].x() > 1 ? 1 : 0; };
  std::vector<SideCut::Piece> pieces;
  for (size_t t = 0; t < pr.tri.size(); ++t) {
    const auto& c = pr.tri[t];
    const int f = pr.faces[t];
    std::array<int, 3> sg{sign(c[0]), sign(c[1]), sign(c[2])};
    const bool neg = sg[0] < 0 || sg[1] < 0 || sg[2] < 0, pos = sg[0] > 0 || sg[1] > 0 || sg[2] > 0;
    if (!(neg && pos)) {
      pieces.push_back({f, c});
      continue;
    }
    int zero = -1;
    for (int k = 0; k < 3; ++k)
      if (sg[k] == 0) zero = k;
    if (zero >= 0) {  // the line passes through corner `zero`: two triangles
      const int a = c[zero], x = c[(zero + 1) % 3], y = c[(zero + 2) % 3];
      const int m = cut_point(x, y);
      pieces.push_back({f, {a, x, m}});
      pieces.push_back({f, {a, m, y}});
      continue;
    }
    int lone = 0;  // the corner alone on its side
    for (int k = 0; k < 3; ++k)
      if (sg[k] != sg[(k + 1) % 3] && sg[k] != sg[(k + 2) % 3]) lone = k;
    const int a = c[lone], x = c[(lone + 1) % 3], y = c[(lone + 2) % 3];
    const int m1 = cut_point(a, x), m2 = cut_point(y, a);
    pieces.push_back({f, {a, m1, m2}});
    // The quad m1 x y m2 (convex): the diagonal whose smaller triangle is larger.
    const double d1 = std::min(tri_det(all_uv[m1], all_uv[x], all_uv[y]), tri_det(all_uv[m1], all_uv[y], all_uv[m2]));
    const double d2 = std::min(tri_det(all_uv[m1], all_uv[x], all_uv[m2]), tri_det(all_uv[m2], all_uv[x], all_uv[y]));
    if (d1 >= d2) {
      pieces.push_back({f, {m1, x, y}});
      pieces.push_back({f, {m1, y, m2}});
    } else {
      pieces.push_back({f, {m1, x, m2}});
      pieces.push_back({f, {m2, x, y}});
    }
  }
  // Each piece's patch and wedge (u, v); held vertices keep their original wedges exactly.
  std::vector<int> piece_patch(pieces.size());
  std::vector<std::array<Vec2, 3>> piece_uv(pieces.size());
  for (size_t i = 0; i < pieces.size(); ++i) {
    int w = -1;
    for (int l : pieces[i].c)
      if (sign(l) != 0) w = sign(l) < 0 ? 0 : 1;
    if (w < 0) return out.with(SideOutcome::Skipped);  // a piece on the line itself: degenerate
    piece_patch[i] = glue[w].patch;
    for (int k = 0; k < 3; ++k) {
      const int l = pieces[i].c[k];
      piece_uv[i][k] = l < nl && held[l] && in_patch[l][w] ? wedge[l][w] : glue[w].to_patch(all_uv[l]);
    }
    const auto& q = piece_uv[i];
    if (!(0.5 * tri_det(q[0], q[1], q[2]) > param::kZeroUvArea)) return out.with(SideOutcome::Skipped);
  }
  out.vertices = std::move(pr.vertices);
  out.new_pos = std::move(new_pos);
  out.pieces = std::move(pieces);
  out.piece_patch = std::move(piece_patch);
  out.piece_uv = std::move(piece_uv);
  return out.with(SideOutcome::Refined);
}

// Writes a planned cut into the chart: new vertices appended, each face of the union replaced by
// its pieces (the first keeps the face id, the others appended).
void commit_side(dissect::Chart& chart, const SideCut& cut) {
  const int nl = static_cast<int>(cut.vertices.size());
  const int first_new = chart.mesh.num_vertices();
  auto chart_vertex = [&](int l) { return l < nl ? cut.vertices[l] : first_new + (l - nl); };
  for (const auto& p : cut.new_pos) chart.mesh.positions.push_back(p);
  int last_face = -1;
  for (size_t i = 0; i < cut.pieces.size(); ++i) {
    const auto& pc = cut.pieces[i];
    const Tri t{chart_vertex(pc.c[0]), chart_vertex(pc.c[1]), chart_vertex(pc.c[2])};
    if (pc.face != last_face) {
      last_face = pc.face;
      chart.mesh.faces[last_face] = t;
      chart.face_patch[last_face] = cut.piece_patch[i];
      chart.face_uv[last_face] = cut.piece_uv[i];
    } else {
      chart.mesh.faces.push_back(t);
      chart.face_patch.push_back(cut.piece_patch[i]);
      chart.face_uv.push_back(cut.piece_uv[i]);
    }
  }
}

struct AcrossResult {
  int sides_refined = 0, sides_skipped = 0, added_vertices = 0, steps = 0;
};

// `border_sweeps` passes over the shared sides of B. The sides are grouped (in patch order, each
// into the first group that has neither of its patches), the sides of a group are planned in
// parallel (their unions share no face) and committed in order: the result does not depend on
// the thread count.
AcrossResult refine_across(dissect::Dissection& b, const std::vector<ReferencePatch>& refs,
                           const RefineOptions& options, const Context& context, const PosePull* pull) {
  AcrossResult out;
  const auto sides = shared_sides(b.chart);
  std::vector<std::vector<int>> groups;
  {
    std::vector<std::vector<char>> used;
    const size_t np = b.chart.patches.size();
    for (size_t i = 0; i < sides.size(); ++i) {
      size_t g = 0;
      while (g < groups.size() && (used[g][sides[i].p] || used[g][sides[i].q])) ++g;
      if (g == groups.size()) {
        groups.emplace_back();
        used.emplace_back(np, 0);
      }
      groups[g].push_back(static_cast<int>(i));
      used[g][sides[i].p] = used[g][sides[i].q] = 1;
    }
  }
  for (int sweep = 0; sweep < options.border_sweeps; ++sweep) {
    std::vector<char> pinned = pinned_vertices(b);
    int refined = 0;
    for (const auto& group : groups) {
      pinned.resize(b.chart.mesh.num_vertices(), 0);
      const ChartIndex index(b.chart);
      std::vector<SideCut> cuts(group.size());
      parallel_for(static_cast<int>(group.size()), options.threads, context, [&](int i) {
        cuts[i] = plan_side(b.chart, index, refs, sides[group[i]], pinned, options, pull);
      });
      for (const auto& cut : cuts) {
        out.steps += cut.steps;
        if (cut.outcome == SideOutcome::Refined) {
          commit_side(b.chart, cut);
          out.added_vertices += static_cast<int>(cut.new_pos.size());
          ++refined;
        }
        if (sweep == 0 && cut.outcome == SideOutcome::Skipped) ++out.sides_skipped;
      }
    }
    out.sides_refined += refined;
    if (refined == 0) break;
  }
  return out;
}

// ---- Corner moves (cone charts) -----------------------------------------------------------------
//
// The k patches around a corner c are glued into one disk: patch j's square turned so that c is at
// its origin and its sides from c lie along +x and +y, then mapped by z -> z^(4/k) rotated by
// 2 pi j / k (sector j). Consecutive patches share the side between them: patch j's +y side is
// patch j+1's +x side, the ray at angle 2 pi (j+1) / k. B's (u, v) is refined on the union with
// the outer border held, then the union is cut again along the k rays.

// The unit vector at angle a pi / k, exact on the axes.
Vec2 half_step_dir(int a, int k) {
  a = ((a % (2 * k)) + 2 * k) % (2 * k);
  if ((2 * a) % k == 0) {
    switch ((2 * a / k) & 3) {
      case 0: return Vec2(1, 0);
      case 1: return Vec2(0, 1);
      case 2: return Vec2(-1, 0);
      default: return Vec2(0, -1);
    }
  }
  const double t = M_PI * a / k;
  return Vec2(std::cos(t), std::sin(t));
}

}  // namespace

Vec2 sector_glue(const Vec2& q, int k, int sector) {
  if (q.x() == 0 && q.y() == 0) return Vec2::Zero();
  const Vec2 a = half_step_dir(2 * sector, k), b = half_step_dir(2 * (sector + 1), k);
  if (q.y() == 0) return q.x() * a;
  if (q.x() == 0) return q.y() * b;
  return q.x() * a + q.y() * b;
}

Vec2 sector_unglue(const Vec2& g, int k, int sector) {
  const Vec2 a = half_step_dir(2 * sector, k), b = half_step_dir(2 * (sector + 1), k);
  const double d = cross2(a, b);
  return Vec2(cross2(g, b) / d, cross2(a, g) / d);
}

namespace {

// The patches around a corner in counter-clockwise order: patch j has the corner as its corner
// index[j]; patch j's side index[j] - 1 (into the corner) is patch j+1's side index[j+1] (out of it).
struct CornerStar {
  int corner = -1;
  std::vector<int> patches, index;
};

using DirectedSides = std::map<std::pair<int, int>, std::vector<std::pair<int, int>>>;

DirectedSides directed_sides(const dissect::Chart& chart) {
  DirectedSides out;
  for (int p = 0; p < static_cast<int>(chart.patches.size()); ++p)
    for (int m = 0; m < 4; ++m) {
      const auto& c = chart.patches[p].corners;
      out[{c[m], c[(m + 1) % 4]}].push_back({p, m});
    }
  return out;
}

// The star of corner c (first met as corner m of patch p), or nullopt when irregular: fewer than 3
// patches, a patch met twice, a side met twice, or a cycle that does not close over every patch
// that has c as a corner.
std::optional<CornerStar> corner_star(const dissect::Chart& chart, const DirectedSides& sides, int p, int m) {
  CornerStar star;
  star.corner = chart.patches[p].corners[m];
  int count = 0;
  for (const auto& info : chart.patches)
    for (int x : info.corners) count += x == star.corner;
  int cp = p, cm = m;
  while (true) {
    if (std::find(star.patches.begin(), star.patches.end(), cp) != star.patches.end()) return std::nullopt;
    star.patches.push_back(cp);
    star.index.push_back(cm);
    const int prev = chart.patches[cp].corners[(cm + 3) % 4];
    const auto it = sides.find({star.corner, prev});
    if (it == sides.end() || it->second.size() != 1) return std::nullopt;
    cp = it->second[0].first;
    cm = it->second[0].second;
    if (cp == p) {
      if (cm != m) return std::nullopt;
      break;
    }
    if (static_cast<int>(star.patches.size()) > count) return std::nullopt;
  }
  const int k = static_cast<int>(star.patches.size());
  if (k < 3 || k != count) return std::nullopt;
  return star;
}

enum class CornerOutcome { Moved, Unchanged, Irregular, Skipped };

struct CornerCut {
  SideCut cut;
  CornerOutcome outcome = CornerOutcome::Unchanged;
  int new_corner = -1;  // local id of the new corner (>= cut.vertices.size(): a new vertex)
  CornerCut& with(CornerOutcome o) {
    outcome = o;
    return *this;
  }
};

// A piece of a cut is a needle when its height is below this fraction of its longest edge.
constexpr double kNeedle = 1e-3;
// A snapped vertex keeps at least this fraction of the uv area of each of its faces.
constexpr double kSnapKeep = 0.5;

// Where a glued vertex lies: the origin, a generic point, or on the line at angle a pi / k
// (a = 2 j: ray j; for odd k, a odd: the continuation of a ray through the origin).
constexpr int kOrigin = -2, kGeneric = -1;

// Refines B's map on the star of a corner and plans the cut along the k rays (see above). `pinned`:
// corners, seeds and features of B. Only an outcome Moved has a cut to commit.
CornerCut plan_corner(const dissect::Chart& chart, const ChartIndex& index, const std::vector<ReferencePatch>& refs,
                      const CornerStar& star, const std::vector<char>& pinned, const RefineOptions& options,
                      const PosePull* pull) {
  CornerCut out;
  const int k = static_cast<int>(star.patches.size());
  auto glue = [&](const Vec2& q, int j) { return sector_glue(q, k, j); };
  auto unglue = [&](const Vec2& g, int j) { return sector_unglue(g, k, j); };
  std::vector<Eigen::Matrix2d> sector_inverse(k);  // the sector glue's inverse Jacobian
  for (int j = 0; j < k; ++j) {
    Eigen::Matrix2d d;
    d.col(0) = half_step_dir(2 * j, k);
    d.col(1) = half_step_dir(2 * (j + 1), k);
    sector_inverse[j] = d.inverse();
  }
  const int nv = chart.mesh.num_vertices();
  std::vector<int> turns(k);
  std::unordered_map<int, int> sector_of;
  for (int j = 0; j < k; ++j) {
    turns[j] = (4 - star.index[j]) % 4;
    sector_of[star.patches[j]] = j;
  }
  std::vector<char> outside(nv, 0);
  const std::vector<int> faces = index.gather(chart, star.patches, outside);
  PatchProblem pr;
  std::unordered_map<int, int> local;
  std::vector<int> tag;
  std::vector<char> held;
  std::vector<char> has_wedge;  // per local vertex and sector
  std::vector<Vec2> wedge;
  std::vector<int> face_sector;
  for (int f : faces) {
    const int w = sector_of[chart.face_patch[f]];
    std::array<int, 3> c{};
    for (int i = 0; i < 3; ++i) {
      const int v = chart.mesh.faces[f][i];
      const Vec2& s = chart.face_uv[f][i];
      const Vec2 q = turn_square(s, turns[w]);
      const Vec2 g = glue(q, w);
      const int t = q.x() == 0 && q.y() == 0 ? kOrigin : q.y() == 0 ? 2 * w : q.x() == 0 ? 2 * ((w + 1) % k) : kGeneric;
      auto [it, added] = local.try_emplace(v, static_cast<int>(pr.vertices.size()));
      const int l = it->second;
      if (added) {
        pr.vertices.push_back(v);
        pr.uv.push_back(g);
        tag.push_back(t);
        held.push_back(outside[v] || (pinned[v] && v != star.corner));
        has_wedge.resize(has_wedge.size() + k, 0);
        wedge.resize(wedge.size() + k, Vec2::Zero());
      }
      const size_t slot = static_cast<size_t>(l) * k + w;
      if (!has_wedge[slot]) {
        if (!added && (pr.uv[l] - g).norm() > 1e-9) return out.with(CornerOutcome::Irregular);
        if (!added && tag[l] == kGeneric) tag[l] = t;
        has_wedge[slot] = 1;
        wedge[slot] = s;
      } else if (wedge[slot] != s) {
        held[l] = 1;  // wedges of one patch disagree: hold it
      }
      c[i] = l;
    }
    pr.add_face(chart, f, chart.face_patch[f], c);
    face_sector.push_back(w);
  }
  pr.add_unknowns(held);
  const int nl = static_cast<int>(pr.vertices.size());
  const auto corner_local = local.find(star.corner);
  if (pr.unknowns == 0 || corner_local == local.end() || held[corner_local->second])
    return out.with(CornerOutcome::Irregular);

  // The reference's metric glued the same way: M_glued = C^T (A M A^T) C with A the turn and C the
  // Jacobian of the inverse sector glue (evaluated at face centroids).
  double area_a = 0;
  for (int p : star.patches) area_a += refs[p].area();
  const double scale = area_a > 0 ? pr.total_area / area_a : 1.0;
  std::vector<Eigen::Matrix2d> lin(k);
  for (int j = 0; j < k; ++j) lin[j] = Glue{star.patches[j], turns[j], 0.0}.linear();
  // A metric ms of patch star.patches[j] at glued point g, in glued (u, v).
  auto glued_metric = [&](int j, const Eigen::Matrix2d& ms) {
    const Eigen::Matrix2d& c = sector_inverse[j];
    return Eigen::Matrix2d(c.transpose() * lin[j] * ms * lin[j].transpose() * c);
  };
  auto hints = std::make_shared<std::vector<int>>(pr.faces.size() * k, -1);
  const MetricFn metric = [&, hints](size_t t, const Vec2& g) {
    double ang = std::atan2(g.y(), g.x());
    if (ang < 0) ang += 2 * M_PI;
    const int j = std::clamp(static_cast<int>(std::floor(ang / (2 * M_PI / k))), 0, k - 1);
    const Vec2 q = unglue(g, j);
    const Vec2 s = turn_square(q.cwiseMax(0.0).cwiseMin(1.0), 4 - turns[j]);
    return Eigen::Matrix2d(scale * glued_metric(j, refs[star.patches[j]].metric(s, (*hints)[t * k + j])));
  };
  if (pull) {
    // The pose pull toward the nearest of the reference's k patches around the corner, glued.
    add_pull(pr, chart, *pull, [&](int, const Vec3& y, const Vec3& n) {
      return nearest_of(
          *pull, k, y, n, [&](int j) { return star.patches[j]; },
          [&](int j, const PullTarget& t) {
            const Vec2 g = glue(turn_square(t.uv, turns[j]), j);
            return PullTarget{g, glued_metric(j, t.metric), t.distance};
          });
    });
  }
  const std::vector<Vec2> start = pr.uv;
  RefineOptions corner_options = options;
  corner_options.iterations = std::min(options.iterations, options.corner_iterations);
  const PatchResult res = solve_problem(pr, metric, corner_options, true, Vec2(4, 4), Vec2(-4, -4));
  out.cut.steps = res.steps;
  if (res.skipped) return out.with(CornerOutcome::Skipped);
  if (!res.changed) return out.with(CornerOutcome::Unchanged);
  std::vector<Vec2> uv = pr.uv;
  for (int l = 0; l < nl; ++l)
    if (held[l]) uv[l] = start[l];  // exactly as they were
    else tag[l] = kGeneric;

  // Sub-triangles (the face holding the origin is split there), with the chart face they come from.
  std::vector<std::array<int, 3>> tri = pr.tri;
  std::vector<int> tri_face(tri.size());
  for (size_t t = 0; t < tri.size(); ++t) tri_face[t] = static_cast<int>(t);
  std::vector<std::vector<int>> vertex_tris(nl);
  for (size_t t = 0; t < tri.size(); ++t)
    for (int l : tri[t]) vertex_tris[l].push_back(static_cast<int>(t));
  // A vertex may be snapped (onto the origin or a ray) when every face around it stays positive
  // and keeps at least kSnapKeep of its uv area: a snap must not crush a face, whose map would
  // then be far more distorted than the cut it saves.
  auto positive_around = [&](int l, const Vec2& was) {
    for (int t : vertex_tris[l]) {
      const auto& c = tri[t];
      const double now = tri_det(uv[c[0]], uv[c[1]], uv[c[2]]);
      const Vec2 keep = uv[l];
      uv[l] = was;
      const double before = tri_det(uv[c[0]], uv[c[1]], uv[c[2]]);
      uv[l] = keep;
      if (!(0.5 * now > 4 * param::kZeroUvArea) || !(now >= kSnapKeep * before)) return false;
    }
    return true;
  };
  int origin = -1;
  std::vector<Vec3> new_pos;
  {
    int best = -1;
    Vec3 bary = Vec3::Zero();
    double score = -kInf;
    for (size_t t = 0; t < tri.size(); ++t) {
      const auto& c = tri[t];
      const double a = tri_det(uv[c[0]], uv[c[1]], uv[c[2]]);
      const Vec2 o = Vec2::Zero();
      const Vec3 b(tri_det(o, uv[c[1]], uv[c[2]]) / a, tri_det(uv[c[0]], o, uv[c[2]]) / a,
                   tri_det(uv[c[0]], uv[c[1]], o) / a);
      if (b.minCoeff() > score) {
        score = b.minCoeff();
        bary = b;
        best = static_cast<int>(t);
      }
    }
    if (best < 0 || score < -1e-12) return out.with(CornerOutcome::Skipped);
    const auto c = tri[best];
    int top = 0;
    for (int i = 1; i < 3; ++i)
      if (bary[i] > bary[top]) top = i;
    if (bary[top] >= 1 - kCutSnap && !held[c[top]]) {
      const Vec2 was = uv[c[top]];
      uv[c[top]] = Vec2::Zero();
      if (positive_around(c[top], was)) origin = c[top];
      else uv[c[top]] = was;
    }
    if (origin < 0) {
      if (score <= 1e-9) return out.with(CornerOutcome::Skipped);  // on an edge: no clean split
      origin = nl;
      uv.push_back(Vec2::Zero());
      tag.push_back(kOrigin);
      const auto& t = chart.mesh.faces[pr.faces[best]];
      new_pos.push_back(bary[0] * chart.mesh.positions[t[0]] + bary[1] * chart.mesh.positions[t[1]] +
                        bary[2] * chart.mesh.positions[t[2]]);
      tri[best] = {origin, c[1], c[2]};
      tri.push_back({c[0], origin, c[2]});
      tri_face.push_back(best);
      tri.push_back({c[0], c[1], origin});
      tri_face.push_back(best);
    }
    tag[origin] = kOrigin;
  }
  std::vector<Vec3> base_pos;  // 3D position per local vertex (original ones, then new ones)
  for (int l = 0; l < nl; ++l) base_pos.push_back(chart.mesh.positions[pr.vertices[l]]);
  for (const auto& p : new_pos) base_pos.push_back(p);
  vertex_tris.assign(uv.size(), {});
  for (size_t t = 0; t < tri.size(); ++t)
    for (int l : tri[t]) vertex_tris[l].push_back(static_cast<int>(t));

  // Snap free vertices near a ray onto it (as a fraction of a crossing edge's extent across it).
  std::vector<Vec2> ray(k);
  for (int j = 0; j < k; ++j) ray[j] = half_step_dir(2 * j, k);
  std::vector<std::pair<int, int>> snap;  // (local vertex, ray)
  for (const auto& c : tri)
    for (int i = 0; i < 3; ++i) {
      const int a = c[i], b = c[(i + 1) % 3];
      for (int j = 0; j < k; ++j) {
        const double sa = cross2(ray[j], uv[a]), sb = cross2(ray[j], uv[b]);
        if (!(sa * sb < 0)) continue;
        const double t = sa / (sa - sb);
        if ((uv[a] + t * (uv[b] - uv[a])).dot(ray[j]) <= 0) continue;
        if (t < kCutSnap && a < nl && !held[a] && tag[a] == kGeneric) snap.push_back({a, j});
        if (t > 1 - kCutSnap && b < nl && !held[b] && tag[b] == kGeneric) snap.push_back({b, j});
      }
    }
  std::sort(snap.begin(), snap.end());
  snap.erase(std::unique(snap.begin(), snap.end()), snap.end());
  for (const auto& [l, j] : snap) {
    if (tag[l] != kGeneric) continue;
    const Vec2 was = uv[l];
    uv[l] = std::max(uv[l].dot(ray[j]), 0.0) * ray[j];
    if (uv[l].squaredNorm() > 0 && positive_around(l, was)) tag[l] = 2 * j;
    else uv[l] = was;
  }

  // Sign of a vertex against the line through the origin along ray m (symbolic for tagged ones).
  auto side = [&](int l, int m) {
    if (tag[l] == kOrigin) return 0;
    if (tag[l] >= 0) {
      const int r = ((tag[l] - 2 * m) % (2 * k) + 2 * k) % (2 * k);
      return r == 0 || r == k ? 0 : r < k ? 1 : -1;
    }
    const double s = cross2(ray[m], uv[l]);
    return s > 0 ? 1 : s < 0 ? -1 : 0;
  };
  // Vertices on the sub-triangles' edges: a cut point lies on edge (a, b) of its sub-triangle.
  std::map<std::tuple<int, int, int>, int> cut;  // (a, b, tag), a < b by chart id -> local id
  std::vector<std::pair<int, int>> on_edge(uv.size(), {-1, -1});
  auto global = [&](int l) { return l < nl ? pr.vertices[l] : nv + (l - nl); };
  bool failed = false;
  auto cut_point = [&](int a, int b, int m) {
    if (global(a) > global(b)) std::swap(a, b);
    const double sa = cross2(ray[m], uv[a]), sb = cross2(ray[m], uv[b]);
    if (!(sa * sb < 0)) {
      failed = true;
      return a;
    }
    const double t = sa / (sa - sb);
    const Vec2 p = uv[a] + t * (uv[b] - uv[a]);
    const int dir = p.dot(ray[m]) > 0 ? 2 * m : (2 * m + k) % (2 * k);
    const auto key = std::make_tuple(a, b, dir);
    const auto it = cut.find(key);
    if (it != cut.end()) return it->second;
    const int id = static_cast<int>(uv.size());
    uv.push_back(p);
    tag.push_back(dir);
    on_edge.push_back({a, b});
    new_pos.push_back((1 - t) * base_pos[a] + t * base_pos[b]);
    base_pos.push_back(new_pos.back());
    cut.emplace(key, id);
    return id;
  };
  // The sub-triangle edge holding both polygon vertices x and y, or (-1, -1).
  auto common_edge = [&](int x, int y, const std::array<int, 3>& c) -> std::pair<int, int> {
    for (int i = 0; i < 3; ++i) {
      const int a = c[i], b = c[(i + 1) % 3];
      auto on = [&](int l) {
        if (l == a || l == b) return true;
        const auto& e = on_edge[l];
        return (e.first == a && e.second == b) || (e.first == b && e.second == a);
      };
      if (on(x) && on(y)) return {a, b};
    }
    return {-1, -1};
  };
  auto clip = [&](const std::vector<int>& poly, int m, int keep, const std::array<int, 3>& c) {
    std::vector<int> res;
    const size_t n = poly.size();
    for (size_t i = 0; i < n; ++i) {
      const int x = poly[i], y = poly[(i + 1) % n];
      const int sx = keep * side(x, m), sy = keep * side(y, m);
      if (sx >= 0) res.push_back(x);
      if ((sx > 0 && sy < 0) || (sx < 0 && sy > 0)) {
        const auto e = common_edge(x, y, c);
        if (e.first < 0) {
          failed = true;
          continue;
        }
        res.push_back(cut_point(e.first, e.second, m));
      }
    }
    return res;
  };
  SideCut& sc = out.cut;
  std::vector<int> piece_sector;
  for (size_t t0 = 0; t0 < pr.tri.size() && !failed; ++t0) {
    const size_t first_piece = sc.pieces.size();
    double area_in = 0, area_out = 0;
    for (size_t t = 0; t < tri.size() && !failed; ++t) {
      if (tri_face[t] != static_cast<int>(t0)) continue;
      const auto& c = tri[t];
      area_in += tri_det(uv[c[0]], uv[c[1]], uv[c[2]]);
      for (int j = 0; j < k && !failed; ++j) {
        std::vector<int> poly(c.begin(), c.end());
        poly = clip(poly, j, 1, c);
        if (poly.size() >= 3) poly = clip(poly, (j + 1) % k, -1, c);
        if (poly.size() < 3) continue;
        // Fan from the vertex whose smallest triangle is largest (collinear cut points).
        const int n = static_cast<int>(poly.size());
        int apex = 0;
        double best = -kInf;
        for (int a = 0; a < n; ++a) {
          double worst = kInf;
          for (int i = 1; i + 1 < n; ++i)
            worst = std::min(worst, tri_det(uv[poly[a]], uv[poly[(a + i) % n]], uv[poly[(a + i + 1) % n]]));
          if (worst > best) best = worst, apex = a;
        }
        if (!(best > 0)) continue;  // a degenerate sliver of the sector's border: nothing inside
        for (int i = 1; i + 1 < n; ++i) {
          const std::array<int, 3> pc{poly[apex], poly[(apex + i) % n], poly[(apex + i + 1) % n]};
          area_out += tri_det(uv[pc[0]], uv[pc[1]], uv[pc[2]]);
          sc.pieces.push_back({pr.faces[t0], pc});
          piece_sector.push_back(j);
        }
      }
    }
    if (sc.pieces.size() == first_piece || std::abs(area_out - area_in) > 1e-9 * std::max(area_in, 1e-300) + 1e-15)
      failed = true;  // a face lost or doubled: the clip went wrong
  }
  if (failed) return out.with(CornerOutcome::Skipped);

  // Each piece's (u, v) in its patch: held vertices keep their wedges, points on a ray or at the
  // origin go exactly onto the square's sides, the rest through the inverse glue.
  for (size_t i = 0; i < sc.pieces.size(); ++i) {
    const int j = piece_sector[i];
    std::array<Vec2, 3> q{};
    for (int n = 0; n < 3; ++n) {
      const int l = sc.pieces[i].c[n];
      Vec2 s;
      if (l < nl && held[l] && has_wedge[static_cast<size_t>(l) * k + j]) {
        q[n] = wedge[static_cast<size_t>(l) * k + j];
        continue;
      }
      if (tag[l] == kOrigin) s = Vec2::Zero();
      else if (tag[l] == 2 * j) s = Vec2(uv[l].norm(), 0);
      else if (tag[l] == 2 * ((j + 1) % k)) s = Vec2(0, uv[l].norm());
      else s = unglue(uv[l], j);
      if (!(s.x() >= -1e-9 && s.y() >= -1e-9 && s.x() <= 1 + 1e-9 && s.y() <= 1 + 1e-9))
        return out.with(CornerOutcome::Skipped);
      q[n] = turn_square(s.cwiseMax(0.0).cwiseMin(1.0), 4 - turns[j]);
    }
    if (!(0.5 * tri_det(q[0], q[1], q[2]) > param::kZeroUvArea)) return out.with(CornerOutcome::Skipped);
    sc.piece_patch.push_back(star.patches[j]);
    sc.piece_uv.push_back(q);
  }
  // No new needles: a piece whose height is below kNeedle of its longest edge (where the energy's
  // edge matrix is floored, local_edges) would weigh far more than its area in every later pass.
  auto needle = [&](const Vec3& x0, const Vec3& x1, const Vec3& x2) {
    const double l2 = std::max({(x1 - x0).squaredNorm(), (x2 - x1).squaredNorm(), (x0 - x2).squaredNorm()});
    return (x1 - x0).cross(x2 - x0).norm() < kNeedle * l2;
  };
  for (const auto& pc : sc.pieces) {
    const auto& t = chart.mesh.faces[pc.face];
    if (!needle(base_pos[pc.c[0]], base_pos[pc.c[1]], base_pos[pc.c[2]])) continue;
    if (!needle(chart.mesh.positions[t[0]], chart.mesh.positions[t[1]], chart.mesh.positions[t[2]]))
      return out.with(CornerOutcome::Skipped);
  }
  // Keep only the new vertices that a piece uses (a crossing with a ray's continuation through
  // the origin is made while clipping, then clipped away), in the order they were made.
  std::vector<int> renumber(new_pos.size(), -1);
  for (const auto& pc : sc.pieces)
    for (int l : pc.c)
      if (l >= nl) renumber[l - nl] = 0;
  if (origin >= nl) renumber[origin - nl] = 0;
  std::vector<Vec3> used_pos;
  for (size_t i = 0; i < renumber.size(); ++i)
    if (renumber[i] == 0) {
      renumber[i] = nl + static_cast<int>(used_pos.size());
      used_pos.push_back(new_pos[i]);
    }
  for (auto& pc : sc.pieces)
    for (int& l : pc.c)
      if (l >= nl) l = renumber[l - nl];
  if (origin >= nl) origin = renumber[origin - nl];
  // Pieces of one face must be consecutive for commit_side: they are (faces in order).
  sc.vertices = std::move(pr.vertices);
  sc.new_pos = std::move(used_pos);
  out.new_corner = origin;
  sc.outcome = SideOutcome::Refined;
  return out.with(CornerOutcome::Moved);
}

struct CornerResult {
  int moved = 0, irregular = 0, skipped = 0, added_vertices = 0, steps = 0;
};

// `corner_sweeps` passes over B's corners (base-domain order: first met in patch order). The
// corners are grouped (in order, each into the first group whose stars share none of its
// patches), planned in parallel within a group and committed in order: the result does not depend
// on the thread count.
CornerResult move_corners(dissect::Dissection& b, const std::vector<ReferencePatch>& refs,
                          const RefineOptions& options, const Context& context, const PosePull* pull) {
  CornerResult out;
  auto& chart = b.chart;
  const int np = static_cast<int>(chart.patches.size());
  std::vector<char> excluded(chart.mesh.num_vertices(), 0);
  for (int s : b.seeds)
    if (s >= 0 && s < static_cast<int>(excluded.size())) excluded[s] = 1;
  for (const auto& f : b.features)
    if (f.vertex >= 0 && f.vertex < static_cast<int>(excluded.size())) excluded[f.vertex] = 1;
  // The corners, by their first (patch, corner index), and their stars' patches (topology: fixed).
  std::vector<std::pair<int, int>> corners;
  std::vector<std::vector<int>> groups;
  {
    std::unordered_map<int, int> seen;
    for (int p = 0; p < np; ++p)
      for (int m = 0; m < 4; ++m)
        if (seen.emplace(chart.patches[p].corners[m], 0).second) corners.push_back({p, m});
    const DirectedSides sides = directed_sides(chart);
    std::vector<std::vector<char>> used;
    std::vector<std::pair<int, int>> regular;
    for (const auto& [p, m] : corners) {
      const int c = chart.patches[p].corners[m];
      if (c >= 0 && c < static_cast<int>(excluded.size()) && excluded[c]) continue;
      const auto star = corner_star(chart, sides, p, m);
      if (!star) {
        ++out.irregular;
        continue;
      }
      size_t g = 0;
      auto clash = [&](size_t gi) {
        for (int q : star->patches)
          if (used[gi][q]) return true;
        return false;
      };
      while (g < groups.size() && clash(g)) ++g;
      if (g == groups.size()) {
        groups.emplace_back();
        used.emplace_back(np, 0);
      }
      groups[g].push_back(static_cast<int>(regular.size()));
      regular.push_back({p, m});
      for (int q : star->patches) used[g][q] = 1;
    }
    corners = std::move(regular);
  }
  for (int sweep = 0; sweep < options.corner_sweeps; ++sweep) {
    int moved = 0;
    for (const auto& group : groups) {
      const std::vector<char> pinned = pinned_vertices(b);
      const DirectedSides sides = directed_sides(chart);
      const ChartIndex index(chart);
      std::vector<CornerCut> cuts(group.size());
      parallel_for(static_cast<int>(group.size()), options.threads, context, [&](int i) {
        const auto [p, m] = corners[group[i]];
        const auto star = corner_star(chart, sides, p, m);
        if (!star) {
          cuts[i].outcome = CornerOutcome::Irregular;
          return;
        }
        cuts[i] = plan_corner(chart, index, refs, *star, pinned, options, pull);
      });
      for (size_t i = 0; i < cuts.size(); ++i) {
        const auto& cc = cuts[i];
        out.steps += cc.cut.steps;
        if (cc.outcome == CornerOutcome::Moved) {
          const auto [p, m] = corners[group[i]];
          const int old_corner = chart.patches[p].corners[m];
          const int nl = static_cast<int>(cc.cut.vertices.size());
          const int new_corner =
              cc.new_corner < nl ? cc.cut.vertices[cc.new_corner] : chart.mesh.num_vertices() + (cc.new_corner - nl);
          commit_side(chart, cc.cut);
          for (auto& info : chart.patches)
            for (int& c : info.corners)
              if (c == old_corner) c = new_corner;
          for (int& v : b.base.vertices)
            if (v == old_corner) v = new_corner;
          out.added_vertices += static_cast<int>(cc.cut.new_pos.size());
          ++moved;
        }
        if (sweep == 0 && cc.outcome == CornerOutcome::Irregular) ++out.irregular;
        if (sweep == 0 && cc.outcome == CornerOutcome::Skipped) ++out.skipped;
      }
    }
    out.moved += moved;
    if (moved == 0) break;
  }
  return out;
}

void count_faces(const dissect::Chart& chart, MeshRefineReport& r) {
  r.flipped_faces = r.zero_area_faces = 0;
  for (const auto& uv : chart.face_uv) {
    const double a = 0.5 * tri_det(uv[0], uv[1], uv[2]);
    if (a < -param::kZeroUvArea) ++r.flipped_faces;
    else if (std::abs(a) <= param::kZeroUvArea) ++r.zero_area_faces;
  }
}

}  // namespace

double sym_dirichlet(const Eigen::Matrix2d& J, Eigen::Vector4d* gradient, Eigen::Matrix4d* hessian) {
  const double d = J.determinant();
  if (!(d > 0)) return kInf;
  const Eigen::Vector4d j(J(0, 0), J(0, 1), J(1, 0), J(1, 1));
  const double s = j.squaredNorm();
  const double id2 = 1.0 / (d * d);
  if (gradient || hessian) {
    const Eigen::Vector4d c(J(1, 1), -J(1, 0), -J(0, 1), J(0, 0));  // d det / d vec(J)
    const double id3 = id2 / d;
    if (gradient) *gradient = 2 * (1 + id2) * j - 2 * s * id3 * c;
    if (hessian) {
      Eigen::Matrix4d k = Eigen::Matrix4d::Zero();
      k(0, 3) = k(3, 0) = 1;
      k(1, 2) = k(2, 1) = -1;
      *hessian = 2 * (1 + id2) * Eigen::Matrix4d::Identity() - 4 * id3 * (j * c.transpose() + c * j.transpose()) +
                 6 * s * id2 * id2 * c * c.transpose() - 2 * s * id3 * k;
    }
  }
  return s * (1 + id2);
}

namespace {

// The reference patch of refine_patch as it is: its uv triangles located exactly (a uniform grid
// over the unit square, about one cell per face), and the 3D point and Jacobian at any uv.
class ExactReference {
 public:
  ExactReference(const param::PatchMesh& ref, const std::vector<Vec2>& uv) : ref_(ref) {
    const size_t nf = ref.faces.size();
    jacobian_.assign(nf, Mat32::Zero());
    std::vector<char> positive(nf, 0);
    for (size_t f = 0; f < nf; ++f) {
      const auto& t = ref.faces[f];
      Mat32 e;
      e.col(0) = ref.positions[t[1]] - ref.positions[t[0]];
      e.col(1) = ref.positions[t[2]] - ref.positions[t[0]];
      Eigen::Matrix2d ds;
      ds.col(0) = uv[t[1]] - uv[t[0]];
      ds.col(1) = uv[t[2]] - uv[t[0]];
      area_ += 0.5 * e.col(0).cross(e.col(1)).norm();
      const double auv = 0.5 * ds.determinant();
      if (!(auv > param::kZeroUvArea)) continue;
      const Mat32 g = e * ds.inverse();
      jacobian_[f] = g;
      positive[f] = 1;
    }
    std::vector<std::array<Vec2, 3>> tris(nf);
    for (size_t f = 0; f < nf; ++f) tris[f] = {uv[ref.faces[f][0]], uv[ref.faces[f][1]], uv[ref.faces[f][2]]};
    locator_.emplace(std::move(tris), positive, true);
  }

  double area() const { return area_; }

  // The face holding q (clamped to the square; the face where q is least outside when it lies in
  // none, e.g. by rounding on an edge) and q's barycentric coordinates in it, clamped to the
  // face; -1 when the patch has no positive uv face. `hint`: a face to try first, updated.
  int locate(const Vec2& q_in, int& hint, Vec3& bary) const {
    return locator_->locate(q_in.cwiseMax(0.0).cwiseMin(1.0), hint, bary);
  }

  // The reference's 3D point at q (linear in the face holding q); false when there is none.
  bool point(const Vec2& q, int& hint, Vec3& x) const {
    Vec3 b;
    const int f = locate(q, hint, b);
    if (f < 0) return false;
    const auto& t = ref_.faces[f];
    x = b[0] * ref_.positions[t[0]] + b[1] * ref_.positions[t[1]] + b[2] * ref_.positions[t[2]];
    return true;
  }

  // point(), and d point / d uv there (the Jacobian of the face holding q).
  bool point(const Vec2& q, int& hint, Vec3& x, Mat32& jacobian) const {
    if (!point(q, hint, x)) return false;
    jacobian = jacobian_[hint];
    return true;
  }

 private:
  const param::PatchMesh& ref_;
  std::vector<Mat32> jacobian_;
  double area_ = 0;
  std::optional<UvLocator> locator_;
};

// vec(J) = a x for J = [Q1 x1 - Q0 x0, Q2 x2 - Q0 x0] P (jacobian_matrix with one Q per corner).
Mat46 jacobian_matrix(const std::array<Eigen::Matrix2d, 3>& q, const Eigen::Matrix2d& p) {
  Mat46 a = Mat46::Zero();
  for (int r = 0; r < 2; ++r)
    for (int b = 0; b < 2; ++b)
      for (int c = 0; c < 2; ++c)
        for (int d = 0; d < 2; ++d) {
          a(2 * r + b, 2 * (d + 1) + c) += q[d + 1](r, c) * p(d, b);
          a(2 * r + b, c) -= q[0](r, c) * p(d, b);
        }
  return a;
}

// The composition for a one-patch problem: per face t of B, the composed map B -> uv -> A
// on t is B's triangle onto the triangle of A's points at t's three uv corners (located exactly in
// A's uv triangles). Its Jacobian, in an orthonormal frame R of that image triangle, linearized at
// the current uv with each corner moving along the A face that holds it (x_k + G_k du_k):
// J = sqrt(s) R^T [x1 - x0, x2 - x0] P, exact at the current uv and in its first derivative, so
// that the solver's fixed points are stationary points of the composition's own energy (a metric
// frozen at the current uv is not: its change with the position is left out of the gradient).
// s = area_B / area_A of the patch.
LinearizeFn composition_linearization(const PatchProblem& prob, const ExactReference& ref, double scale) {
  auto hints = std::make_shared<std::vector<int>>(3 * prob.faces.size(), -1);
  const double root = std::sqrt(scale);
  return [&prob, &ref, root, hints](size_t t, Mat46& a, Eigen::Vector4d& b) {
    const auto& c = prob.tri[t];
    const Eigen::Matrix2d& p = prob.dm_inv[t];
    Vec3 x[3];
    Mat32 g[3];
    for (int k = 0; k < 3; ++k)
      if (!ref.point(prob.uv[c[k]], (*hints)[3 * t + k], x[k], g[k])) {  // no positive face at all
        a = jacobian_matrix(root * Eigen::Matrix2d::Identity(), p);
        b.setZero();
        return;
      }
    Mat32 e;
    e.col(0) = x[1] - x[0];
    e.col(1) = x[2] - x[0];
    // The frame: the image triangle's plane, oriented as it (else the plane of corner 0's face).
    Vec3 n = e.col(0).cross(e.col(1));
    Vec3 r1 = e.col(0).norm() > 0 ? Vec3(e.col(0)) : Vec3(e.col(1));
    if (!(n.norm() > 1e-14 * e.col(0).norm() * e.col(1).norm()) || !(r1.norm() > 0)) {
      n = g[0].col(0).cross(g[0].col(1));
      r1 = g[0].col(0);
    }
    r1.normalize();
    const Vec3 r2 = n.cross(r1).normalized();
    Mat32 r;
    r.col(0) = r1;
    r.col(1) = r2;
    std::array<Eigen::Matrix2d, 3> q;
    for (int k = 0; k < 3; ++k) q[k] = root * r.transpose() * g[k];
    a = jacobian_matrix(q, p);
    const Eigen::Matrix2d j = root * r.transpose() * e * p;
    Vec6 u;
    u << prob.uv[c[0]], prob.uv[c[1]], prob.uv[c[2]];
    b = Eigen::Vector4d(j(0, 0), j(0, 1), j(1, 0), j(1, 1)) - a * u;
  };
}

// refine_patch's and pull_patch's checks (`who` names the caller) and the patch as a problem: every
// vertex its own wedge; boundary loop, held and unused ones fixed. None: nothing to solve.
std::optional<PatchProblem> node_problem(const char* who, const param::PatchMesh& ref, const std::vector<Vec2>& ref_uv,
                                         const param::PatchMesh& patch, const std::vector<Vec2>& uv,
                                         const std::vector<char>& held, const RefineOptions& options) {
  if (ref_uv.size() != ref.positions.size() || uv.size() != patch.positions.size() ||
      held.size() != patch.positions.size())
    throw InvalidInput(std::string(who) + ": the reference patch has " + std::to_string(ref.positions.size()) +
                       " vertices and " + std::to_string(ref_uv.size()) + " uv, the patch " +
                       std::to_string(patch.positions.size()) + " vertices, " + std::to_string(uv.size()) + " uv and " +
                       std::to_string(held.size()) + " held flags; expected equal counts");
  if (options.iterations < 0 || !(options.tolerance >= 0))
    throw InvalidInput(std::string(who) + ": iterations (" + std::to_string(options.iterations) + ") and tolerance (" +
                       std::to_string(options.tolerance) + ") must be >= 0");
  if (ref.faces.empty() || patch.faces.empty() || options.iterations == 0) return std::nullopt;
  for (const auto& t : ref.faces)
    for (int v : t)
      if (v < 0 || v >= static_cast<int>(ref.positions.size()))
        throw InvalidInput(std::string(who) + ": a face of the reference uses vertex " + std::to_string(v) +
                           ", expected 0.." + std::to_string(ref.positions.size() - 1));
  // The patch as a problem: every vertex its own wedge; boundary loop, held and unused ones fixed.
  const size_t nv = patch.positions.size();
  std::vector<char> fixed(nv, 1);
  for (const auto& t : patch.faces)
    for (int v : t)
      if (v < 0 || v >= static_cast<int>(nv))
        throw InvalidInput(std::string(who) + ": a face uses vertex " + std::to_string(v) + ", expected 0.." +
                           std::to_string(nv - 1));
      else
        fixed[v] = held[v] != 0;
  for (int v : patch.boundary)
    if (v >= 0 && v < static_cast<int>(nv)) fixed[v] = 1;
  PatchProblem pr;
  pr.vertices.resize(nv);
  pr.uv = uv;
  pr.var.assign(nv, -1);
  pr.dims.assign(nv, 0);
  pr.basis.assign(nv, Vec2::Zero());
  for (size_t v = 0; v < nv; ++v) {
    pr.vertices[v] = static_cast<int>(v);
    if (!fixed[v]) {
      pr.var[v] = pr.unknowns;
      pr.dims[v] = 2;
      pr.unknowns += 2;
    }
  }
  for (size_t f = 0; f < patch.faces.size(); ++f) {
    const auto& t = patch.faces[f];
    pr.faces.push_back(static_cast<int>(f));
    pr.face_patch.push_back(0);
    pr.tri.push_back({t[0], t[1], t[2]});
    double area = 0;
    const Eigen::Matrix2d dm = local_edges(patch.positions[t[0]], patch.positions[t[1]], patch.positions[t[2]], area);
    pr.dm_inv.push_back(dm.inverse());
    pr.area.push_back(area);
    pr.total_area += area;
  }
  if (pr.unknowns == 0) return std::nullopt;
  return pr;
}

}  // namespace

bool refine_patch(const param::PatchMesh& ref, const std::vector<Vec2>& ref_uv, const param::PatchMesh& patch,
                  std::vector<Vec2>& uv, const std::vector<char>& held, const RefineOptions& options,
                  const NodeRefineOptions& node) {
  if (!(node.max_start_distortion >= 0))
    throw InvalidInput("refine_patch: max_start_distortion (" + std::to_string(node.max_start_distortion) +
                       ") must be >= 0 (0: no limit)");
  auto problem = node_problem("refine_patch", ref, ref_uv, patch, uv, held, options);
  if (!problem) return false;
  PatchProblem& pr = *problem;
  const ExactReference exact(ref, ref_uv);
  const double scale = exact.area() > 0 ? pr.total_area / exact.area() : 1.0;
  const LinearizeFn linearize = composition_linearization(pr, exact, scale);
  const MetricFn unused = [](size_t, const Vec2&) { return Eigen::Matrix2d(Eigen::Matrix2d::Identity()); };
  if (node.max_start_distortion > 0) {
    const PatchResult start = solve_problem(pr, unused, options, false, Vec2(1, 1), Vec2(0, 0), &linearize);
    if (!(start.area > 0) || start.energy_before / start.area / 4 > node.max_start_distortion) return false;
  }
  const PatchResult r = solve_problem(pr, unused, options, true, Vec2(1, 1), Vec2(0, 0), &linearize);
  if (!r.changed) return false;
  uv = pr.uv;
  return true;
}

dissect::NodeMapRefiner node_refiner(const RefineOptions& options, const NodeRefineOptions& node) {
  return [options, node](const param::PatchMesh& ref, const std::vector<Vec2>& ref_uv, const param::PatchMesh& patch,
                         std::vector<Vec2>& uv, const std::vector<char>& held) {
    return refine_patch(ref, ref_uv, patch, uv, held, options, node);
  };
}

bool untangle_patch(const param::PatchMesh& patch, std::vector<Vec2>& uv, const std::vector<char>& held,
                    const std::vector<Vec2>& target, const std::vector<char>& has_target, double pull,
                    const RefineOptions& options) {
  const size_t n = patch.positions.size();
  if (uv.size() != n || held.size() != n || target.size() != n || has_target.size() != n)
    throw InvalidInput("untangle_patch: the patch has " + std::to_string(n) + " vertices, " +
                       std::to_string(uv.size()) + " uv, " + std::to_string(held.size()) + " held flags, " +
                       std::to_string(target.size()) + " targets and " + std::to_string(has_target.size()) +
                       " target flags; expected equal counts");
  if (!(pull >= 0 && std::isfinite(pull)))
    throw InvalidInput("untangle_patch: pull " + std::to_string(pull) + " must be finite and >= 0");
  // The patch is its own reference: node_problem's checks, with `patch` in both roles.
  auto problem = node_problem("untangle_patch", patch, uv, patch, uv, held, options);
  if (!problem) return false;
  PatchProblem& pr = *problem;
  // Each face's frame is its start (u, v) triangle instead of its 3D triangle, so the distortion
  // is 4 per unit area at the start however squeezed the map is on the surface (measured against
  // the 3D triangles or the first mesh's map, a squeezed node starts at 10^5..10^6 and the pull
  // moves nothing); the pull's weight per vertex is a third of its faces' start uv area.
  // Faces without a free vertex add a constant: left out (a local untangle solves only its region).
  {
    size_t kept = 0;
    for (size_t t = 0; t < pr.tri.size(); ++t) {
      const auto& c = pr.tri[t];
      if (pr.dims[c[0]] == 0 && pr.dims[c[1]] == 0 && pr.dims[c[2]] == 0) continue;
      pr.faces[kept] = pr.faces[t];
      pr.face_patch[kept] = pr.face_patch[t];
      pr.tri[kept] = pr.tri[t];
      pr.dm_inv[kept] = pr.dm_inv[t];
      pr.area[kept] = pr.area[t];
      ++kept;
    }
    pr.faces.resize(kept);
    pr.face_patch.resize(kept);
    pr.tri.resize(kept);
    pr.dm_inv.resize(kept);
    pr.area.resize(kept);
  }
  std::vector<double> area(pr.uv.size(), 0.0);
  pr.total_area = 0;
  for (size_t t = 0; t < pr.tri.size(); ++t) {
    const auto& c = pr.tri[t];
    Eigen::Matrix2d e;
    e.col(0) = pr.uv[c[1]] - pr.uv[c[0]];
    e.col(1) = pr.uv[c[2]] - pr.uv[c[0]];
    const double a = 0.5 * e.determinant();
    if (!(a > param::kZeroUvArea)) return false;  // not a bijective start
    pr.dm_inv[t] = e.inverse();
    pr.area[t] = a;
    pr.total_area += a;
    for (int l : c) area[l] += a / 3;
  }
  pr.pull.assign(pr.uv.size(), Eigen::Matrix2d::Zero());
  pr.target.assign(pr.uv.size(), Vec2::Zero());
  for (size_t v = 0; v < pr.uv.size(); ++v)
    if (pr.dims[v] > 0 && has_target[v]) {
      pr.target[v] = target[v];
      pr.pull[v] = pull * area[v] * Eigen::Matrix2d::Identity();
    }
  const MetricFn identity = [](size_t, const Vec2&) { return Eigen::Matrix2d(Eigen::Matrix2d::Identity()); };
  if (!solve_problem(pr, identity, options, true).changed) return false;
  uv = pr.uv;
  return true;
}

dissect::NodeMapPuller untangler(const RefineOptions& options, double pull) {
  return [options, pull](const param::PatchMesh& patch, std::vector<Vec2>& uv, const std::vector<char>& held,
                         const std::vector<Vec2>& target, const std::vector<char>& has_target, bool polish) {
    RefineOptions o = options;
    if (polish) o.iterations = std::min(o.iterations, kPolishIterations);
    return untangle_patch(patch, uv, held, target, has_target, pull, o);
  };
}

double map_energy(const dissect::Dissection& a, const dissect::Dissection& b) {
  std::vector<dissect::Dissection> pair{a, b};
  RefineOptions o;
  o.reference = 0;
  check_set(pair, o);
  const MeshResult r = run_mesh(pair[1], build_refs(pair[0].chart, o, {}), o, false, {});
  return r.area > 0 ? r.energy_before / r.area / 4 : 0;
}

RefineReport refine_maps(std::vector<dissect::Dissection>& meshes, const RefineOptions& options,
                         const Context& context) {
  check_set(meshes, options);
  RefineReport report;
  report.meshes.resize(meshes.size());
  const std::vector<ReferencePatch> refs = build_refs(meshes[options.reference].chart, options, context);
  std::vector<PullPatch> pull_patches;
  double pull_weight = 0;
  if (options.pose_pull > 0) {
    const dissect::Chart& ref = meshes[static_cast<size_t>(options.reference)].chart;
    pull_patches = build_pull_patches(ref, options, context);
    const double len = kPullLength * bounding_box(ref.mesh.positions).diagonal();
    pull_weight = options.pose_pull / (len * len);
  }
  context.report("refine maps", 0);
  for (size_t i = 0; i < meshes.size(); ++i) {
    auto& r = report.meshes[i];
    if (static_cast<int>(i) == options.reference) {
      r.reference = true;
      count_faces(meshes[i].chart, r);
      continue;
    }
    const dissect::Chart& ref = meshes[static_cast<size_t>(options.reference)].chart;
    const dissect::Chart& c = meshes[i].chart;
    if (c.mesh.positions == ref.mesh.positions && c.mesh.faces == ref.mesh.faces && c.face_patch == ref.face_patch &&
        c.face_uv == ref.face_uv) {
      r.identity = true;
      count_faces(meshes[i].chart, r);
      continue;
    }
    PosePull pose;
    const PosePull* pull = nullptr;  // none for meshes in different poses
    if (options.pose_pull > 0) {
      pose.ref = &ref;
      pose.patches = &pull_patches;
      pose.to_ref = pose_to_reference(meshes[static_cast<size_t>(options.reference)], meshes[i]);
      pose.weight = pull_weight;
      pull = &pose;
    }
    double before = -1;
    const bool corners = options.move_corners && options.iterations > 0 && options.corner_sweeps > 0;
    const bool across = options.across_borders && options.iterations > 0 && options.border_sweeps > 0;
    if (corners || across) {
      const MeshResult b = run_mesh(meshes[i], refs, options, false, context);
      before = b.area > 0 ? b.energy_before / b.area / 4 : 0;
    }
    if (corners) {
      // An interior pass first: the corner stars then start from maps already refined inside
      // their patches (measured: gen-s1 mean 1.23% -> 1.02% against moving the dissection's
      // corners directly).
      r.newton_steps += run_mesh(meshes[i], refs, options, true, context, pull).steps;
      const CornerResult c = move_corners(meshes[i], refs, options, context, pull);
      r.corners_moved = c.moved;
      r.corners_irregular = c.irregular;
      r.corners_skipped = c.skipped;
      r.corner_cut_vertices = c.added_vertices;
      r.newton_steps += c.steps;
      update_figures(meshes[i], std::vector<char>(meshes[i].chart.patches.size(), 1));
    }
    if (across) {
      const AcrossResult a = refine_across(meshes[i], refs, options, context, pull);
      r.sides_refined = a.sides_refined;
      r.sides_skipped = a.sides_skipped;
      r.cut_vertices = a.added_vertices;
      r.newton_steps += a.steps;
      update_figures(meshes[i], std::vector<char>(meshes[i].chart.patches.size(), 1));
    }
    const MeshResult m = run_mesh(meshes[i], refs, options, true, context, pull);
    r.free_vertices = m.free;
    r.held_vertices = m.held;
    r.newton_steps += m.steps;
    r.patches_refined = m.refined;
    r.patches_skipped = m.skipped;
    r.energy_before = before >= 0 ? before : m.area > 0 ? m.energy_before / m.area / 4 : 0;
    r.energy_after = m.area > 0 ? m.energy_after / m.area / 4 : 0;
    count_faces(meshes[i].chart, r);
    context.report("refine maps", static_cast<double>(i + 1) / meshes.size());
  }
  context.report("refine maps", 1);
  return report;
}

}  // namespace qs::maprefine
