// Sparse LDL^T factorization of a symmetric matrix with a fixed pattern, for the implicit
// scheme's direct solver: all memory is sized once by analyze(); factorize() and solve()
// allocate nothing, so the time step stays allocation-free on the direct path too.
//
// The algorithm is the up-looking row-by-row LDL^T of T. A. Davis, "Algorithm 849: a concise
// sparse Cholesky factorization package", ACM TOMS 31(4), 2005 (also Davis, Direct Methods for
// Sparse Linear Systems, SIAM 2006, ch. 4): the elimination tree and the column counts of L come
// from the pattern alone; row k of L is the solution of a sparse triangular system whose pattern
// is the set of etree paths from the entries of column k of A. The fill-reducing ordering is
// Eigen's approximate minimum degree (AMDOrdering), computed once.
#pragma once

#include <Eigen/SparseCore>
#include <vector>

namespace ricochet {

class SparseLdlt {
 public:
  using RowMajor = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

  // Symbolic analysis of a structurally symmetric matrix stored with both triangles (the
  // pattern of `a` must not change afterwards; its values are read by factorize). Allocates.
  void analyze(const RowMajor& a);

  // Numeric factorization P A P^T = L D L^T of the values a.valuePtr()[0 .. nnz). Returns false
  // as soon as a pivot D_kk is not positive and finite (A not positive definite).
  bool factorize(const double* a_values);

  // x = A^-1 b with the last successful factorization; x and b may be the same vector.
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const;

  int size() const { return n_; }
  long factor_nonzeros() const { return static_cast<long>(l_rows_.size()); }
  double min_pivot() const;  // smallest D_kk of the last factorization

 private:
  int n_ = 0;
  std::vector<int> perm_;     // perm_[new] = old
  std::vector<int> inverse_;  // inverse_[old] = new
  // The upper triangle of P A P^T by columns (row indices <= column), with the position of each
  // entry's value in the input matrix.
  std::vector<int> col_start_, col_rows_, col_source_;
  std::vector<int> parent_;  // elimination tree
  // L (unit lower, strictly below the diagonal) by columns; l_count_ counts the entries filled
  // so far in the numeric phase.
  std::vector<int> l_start_, l_rows_, l_count_;
  std::vector<double> l_values_;
  std::vector<double> d_;
  // Workspace of the numeric phase.
  std::vector<double> y_;
  std::vector<int> pattern_, flag_;
  mutable std::vector<double> work_;  // permuted right-hand side of solve
};

}  // namespace ricochet
