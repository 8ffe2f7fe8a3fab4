#include "qs/param/sparse_cholesky.h"

#include "qs/core/error.h"

#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <cmath>
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

// An ordering given back (ordering()) skips the ordering and gives the same factor, bit for bit;
// another permutation solves the system too; what is not a permutation of the rows is refused.
TEST(SupernodalCholesky, AGivenOrderingGivesTheSameFactor) {
  const Eigen::SparseMatrix<double> a = grid_system(30, 5);
  const Eigen::MatrixXd rhs = Eigen::MatrixXd::Random(a.rows(), 2);
  SupernodalCholesky amd;
  amd.analyze(a);
  ASSERT_TRUE(amd.factorize(a));
  const Eigen::MatrixXd x = amd.solve(rhs);
  SupernodalCholesky given;
  given.analyze(a, amd.ordering());
  EXPECT_EQ(given.ordering(), amd.ordering());
  ASSERT_TRUE(given.factorize(a));
  EXPECT_EQ(given.solve(rhs), x);
  EXPECT_EQ(given.factor_entries(), amd.factor_entries());

  std::vector<int> identity(a.rows());
  for (int i = 0; i < a.rows(); ++i) identity[i] = i;
  SupernodalCholesky natural;
  natural.analyze(a, identity);
  ASSERT_TRUE(natural.factorize(a));
  EXPECT_LT((natural.solve(rhs) - x).norm(), 1e-9 * x.norm());
  EXPECT_GT(natural.factor_entries(), amd.factor_entries());  // a band: more fill than AMD's

  std::vector<int> repeated = identity;
  repeated[1] = 0;
  const std::vector<int> short_order(identity.begin(), identity.end() - 1);
  std::vector<int> out_of_range = identity;
  out_of_range[0] = static_cast<int>(a.rows());
  for (const std::vector<int>* bad : std::vector<const std::vector<int>*>{&repeated, &short_order, &out_of_range}) {
    SupernodalCholesky llt;
    EXPECT_THROW(llt.analyze(a, *bad), InternalError);
  }
}

/// The grid's vertex positions, one row per unknown (`per_vertex` unknowns of a vertex at its point).
Eigen::MatrixXd grid_points(int n, int per_vertex) {
  Eigen::MatrixXd p(n * n * per_vertex, 2);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      for (int k = 0; k < per_vertex; ++k) p.row((y * n + x) * per_vertex + k) << 0.01 * x, 0.02 * y;
  return p;
}

/// A system with two unknowns per grid vertex (the 2x2 blocks of a map's Hessian): the grid
/// system on both coordinates, coupled at each vertex by [[e, e], [e, e]] (e a tenth of the
/// diagonal), which keeps it positive definite.
Eigen::SparseMatrix<double> two_per_vertex(const Eigen::SparseMatrix<double>& a) {
  std::vector<Eigen::Triplet<double>> t;
  for (int j = 0; j < a.outerSize(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, j); it; ++it) {
      const double extra = it.row() == it.col() ? 0.1 * it.value() : 0.0;  // keeps it positive definite
      t.emplace_back(2 * it.row(), 2 * it.col(), it.value() + extra);
      t.emplace_back(2 * it.row() + 1, 2 * it.col() + 1, it.value() + extra);
      if (it.row() == it.col()) t.emplace_back(2 * it.row() + 1, 2 * it.col(), extra);
    }
  Eigen::SparseMatrix<double> b(2 * a.rows(), 2 * a.cols());
  b.setFromTriplets(t.begin(), t.end());
  return b;
}

// Ordered by nested dissection of the rows' points, the factor solves as AMD's does, with about its
// fill, and gives the same bits on every thread count.
TEST(SupernodalCholesky, NestedDissectionOfPointsSolvesAsAmdDoes) {
  for (int n : {1, 3, 20, 100}) {  // 100: enough work for the threads to take subtrees
    const Eigen::SparseMatrix<double> a = two_per_vertex(grid_system(n, 4));
    const Eigen::MatrixXd points = grid_points(n, 2);
    const Eigen::MatrixXd rhs = Eigen::MatrixXd::Random(a.rows(), 2);
    SupernodalCholesky amd, nd;
    amd.analyze(a);
    nd.analyze(a, &points);
    ASSERT_TRUE(amd.factorize(a)) << "n = " << n;
    ASSERT_TRUE(nd.factorize(a)) << "n = " << n;
    const Eigen::MatrixXd x = nd.solve(rhs);
    EXPECT_LT((x - amd.solve(rhs)).norm(), 1e-9 * x.norm()) << "n = " << n;
    EXPECT_LT((a.selfadjointView<Eigen::Lower>() * x - rhs).norm(), 1e-9 * rhs.norm()) << "n = " << n;
    if (n == 100) {  // a sound ordering: about AMD's fill on a grid (its gain is in larger supernodes)
      EXPECT_LT(nd.factor_entries(), 1.25 * amd.factor_entries());
    }
    for (int threads : {2, 3}) {
      SupernodalCholesky again;
      again.analyze(a, &points);
      ASSERT_TRUE(again.factorize(a, threads));
      EXPECT_EQ(again.solve(rhs), x) << "n = " << n << ", " << threads << " threads";
    }
  }
}

// A system whose top fronts are eliminated by blocks (a few hundred rows and more: the separators
// of a 320 x 320 grid), solved with its subtrees and blocks on 1, 2 and 3 threads: the same bits,
// and the solution of the system.
TEST(SupernodalCholesky, LargeFrontsGiveTheSameBitsOnAnyThreadCount) {
  const int n = 320;
  const Eigen::SparseMatrix<double> a = grid_system(n, 7);
  const Eigen::MatrixXd points = grid_points(n, 1);
  const Eigen::MatrixXd rhs = Eigen::MatrixXd::Random(a.rows(), 3);
  Eigen::MatrixXd first;
  for (int threads : {1, 2, 3}) {
    SupernodalCholesky llt;
    llt.analyze(a, &points);
    ASSERT_TRUE(llt.factorize(a, threads));
    const Eigen::MatrixXd x = llt.solve(rhs, threads);
    EXPECT_LT((a.selfadjointView<Eigen::Lower>() * x - rhs).norm(), 1e-9 * rhs.norm()) << threads << " threads";
    if (first.size() == 0) first = x;
    else EXPECT_EQ(x, first) << threads << " threads";
  }
}

// Points with the wrong row count are refused; points that are not finite fall back to AMD.
TEST(SupernodalCholesky, ChecksThePoints) {
  const Eigen::SparseMatrix<double> a = grid_system(5, 5);
  SupernodalCholesky llt;
  const Eigen::MatrixXd few = Eigen::MatrixXd::Zero(3, 2);
  EXPECT_THROW(llt.analyze(a, &few), InternalError);
  Eigen::MatrixXd bad = grid_points(5, 1);
  bad(7, 0) = std::nan("");
  llt.analyze(a, &bad);
  ASSERT_TRUE(llt.factorize(a));
  const Eigen::MatrixXd rhs = Eigen::MatrixXd::Ones(a.rows(), 1);
  EXPECT_LT((a.selfadjointView<Eigen::Lower>() * llt.solve(rhs) - rhs).norm(), 1e-9 * rhs.norm());
}

// A pivot that fails in a subtree run on another thread is reported as on one thread.
TEST(SupernodalCholesky, RefusesAnIndefiniteMatrixOnThreads) {
  Eigen::SparseMatrix<double> a = grid_system(200, 6);
  a.coeffRef(5, 5) = -1.0;
  const Eigen::MatrixXd points = grid_points(200, 1);
  SupernodalCholesky llt;
  llt.analyze(a, &points);
  EXPECT_FALSE(llt.factorize(a, 1));
  EXPECT_FALSE(llt.factorize(a, 2));
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
