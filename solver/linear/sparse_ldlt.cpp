#include "solver/linear/sparse_ldlt.hpp"

#include <Eigen/OrderingMethods>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace ricochet {

void SparseLdlt::analyze(const RowMajor& a) {
  if (a.rows() != a.cols()) throw std::invalid_argument("SparseLdlt: matrix not square");
  n_ = static_cast<int>(a.rows());
  const int n = n_;

  // Fill-reducing ordering. The matrix is symmetric, so its row-major arrays are also the
  // column-major arrays of the same matrix.
  Eigen::SparseMatrix<double, Eigen::ColMajor, int> pattern = a.transpose();
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> amd;
  Eigen::AMDOrdering<int>()(pattern, amd);
  perm_.assign(amd.indices().data(), amd.indices().data() + n);
  inverse_.assign(n, 0);
  for (int k = 0; k < n; ++k) inverse_[perm_[k]] = k;

  // The upper triangle of P A P^T by columns: entry (r, c) of A goes to (inverse r, inverse c).
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  col_start_.assign(n + 1, 0);
  for (int r = 0; r < n; ++r)
    for (int q = outer[r]; q < outer[r + 1]; ++q) {
      const int i = inverse_[r], j = inverse_[inner[q]];
      if (i <= j) ++col_start_[j + 1];
    }
  for (int j = 0; j < n; ++j) col_start_[j + 1] += col_start_[j];
  col_rows_.assign(col_start_[n], 0);
  col_source_.assign(col_start_[n], 0);
  std::vector<int> next(col_start_.begin(), col_start_.end() - 1);
  for (int r = 0; r < n; ++r)
    for (int q = outer[r]; q < outer[r + 1]; ++q) {
      const int i = inverse_[r], j = inverse_[inner[q]];
      if (i > j) continue;
      col_rows_[next[j]] = i;
      col_source_[next[j]++] = q;
    }

  // Elimination tree and the number of entries of each column of L (Davis's ldl_symbolic).
  parent_.assign(n, -1);
  flag_.assign(n, -1);
  l_count_.assign(n, 0);
  for (int k = 0; k < n; ++k) {
    flag_[k] = k;
    for (int p = col_start_[k]; p < col_start_[k + 1]; ++p)
      for (int i = col_rows_[p]; i < k && flag_[i] != k; i = parent_[i]) {
        if (parent_[i] == -1) parent_[i] = k;
        ++l_count_[i];
        flag_[i] = k;
      }
  }
  l_start_.assign(n + 1, 0);
  for (int k = 0; k < n; ++k) l_start_[k + 1] = l_start_[k] + l_count_[k];
  l_rows_.assign(l_start_[n], 0);
  l_values_.assign(l_start_[n], 0.0);
  d_.assign(n, 0.0);
  y_.assign(n, 0.0);
  pattern_.assign(n, 0);
  work_.assign(n, 0.0);
}

bool SparseLdlt::factorize(const double* a_values) {
  const int n = n_;
  for (int k = 0; k < n; ++k) {
    // Row k of L: solve L(0:k, 0:k) D y = A(0:k, k) on the pattern of the etree paths that
    // start at the entries of column k, collected topologically in pattern_[top, n).
    y_[k] = 0.0;
    int top = n;
    flag_[k] = k;
    l_count_[k] = 0;
    for (int p = col_start_[k]; p < col_start_[k + 1]; ++p) {
      int i = col_rows_[p];
      y_[i] += a_values[col_source_[p]];
      int len = 0;
      for (; flag_[i] != k; i = parent_[i]) {
        pattern_[len++] = i;
        flag_[i] = k;
      }
      while (len > 0) pattern_[--top] = pattern_[--len];
    }
    double d = y_[k];
    y_[k] = 0.0;
    for (; top < n; ++top) {
      const int i = pattern_[top];
      const double yi = y_[i];
      y_[i] = 0.0;
      const int end = l_start_[i] + l_count_[i];
      for (int p = l_start_[i]; p < end; ++p) y_[l_rows_[p]] -= l_values_[p] * yi;
      const double l_ki = yi / d_[i];
      d -= l_ki * yi;
      l_rows_[end] = k;
      l_values_[end] = l_ki;
      ++l_count_[i];
    }
    d_[k] = d;
    if (!(d > 0.0) || !std::isfinite(d)) {
      // Leave the workspace clean for the next attempt (y_ entries on the pattern are zeroed
      // above; flags are per k, so nothing else to reset).
      return false;
    }
  }
  return true;
}

void SparseLdlt::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
  const int n = n_;
  const int* start = l_start_.data();
  const int* rows = l_rows_.data();
  const double* l = l_values_.data();
  double* w = work_.data();
  for (int k = 0; k < n; ++k) w[k] = b[perm_[k]];
  for (int j = 0; j < n; ++j) {  // L w = b, by columns
    const double wj = w[j];
    for (int p = start[j]; p < start[j + 1]; ++p) w[rows[p]] -= l[p] * wj;
  }
  for (int j = 0; j < n; ++j) w[j] /= d_[j];
  for (int j = n - 1; j >= 0; --j) {  // L^T w = D^-1 L^-1 b: a dot product per row of L^T
    // Four partial sums: the dot product is bound by the latency of one accumulator otherwise.
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    int p = start[j];
    const int end = start[j + 1];
    for (; p + 3 < end; p += 4) {
      s0 += l[p] * w[rows[p]];
      s1 += l[p + 1] * w[rows[p + 1]];
      s2 += l[p + 2] * w[rows[p + 2]];
      s3 += l[p + 3] * w[rows[p + 3]];
    }
    for (; p < end; ++p) s0 += l[p] * w[rows[p]];
    w[j] -= (s0 + s1) + (s2 + s3);
  }
  x.resize(n);  // no allocation when x already has n entries
  for (int k = 0; k < n; ++k) x[perm_[k]] = w[k];
}

double SparseLdlt::min_pivot() const {
  return n_ == 0 ? 0.0 : *std::min_element(d_.begin(), d_.end());
}

}  // namespace ricochet
