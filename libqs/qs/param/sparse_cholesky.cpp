// Supernodal multifrontal sparse Cholesky (Liu 1992; Davis, "Direct Methods for Sparse Linear
// Systems", 2006): AMD ordering, elimination tree in postorder, fundamental supernodes, one dense
// frontal matrix per supernode.

#include "qs/param/sparse_cholesky.h"

#include <Eigen/Cholesky>
#include <Eigen/OrderingMethods>
#include <algorithm>
#include <string>

#include "qs/core/error.h"

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

/// Elimination tree of the permuted lower triangle (Liu's algorithm with path compression).
std::vector<int> elimination_tree(int n, const std::vector<int>& col_start, const std::vector<int>& row_index) {
  // Row k's columns j < k: the lower triangle read by rows.
  std::vector<int> row_start(n + 1, 0), cols(row_index.size());
  for (int r : row_index) ++row_start[r + 1];
  for (int k = 0; k < n; ++k) row_start[k + 1] += row_start[k];
  std::vector<int> fill(row_start.begin(), row_start.end() - 1);
  for (int j = 0; j < n; ++j)
    for (int q = col_start[j]; q < col_start[j + 1]; ++q) cols[fill[row_index[q]]++] = j;
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

void require_compressed(const Eigen::SparseMatrix<double>& a) {
  if (!a.isCompressed() || a.rows() != a.cols())
    throw InternalError("SupernodalCholesky: the matrix must be square and compressed");
}

}  // namespace

void SupernodalCholesky::analyze(const Eigen::SparseMatrix<double>& lower) {
  require_compressed(lower);
  n_ = static_cast<int>(lower.cols());
  const int n = n_;
  // AMD on the symmetric pattern; Eigen's permutation maps new positions to old rows.
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> pinv;
  Eigen::AMDOrdering<int> amd;
  amd(lower, pinv);
  new_index_.assign(n, 0);
  for (int k = 0; k < n; ++k) new_index_[pinv.indices()[k]] = k;
  permuted_lower(lower, new_index_, col_start_, row_index_, source_);
  // Postorder of the elimination tree: every subtree's columns consecutive, children first.
  {
    const std::vector<int> parent = elimination_tree(n, col_start_, row_index_);
    std::vector<int> head(n, -1), next(n, -1);
    for (int j = n - 1; j >= 0; --j)
      if (parent[j] >= 0) {
        next[j] = head[parent[j]];
        head[parent[j]] = j;
      }
    std::vector<int> post(n), stack;
    int k = 0;
    for (int root = 0; root < n; ++root) {
      if (parent[root] != -1) continue;
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
    permuted_lower(lower, new_index_, col_start_, row_index_, source_);
  }
  const std::vector<int> parent = elimination_tree(n, col_start_, row_index_);
  // Column structures (rows below the diagonal), merged up the tree; each is kept until its
  // parent has merged it. Column j joins the supernode of j - 1 when it is j - 1's parent and the
  // supernode's dense panel would hold few explicit zeros (relaxed supernodes, with CHOLMOD's
  // default thresholds: up to 4 columns always, 16 with under 80% zeros, 48 with under 10%, any
  // with under 5%): the supernode's rows are then its columns and the last one's structure.
  std::vector<std::vector<int>> below(n);
  std::vector<int> child_head(n, -1), child_next(n, -1);
  for (int j = n - 1; j >= 0; --j)
    if (parent[j] >= 0) {
      child_next[j] = child_head[parent[j]];
      child_head[parent[j]] = j;
    }
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
      std::set_union(s.begin(), s.end(), below[c].begin(), below[c].end(), std::back_inserter(merged));
      s.swap(merged);
    }
    // A child's structure holds j itself (its parent): drop it.
    if (!s.empty() && s.front() == j) s.erase(s.begin());
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
  panel_.assign(ns, Eigen::MatrixXd());
}

bool SupernodalCholesky::factorize(const Eigen::SparseMatrix<double>& lower) {
  require_compressed(lower);
  if (lower.cols() != n_) throw InternalError("SupernodalCholesky: factorize() with another size than analyze()");
  const double* value = lower.valuePtr();
  const int ns = static_cast<int>(panel_.size());
  std::vector<int> relpos(n_, 0);
  // Per supernode: the update to its parent's front, its lower triangle packed by columns.
  std::vector<std::vector<double>> update(ns);
  std::vector<int> head(ns, -1), next(ns, -1), at;
  for (int s = ns - 1; s >= 0; --s)
    if (parent_[s] >= 0) {
      next[s] = head[parent_[s]];
      head[parent_[s]] = s;
    }
  for (int s = 0; s < ns; ++s) {
    const int* rs = rows_.data() + row_start_[s];
    const int m = row_start_[s + 1] - row_start_[s], k = first_[s + 1] - first_[s];
    for (int a = 0; a < m; ++a) relpos[rs[a]] = a;
    Eigen::MatrixXd front = Eigen::MatrixXd::Zero(m, m);  // the lower triangle is used
    for (int c = first_[s]; c < first_[s + 1]; ++c)
      for (int q = col_start_[c]; q < col_start_[c + 1]; ++q)
        front(relpos[row_index_[q]], c - first_[s]) += value[source_[q]];
    for (int t = head[s]; t != -1; t = next[t]) {
      const int kt = first_[t + 1] - first_[t];
      const int* rt = rows_.data() + row_start_[t] + kt;
      const int mt = row_start_[t + 1] - row_start_[t] - kt;
      at.resize(mt);
      for (int a = 0; a < mt; ++a) at[a] = relpos[rt[a]];
      const double* u = update[t].data();
      for (int b = 0; b < mt; ++b) {
        double* column = &front(0, at[b]);
        for (int a = b; a < mt; ++a) column[at[a]] += *u++;
      }
      std::vector<double>().swap(update[t]);
    }
    Eigen::Ref<Eigen::MatrixXd> diagonal_block = front.topLeftCorner(k, k);
    Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> llt(diagonal_block);  // in place: L11 in the lower triangle
    if (llt.info() != Eigen::Success) return false;
    const auto l11 = front.topLeftCorner(k, k).triangularView<Eigen::Lower>();
    if (m > k) {
      auto l21 = front.bottomLeftCorner(m - k, k);
      l11.transpose().solveInPlace<Eigen::OnTheRight>(l21);
      auto u = front.bottomRightCorner(m - k, m - k);
      u.selfadjointView<Eigen::Lower>().rankUpdate(l21, -1.0);
      std::vector<double>& packed = update[s];
      packed.resize(static_cast<std::size_t>(m - k) * (m - k + 1) / 2);
      double* out = packed.data();
      for (int b = 0; b < m - k; ++b)
        for (int a = b; a < m - k; ++a) *out++ = u(a, b);
    }
    front.conservativeResize(m, k);  // keeps the first k columns in place (column-major)
    panel_[s] = std::move(front);
  }
  return true;
}

Eigen::MatrixXd SupernodalCholesky::solve(const Eigen::MatrixXd& b) const {
  const int ns = static_cast<int>(panel_.size());
  Eigen::MatrixXd y(n_, b.cols());
  for (int i = 0; i < n_; ++i) y.row(new_index_[i]) = b.row(i);
  Eigen::MatrixXd g;
  for (int s = 0; s < ns; ++s) {  // L z = y
    const int m = row_start_[s + 1] - row_start_[s], k = first_[s + 1] - first_[s];
    const Eigen::MatrixXd& l = panel_[s];
    auto ys = y.middleRows(first_[s], k);
    l.topRows(k).triangularView<Eigen::Lower>().solveInPlace(ys);
    if (m > k) {
      g.noalias() = l.bottomRows(m - k) * ys;
      const int* r = rows_.data() + row_start_[s] + k;
      for (int a = 0; a < m - k; ++a) y.row(r[a]) -= g.row(a);
    }
  }
  for (int s = ns - 1; s >= 0; --s) {  // L^T x = z
    const int m = row_start_[s + 1] - row_start_[s], k = first_[s + 1] - first_[s];
    const Eigen::MatrixXd& l = panel_[s];
    auto ys = y.middleRows(first_[s], k);
    if (m > k) {
      const int* r = rows_.data() + row_start_[s] + k;
      g.resize(m - k, y.cols());
      for (int a = 0; a < m - k; ++a) g.row(a) = y.row(r[a]);
      ys.noalias() -= l.bottomRows(m - k).transpose() * g;
    }
    l.topRows(k).triangularView<Eigen::Lower>().transpose().solveInPlace(ys);
  }
  Eigen::MatrixXd x(n_, b.cols());
  for (int i = 0; i < n_; ++i) x.row(i) = y.row(new_index_[i]);
  return x;
}

long SupernodalCholesky::factor_entries() const {
  long e = 0;
  for (const auto& p : panel_) e += static_cast<long>(p.size()) - p.cols() * (p.cols() - 1) / 2;
  return e;
}

}  // namespace qs::param
