// Von Mises equivalents of the three stress measures at a 3D integration point, the 3D
// counterparts of stress.hpp (whose StressMeasure, VonMises2, VonMisesRatio, SymTensor6 and
// StressPeaks they share). With P the first Piola-Kirchhoff stress and F the deformation
// gradient (3 x 3; no out-of-plane state in 3D):
//   Kirchhoff           tau   = P F^T
//   Cauchy              sigma = tau / J,   J = det F
//   2nd Piola-Kirchhoff S     = F^-1 P,    J S = adj(F) P  (adj F = cof(F)^T = J F^-1)
// and the von Mises equivalent of a symmetric tensor A,
//   vm(A)^2 = 1/2 [(a11 - a22)^2 + (a22 - a33)^2 + (a33 - a11)^2] + 3 (a12^2 + a23^2 + a13^2)
//           = 3/2 |dev A|^2,
// so vm(tau) = J vm(sigma) exactly. tau and J S are symmetric for an isotropic hyperelastic law
// up to round-off; their off-diagonal entries are taken as the mean of the two (as in 2D).
// Every function is material-independent, fixed-size and allocation-free.
#pragma once

#include <array>
#include <cmath>

#include "solver/materials/stress.hpp"
#include "solver/core/types.hpp"

namespace ricochet {

// vm^2 of the symmetric tensor (a11, a22, a33, a12, a23, a13) [Pa^2].
inline double von_mises_squared(double a11, double a22, double a33, double a12, double a23, double a13) {
  const double d1 = a11 - a22, d2 = a22 - a33, d3 = a33 - a11;
  return 0.5 * (d1 * d1 + d2 * d2 + d3 * d3) + 3.0 * (a12 * a12 + a23 * a23 + a13 * a13);
}

// Sum of squares of a 3x3 matrix, in scalars (squared_norm of stress.hpp).
inline double squared_norm(const Mat3& a) {
  double s = 0.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) s += a(i, j) * a(i, j);
  return s;
}

// tau = P F^T as (t11, t22, t33, t12, t23, t13), off-diagonals symmetrized.
inline std::array<double, 6> kirchhoff_stress(const Mat3& F, const Mat3& P) {
  auto t = [&](int i, int j) { return P(i, 0) * F(j, 0) + P(i, 1) * F(j, 1) + P(i, 2) * F(j, 2); };
  return {t(0, 0), t(1, 1), t(2, 2), 0.5 * (t(0, 1) + t(1, 0)), 0.5 * (t(1, 2) + t(2, 1)), 0.5 * (t(0, 2) + t(2, 0))};
}

// J S = adj(F) P as (11, 22, 33, 12, 23, 13), off-diagonals symmetrized. adj(F)(i, k) is the
// cofactor of F(k, i).
inline std::array<double, 6> scaled_pk2_stress(const Mat3& F, const Mat3& P) {
  Mat3 adj;
  adj(0, 0) = F(1, 1) * F(2, 2) - F(1, 2) * F(2, 1);
  adj(0, 1) = F(0, 2) * F(2, 1) - F(0, 1) * F(2, 2);
  adj(0, 2) = F(0, 1) * F(1, 2) - F(0, 2) * F(1, 1);
  adj(1, 0) = F(1, 2) * F(2, 0) - F(1, 0) * F(2, 2);
  adj(1, 1) = F(0, 0) * F(2, 2) - F(0, 2) * F(2, 0);
  adj(1, 2) = F(0, 2) * F(1, 0) - F(0, 0) * F(1, 2);
  adj(2, 0) = F(1, 0) * F(2, 1) - F(1, 1) * F(2, 0);
  adj(2, 1) = F(0, 1) * F(2, 0) - F(0, 0) * F(2, 1);
  adj(2, 2) = F(0, 0) * F(1, 1) - F(0, 1) * F(1, 0);
  auto s = [&](int i, int j) { return adj(i, 0) * P(0, j) + adj(i, 1) * P(1, j) + adj(i, 2) * P(2, j); };
  return {s(0, 0), s(1, 1), s(2, 2), 0.5 * (s(0, 1) + s(1, 0)), 0.5 * (s(1, 2) + s(2, 1)), 0.5 * (s(0, 2) + s(2, 0))};
}

inline double von_mises_squared(const std::array<double, 6>& a) {
  return von_mises_squared(a[0], a[1], a[2], a[3], a[4], a[5]);
}

// The squared equivalent of one measure as a ratio num / den (stress.hpp: no division or square
// root where the force pass ranks every point).
inline VonMisesRatio von_mises_ratio(const Mat3& F, const Mat3& P, double det_f, StressMeasure measure) {
  if (measure == StressMeasure::pk2) return {von_mises_squared(scaled_pk2_stress(F, P)), det_f * det_f};
  const double k2 = von_mises_squared(kirchhoff_stress(F, P));
  if (measure == StressMeasure::kirchhoff) return {k2, 1.0};
  return {k2, det_f * det_f};
}

// The three measures' ratios at one point, indexed by StressMeasure, each von_mises_ratio's.
inline std::array<VonMisesRatio, kStressMeasures> von_mises_ratios(const Mat3& F, const Mat3& P, double det_f) {
  const double k2 = von_mises_squared(kirchhoff_stress(F, P));
  std::array<VonMisesRatio, kStressMeasures> r;
  r[static_cast<int>(StressMeasure::cauchy)] = {k2, det_f * det_f};
  r[static_cast<int>(StressMeasure::pk2)] = {von_mises_squared(scaled_pk2_stress(F, P)), det_f * det_f};
  r[static_cast<int>(StressMeasure::kirchhoff)] = {k2, 1.0};
  return r;
}

// The three squared equivalents at one point, indexed by StressMeasure [Pa^2].
inline VonMises2 von_mises_squared(const Mat3& F, const Mat3& P, double det_f) {
  const std::array<VonMisesRatio, kStressMeasures> r = von_mises_ratios(F, P, det_f);
  VonMises2 out;
  for (int m = 0; m < kStressMeasures; ++m) out[m] = r[m].value();
  return out;
}

// The Cauchy stress sigma = P F^T / J [Pa] and the Green-Lagrange strain E = (F^T F - I) / 2 [-]
// at one point, symmetric tensors in VTK order (XX, YY, ZZ, XY, YZ, XZ) (cell_tensors()).
inline void cauchy_and_green_lagrange(const Mat3& F, const Mat3& P, double det_f, SymTensor6& sigma,
                                      SymTensor6& strain) {
  const std::array<double, 6> t = kirchhoff_stress(F, P);
  for (int k = 0; k < 6; ++k) sigma[k] = t[k] / det_f;
  auto c = [&](int i, int j) { return F(0, i) * F(0, j) + F(1, i) * F(1, j) + F(2, i) * F(2, j); };
  strain = {0.5 * (c(0, 0) - 1.0), 0.5 * (c(1, 1) - 1.0), 0.5 * (c(2, 2) - 1.0), 0.5 * c(0, 1), 0.5 * c(1, 2), 0.5 * c(0, 2)};
}

// Whether the squared equivalent of `measure` at a point can exceed `threshold` [Pa^2], from a
// cheap upper bound (Frobenius norms): vm(A)^2 = 3/2 |dev A|^2 <= 3/2 |A|^2; |tau| <= |P| |F|, and
// sigma = tau / J; |S| = |F^-1 P| <= |cof F| |P| / |J| with |cof F|^2 <= |F|^4 / 3 (for singular
// values s_i: s1^2 s2^2 + s2^2 s3^2 + s3^2 s1^2 <= (s1^2 + s2^2 + s3^2)^2 / 3), so
// vm(S)^2 <= |P|^2 |F|^4 / (2 J^2). The factors carry 0.1 % more (1.5015, 0.5005), so that
// round-off never skips a point at the threshold itself (as stress.hpp's bound).
inline bool von_mises_may_exceed(const Mat3& F, const Mat3& P, double det_f, StressMeasure measure, double threshold) {
  if (!(threshold > 0.0)) return true;
  const double ff = squared_norm(F), pp = squared_norm(P);
  if (measure == StressMeasure::pk2) return 0.5005 * (pp * ff * ff) > threshold * (det_f * det_f);
  const double bound = 1.5015 * (pp * ff);
  if (measure == StressMeasure::kirchhoff) return bound > threshold;
  return bound > threshold * (det_f * det_f);
}

}  // namespace ricochet
