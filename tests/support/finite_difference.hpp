// Central differences for the derivative checks of the materials, the element kernels and the
// tangent matrices: each entry of the argument moved by +h and -h, the difference of the two
// values over 2 h. The caller chooses h and the tolerance (truncation ~ h^2, round-off ~ eps / h).
#pragma once

#include <Eigen/Core>

namespace ricochet::test_support {

// d w / d x_i for every entry i of x (a vector or a matrix): the gradient, shaped like x.
// w(x) returns a double, e.g. the stored energy density W(F), whose gradient is P.
template <class Arg, class ScalarFn>
typename Arg::PlainObject fd_gradient(const ScalarFn& w, const Arg& x, double h) {
  using Plain = typename Arg::PlainObject;
  Plain g = Plain::Zero(x.rows(), x.cols());
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    Plain xp = x, xm = x;
    xp.data()[i] += h;
    xm.data()[i] -= h;
    g.data()[i] = (w(xp) - w(xm)) / (2.0 * h);
  }
  return g;
}

// The tangent dP/dF of an N x N function P(F) in the layout of material_tangent():
// A(N i + j, N k + l) = dP_ij / dF_kl.
template <int N, class MatrixFn>
Eigen::Matrix<double, N * N, N * N> fd_tangent(const MatrixFn& p_of, const Eigen::Matrix<double, N, N>& f,
                                               double h) {
  using MatN = Eigen::Matrix<double, N, N>;
  Eigen::Matrix<double, N * N, N * N> a;
  for (int k = 0; k < N; ++k)
    for (int l = 0; l < N; ++l) {
      MatN fp = f, fm = f;
      fp(k, l) += h;
      fm(k, l) -= h;
      const MatN dp = (p_of(fp) - p_of(fm)) / (2.0 * h);
      for (int i = 0; i < N; ++i)
        for (int j = 0; j < N; ++j) a(N * i + j, N * k + l) = dp(i, j);
    }
  return a;
}

// The Jacobian of a vector function y(x): column d is dy/dx_d.
template <class VectorFn>
Eigen::MatrixXd fd_jacobian(const VectorFn& y, const Eigen::VectorXd& x, double h) {
  Eigen::MatrixXd j;
  for (Eigen::Index d = 0; d < x.size(); ++d) {
    Eigen::VectorXd xp = x, xm = x;
    xp[d] += h;
    xm[d] -= h;
    const Eigen::VectorXd col = (y(xp) - y(xm)) / (2.0 * h);
    if (d == 0) j.resize(col.size(), x.size());
    j.col(d) = col;
  }
  return j;
}

}  // namespace ricochet::test_support
