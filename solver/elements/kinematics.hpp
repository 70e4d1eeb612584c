// Kinematics shared by the element kernels.
#pragma once

#include <array>

#include "solver/core/types.hpp"

namespace ricochet {

// Element rows of a flat, interleaved DOF array (x0, y0, x1, ...): N x 2, rows = element nodes.
template <int N>
inline Eigen::Matrix<double, N, 2> gather(const double* a, const std::array<int, N>& c) {
  Eigen::Matrix<double, N, 2> e;
  for (int i = 0; i < N; ++i) {
    e(i, 0) = a[2 * c[i]];
    e(i, 1) = a[2 * c[i] + 1];
  }
  return e;
}

// Adds element rows (N x 2) into a flat, interleaved DOF array.
template <int N>
inline void scatter(double* f, const std::array<int, N>& c, const Eigen::Matrix<double, N, 2>& fe) {
  for (int i = 0; i < N; ++i) {
    f[2 * c[i]] += fe(i, 0);
    f[2 * c[i] + 1] += fe(i, 1);
  }
}

// F = I + ue^T dN/dX, built as columns F.col(J) = e_J + sum_I ue.row(I)^T dN(I, J): 2-wide
// FMAs that stay in registers. (The Eigen expression `I + ue^T dN` makes GCC 12 store the four
// dot products separately and reload them as vectors, a store-forwarding stall.)
// ue: N x 2 nodal displacements (rows = element nodes); dn: N x 2 shape-function gradients.
template <int N>
EIGEN_ALWAYS_INLINE Mat2 deformation_gradient(const Eigen::Matrix<double, N, 2>& ue,
                                              const Eigen::Matrix<double, N, 2>& dn) {
  Mat2 F = Mat2::Identity();
  for (int I = 0; I < N; ++I) {
    const Vec2 uI = ue.row(I).transpose();
    F.col(0) += uI * dn(I, 0);
    F.col(1) += uI * dn(I, 1);
  }
  return F;
}

}  // namespace ricochet
