#include "solver/linear/single_factor.hpp"

#include <cholmod.h>

#include <algorithm>
#include <stdexcept>

namespace ricochet {

void SingleFactor::reserve(const cholmod_factor* l) {
  if (l == nullptr || l->xtype != CHOLMOD_REAL || l->itype != CHOLMOD_INT)
    throw std::invalid_argument("SingleFactor::reserve: needs a numeric real factor with int indices");
  n_ = static_cast<int>(l->n);
  super_ = l->is_super != 0;
  const int* perm = static_cast<const int*>(l->Perm);
  perm_.assign(perm, perm + n_);
  work_.assign(static_cast<std::size_t>(n_) * kMaxBlock, 0.0);
  if (super_) {
    const int ns = static_cast<int>(l->nsuper);
    const int* super = static_cast<const int*>(l->super);
    const int* pi = static_cast<const int*>(l->pi);
    const int* px = static_cast<const int*>(l->px);
    const int* s = static_cast<const int*>(l->s);
    first_.assign(super, super + ns + 1);
    rowptr_.assign(pi, pi + ns + 1);
    valptr_.assign(px, px + ns + 1);
    rows_.assign(s, s + pi[ns]);
    int below = 0;
    for (int k = 0; k < ns; ++k) below = std::max(below, (pi[k + 1] - pi[k]) - (super[k + 1] - super[k]));
    below_.assign(static_cast<std::size_t>(below) * kMaxBlock, 0.0);
    values_.assign(static_cast<std::size_t>(l->xsize), 0.0f);
    colptr_.clear();
    diag_.clear();
  } else {
    if (l->is_ll) throw std::invalid_argument("SingleFactor::reserve: a simplicial factor must be L D L^T");
    const int* count = static_cast<const int*>(l->ColCount);
    colptr_.assign(static_cast<std::size_t>(n_) + 1, 0);
    for (int j = 0; j < n_; ++j) colptr_[j + 1] = colptr_[j] + std::max(count[j] - 1, 0);
    rows_.assign(static_cast<std::size_t>(colptr_[n_]), 0);
    values_.assign(rows_.size(), 0.0f);
    diag_.assign(static_cast<std::size_t>(n_), 1.0);
    first_.clear();
    rowptr_.clear();
    valptr_.clear();
  }
}

void SingleFactor::copy(const cholmod_factor* l) {
  if (static_cast<int>(l->n) != n_ || (l->is_super != 0) != super_)
    throw std::invalid_argument("SingleFactor::copy: the factor's structure changed since reserve()");
  const double* x = static_cast<const double*>(l->x);
  if (super_) {
    std::transform(x, x + values_.size(), values_.begin(), [](double v) { return static_cast<float>(v); });
    return;
  }
  // Simplicial: the analysis fixed each column's count (ColCount); the numeric factor of a fixed
  // pattern keeps it.
  const int* p = static_cast<const int*>(l->p);
  const int* i = static_cast<const int*>(l->i);
  const int* nz = static_cast<const int*>(l->nz);
  for (int j = 0; j < n_; ++j) {
    const int off = nz[j] - 1;
    if (off != colptr_[j + 1] - colptr_[j])
      throw std::invalid_argument("SingleFactor::copy: the factor's structure changed since reserve()");
    diag_[j] = x[p[j]];
    for (int k = 0; k < off; ++k) {
      rows_[colptr_[j] + k] = i[p[j] + 1 + k];
      values_[colptr_[j] + k] = static_cast<float>(x[p[j] + 1 + k]);
    }
  }
}

double SingleFactor::bytes() const {
  return static_cast<double>(values_.size()) * sizeof(float) + static_cast<double>(rows_.size()) * sizeof(int) +
         static_cast<double>(diag_.size()) * sizeof(double);
}

// L D L^T, column by column: forward L y = b (column-oriented), D, backward L^T x = y (row-
// oriented over L's columns).
template <int NC>
void SingleFactor::solve_simplicial(double* w) const {
  const int* rows = rows_.data();
  const float* values = values_.data();
  for (int j = 0; j < n_; ++j) {
    double yj[NC];
    for (int c = 0; c < NC; ++c) yj[c] = w[j * NC + c];
    for (int k = colptr_[j]; k < colptr_[j + 1]; ++k) {
      const double v = values[k];
      double* wr = w + static_cast<std::size_t>(rows[k]) * NC;
      for (int c = 0; c < NC; ++c) wr[c] -= v * yj[c];
    }
  }
  for (int j = 0; j < n_; ++j)
    for (int c = 0; c < NC; ++c) w[j * NC + c] /= diag_[j];
  for (int j = n_ - 1; j >= 0; --j) {
    double sum[NC];
    for (int c = 0; c < NC; ++c) sum[c] = w[j * NC + c];
    for (int k = colptr_[j]; k < colptr_[j + 1]; ++k) {
      const double v = values[k];
      const double* wr = w + static_cast<std::size_t>(rows[k]) * NC;
      for (int c = 0; c < NC; ++c) sum[c] -= v * wr[c];
    }
    for (int c = 0; c < NC; ++c) w[j * NC + c] = sum[c];
  }
}

// L L^T by supernodes: each supernode's block is nsrow x nscol, column-major, its first nscol
// rows the supernode's own columns (lower triangle used). The rows below them are updated
// through a dense buffer (one gather or scatter per row and supernode, and contiguous loops over
// the block's columns), not row by row through the index list for every column.
template <int NC>
void SingleFactor::solve_supernodal(double* w) {
  const int ns = static_cast<int>(first_.size()) - 1;
  double* t = below_.data();
  for (int s = 0; s < ns; ++s) {
    const int k1 = first_[s], nscol = first_[s + 1] - k1;
    const int nsrow = rowptr_[s + 1] - rowptr_[s], nbelow = nsrow - nscol;
    const int* below_rows = rows_.data() + rowptr_[s] + nscol;
    const float* block = values_.data() + valptr_[s];
    double* xs = w + static_cast<std::size_t>(k1) * NC;  // the supernode's own unknowns
    for (int i = 0; i < nbelow * NC; ++i) t[i] = 0.0;
    for (int j = 0; j < nscol; ++j) {
      const float* col = block + static_cast<std::size_t>(j) * nsrow;
      double xj[NC];
      const double d = col[j];
      for (int c = 0; c < NC; ++c) xj[c] = (xs[j * NC + c] /= d);
      for (int i = j + 1; i < nscol; ++i)
        for (int c = 0; c < NC; ++c) xs[i * NC + c] -= static_cast<double>(col[i]) * xj[c];
      const float* low = col + nscol;
      for (int i = 0; i < nbelow; ++i)
        for (int c = 0; c < NC; ++c) t[i * NC + c] += static_cast<double>(low[i]) * xj[c];
    }
    for (int i = 0; i < nbelow; ++i) {
      double* wr = w + static_cast<std::size_t>(below_rows[i]) * NC;
      for (int c = 0; c < NC; ++c) wr[c] -= t[i * NC + c];
    }
  }
  for (int s = ns - 1; s >= 0; --s) {
    const int k1 = first_[s], nscol = first_[s + 1] - k1;
    const int nsrow = rowptr_[s + 1] - rowptr_[s], nbelow = nsrow - nscol;
    const int* below_rows = rows_.data() + rowptr_[s] + nscol;
    const float* block = values_.data() + valptr_[s];
    double* xs = w + static_cast<std::size_t>(k1) * NC;
    for (int i = 0; i < nbelow; ++i) {
      const double* wr = w + static_cast<std::size_t>(below_rows[i]) * NC;
      for (int c = 0; c < NC; ++c) t[i * NC + c] = wr[c];
    }
    for (int j = nscol - 1; j >= 0; --j) {
      const float* col = block + static_cast<std::size_t>(j) * nsrow;
      const float* low = col + nscol;
      double sum[NC];
      for (int c = 0; c < NC; ++c) sum[c] = 0.0;
      for (int i = 0; i < nbelow; ++i)
        for (int c = 0; c < NC; ++c) sum[c] += static_cast<double>(low[i]) * t[i * NC + c];
      for (int i = j + 1; i < nscol; ++i)
        for (int c = 0; c < NC; ++c) sum[c] += static_cast<double>(col[i]) * xs[i * NC + c];
      const double d = col[j];
      for (int c = 0; c < NC; ++c) xs[j * NC + c] = (xs[j * NC + c] - sum[c]) / d;
    }
  }
}

void SingleFactor::solve(const double* b, double* x, int ncol) {
  if (ncol < 1 || ncol > kMaxBlock) throw std::invalid_argument("SingleFactor::solve: ncol out of range");
  double* w = work_.data();
  const std::size_t n = static_cast<std::size_t>(n_);
  for (int k = 0; k < n_; ++k)
    for (int c = 0; c < ncol; ++c) w[static_cast<std::size_t>(k) * ncol + c] = b[c * n + perm_[k]];
  switch (ncol) {
    case 1: super_ ? solve_supernodal<1>(w) : solve_simplicial<1>(w); break;
    case 2: super_ ? solve_supernodal<2>(w) : solve_simplicial<2>(w); break;
    case 3: super_ ? solve_supernodal<3>(w) : solve_simplicial<3>(w); break;
    default: super_ ? solve_supernodal<4>(w) : solve_simplicial<4>(w); break;
  }
  for (int k = 0; k < n_; ++k)
    for (int c = 0; c < ncol; ++c) x[c * n + perm_[k]] = w[static_cast<std::size_t>(k) * ncol + c];
}

}  // namespace ricochet
