// Supernodal multifrontal sparse Cholesky (Liu 1992; Davis, "Direct Methods for Sparse Linear
// Systems", 2006): AMD or nested-dissection ordering, elimination tree in postorder, relaxed
// supernodes, one dense frontal matrix per supernode.

#include "qs/param/sparse_cholesky.h"

#include <Eigen/OrderingMethods>
#include <algorithm>
#include <limits>
#include <memory>
#include <string>

#include "qs/core/error.h"
#include "qs/core/parallel.h"
#include "qs/param/dense_kernels.h"

namespace qs::param {
namespace {

/// The lower triangle of P A P^T in compressed columns (rows ascending in each column), with the
/// index of each entry's value in the input's value array.
void permuted_lower(const Eigen::SparseMatrix<double>& a, const std::vector<int>& new_index, std::vector<int>& col_start,
                    std::vector<int>& row_index, std::vector<long>& source) {
  const int n = static_cast<int>(a.cols());
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  col_start.assign(n + 1, 0);
  for (int j = 0; j < n; ++j)
    for (int p = outer[j]; p < outer[j + 1]; ++p)
      if (inner[p] >= j) ++col_start[std::min(new_index[inner[p]], new_index[j]) + 1];
  for (int j = 0; j < n; ++j) col_start[j + 1] += col_start[j];
  row_index.resize(col_start[n]);
  source.resize(col_start[n]);
  std::vector<int> fill(col_start.begin(), col_start.end() - 1);
  for (int j = 0; j < n; ++j)
    for (int p = outer[j]; p < outer[j + 1]; ++p) {
      if (inner[p] < j) continue;
      const int r = new_index[inner[p]], c = new_index[j];
      const int q = fill[std::min(r, c)]++;
      row_index[q] = std::max(r, c);
      source[q] = p;
    }
  std::vector<std::pair<int, long>> col;
  for (int j = 0; j < n; ++j) {
    col.clear();
    for (int q = col_start[j]; q < col_start[j + 1]; ++q) col.emplace_back(row_index[q], source[q]);
    std::sort(col.begin(), col.end());
    for (int q = col_start[j]; q < col_start[j + 1]; ++q) {
      row_index[q] = col[q - col_start[j]].first;
      source[q] = col[q - col_start[j]].second;
    }
  }
}

/// Elimination tree of P A P^T, from A's lower triangle and P (new_index[row] = its position):
/// Liu's algorithm with path compression.
std::vector<int> elimination_tree(const Eigen::SparseMatrix<double>& a, const std::vector<int>& new_index) {
  const int n = static_cast<int>(a.cols());
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  // Row k's columns j < k of the permuted lower triangle (in any order: the tree is the same).
  std::vector<int> row_start(n + 1, 0);
  for (int j = 0; j < n; ++j)
    for (int p = outer[j]; p < outer[j + 1]; ++p)
      if (inner[p] > j) ++row_start[std::max(new_index[inner[p]], new_index[j]) + 1];
  for (int k = 0; k < n; ++k) row_start[k + 1] += row_start[k];
  std::vector<int> cols(row_start[n]), fill(row_start.begin(), row_start.end() - 1);
  for (int j = 0; j < n; ++j)
    for (int p = outer[j]; p < outer[j + 1]; ++p)
      if (inner[p] > j) {
        const int r = new_index[inner[p]], c = new_index[j];
        cols[fill[std::max(r, c)]++] = std::min(r, c);
      }
  std::vector<int> parent(n, -1), ancestor(n, -1);
  for (int k = 0; k < n; ++k)
    for (int q = row_start[k]; q < row_start[k + 1]; ++q)
      for (int i = cols[q]; i != -1 && i < k;) {
        const int next = ancestor[i];
        ancestor[i] = k;
        if (next == -1) parent[i] = k;
        i = next;
      }
  return parent;
}

/// Each node's children in a forest given by its parents (-1: a root), in increasing order:
/// first_child[p], then next_sibling[c] until -1.
void child_lists(const std::vector<int>& parent, std::vector<int>& first_child, std::vector<int>& next_sibling) {
  const int n = static_cast<int>(parent.size());
  first_child.assign(n, -1);
  next_sibling.assign(n, -1);
  for (int j = n - 1; j >= 0; --j)
    if (parent[j] >= 0) {
      next_sibling[j] = first_child[parent[j]];
      first_child[parent[j]] = j;
    }
}

/// A^T + A for a lower triangle A, its pattern only (values zero), rows ascending in each column:
/// what Eigen's AMDOrdering builds for its minimum degree ordering, without a sparse transpose
/// and sum.
Eigen::SparseMatrix<double> symmetric_pattern(const Eigen::SparseMatrix<double>& a) {
  const int n = static_cast<int>(a.cols());
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  // Column j: A's row j left of the diagonal (transposed), then A's column j.
  std::vector<int> start(n + 1, 0);
  for (int j = 0; j < n; ++j)
    for (int p = outer[j]; p < outer[j + 1]; ++p) {
      ++start[j + 1];
      if (inner[p] > j) ++start[inner[p] + 1];
    }
  for (int j = 0; j < n; ++j) start[j + 1] += start[j];
  Eigen::SparseMatrix<double> c(n, n);
  c.resizeNonZeros(start[n]);
  std::copy(start.begin(), start.end(), c.outerIndexPtr());
  int* rows = c.innerIndexPtr();
  std::fill(c.valuePtr(), c.valuePtr() + start[n], 0.0);
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (int j = 0; j < n; ++j)
    for (int p = outer[j]; p < outer[j + 1]; ++p)
      if (inner[p] > j) rows[fill[inner[p]]++] = j;
  for (int j = 0; j < n; ++j)
    for (int p = outer[j]; p < outer[j + 1]; ++p) rows[fill[j]++] = inner[p];
  return c;
}

/// The symmetric adjacency (CSR, no diagonal) of a lower triangle's pattern.
void adjacency(const Eigen::SparseMatrix<double>& a, std::vector<int>& start, std::vector<int>& adj) {
  const int n = static_cast<int>(a.cols());
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  start.assign(n + 1, 0);
  for (int j = 0; j < n; ++j)
    for (int p = outer[j]; p < outer[j + 1]; ++p)
      if (inner[p] > j) {
        ++start[inner[p] + 1];
        ++start[j + 1];
      }
  for (int j = 0; j < n; ++j) start[j + 1] += start[j];
  adj.resize(start[n]);
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (int j = 0; j < n; ++j)
    for (int p = outer[j]; p < outer[j + 1]; ++p)
      if (inner[p] > j) {
        adj[fill[inner[p]]++] = j;
        adj[fill[j]++] = inner[p];
      }
}

/// Nested dissection of a graph whose nodes have points: a part is cut across the axis of its
/// largest extent, at the position within the middle 30% of its nodes (in that axis's order)
/// where the fewest edges cross per node of the smaller side; the nodes of one side that touch the
/// other (the side with fewer such nodes) form the separator, ordered after both sides. Parts of
/// at most `leaf` nodes keep their index order.
class Dissector {
 public:
  Dissector(const Eigen::MatrixXd& points, const std::vector<int>& start, const std::vector<int>& adj, int leaf)
      : points_(points), start_(start), adj_(adj), leaf_(leaf), part_(points.rows(), 0), rank_(points.rows(), 0) {}

  /// The nodes in elimination order.
  std::vector<int> order() {
    const int n = static_cast<int>(points_.rows());
    std::vector<std::vector<int>> sorted(points_.cols(), std::vector<int>(n));
    for (int a = 0; a < points_.cols(); ++a) {
      for (int i = 0; i < n; ++i) sorted[a][i] = i;
      std::stable_sort(sorted[a].begin(), sorted[a].end(),
                       [&](int x, int y) { return points_(x, a) < points_(y, a); });
    }
    out_.reserve(n);
    run(std::move(sorted));
    return std::move(out_);
  }

 private:
  // `lists`: the part's nodes in each axis's order.
  void run(std::vector<std::vector<int>> lists) {
    const int m = static_cast<int>(lists[0].size());
    if (m <= leaf_) {
      std::vector<int> ids = std::move(lists[0]);
      std::sort(ids.begin(), ids.end());
      out_.insert(out_.end(), ids.begin(), ids.end());
      return;
    }
    const int me = ++stamp_;
    for (int i : lists[0]) part_[i] = me;
    // The axis of the largest extent; the edges crossing each cut position across it (a
    // difference array over the ranks).
    int best_axis = 0, best_cut = m / 2;
    double extent = -1;
    for (size_t a = 0; a < lists.size(); ++a) {
      const auto axis = static_cast<Eigen::Index>(a);
      const double e = points_(lists[a].back(), axis) - points_(lists[a].front(), axis);
      if (e > extent) {
        extent = e;
        best_axis = static_cast<int>(a);
      }
    }
    double best_score = std::numeric_limits<double>::infinity();
    std::vector<long> diff(m + 1);
    const int lo = std::max(1, static_cast<int>(0.35 * m)), hi = std::min(m - 1, static_cast<int>(0.65 * m));
    {
      const std::vector<int>& l = lists[best_axis];
      for (int k = 0; k < m; ++k) rank_[l[k]] = k;
      std::fill(diff.begin(), diff.end(), 0);
      for (int k = 0; k < m; ++k) {
        const int i = l[k];
        for (int q = start_[i]; q < start_[i + 1]; ++q) {
          const int j = adj_[q];
          if (part_[j] != me || rank_[j] <= k) continue;
          ++diff[k + 1];  // cuts at k + 1 .. rank(j) separate i from j
          --diff[rank_[j] + 1];
        }
      }
      long cross = 0;
      for (int c = 1; c <= hi; ++c) {
        cross += diff[c];
        if (c < lo) continue;
        const double score = static_cast<double>(cross) / std::min(c, m - c);
        if (score < best_score) {
          best_score = score;
          best_cut = c;
        }
      }
    }
    const std::vector<int>& l = lists[best_axis];
    const int left = ++stamp_, right = ++stamp_;
    for (int k = 0; k < m; ++k) part_[l[k]] = k < best_cut ? left : right;
    auto touching = [&](int from, int to) {
      std::vector<int> t;
      for (int i : l)
        if (part_[i] == from)
          for (int q = start_[i]; q < start_[i + 1]; ++q)
            if (part_[adj_[q]] == to) {
              t.push_back(i);
              break;
            }
      return t;
    };
    std::vector<int> from_left = touching(left, right), from_right = touching(right, left);
    std::vector<int> separator = std::move(from_left.size() <= from_right.size() ? from_left : from_right);
    const int cut = ++stamp_;
    for (int i : separator) part_[i] = cut;
    std::vector<std::vector<int>> left_lists(lists.size()), right_lists(lists.size());
    for (size_t a = 0; a < lists.size(); ++a) {
      for (int i : lists[a])
        if (part_[i] == left) left_lists[a].push_back(i);
        else if (part_[i] == right) right_lists[a].push_back(i);
      std::vector<int>().swap(lists[a]);
    }
    run(std::move(left_lists));
    run(std::move(right_lists));
    out_.insert(out_.end(), separator.begin(), separator.end());
  }

  const Eigen::MatrixXd& points_;
  const std::vector<int>& start_;
  const std::vector<int>& adj_;
  int leaf_;
  std::vector<int> part_, rank_, out_;
  int stamp_ = 0;
};

/// Parts of the nested dissection that keep their own order (nodes).
constexpr int kDissectionLeaf = 32;

/// The rows of `lower` in nested-dissection order (Dissector) of the graph whose nodes are the
/// rows' distinct points (rows at one point stay together, in index order); new_index[row] = its
/// position.
void nested_dissection(const Eigen::SparseMatrix<double>& lower, const Eigen::MatrixXd& p,
                       std::vector<int>& new_index) {
  const int n = static_cast<int>(lower.cols());
  const int d = static_cast<int>(p.cols());
  std::vector<int> by_point(n);
  for (int i = 0; i < n; ++i) by_point[i] = i;
  std::sort(by_point.begin(), by_point.end(), [&](int x, int y) {
    for (int a = 0; a < d; ++a)
      if (p(x, a) != p(y, a)) return p(x, a) < p(y, a);
    return x < y;
  });
  std::vector<int> node(n), node_start;
  for (int k = 0; k < n; ++k) {
    const int i = by_point[k];
    bool same = k > 0;
    for (int a = 0; a < d && same; ++a) same = p(i, a) == p(by_point[k - 1], a);
    if (!same) node_start.push_back(k);
    node[i] = static_cast<int>(node_start.size()) - 1;
  }
  const int nodes = static_cast<int>(node_start.size());
  node_start.push_back(n);
  Eigen::MatrixXd node_point(nodes, d);
  for (int v = 0; v < nodes; ++v) node_point.row(v) = p.row(by_point[node_start[v]]);
  std::vector<int> row_start, row_adj;
  adjacency(lower, row_start, row_adj);
  std::vector<int> start(nodes + 1, 0), adj, seen(nodes, -1);
  adj.reserve(row_adj.size() / 2);
  for (int v = 0; v < nodes; ++v) {
    for (int k = node_start[v]; k < node_start[v + 1]; ++k) {
      const int i = by_point[k];
      for (int q = row_start[i]; q < row_start[i + 1]; ++q) {
        const int w = node[row_adj[q]];
        if (w != v && seen[w] != v) {
          seen[w] = v;
          adj.push_back(w);
        }
      }
    }
    start[v + 1] = static_cast<int>(adj.size());
  }
  const std::vector<int> order = Dissector(node_point, start, adj, kDissectionLeaf).order();
  new_index.assign(n, 0);
  int k = 0;
  for (int v : order)
    for (int q = node_start[v]; q < node_start[v + 1]; ++q) new_index[by_point[q]] = k++;
}

/// Factorizations of less work than this (k m^2 summed over the supernodes, about the
/// multiply-adds) run on one thread: a few milliseconds, less than starting threads is worth.
constexpr double kParallelWork = 2e7;

/// Fronts of at least this many rows are eliminated by blocks of kBlock columns (eliminate()).
constexpr int kBlockedFront = 384;
constexpr int kBlock = 128;

/// Eliminates the first k columns of the dense symmetric m x m matrix f, column-major (its lower
/// triangle is read and written): L11 and L21 of f = [L11 0; L21 I] [I 0; 0 S] [L11^T L21^T; 0 I]
/// over f's first k columns, the Schur complement S over its lower right block. Fronts of
/// kBlockedFront rows or more go by right-looking blocks of kBlock columns, their row and column
/// tasks on up to `threads` threads; each task's arithmetic is the same on any thread count, and so
/// are the bits. False when a pivot is not positive.
bool eliminate(double* f, int m, int k, int threads) {
  const dense::Kernels& kernel = dense::kernels();
  if (m < kBlockedFront) {
    if (!kernel.cholesky(f, k, m)) return false;  // L11 in the lower triangle
    if (m > k) {
      kernel.solve_right_lower_transposed(f, k, m, f + k, m - k, m);
      kernel.rank_update(f + k + static_cast<std::ptrdiff_t>(k) * m, m - k, m, f + k, k, m);
    }
    return true;
  }
  auto at = [&](int row, int column) { return f + row + static_cast<std::ptrdiff_t>(column) * m; };
  Context pool;
  pool.threads = threads;
  for (int j0 = 0; j0 < k; j0 += kBlock) {
    const int jb = std::min(kBlock, k - j0);
    if (!kernel.cholesky(at(j0, j0), jb, m)) return false;
    const int r0 = j0 + jb;
    if (r0 >= m) break;
    const int tasks = (m - r0 + kBlock - 1) / kBlock;
    parallel_for(tasks, threads, pool, [&](int t) {  // L21 of this block column, kBlock rows a task
      const int a = r0 + t * kBlock;
      kernel.solve_right_lower_transposed(at(j0, j0), jb, m, at(a, j0), std::min(kBlock, m - a), m);
    });
    parallel_for(tasks, threads, pool, [&](int t) {  // the trailing matrix, kBlock columns a task
      const int c0 = r0 + t * kBlock, cb = std::min(kBlock, m - c0);
      kernel.rank_update(at(c0, c0), cb, m, at(c0, j0), jb, m);
      if (c0 + cb < m)
        kernel.multiply_subtract(at(c0 + cb, c0), m - c0 - cb, cb, m, at(c0 + cb, j0), m, at(c0, j0), m, jb);
    });
  }
  return true;
}

void require_compressed(const Eigen::SparseMatrix<double>& a) {
  if (!a.isCompressed() || a.rows() != a.cols())
    throw InternalError("SupernodalCholesky: the matrix must be square and compressed");
}

}  // namespace

bool is_permutation_of(const std::vector<int>& order, int n) {
  if (static_cast<int>(order.size()) != n) return false;
  std::vector<char> seen(n, 0);
  for (const int r : order) {
    if (r < 0 || r >= n || seen[r]) return false;
    seen[r] = 1;
  }
  return true;
}

void SupernodalCholesky::analyze(const Eigen::SparseMatrix<double>& lower, const Eigen::MatrixXd* points) {
  require_compressed(lower);
  const int n = static_cast<int>(lower.cols());
  if (points && points->rows() != n)
    throw InternalError("SupernodalCholesky: " + std::to_string(points->rows()) + " points for " + std::to_string(n) +
                        " rows");
  std::vector<int> order;
  if (points && points->cols() > 0 && n > 0 && points->allFinite()) {
    nested_dissection(lower, *points, order);
  } else {
    // AMD on the symmetric pattern; Eigen's permutation maps new positions to old rows.
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> pinv;
    Eigen::SparseMatrix<double> symmetric = symmetric_pattern(lower);
    Eigen::internal::minimum_degree_ordering(symmetric, pinv);
    order.assign(n, 0);
    for (int k = 0; k < n; ++k) order[pinv.indices()[k]] = k;
  }
  analyze_ordered(lower, std::move(order));
}

void SupernodalCholesky::analyze(const Eigen::SparseMatrix<double>& lower, const std::vector<int>& ordering) {
  require_compressed(lower);
  const int n = static_cast<int>(lower.cols());
  if (!is_permutation_of(ordering, n))
    throw InternalError("SupernodalCholesky: the ordering given is not a permutation of the " + std::to_string(n) +
                        " rows");
  analyze_ordered(lower, ordering);
}

void SupernodalCholesky::analyze_ordered(const Eigen::SparseMatrix<double>& lower, std::vector<int> order) {
  n_ = static_cast<int>(lower.cols());
  const int n = n_;
  new_index_ = std::move(order);
  // Postorder of the elimination tree: every subtree's columns consecutive, children first. The
  // tree itself is the same, relabelled.
  std::vector<int> parent(n, -1);
  {
    const std::vector<int> tree = elimination_tree(lower, new_index_);
    std::vector<int> head, next;
    child_lists(tree, head, next);
    std::vector<int> post(n), stack;
    int k = 0;
    for (int root = 0; root < n; ++root) {
      if (tree[root] != -1) continue;
      stack.push_back(root);
      while (!stack.empty()) {
        const int p = stack.back();
        if (head[p] == -1) {
          stack.pop_back();
          post[p] = k++;
        } else {
          const int c = head[p];
          head[p] = next[c];
          stack.push_back(c);
        }
      }
    }
    for (int& x : new_index_) x = post[x];
    for (int j = 0; j < n; ++j) parent[post[j]] = tree[j] < 0 ? -1 : post[tree[j]];
  }
  permuted_lower(lower, new_index_, col_start_, row_index_, source_);
  // Column structures (rows below the diagonal), merged up the tree; each is kept until its
  // parent has merged it. Column j joins the supernode of j - 1 when it is j - 1's parent and the
  // supernode's dense panel would hold few explicit zeros (relaxed supernodes, with CHOLMOD's
  // default thresholds: up to 4 columns always, 16 with under 80% zeros, 48 with under 10%, any
  // with under 5%): the supernode's rows are then its columns and the last one's structure.
  std::vector<std::vector<int>> below(n);
  std::vector<int> child_head, child_next;
  child_lists(parent, child_head, child_next);
  first_.clear();
  row_start_.assign(1, 0);
  rows_.clear();
  std::vector<int> super_of(n), merged;
  long entries = 0;  // nonzeros of L in the current supernode's columns
  auto finish_super = [&](int last) {
    for (int c = first_.back(); c <= last; ++c) rows_.push_back(c);
    rows_.insert(rows_.end(), below[last].begin(), below[last].end());
    row_start_.push_back(static_cast<int>(rows_.size()));
  };
  for (int j = 0; j < n; ++j) {
    std::vector<int>& s = below[j];
    for (int q = col_start_[j]; q < col_start_[j + 1]; ++q)
      if (row_index_[q] > j) s.push_back(row_index_[q]);
    for (int c = child_head[j]; c != -1; c = child_next[c]) {
      merged.clear();
      // A child's structure starts with j itself (its parent, its first row below the diagonal).
      std::set_union(s.begin(), s.end(), below[c].begin() + 1, below[c].end(), std::back_inserter(merged));
      s.swap(merged);
    }
    bool extend = false;
    if (j > 0 && parent[j - 1] == j) {
      const long k = j - first_.back() + 1, m = k + static_cast<long>(s.size());
      const long dense = k * m - k * (k - 1) / 2;
      const double zeros = 1.0 - static_cast<double>(entries + static_cast<long>(s.size()) + 1) / static_cast<double>(dense);
      extend = k <= 4 || (k <= 16 && zeros < 0.8) || (k <= 48 && zeros < 0.1) || zeros < 0.05;
    }
    if (!extend) {
      if (j > 0) finish_super(j - 1);
      first_.push_back(j);
      entries = 0;
    }
    entries += static_cast<long>(s.size()) + 1;
    super_of[j] = static_cast<int>(first_.size()) - 1;
    for (int c = child_head[j]; c != -1; c = child_next[c]) std::vector<int>().swap(below[c]);
  }
  if (n > 0) finish_super(n - 1);
  const int ns = static_cast<int>(first_.size());
  first_.push_back(n);
  parent_.assign(ns, -1);
  for (int s = 0; s < ns; ++s) {
    const int last = first_[s + 1] - 1;
    if (parent[last] >= 0) parent_[s] = super_of[parent[last]];
  }
  child_lists(parent_, first_child_, next_sibling_);
  panel_.assign(ns, Eigen::MatrixXd());
}

SupernodalCholesky::Plan SupernodalCholesky::plan(int count) const {
  // Subtrees (consecutive in the postorder: [lowest[s], s]) handed to the threads: the roots'
  // subtrees, the heaviest split into its children's while it exceeds a quarter of a thread's
  // share; the supernodes split off (the top of the tree) run afterwards, in order, their dense
  // work on all threads. A factorization of little work (k m^2 summed over the supernodes) runs on
  // one thread.
  const int ns = static_cast<int>(parent_.size());
  Plan p;
  if (count <= 1 || ns < 2) return p;
  p.lowest.resize(ns);
  std::vector<double> work(ns, 0.0);
  double total = 0;
  for (int s = 0; s < ns; ++s) p.lowest[s] = s;
  for (int s = 0; s < ns; ++s) {
    const double m = row_start_[s + 1] - row_start_[s], k = first_[s + 1] - first_[s];
    work[s] += k * m * m;
    if (parent_[s] >= 0) {
      p.lowest[parent_[s]] = std::min(p.lowest[parent_[s]], p.lowest[s]);
      work[parent_[s]] += work[s];
    } else {
      total += work[s];
    }
  }
  if (total < kParallelWork) return p;
  for (int s = 0; s < ns; ++s)
    if (parent_[s] < 0) p.tasks.push_back(s);
  const double limit = total / (4.0 * count);
  for (;;) {
    auto heaviest = std::max_element(p.tasks.begin(), p.tasks.end(), [&](int a, int b) { return work[a] < work[b]; });
    if (heaviest == p.tasks.end() || work[*heaviest] <= limit || first_child_[*heaviest] == -1) break;
    const int s = *heaviest;
    p.tasks.erase(heaviest);
    p.top.push_back(s);
    for (int t = first_child_[s]; t != -1; t = next_sibling_[t]) p.tasks.push_back(t);
  }
  std::sort(p.tasks.begin(), p.tasks.end(),
            [&](int a, int b) { return work[a] > work[b] || (work[a] == work[b] && a < b); });
  std::sort(p.top.begin(), p.top.end());
  return p;
}

bool SupernodalCholesky::factorize(const Eigen::SparseMatrix<double>& lower, int threads) {
  require_compressed(lower);
  if (lower.cols() != n_) throw InternalError("SupernodalCholesky: factorize() with another size than analyze()");
  const double* value = lower.valuePtr();
  const int ns = static_cast<int>(panel_.size());
  // Per supernode: the update to its parent's front, its lower triangle packed by columns.
  std::vector<std::unique_ptr<double[]>> update(ns);
  // Supernode s's front: its entries of the matrix and its children's updates (in child order),
  // its first k columns eliminated (on up to dense_threads threads); its columns of L go to
  // panel_[s], its update to update[s]. relpos: a workspace of n_ entries; buffer: room for the
  // front (m^2). False when a pivot is not positive.
  auto process = [&](int s, std::vector<int>& relpos, std::vector<int>& at, double* buffer, int dense_threads) {
    const int* rs = rows_.data() + row_start_[s];
    const int m = row_start_[s + 1] - row_start_[s], k = first_[s + 1] - first_[s];
    for (int a = 0; a < m; ++a) relpos[rs[a]] = a;
    Eigen::Map<Eigen::MatrixXd> front(buffer, m, m);  // only its lower triangle is read or written: zeroed
    for (int b = 0; b < m; ++b) std::fill(&front(b, b), &front(0, b) + m, 0.0);
    for (int c = first_[s]; c < first_[s + 1]; ++c)
      for (int q = col_start_[c]; q < col_start_[c + 1]; ++q)
        front(relpos[row_index_[q]], c - first_[s]) += value[source_[q]];
    for (int t = first_child_[s]; t != -1; t = next_sibling_[t]) {
      const int kt = first_[t + 1] - first_[t];
      const int* rt = rows_.data() + row_start_[t] + kt;
      const int mt = row_start_[t + 1] - row_start_[t] - kt;
      at.resize(mt);
      for (int a = 0; a < mt; ++a) at[a] = relpos[rt[a]];
      const double* u = update[t].get();
      for (int b = 0; b < mt; ++b) {
        double* column = &front(0, at[b]);
        for (int a = b; a < mt; ++a) column[at[a]] += *u++;
      }
      update[t].reset();
    }
    if (!eliminate(buffer, m, k, dense_threads)) return false;
    if (m > k) {
      update[s].reset(new double[static_cast<std::size_t>(m - k) * (m - k + 1) / 2]);
      double* out = update[s].get();
      for (int b = k; b < m; ++b) out = std::copy(&front(b, b), &front(0, b) + m, out);
    }
    panel_[s].resize(m, k);  // the size of the last factorization's: no allocation
    panel_[s] = front.leftCols(k);
    return true;
  };
  // The largest front of a range of supernodes.
  auto largest_front = [&](int from, int to) {
    std::size_t most = 0;
    for (int s = from; s <= to; ++s) {
      const std::size_t m = static_cast<std::size_t>(row_start_[s + 1] - row_start_[s]);
      most = std::max(most, m * m);
    }
    return most;
  };
  // Every supernode's computation is the same whichever thread runs it, in whatever order
  // independent subtrees run and on however many threads its dense work is split, so the factor
  // does not depend on the thread count.
  const int count = inside_parallel_loop() ? 1 : thread_count(threads, Context{});
  std::vector<int> relpos(n_, 0), at;
  // The calling thread's front buffer is kept from one factorization to the next (no fresh pages).
  front_buffer_.resize(std::max(front_buffer_.size(), largest_front(0, ns - 1)));
  const Plan p = plan(count);
  if (p.tasks.empty()) {
    for (int s = 0; s < ns; ++s)
      if (!process(s, relpos, at, front_buffer_.data(), 1)) return false;
    return true;
  }
  std::vector<char> ok(p.tasks.size(), 1);
  Context threads_only;
  threads_only.threads = count;
  parallel_for(static_cast<int>(p.tasks.size()), count, threads_only, [&](int i) {
    const int root = p.tasks[i];
    std::vector<int> rel(n_, 0), at_i;
    const std::unique_ptr<double[]> buffer(new double[largest_front(p.lowest[root], root)]);
    for (int s = p.lowest[root]; s <= root && ok[i]; ++s) ok[i] = process(s, rel, at_i, buffer.get(), 1);
  });
  if (std::find(ok.begin(), ok.end(), 0) != ok.end()) return false;
  for (int s : p.top)
    if (!process(s, relpos, at, front_buffer_.data(), count)) return false;
  return true;
}

Eigen::MatrixXd SupernodalCholesky::solve(const Eigen::MatrixXd& b, int threads) const {
  using Rows = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const int ns = static_cast<int>(panel_.size());
  const Eigen::Index nc = b.cols();
  Rows y(n_, nc);
  for (int i = 0; i < n_; ++i) y.row(new_index_[i]) = b.row(i);
  // L z = y, as the factorization goes: supernode s takes its children's contributions to its rows
  // (in child order), solves its diagonal block, and hands L21 z_s, with the children's
  // contributions to rows below its own, to its parent. So no two subtrees write the same row, and
  // the sums do not depend on the order in which subtrees run.
  std::vector<Rows> carry(ns);
  auto forward = [&](int s, std::vector<int>& relpos) {
    const int* rs = rows_.data() + row_start_[s];
    const int m = row_start_[s + 1] - row_start_[s], k = first_[s + 1] - first_[s];
    const Eigen::MatrixXd& l = panel_[s];
    auto ys = y.middleRows(first_[s], k);
    Rows below = Rows::Zero(m - k, nc);
    for (int a = 0; a < m; ++a) relpos[rs[a]] = a;
    for (int t = first_child_[s]; t != -1; t = next_sibling_[t]) {
      const int kt = first_[t + 1] - first_[t];
      const int* rt = rows_.data() + row_start_[t] + kt;
      for (Eigen::Index a = 0; a < carry[t].rows(); ++a) {
        const int r = relpos[rt[a]];
        if (r < k) ys.row(r) -= carry[t].row(a);
        else below.row(r - k) += carry[t].row(a);
      }
      Rows().swap(carry[t]);
    }
    l.topRows(k).triangularView<Eigen::Lower>().solveInPlace(ys);
    if (m > k) below.noalias() += l.bottomRows(m - k) * ys;
    carry[s] = std::move(below);
  };
  // L^T x = z: supernode s needs x at its rows below, its ancestors' columns, only.
  auto backward = [&](int s, Rows& g) {
    const int m = row_start_[s + 1] - row_start_[s], k = first_[s + 1] - first_[s];
    const Eigen::MatrixXd& l = panel_[s];
    auto ys = y.middleRows(first_[s], k);
    if (m > k) {
      const int* r = rows_.data() + row_start_[s] + k;
      g.resize(m - k, nc);
      for (int a = 0; a < m - k; ++a) g.row(a) = y.row(r[a]);
      ys.noalias() -= l.bottomRows(m - k).transpose() * g;
    }
    l.topRows(k).triangularView<Eigen::Lower>().transpose().solveInPlace(ys);
  };
  const int count = inside_parallel_loop() ? 1 : thread_count(threads, Context{});
  const Plan p = plan(count);
  std::vector<int> relpos(n_, 0);
  Rows g;
  if (p.tasks.empty()) {
    for (int s = 0; s < ns; ++s) forward(s, relpos);
    for (int s = ns - 1; s >= 0; --s) backward(s, g);
  } else {
    Context threads_only;
    threads_only.threads = count;
    const int nt = static_cast<int>(p.tasks.size());
    parallel_for(nt, count, threads_only, [&](int i) {
      std::vector<int> rel(n_, 0);
      for (int s = p.lowest[p.tasks[i]]; s <= p.tasks[i]; ++s) forward(s, rel);
    });
    for (int s : p.top) forward(s, relpos);
    for (auto s = p.top.rbegin(); s != p.top.rend(); ++s) backward(*s, g);
    parallel_for(nt, count, threads_only, [&](int i) {
      Rows g_i;
      for (int s = p.tasks[i]; s >= p.lowest[p.tasks[i]]; --s) backward(s, g_i);
    });
  }
  Eigen::MatrixXd x(n_, nc);
  for (int i = 0; i < n_; ++i) x.row(i) = y.row(new_index_[i]);
  return x;
}

long SupernodalCholesky::factor_entries() const {
  long e = 0;
  for (const auto& p : panel_) e += static_cast<long>(p.size()) - p.cols() * (p.cols() - 1) / 2;
  return e;
}

}  // namespace qs::param
