// Von Mises equivalents of three stress measures at an integration point, and the per-step
// peaks the force pass tracks (internal_forces.hpp). With P the first Piola-Kirchhoff stress,
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

}  // namespace ricochet
