#pragma once
// Sparse Cholesky factorization by supernodes (multifrontal): each front is a dense matrix
// factorized with Eigen's dense kernels, which run many times faster than a column-by-column
// (simplicial) factorization on the large separators of surface meshes.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <vector>

namespace qs::param {

/// Whether `order` holds each of 0 .. n-1 once (an ordering analyze() accepts for n rows).
bool is_permutation_of(const std::vector<int>& order, int n);

/// A = L L^T for a symmetric positive definite sparse matrix, its rows and columns ordered by AMD,
/// or by nested dissection when each row has a point (a mesh vertex's position: rows of one
/// vertex at one point). analyze() once per sparsity pattern, then factorize() for each set of
/// values with that pattern, then solve(). Deterministic: the same input gives the same bits.
class SupernodalCholesky {
 public:
  /// The ordering and the supernodes of `lower`'s pattern. \pre square; only the lower triangle
  /// (the diagonal included) is read. `points`: null (AMD), or one point per row (a row of any
  /// width): the pattern's graph is cut recursively across its longest axis (fewest
  /// crossing edges per balance), each separator ordered after its two sides; on meshes its factor takes
  /// fewer operations than AMD's. \throws InternalError when points has another row count.
  void analyze(const Eigen::SparseMatrix<double>& lower, const Eigen::MatrixXd* points = nullptr);
  /// The same with the ordering given: `ordering` from an earlier analysis of the same pattern
  /// (ordering()) gives the same supernodes and factor without ordering again. Any other
  /// permutation of the rows works too, with its own fill. \throws InternalError when it is not
  /// a permutation of the rows.
  void analyze(const Eigen::SparseMatrix<double>& lower, const std::vector<int>& ordering);
  /// The analysis's ordering: the row of the permuted matrix for each original row.
  const std::vector<int>& ordering() const { return new_index_; }
  /// Factorizes `lower` (the pattern given to analyze()). False when a pivot is not positive
  /// (the matrix is not positive definite in floating point); the factor is then unusable.
  /// Independent subtrees of the elimination tree, then the dense blocks of the fronts above them,
  /// run on up to `threads` threads (0: one per hardware thread; one inside another parallel_for's
  /// body); the factor does not depend on it.
  bool factorize(const Eigen::SparseMatrix<double>& lower, int threads = 1);
  /// x with A x = b, for every column of b, independent subtrees on up to `threads` threads as in
  /// factorize() (the result does not depend on it). \pre factorize() returned true.
  Eigen::MatrixXd solve(const Eigen::MatrixXd& b, int threads = 1) const;
  /// Entries of the factor L (the diagonal included).
  long factor_entries() const;

 private:
  /// analyze() after the ordering: `order` is postordered, then the supernodes and the structures.
  void analyze_ordered(const Eigen::SparseMatrix<double>& lower, std::vector<int> order);
  /// How the threads share the tree: the subtrees [lowest[t], t] of `tasks` (heaviest first) run
  /// concurrently, then the supernodes of `top` in order. No tasks: one thread, in order.
  struct Plan {
    std::vector<int> lowest, tasks, top;
  };
  Plan plan(int count) const;

  int n_ = 0;
  std::vector<int> new_index_;    ///< row of the permuted matrix for each original row
  std::vector<int> first_;        ///< supernode s holds columns first_[s] .. first_[s + 1] - 1
  std::vector<int> row_start_;    ///< supernode s's rows: rows_[row_start_[s] .. row_start_[s + 1])
  std::vector<int> rows_;         ///< its own columns first, then the rows below (ascending)
  std::vector<int> parent_;       ///< the supernode its update goes to, or -1
  std::vector<int> first_child_, next_sibling_;  ///< each supernode's children, in order (-1 ends)
  // The permuted lower triangle (CSC) and where each entry of the input goes in it.
  std::vector<int> col_start_, row_index_;
  std::vector<long> source_;      ///< per permuted entry: its index in the input's value array
  std::vector<Eigen::MatrixXd> panel_;  ///< per supernode: its columns of L (rows_ x columns)
  std::vector<double> front_buffer_;     ///< room for the largest front, kept between factorizations
};

}  // namespace qs::param
