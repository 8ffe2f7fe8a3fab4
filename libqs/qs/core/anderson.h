#pragma once
// Anderson acceleration of a fixed-point iteration x <- G(x) (type II, Walker and Ni 2011; for
// local/global geometry solvers, Peng, Deng, Zhang and Liu 2018): from the last few steps' results
// g = G(x) and residuals f = g - x, the combination of them whose residual is least. The caller
// keeps the safeguard (an accelerated point that does not lower its energy is dropped, and the
// history cleared). Deterministic: serial sums in a fixed order.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <vector>

namespace qs {

class Anderson {
 public:
  /// \pre depth >= 1: how many past steps are combined.
  explicit Anderson(int depth) : depth_(depth) {}

  /// Forgets the history (a new problem, or a rejected step).
  void clear() {
    dg_.clear();
    df_.clear();
    last_g_.resize(0);
  }

  /// Records the step x -> g (the residual f = g - x). Returns true with next() the accelerated
  /// point when there is history to combine; false (use g itself) on the first step after clear()
  /// or when the combination is not finite.
  bool step(const Eigen::VectorXd& g, const Eigen::VectorXd& f) {
    if (last_g_.size() > 0) {
      dg_.push_back(g - last_g_);
      df_.push_back(f - last_f_);
      if (static_cast<int>(dg_.size()) > depth_) {
        dg_.erase(dg_.begin());
        df_.erase(df_.begin());
      }
    }
    last_g_ = g;
    last_f_ = f;
    if (dg_.empty()) return false;
    // theta = argmin |f - dF theta|, by its normal equations (a few unknowns).
    const int m = static_cast<int>(df_.size());
    Eigen::MatrixXd normal(m, m);
    Eigen::VectorXd rhs(m);
    for (int i = 0; i < m; ++i) {
      rhs[i] = df_[i].dot(f);
      for (int j = 0; j <= i; ++j) normal(i, j) = normal(j, i) = df_[i].dot(df_[j]);
    }
    normal.diagonal() *= 1 + 1e-10;
    const Eigen::VectorXd theta = normal.ldlt().solve(rhs);
    if (!theta.allFinite()) return false;
    next_ = g;
    for (int i = 0; i < m; ++i) next_ -= theta[i] * dg_[i];
    return true;
  }

  const Eigen::VectorXd& next() const { return next_; }

 private:
  int depth_;
  std::vector<Eigen::VectorXd> dg_, df_;  ///< differences of consecutive g and f, oldest first
  Eigen::VectorXd last_g_, last_f_, next_;
};

}  // namespace qs
