#include "qs/param/dense_kernels.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <random>

namespace qs::param::dense {
namespace {

/// A random symmetric positive definite matrix of size n.
Eigen::MatrixXd spd(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd a(n, n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) a(i, j) = u(rng);
  return a * a.transpose() + n * Eigen::MatrixXd::Identity(n, n);
}

/// One front's elimination with `kernel`: the first k columns of the m x m matrix f by blocks of
/// b columns, as the supernodal factorization goes; returns f (lower triangle meaningful).
Eigen::MatrixXd eliminate(const Kernels& kernel, Eigen::MatrixXd f, int k, int b) {
  const int m = static_cast<int>(f.rows());
  auto at = [&](int r, int c) { return f.data() + r + static_cast<std::ptrdiff_t>(c) * m; };
  for (int j0 = 0; j0 < k; j0 += b) {
    const int jb = std::min(b, k - j0), r0 = j0 + jb;
    EXPECT_TRUE(kernel.cholesky(at(j0, j0), jb, m));
    if (r0 >= m) break;
    kernel.solve_right_lower_transposed(at(j0, j0), jb, m, at(r0, j0), m - r0, m);
    kernel.rank_update(at(r0, r0), std::min(b, m - r0), m, at(r0, j0), jb, m);
    if (r0 + b < m) {
      kernel.rank_update(at(r0 + b, r0 + b), m - r0 - b, m, at(r0 + b, j0), jb, m);
      kernel.multiply_subtract(at(r0 + b, r0), m - r0 - b, b, m, at(r0 + b, j0), m, at(r0, j0), m, jb);
    }
  }
  return f;
}

TEST(DenseKernels, EliminationMatchesADenseCholesky) {
  const int m = 300, k = 200;
  const Eigen::MatrixXd a = spd(m, 7);
  std::vector<const Kernels*> all{&portable_kernels()};
  if (avx2_kernels()) all.push_back(avx2_kernels());
  for (const Kernels* kernel : all) {
    SCOPED_TRACE(kernel->name);
    const Eigen::MatrixXd f = eliminate(*kernel, a, k, 64);
    // L11 and L21 are the first k columns of the whole matrix's Cholesky factor; the lower right
    // block holds the Schur complement, whose own factor completes it.
    const Eigen::MatrixXd l = a.llt().matrixL();
    const Eigen::MatrixXd lk = f.leftCols(k).triangularView<Eigen::Lower>();
    EXPECT_LT((lk - l.leftCols(k)).cwiseAbs().maxCoeff(), 1e-10);
    const Eigen::MatrixXd s = f.bottomRightCorner(m - k, m - k).selfadjointView<Eigen::Lower>();
    const Eigen::MatrixXd ls = s.llt().matrixL();
    EXPECT_LT((ls - l.bottomRightCorner(m - k, m - k)).cwiseAbs().maxCoeff(), 1e-10);
  }
}

TEST(DenseKernels, AVX2AgreesWithThePortableBuildToRounding) {
  if (!avx2_kernels()) GTEST_SKIP() << "this processor lacks AVX2 or FMA";
  EXPECT_EQ(&kernels(), avx2_kernels());
  const Eigen::MatrixXd a = spd(257, 3);
  const Eigen::MatrixXd p = eliminate(portable_kernels(), a, 150, 50);
  const Eigen::MatrixXd q = eliminate(*avx2_kernels(), a, 150, 50);
  const Eigen::MatrixXd d = (p - q).triangularView<Eigen::Lower>();
  EXPECT_LT(d.cwiseAbs().maxCoeff(), 1e-11 * p.cwiseAbs().maxCoeff());
}

TEST(DenseKernels, ANonPositivePivotIsReported) {
  for (const Kernels* kernel : {&portable_kernels(), avx2_kernels()}) {
    if (!kernel) continue;
    Eigen::MatrixXd a = spd(20, 5);
    a(10, 10) = -1.0;
    EXPECT_FALSE(kernel->cholesky(a.data(), 20, 20)) << kernel->name;
  }
}

}  // namespace
}  // namespace qs::param::dense
