#include "qs/param/sparse_cholesky.h"

#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <random>
#include <vector>

namespace qs::param {
namespace {

/// The lower triangle of a grid Laplacian (n x n vertices, 8 neighbours, random positive weights)
/// with its border fixed: symmetric positive definite, the kind of system a patch map solves.
Eigen::SparseMatrix<double> grid_system(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> weight(0.01, 10.0);
  auto id = [n](int x, int y) { return y * n + x; };
  std::vector<double> diag(n * n, 0.0);
  std::vector<Eigen::Triplet<double>> t;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      for (const auto& [dx, dy] : {std::pair{1, 0}, {0, 1}, {1, 1}, {-1, 1}}) {
        const int u = x + dx, v = y + dy;
        if (u < 0 || u >= n || v >= n) continue;
        const double w = weight(rng);
        diag[id(x, y)] += w;
        diag[id(u, v)] += w;
        t.emplace_back(std::max(id(x, y), id(u, v)), std::min(id(x, y), id(u, v)), -w);
      }
  // The border (fixed) only adds to the diagonal: border-adjacent rows become dominant.
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const bool border = x == 0 || y == 0 || x == n - 1 || y == n - 1;
      t.emplace_back(id(x, y), id(x, y), diag[id(x, y)] + (border ? weight(rng) : 0.0));
    }
  Eigen::SparseMatrix<double> a(n * n, n * n);
  a.setFromTriplets(t.begin(), t.end());
  return a;
}

// The supernodal factor solves the system as the simplicial one does (to rounding), for new
// values on the same pattern too, and the same input gives the same bits.
TEST(SupernodalCholesky, SolvesLikeTheSimplicialFactorOnGridSystems) {
  for (int n : {1, 2, 7, 60}) {
    const Eigen::SparseMatrix<double> a = grid_system(n, 1), b_values = grid_system(n, 2);
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Random(n * n, 2);
    SupernodalCholesky llt;
    llt.analyze(a);
    for (const auto* m : {&a, &b_values}) {
      ASSERT_TRUE(llt.factorize(*m)) << "n = " << n;
      const Eigen::MatrixXd x = llt.solve(rhs);
      Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> ref(*m);
      const Eigen::MatrixXd y = ref.solve(rhs);
      EXPECT_LT((x - y).norm(), 1e-9 * y.norm()) << "n = " << n;
      const Eigen::MatrixXd residual = m->selfadjointView<Eigen::Lower>() * x - rhs;
      EXPECT_LT(residual.norm(), 1e-9 * rhs.norm()) << "n = " << n;
      SupernodalCholesky again;
      again.analyze(*m);
      ASSERT_TRUE(again.factorize(*m));
      EXPECT_EQ(again.solve(rhs), x) << "n = " << n;
    }
    EXPECT_GE(llt.factor_entries(), a.nonZeros());
  }
}

// A matrix that is not positive definite is refused, not factorized into NaN.
TEST(SupernodalCholesky, RefusesAnIndefiniteMatrix) {
  Eigen::SparseMatrix<double> a = grid_system(10, 3);
  a.coeffRef(57, 57) = -1.0;
  SupernodalCholesky llt;
  llt.analyze(a);
  EXPECT_FALSE(llt.factorize(a));
}

}  // namespace
}  // namespace qs::param
