// The distortion energy (symmetric Dirichlet against the reference's metric) and its projected
// Newton solver, shared by every refinement of map_refine.h.
#include "qs/maprefine/map_refine_detail.h"

#include <Eigen/Cholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <memory>

#include "qs/core/parallel.h"
#include "qs/param/sparse_cholesky.h"
#include "qs/param/square_param.h"

namespace qs::maprefine {

namespace detail {

namespace {

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

// Local face t's corner uv as one vector (u0, v0, u1, v1, u2, v2).
Vec6 corner_uv(const PatchProblem& prob, size_t t, const std::vector<Vec2>& uv) {
  const auto& c = prob.tri[t];
  Vec6 x;
  x << uv[c[0]], uv[c[1]], uv[c[2]];
  return x;
}

}  // namespace

ReferencePatch::ReferencePatch(const dissect::Chart& chart, std::vector<int> faces) : faces_(std::move(faces)) {
  const size_t nf = faces_.size();
  metric_.assign(nf, Eigen::Matrix2d::Zero());
  // Location (faces with a positive uv area only; a point outside every face of its cell takes
  // the least outside of them): the other faces' metric is never read.
  std::vector<std::array<Vec2, 3>> tris(nf);
  std::vector<char> positive(nf, 0);
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
    tris[i] = uv;
    if (0.5 * ds.determinant() > param::kZeroUvArea) {
      const Mat32 g = e * ds.inverse();
      metric_[i] = g.transpose() * g;
      positive[i] = 1;
    }
  }
  locator_.emplace(std::move(tris), positive, false);
}

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

namespace {

// Problems with at least this many faces run their per-face passes on RefineOptions::threads.
constexpr size_t kParallelSolveFaces = 20000;
// Problems with at least this many unknowns order their Hessian by nested dissection.
constexpr int kNestedDissectionUnknowns = 12000;

class PatchSolver {
 public:
  // `metric`: the reference's (scaled) metric for local face t at uv point q of the problem;
  // `linearize`, when given, replaces it (the per-face Jacobian's affine model at the current uv).
  // `threads`: the factorization's (RefineOptions::threads).
  PatchSolver(PatchProblem& prob, const MetricFn& metric, const LinearizeFn* linearize, int threads)
      : prob_(prob), metric_(metric), linearize_(linearize), threads_(threads) {
    a_.resize(prob.faces.size());
    b_.assign(prob.faces.size(), Eigen::Vector4d::Zero());
    face_value_.resize(prob.faces.size());
    count_ = prob.faces.size() < kParallelSolveFaces || inside_parallel_loop() ? 1 : thread_count(threads, Context{});
  }

  // Re-evaluates the reference metric at the faces' uv centroids and the per-face Jacobian maps.
  void update_metric() {
    if (linearize_) {
      for_faces([&](size_t t) { (*linearize_)(t, a_[t], b_[t]); });
      return;
    }
    for_faces([&](size_t t) { a_[t] = metric_jacobian(prob_, t, metric_); });
  }

  // Distortion energy (sum of area * symDirichlet) at uv under the current metric; +inf when a
  // face folds. The faces' terms are summed in face order.
  double distortion(const std::vector<Vec2>& uv) const {
    for_faces([&](size_t t) { face_value_[t] = face_energy(prob_, t, a_[t], b_[t], uv); });
    double e = 0;
    for (const double f : face_value_) {
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
    // The Hessian's entries come in the same order at every step (assemble), each added straight
    // into the value where it lands (slot_); the pattern is fixed by the faces (analyze).
    double diag = 0;  // the largest single diagonal contribution (scales the regularization)
    Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
    if (!analyzed_) analyze();
    double* const value = h_.valuePtr();
    std::fill(value, value + h_.nonZeros(), 0.0);
    const int* slot = slot_.data();
    if (!assemble(g, [&](int row, int col, double x) {
          value[*slot++] += x;
          if (row == col) diag = std::max(diag, x);
        }))
      return false;
    std::vector<double> plain(n);
    for (int i = 0; i < n; ++i) plain[i] = h_.valuePtr()[diag_slot_[i]];
    Eigen::VectorXd d;
    double mu = 1e-10 * std::max(diag, 1e-300);
    for (int attempt = 0; attempt < 6; ++attempt, mu *= 100) {
      for (int i = 0; i < n; ++i) h_.valuePtr()[diag_slot_[i]] = plain[i] + mu;
      if (!llt_.factorize(h_, threads_)) continue;  // not positive definite: more regularization
      d = llt_.solve(-g, threads_);
      if (d.allFinite() && g.dot(d) < 0) break;
      d.resize(0);
    }
    if (d.size() == 0) return false;
    // Direction per local vertex; cap the step below the first fold.
    std::vector<Vec2> dir(prob_.uv.size(), Vec2::Zero());
    for (size_t v = 0; v < prob_.uv.size(); ++v)
      if (prob_.dims[v] == 2) dir[v] = Vec2(d[prob_.var[v]], d[prob_.var[v] + 1]);
      else if (prob_.dims[v] == 1) dir[v] = d[prob_.var[v]] * prob_.basis[v];
    for_faces([&](size_t t) {
      const auto& c = prob_.tri[t];
      face_value_[t] = flip_step(prob_.uv[c[0]], prob_.uv[c[1]], prob_.uv[c[2]], dir[c[0]], dir[c[1]], dir[c[2]]);
    });
    const double alpha_max =
        face_value_.empty() ? kInf : *std::min_element(face_value_.begin(), face_value_.end());
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
  int threads_;
  int count_ = 1;  // threads of the per-face passes
  mutable std::vector<double> face_value_;  // per face: energy, flip step or symDirichlet
  std::vector<Vec6> face_gradient_;
  std::vector<Mat6> face_hessian_;

  // body(t) for every local face t; a large problem's faces in chunks on count_ threads (each
  // face's result goes to its own slot, so nothing depends on the thread count).
  template <class F>
  void for_faces(F&& body) const {
    const size_t nf = prob_.faces.size();
    if (count_ <= 1) {
      for (size_t t = 0; t < nf; ++t) body(t);
      return;
    }
    const int chunks = 4 * count_;
    Context threads_only;
    threads_only.threads = count_;
    parallel_for(chunks, count_, threads_only, [&](int k) {
      const size_t end = nf * static_cast<size_t>(k + 1) / chunks;
      for (size_t t = nf * static_cast<size_t>(k) / chunks; t < end; ++t) body(t);
    });
  }
  // The gradient into g and every Hessian entry to add(row, col, value), faces then the pose pull,
  // in the same order at every call; false when a face's energy is not finite.
  template <class Add>
  bool assemble(Eigen::VectorXd& g, Add&& add) {
    // Face t's gradient and projected Hessian in its corner uv; false when its energy is not finite.
    auto face_terms = [&](size_t t, Vec6& gx, Mat6& hx) {
      const Eigen::Vector4d j = a_[t] * corner_uv(prob_, t, prob_.uv) + b_[t];
      Eigen::Matrix2d jm;
      jm << j[0], j[1], j[2], j[3];
      Eigen::Vector4d gj;
      if (!std::isfinite(sym_dirichlet(jm, &gj))) return false;
      const Eigen::Matrix4d hp = projected_hessian(jm);
      gx = prob_.area[t] * a_[t].transpose() * gj;
      hx = prob_.area[t] * a_[t].transpose() * hp * a_[t];
      return true;
    };
    // On several threads every face's terms first (kept per face), then added in face order.
    const bool kept = count_ > 1;
    if (kept) {
      face_gradient_.resize(prob_.faces.size());
      face_hessian_.resize(prob_.faces.size());
      for_faces([&](size_t t) { face_value_[t] = face_terms(t, face_gradient_[t], face_hessian_[t]) ? 0.0 : kInf; });
    }
    Vec6 own_gx;
    Mat6 own_hx;
    for (size_t t = 0; t < prob_.faces.size(); ++t) {
      if (kept ? !std::isfinite(face_value_[t]) : !face_terms(t, own_gx, own_hx)) return false;
      const Vec6& gx = kept ? face_gradient_[t] : own_gx;
      const Mat6& hx = kept ? face_hessian_[t] : own_hx;
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

  // The Hessian's pattern, the same at every step: each face's unknowns with each other, the pose
  // pull's blocks and the whole diagonal, which takes the regularization; ordered once. slot_[k] is
  // where assemble's k-th entry lands in the value array, diag_slot_ each diagonal entry. Built by
  // columns from the faces of each unknown, in linear time.
  void analyze() {
    const int n = prob_.unknowns;
    const size_t nf = prob_.faces.size();
    // Each face's unknowns, and where its ncols^2 entries start in assemble's order.
    std::vector<std::array<int, 6>> face_cols(nf);
    std::vector<int> face_ncols(nf);
    std::vector<size_t> first(nf + 1, 0);
    std::vector<int> faces_start(n + 1, 0);
    std::array<std::pair<int, Vec2>, 6> cols;
    std::array<int, 6> corner{};
    for (size_t t = 0; t < nf; ++t) {
      const int ncols = face_columns(t, cols, corner);
      face_ncols[t] = ncols;
      for (int r = 0; r < ncols; ++r) {
        face_cols[t][r] = cols[r].first;
        ++faces_start[cols[r].first + 1];
      }
      first[t + 1] = first[t] + static_cast<size_t>(ncols) * ncols;
    }
    for (int j = 0; j < n; ++j) faces_start[j + 1] += faces_start[j];
    std::vector<int> faces_of(faces_start[n]), fill(faces_start.begin(), faces_start.end() - 1);
    for (size_t t = 0; t < nf; ++t)
      for (int r = 0; r < face_ncols[t]; ++r) faces_of[fill[face_cols[t][r]]++] = static_cast<int>(t);
    // The pull's entries follow the faces': a 2 x 2 block per free vertex of dimension 2, one entry
    // per vertex of dimension 1.
    std::vector<int> vertex_of(n, -1);
    std::vector<size_t> pull_first(prob_.pull.size() + 1, first[nf]);
    for (size_t v = 0; v < prob_.uv.size(); ++v)
      for (int k = 0; k < prob_.dims[v]; ++k) vertex_of[prob_.var[v] + k] = static_cast<int>(v);
    for (size_t v = 0; v < prob_.pull.size(); ++v)
      pull_first[v + 1] = pull_first[v] + static_cast<size_t>(prob_.dims[v]) * prob_.dims[v];
    slot_.assign(pull_first.back(), 0);
    diag_slot_.resize(n);
    std::vector<int> outer(n + 1, 0), inner, mark(n, -1), rows, at(n, 0);
    inner.reserve(static_cast<size_t>(n) * 8);
    for (int j = 0; j < n; ++j) {
      const int v = vertex_of[j];
      const bool pulled = v >= 0 && static_cast<size_t>(v) < prob_.pull.size();
      rows.assign(1, j);  // the diagonal
      mark[j] = j;
      auto add_row = [&](int r) {
        if (mark[r] != j) {
          mark[r] = j;
          rows.push_back(r);
        }
      };
      for (int q = faces_start[j]; q < faces_start[j + 1]; ++q) {
        const int t = faces_of[q];
        for (int r = 0; r < face_ncols[t]; ++r) add_row(face_cols[t][r]);
      }
      if (pulled)
        for (int k = 0; k < prob_.dims[v]; ++k) add_row(prob_.var[v] + k);
      std::sort(rows.begin(), rows.end());
      for (int r : rows) {
        at[r] = static_cast<int>(inner.size());
        inner.push_back(r);
      }
      outer[j + 1] = static_cast<int>(inner.size());
      for (int q = faces_start[j]; q < faces_start[j + 1]; ++q) {
        const int t = faces_of[q];
        const int ncols = face_ncols[t];
        const int c = static_cast<int>(std::find(face_cols[t].begin(), face_cols[t].begin() + ncols, j) -
                                       face_cols[t].begin());
        for (int r = 0; r < ncols; ++r) slot_[first[t] + static_cast<size_t>(r) * ncols + c] = at[face_cols[t][r]];
      }
      if (pulled) {
        const int d = prob_.dims[v], c = j - prob_.var[v];
        for (int r = 0; r < d; ++r) slot_[pull_first[v] + static_cast<size_t>(r) * d + c] = at[prob_.var[v] + r];
      }
      diag_slot_[j] = at[j];
    }
    h_.resize(n, n);
    h_.resizeNonZeros(static_cast<Eigen::Index>(inner.size()));
    std::copy(outer.begin(), outer.end(), h_.outerIndexPtr());
    std::copy(inner.begin(), inner.end(), h_.innerIndexPtr());
    std::fill(h_.valuePtr(), h_.valuePtr() + inner.size(), 0.0);
    // A large problem is ordered by nested dissection of the unknowns' vertices at their (u, v),
    // a small one by AMD (measured: AMD's factor is the faster below about 10^4 unknowns; nested
    // dissection analyzes and factorizes 1.5-2 times faster at 2-7 x 10^4).
    if (n < kNestedDissectionUnknowns) {
      llt_.analyze(h_);
    } else {
      Eigen::MatrixXd points(n, 2);
      for (size_t v = 0; v < prob_.uv.size(); ++v)
        for (int k = 0; k < prob_.dims[v]; ++k) points.row(prob_.var[v] + k) = prob_.uv[v].transpose();
      llt_.analyze(h_, &points);
    }
    analyzed_ = true;
  }

  std::vector<Mat46> a_;
  std::vector<Eigen::Vector4d> b_;
  Eigen::SparseMatrix<double> h_;
  std::vector<int> slot_, diag_slot_;  // Eigen's sparse indices are int
  param::SupernodalCholesky llt_;
  bool analyzed_ = false;
};

}  // namespace

// Refines a problem's free (u, v) (all inside [0, hi.x] x [0, hi.y]) under `metric`.
PatchResult solve_problem(PatchProblem& pr, const MetricFn& metric, const RefineOptions& options, bool optimize,
                          const Vec2& hi, const Vec2& lo, const LinearizeFn* linearize,
                          double max_start_distortion) {
  PatchResult res;
  res.area = pr.total_area;
  for (int v : pr.var) (v >= 0 ? res.free : res.held) += 1;
  if (pr.faces.empty()) return res;
  PatchSolver solver(pr, metric, linearize, options.threads);
  solver.update_metric();
  const std::vector<Vec2> start = pr.uv;
  res.energy_before = solver.distortion(pr.uv);
  double e = std::isfinite(res.energy_before) ? res.energy_before + solver.pull(pr.uv) : kInf;  // energy()
  const double e_start = e;
  res.energy_after = res.energy_before;
  if (!std::isfinite(e)) {
    res.skipped = true;  // folded to start with: left alone, and left out of the energies
    res.energy_before = res.energy_after = res.area = 0;
    return res;
  }
  if (max_start_distortion > 0 && (!(res.area > 0) || res.energy_before / res.area / 4 > max_start_distortion)) {
    res.skipped = true;
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

}  // namespace detail

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

double sym_dirichlet(const Eigen::Matrix2d& J, Eigen::Vector4d* gradient, Eigen::Matrix4d* hessian) {
  const double d = J.determinant();
  if (!(d > 0)) return detail::kInf;
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

}  // namespace qs::maprefine
