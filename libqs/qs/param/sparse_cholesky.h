#pragma once
// Sparse Cholesky factorization by supernodes (multifrontal): each front is a dense matrix
// factorized with Eigen's dense kernels, which run many times faster than a column-by-column
// (simplicial) factorization on the large separators of surface meshes.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

namespace qs::param {

/// A = L L^T for a symmetric positive definite sparse matrix, its rows and columns ordered by AMD.
/// analyze() once per sparsity pattern, then factorize() for each set of values with that
/// pattern, then solve(). Deterministic: the same input gives the same bits.
class SupernodalCholesky {
 public:
  /// The ordering and the supernodes of `lower`'s pattern. \pre square; only the lower triangle
  /// (the diagonal included) is read.
  void analyze(const Eigen::SparseMatrix<double>& lower);
  /// Factorizes `lower` (the pattern given to analyze()). False when a pivot is not positive
  /// (the matrix is not positive definite in floating point); the factor is then unusable.
  bool factorize(const Eigen::SparseMatrix<double>& lower);
  /// x with A x = b, for every column of b. \pre factorize() returned true.
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b) const;
  /// Entries of the factor L (the diagonal included).
  long factor_entries() const;

 private:
  int n_ = 0;
  std::vector<int> new_index_;    ///< row of the permuted matrix for each original row
  std::vector<int> first_;        ///< supernode s holds columns first_[s] .. first_[s + 1] - 1
  std::vector<int> row_start_;    ///< supernode s's rows: rows_[row_start_[s] .. row_start_[s + 1])
  std::vector<int> rows_;         ///< its own columns first, then the rows below (ascending)
  std::vector<int> parent_;       ///< the supernode its update goes to, or -1
  // The permuted lower triangle (CSC) and where each entry of the input goes in it.
  std::vector<int> col_start_, row_index_;
  std::vector<long> source_;      ///< per permuted entry: its index in the input's value array
  std::vector<Eigen::MatrixXd> panel_;  ///< per supernode: its columns of L (rows_ x columns)
};

}  // namespace qs::param
