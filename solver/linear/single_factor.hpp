// A single-precision copy of a CHOLMOD factor and its triangular solves (docs/implicit.md,
// "Single-precision solves"). The implicit scheme's modified Newton solves with a factor kept
// over iterations and steps: the factor stands for the current tangent only approximately, and
// the residual, computed in double precision, decides convergence. A copy of L rounded to float
// (relative perturbation 6e-8, far below a kept factor's own staleness) then converges to the
// same state, while each solve reads half the bytes of L: on meshes whose factor no longer fits
// the cache the solves are bound by memory traffic, not by flops. The right-hand sides, the
// unknowns and all sums stay in double precision; only L's entries are stored as float.
//
// Both of CHOLMOD's layouts are copied in their own structure: simplicial L D L^T (column j's
// first entry is D_jj, the others L's below the diagonal) and supernodal L L^T (dense column-
// major blocks per supernode, with one list of row indices per supernode). The permutation is
// applied here: x = P^T L^-T (D^-1) L^-1 P b, as cholmod_solve(CHOLMOD_A).
//
// reserve() sizes everything from the analysed factor (allocates); copy() after each numeric
// factorization and solve() allocate nothing.
#pragma once

#include <vector>

struct cholmod_factor_struct;

namespace ricochet {

class SingleFactor {
 public:
  static constexpr int kMaxBlock = 4;  // right-hand sides per sweep (CholmodFactor::kMaxBlock)

  // Sizes the copy for the analysed factor `l` (its structure: simplicial or supernodal).
  void reserve(const cholmod_factor_struct* l);
  // Rounds the numeric factor `l` (same structure as reserve()'s) into the copy.
  void copy(const cholmod_factor_struct* l);
  // X = A^-1 B for ncol (1 .. kMaxBlock) column-major n x ncol arrays; x may equal b.
  void solve(const double* b, double* x, int ncol);

  bool empty() const { return n_ == 0; }
  double bytes() const;  // the copy's storage (values and indices)

 private:
  template <int NC>
  void solve_simplicial(double* w) const;
  template <int NC>
  void solve_supernodal(double* w);

  int n_ = 0;
  bool super_ = false;
  std::vector<int> perm_;
  // simplicial: column j's off-diagonal entries are [colptr_[j], colptr_[j + 1]) of rows_ and
  // values_; diag_ = D.
  std::vector<int> colptr_;
  std::vector<double> diag_;
  // supernodal: supernode s has columns [first_[s], first_[s + 1]), rows
  // rows_[rowptr_[s] ...) (its own columns first), values values_[valptr_[s] ...) column-major
  // with leading dimension rowptr_[s + 1] - rowptr_[s].
  std::vector<int> first_, rowptr_;
  std::vector<long> valptr_;
  std::vector<int> rows_;
  std::vector<float> values_;
  std::vector<double> below_;  // supernodal: a supernode's rows below its columns, x kMaxBlock
  std::vector<double> work_;  // n x kMaxBlock, row-interleaved (x[row * NC + c])
};

}  // namespace ricochet
