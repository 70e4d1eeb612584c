// Von Mises equivalents of three stress measures at an integration point, and the per-step
// peaks the force pass tracks (internal_forces.hpp), in 2D and (below) 3D. In 2D, with P the first Piola-Kirchhoff stress,
// F the deformation gradient and (F33, S33) the out-of-plane stretch and 2nd Piola-Kirchhoff
// stress of the material law:
//   Kirchhoff           tau   = P F^T,         tau33   = F33^2 S33
//   Cauchy              sigma = tau / J,       J       = det F * F33
//   2nd Piola-Kirchhoff S     = F^-1 P,        S33
// and the von Mises equivalent of a tensor A with in-plane block a and out-of-plane a33,
//   vm(A)^2 = 1/2 [(a11 - a22)^2 + (a22 - a33)^2 + (a33 - a11)^2] + 3 a12^2,
// so vm(tau) = J vm(sigma) exactly. The three coincide at small strain; which one a publication
// quotes is rarely stated (docs/oblique-plate.md compares them on the oblique plate).
#pragma once

#include <array>
#include <cmath>

#include "solver/core/force_totals.hpp"
#include "solver/core/types.hpp"

namespace ricochet {

// Sum of squares of a 2x2 matrix, written in scalars: Eigen's squaredNorm() packs the
// matrix into one vector register, which after the kernels' 2-wide arithmetic is a
// store-forwarding stall (several times the cost of the arithmetic).
inline double squared_norm(const Mat2& a) {
  return a(0, 0) * a(0, 0) + a(1, 0) * a(1, 0) + a(0, 1) * a(0, 1) + a(1, 1) * a(1, 1);
}

inline double von_mises_squared(double a11, double a22, double a33, double a12) {
  const double d1 = a11 - a22, d2 = a22 - a33, d3 = a33 - a11;
  return 0.5 * (d1 * d1 + d2 * d2 + d3 * d3) + 3.0 * a12 * a12;
}

// F33^2 of a material law: its own stretch33_squared(F) where it has one (no square root),
// else from out_of_plane().
template <class Mat>
inline double stretch33_squared(const Mat& mat, const Mat2& F, double stretch) {
  if constexpr (requires { mat.stretch33_squared(F); })
    return mat.stretch33_squared(F);
  else
    return stretch * stretch;
}

// The squared equivalent of one measure alone, as a ratio num / den (den > 0 for det F > 0):
// what the force pass evaluates at every integration point of every step, so it needs no
// division or square root there. The largest of several ratios is found by cross-multiplying
// (ratio_greater), and one division per cell gives the value.
// The pieces of von_mises_ratio, from the material's out-of-plane state o (out_of_plane(F)).
// det F * S = adj(F) P, and S33 scaled alike.
template <class OutOfPlaneState>
inline VonMisesRatio pk2_ratio(const Mat2& F, const Mat2& P, double det_f, const OutOfPlaneState& o) {
  const double a11 = F(1, 1) * P(0, 0) - F(0, 1) * P(1, 0);
  const double a12 = F(1, 1) * P(0, 1) - F(0, 1) * P(1, 1);
  const double a21 = F(0, 0) * P(1, 0) - F(1, 0) * P(0, 0);
  const double a22 = F(0, 0) * P(1, 1) - F(1, 0) * P(0, 1);
  return {von_mises_squared(a11, a22, det_f * o.pk2, 0.5 * (a12 + a21)), det_f * det_f};
}
// vm(tau)^2 with F33^2 = f33_2; tau = P F^T in scalars (see squared_norm).
template <class OutOfPlaneState>
inline double kirchhoff_squared(const Mat2& F, const Mat2& P, double f33_2, const OutOfPlaneState& o) {
  const double t11 = P(0, 0) * F(0, 0) + P(0, 1) * F(0, 1);
  const double t22 = P(1, 0) * F(1, 0) + P(1, 1) * F(1, 1);
  const double t12 = 0.5 * (P(0, 0) * F(1, 0) + P(0, 1) * F(1, 1) + P(1, 0) * F(0, 0) + P(1, 1) * F(0, 1));
  return von_mises_squared(t11, t22, f33_2 * o.pk2, t12);
}

template <class Mat>
inline VonMisesRatio von_mises_ratio(const Mat& mat, const Mat2& F, const Mat2& P, double det_f, StressMeasure measure) {
  const auto o = mat.out_of_plane(F);
  if (measure == StressMeasure::pk2) return pk2_ratio(F, P, det_f, o);
  const double f33_2 = stretch33_squared(mat, F, o.stretch);
  const double k2 = kirchhoff_squared(F, P, f33_2, o);
  if (measure == StressMeasure::kirchhoff) return {k2, 1.0};
  return {k2, det_f * det_f * f33_2};  // J^2 = (det F F33)^2
}

// The three measures' ratios at one point, indexed by StressMeasure, each von_mises_ratio's,
// with the material's out-of-plane state evaluated once (for a history sample, which needs
// all three at every point).
template <class Mat>
inline std::array<VonMisesRatio, kStressMeasures> von_mises_ratios(const Mat& mat, const Mat2& F, const Mat2& P,
                                                                   double det_f) {
  const auto o = mat.out_of_plane(F);
  const double f33_2 = stretch33_squared(mat, F, o.stretch);
  const double k2 = kirchhoff_squared(F, P, f33_2, o);
  std::array<VonMisesRatio, kStressMeasures> r;
  r[static_cast<int>(StressMeasure::cauchy)] = {k2, det_f * det_f * f33_2};
  r[static_cast<int>(StressMeasure::pk2)] = pk2_ratio(F, P, det_f, o);
  r[static_cast<int>(StressMeasure::kirchhoff)] = {k2, 1.0};
  return r;
}

// The three squared equivalents at one integration point, indexed by StressMeasure [Pa^2]
// (for the history samples and the fields, not the per-step pass).
template <class Mat>
inline VonMises2 von_mises_squared(const Mat& mat, const Mat2& F, const Mat2& P, double det_f) {
  const std::array<VonMisesRatio, kStressMeasures> r = von_mises_ratios(mat, F, P, det_f);
  VonMises2 out;
  for (int m = 0; m < kStressMeasures; ++m) out[m] = r[m].value();
  return out;
}

// A symmetric 3x3 tensor in VTK's order of components (XX, YY, ZZ, XY, YZ, XZ), the order
// ParaView reads six-component arrays in. In 2D the YZ and XZ components are 0.
using SymTensor6 = std::array<double, 6>;

// The Cauchy stress sigma [Pa] and the Green-Lagrange strain E [-] at one integration point,
// from the in-plane F, its P = mat.first_piola(F) and det F, with the material's out-of-plane
// state (F33, S33):
//   tau = P F^T (in-plane block, symmetrized), tau33 = F33^2 S33, J = det F F33,
//   sigma = tau / J  (so sigma_zz = 0 in plane stress, where S33 = 0),
//   E = (F^T F - I) / 2,  E_zz = (F33^2 - 1) / 2  (0 in plane strain, where F33 = 1; in plane
//   stress the thickness stretch of the law, which eliminates F33 by S33 = 0).
// The field output's per-cell tensors (cell_tensors(), internal_forces.hpp; docs/outputs.md);
// not evaluated in the time step.
template <class Mat>
inline void cauchy_and_green_lagrange(const Mat& mat, const Mat2& F, const Mat2& P, double det_f, SymTensor6& sigma,
                                      SymTensor6& strain) {
  const auto o = mat.out_of_plane(F);
  const double f33_2 = stretch33_squared(mat, F, o.stretch);
  const double j = det_f * std::sqrt(f33_2);
  const double t11 = P(0, 0) * F(0, 0) + P(0, 1) * F(0, 1);
  const double t22 = P(1, 0) * F(1, 0) + P(1, 1) * F(1, 1);
  const double t12 = 0.5 * (P(0, 0) * F(1, 0) + P(0, 1) * F(1, 1) + P(1, 0) * F(0, 0) + P(1, 1) * F(0, 1));
  sigma = {t11 / j, t22 / j, f33_2 * o.pk2 / j, t12 / j, 0.0, 0.0};
  const double c11 = F(0, 0) * F(0, 0) + F(1, 0) * F(1, 0);
  const double c22 = F(0, 1) * F(0, 1) + F(1, 1) * F(1, 1);
  const double c12 = F(0, 0) * F(0, 1) + F(1, 0) * F(1, 1);
  strain = {0.5 * (c11 - 1.0), 0.5 * (c22 - 1.0), 0.5 * (f33_2 - 1.0), 0.5 * c12, 0.0, 0.0};
}

// Whether the squared equivalent at a point can exceed `threshold` [Pa^2], from a cheap upper
// bound: vm(A)^2 = 3/2 |dev A|^2 <= 3/2 |A|^2, with |P F^T| <= |P| |F| for tau (and sigma =
// tau / J), and |F^-1 P| <= |F| |P| / |det F| for S (|F^-1| = |F| / |det F| for a 2x2 matrix);
// Frobenius norms. Most points of a step are far below the run's peak so far and skip the exact
// value; the factor 1.001 keeps round-off from skipping a point at the threshold itself.
template <class Mat>
inline bool von_mises_may_exceed(const Mat& mat, const Mat2& F, const Mat2& P, double det_f, StressMeasure measure,
                                 double threshold) {
  if (!(threshold > 0.0)) return true;
  const auto o = mat.out_of_plane(F);
  const double pf = squared_norm(P) * squared_norm(F);
  if (measure == StressMeasure::pk2) {
    const double s33 = det_f * o.pk2;
    return 1.5015 * (pf + s33 * s33) > threshold * det_f * det_f;
  }
  const double f33_2 = stretch33_squared(mat, F, o.stretch);
  const double t33 = f33_2 * o.pk2;
  const double bound = 1.5015 * (pf + t33 * t33);
  if (measure == StressMeasure::kirchhoff) return bound > threshold;
  return bound > threshold * det_f * det_f * f33_2;
}

// ------------------------------------------------------------------------------------------ 3D
// The same at a 3D integration point, with the same StressMeasure, VonMises2, VonMisesRatio and
// SymTensor6 and the same function names, overloaded on Mat3. With P the first Piola-Kirchhoff stress and F the deformation
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

// vm^2 of the symmetric tensor (a11, a22, a33, a12, a23, a13) [Pa^2].
inline double von_mises_squared(double a11, double a22, double a33, double a12, double a23, double a13) {
  const double d1 = a11 - a22, d2 = a22 - a33, d3 = a33 - a11;
  return 0.5 * (d1 * d1 + d2 * d2 + d3 * d3) + 3.0 * (a12 * a12 + a23 * a23 + a13 * a13);
}

// Sum of squares of a 3x3 matrix, in scalars (as the 2x2 squared_norm).
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

// adj F = J F^-1 = (cof F)^T: adj(F)(i, k) is the cofactor of F(k, i), written out (the 3D laws
// take their cofactor matrix from it, material3d.cpp; their lane form has its own,
// material_lanes3.hpp).
inline Mat3 adjugate(const Mat3& F) {
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
  return adj;
}

// J S = adj(F) P as (11, 22, 33, 12, 23, 13), off-diagonals symmetrized.
inline std::array<double, 6> scaled_pk2_stress(const Mat3& F, const Mat3& P) {
  const Mat3 adj = adjugate(F);
  auto s = [&](int i, int j) { return adj(i, 0) * P(0, j) + adj(i, 1) * P(1, j) + adj(i, 2) * P(2, j); };
  return {s(0, 0), s(1, 1), s(2, 2), 0.5 * (s(0, 1) + s(1, 0)), 0.5 * (s(1, 2) + s(2, 1)), 0.5 * (s(0, 2) + s(2, 0))};
}

inline double von_mises_squared(const std::array<double, 6>& a) {
  return von_mises_squared(a[0], a[1], a[2], a[3], a[4], a[5]);
}

// The squared equivalent of one measure as a ratio num / den (as in 2D: no division or square
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
// round-off never skips a point at the threshold itself (as the 2D bound).
inline bool von_mises_may_exceed(const Mat3& F, const Mat3& P, double det_f, StressMeasure measure, double threshold) {
  if (!(threshold > 0.0)) return true;
  const double ff = squared_norm(F), pp = squared_norm(P);
  if (measure == StressMeasure::pk2) return 0.5005 * (pp * ff * ff) > threshold * (det_f * det_f);
  const double bound = 1.5015 * (pp * ff);
  if (measure == StressMeasure::kirchhoff) return bound > threshold;
  return bound > threshold * (det_f * det_f);
}

}  // namespace ricochet
