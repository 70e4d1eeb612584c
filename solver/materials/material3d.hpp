// The four hyperelastic laws of material.hpp in three dimensions (docs/three-dimensions.md,
// "Materials in 3D"). Each is a value type with the 2D contract less the plane reduction:
//   double energy_density(F)   W(F), strain energy per unit reference volume [J/m^3]
//   Mat3   first_piola(F)      P = dW/dF, the first Piola-Kirchhoff stress [Pa]
//   first_piola_and_tangent(F, P, A)  P and A = dP/dF in one pass [Pa], A indexed
//                              A(3*i + J, 3*k + L) = dP_iJ / dF_kL (i, k spatial and J, L
//                              material indices in 0..2). Hyperelastic, so A = A^T (to
//                              round-off). P is the formula of first_piola(F), equal to it up
//                              to round-off (the compiler may contract it differently, a few ulps)
//   double wave_speed()        small-strain dilatational wave speed sqrt((lambda + 2 mu) / rho)
//                              [m/s], lambda and mu the law's small-strain Lame constants
//   double density             reference mass density rho [kg/m^3]
// F is the 3x3 deformation gradient, det F > 0. The strain-energy functions are exactly those
// the 2D laws use (their 3D forms, in the comments of material.hpp): the 2D plane-strain law is
// the 3D law restricted to F = diag(F2, 1), tested in tests/solver/materials/test_hyperelastic3d.cpp.
//
// Notation of the comments: C = F^T F, b = F F^T, E = (C - I)/2, J = det F, H = cof F = J F^-T,
// G = F^-T, I1 = tr C = |F|^2, I2 = ((tr C)^2 - tr C^2)/2 = |cof F|^2, delta the identity.
// A(i J, k L) is A(3*i + J, 3*k + L).
//
// No heap allocation, no virtual calls: everything is fixed-size Eigen or scalars (these run
// inside the time steps once the 3D kernels use them; today no kernel does).
#pragma once

#include <cmath>
#include <variant>

#include "solver/core/types.hpp"

namespace ricochet {

// dP/dF of a 3D law, A(3*i + J, 3*k + L) = dP_iJ / dF_kL [Pa].
using Mat9 = Eigen::Matrix<double, 9, 9>;

// St Venant-Kirchhoff (Holzapfel 2000, Ch. 6; Bonet & Wood 2008, Ch. 6):
//   W = lambda/2 (tr E)^2 + mu E:E,   S = lambda tr(E) I + 2 mu E,   P = F S,
//   A(iJ, kL) = delta_ik S_JL + lambda F_iJ F_kL + mu (F_iL F_kJ + b_ik delta_JL)
// (the initial-stress term delta_ik S_JL plus F_iM F_kN C_MJNL with the constant material
// elasticity tensor C_MJNL = lambda delta_MJ delta_NL + mu (delta_MN delta_JL + delta_ML delta_JN)).
// St Venant-Kirchhoff's P = F S from the nine entries of F (row-major, f[Stride k]) into
// p[Stride k], written out once: first_piola() runs it on one F (Stride 1), the 3D force
// kernels on kLanes of them (material_lanes3.hpp, Stride kLanes), so the two give the same bits.
//   C_ij = (F_0i F_0j + F_1i F_1j) + F_2i F_2j,  E = (C - I) / 2,  tr E = E_00 + (E_11 + E_22),
//   S = 2 mu E + lambda tr E I,  P_ij = (F_i0 S_0j + F_i1 S_1j) + F_i2 S_2j.
template <int Stride>
inline void svk_first_piola3(double lambda, double mu, const double* f, double* p) {
  auto F = [&](int k) { return f[Stride * k]; };
  auto c = [&](int i, int j) { return (F(i) * F(j) + F(3 + i) * F(3 + j)) + F(6 + i) * F(6 + j); };
  const double mu2 = 2.0 * mu;
  const double e00 = 0.5 * (c(0, 0) - 1.0), e11 = 0.5 * (c(1, 1) - 1.0), e22 = 0.5 * (c(2, 2) - 1.0);
  const double e01 = 0.5 * c(0, 1), e02 = 0.5 * c(0, 2), e12 = 0.5 * c(1, 2);
  const double ltr = lambda * (e00 + (e11 + e22));
  const double s00 = mu2 * e00 + ltr, s11 = mu2 * e11 + ltr, s22 = mu2 * e22 + ltr;
  const double s01 = mu2 * e01, s02 = mu2 * e02, s12 = mu2 * e12;
  for (int i = 0; i < 3; ++i) {
    const double a = F(3 * i), b = F(3 * i + 1), d = F(3 * i + 2);
    p[Stride * (3 * i)] = (a * s00 + b * s01) + d * s02;
    p[Stride * (3 * i + 1)] = (a * s01 + b * s11) + d * s12;
    p[Stride * (3 * i + 2)] = (a * s02 + b * s12) + d * s22;
  }
}

struct StVenantKirchhoff3 {
  double lambda = 0.0;         // first Lame constant [Pa]
  double shear_modulus = 0.0;  // mu [Pa]
  double density = 0.0;        // [kg/m^3]

  static StVenantKirchhoff3 make(double young, double poisson, double density);

  double energy_density(const Mat3& F) const;
  Mat3 first_piola(const Mat3& F) const;
  void first_piola_and_tangent(const Mat3& F, Mat3& P, Mat9& A) const;
  double wave_speed() const { return std::sqrt((lambda + 2.0 * shear_modulus) / density); }
};

// Compressible neo-Hookean (Bonet & Wood 2008, Ch. 6, the compressible neo-Hookean material;
// Holzapfel 2000, Ch. 6):
//   W = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2,
//   P = mu F + (lambda ln J - mu) G,
//   A(iJ, kL) = mu delta_ik delta_JL + lambda G_iJ G_kL - (lambda ln J - mu) G_iL G_kJ
// (d ln J / dF = G and dG_iJ / dF_kL = -G_iL G_kJ).
struct NeoHookean3 {
  double lambda = 0.0;         // first Lame constant [Pa]
  double shear_modulus = 0.0;  // mu [Pa]
  double density = 0.0;        // [kg/m^3]

  static NeoHookean3 make(double young, double poisson, double density);

  double energy_density(const Mat3& F) const;
  Mat3 first_piola(const Mat3& F) const;
  void first_piola_and_tangent(const Mat3& F, Mat3& P, Mat9& A) const;
  double wave_speed() const { return std::sqrt((lambda + 2.0 * shear_modulus) / density); }
};

// Blatz-Ko foam rubber, the f = 0 form (Blatz & Ko 1962; Feng, Magnain & Cros 2006; Holzapfel
// 2000, Ch. 6):
//   W = mu/2 (I2/I3 + 2 sqrt(I3) - 5) = mu/2 (tr C^-1 + 2 J - 5),   tr C^-1 = |G|^2,
//   S = mu (J C^-1 - C^-2),   P = F S = mu (J G - M),   M = G G^T G,
//   A(iJ, kL) = mu [ J (G_iJ G_kL - G_iL G_kJ) + G_iL M_kJ + M_iL G_kJ + (G G^T)_ik (G^T G)_JL ]
// (d(J G)/dF = J (G (x) G - G_iL G_kJ), and M differentiated factor by factor with
// dG_iJ / dF_kL = -G_iL G_kJ). Small-strain limit: lambda = mu (Poisson's ratio 1/4).
struct BlatzKo3 {
  double shear_modulus = 0.0;  // mu [Pa]
  double lambda = 0.0;         // small-strain first Lame constant (= mu) [Pa]
  double density = 0.0;        // [kg/m^3]

  static BlatzKo3 make(double shear_modulus, double density);

  double energy_density(const Mat3& F) const;
  Mat3 first_piola(const Mat3& F) const;
  void first_piola_and_tangent(const Mat3& F, Mat3& P, Mat9& A) const;
  double wave_speed() const { return std::sqrt((lambda + 2.0 * shear_modulus) / density); }
};

// Derivatives of an energy W(I1, I2, J) (first and second), for invariant_piola3() and
// invariant_piola_and_tangent3().
struct InvariantDerivatives3 {
  double w1 = 0.0, w2 = 0.0, wj = 0.0;                              // W_1, W_2, W_J
  double w11 = 0.0, w12 = 0.0, w1j = 0.0, w22 = 0.0, w2j = 0.0, wjj = 0.0;  // second
};

// P and A of W(I1, I2, J) by the chain rule (Holzapfel 2000, Ch. 6; Bonet & Wood 2008, Ch. 6:
// the derivatives of the invariants, dI1/dC = I, dI2/dC = I1 I - C, dJ/dC = J C^-1 / 2, pushed
// to F by dI/dF = 2 F dI/dC; the second derivatives differentiate these once more in F):
//   g1 = dI1/dF = 2 F,   g2 = dI2/dF = 2 (I1 F - F C),   gJ = dJ/dF = H,
//   P = W_1 g1 + W_2 g2 + W_J gJ,
//   A = W_1 d2I1 + W_2 d2I2 + W_J d2J + sum over a, b in {1, 2, J} of W_ab ga (x) gb, with
//   d2I1(iJ, kL) = 2 delta_ik delta_JL,
//   d2I2(iJ, kL) = 2 [2 F_iJ F_kL + I1 delta_ik delta_JL - delta_ik C_JL - b_ik delta_JL - F_iL F_kJ],
//   d2J(iJ, kL)  = (H_iJ H_kL - H_iL H_kJ) / J.
Mat3 invariant_piola3(const Mat3& F, const InvariantDerivatives3& d);
void invariant_piola_and_tangent3(const Mat3& F, const InvariantDerivatives3& d, Mat3& P,
                                  Mat9& A);

// Compressible Mooney-Rivlin with isochoric invariants (Mooney 1940, Rivlin 1948; the
// decoupled isochoric-volumetric form, Holzapfel 2000, Ch. 6):
//   W = c10 (J^(-2/3) I1 - 3) + c01 (J^(-4/3) I2 - 3) + kappa/2 (J - 1)^2,
// P and A by invariant_piola_and_tangent3() with
//   W_1 = c10 J^(-2/3),  W_2 = c01 J^(-4/3),
//   W_J = -2/3 c10 J^(-5/3) I1 - 4/3 c01 J^(-7/3) I2 + kappa (J - 1),
//   W_11 = W_12 = W_22 = 0,  W_1J = -2/3 c10 J^(-5/3),  W_2J = -4/3 c01 J^(-7/3),
//   W_JJ = 10/9 c10 J^(-8/3) I1 + 28/9 c01 J^(-10/3) I2 + kappa.
// Small-strain limit: mu = 2 (c10 + c01), bulk modulus kappa, lambda = kappa - 2 mu / 3.
struct MooneyRivlin3 {
  double c10 = 0.0;            // [Pa]
  double c01 = 0.0;            // [Pa]
  double bulk_modulus = 0.0;   // kappa [Pa]
  double shear_modulus = 0.0;  // small-strain mu = 2 (c10 + c01) [Pa]
  double lambda = 0.0;         // small-strain first Lame constant kappa - 2 mu / 3 [Pa]
  double density = 0.0;        // [kg/m^3]

  static MooneyRivlin3 make(double c10, double c01, double bulk_modulus, double density);

  // W_1 ... W_JJ at (I1, I2, J).
  InvariantDerivatives3 derivatives(double i1, double i2, double j) const;
  double energy_density(const Mat3& F) const;
  Mat3 first_piola(const Mat3& F) const;
  void first_piola_and_tangent(const Mat3& F, Mat3& P, Mat9& A) const;
  double wave_speed() const { return std::sqrt((lambda + 2.0 * shear_modulus) / density); }
};

// The same alternatives, in the same order, as the 2D Material.
using Material3 = std::variant<StVenantKirchhoff3, NeoHookean3, BlatzKo3, MooneyRivlin3>;

double material_density(const Material3& m);
double material_wave_speed(const Material3& m);
// A = dP/dF of the material at F, indexed A(3*i + J, 3*k + L) = dP_iJ / dF_kL [Pa].
Mat9 material_tangent(const Material3& m, const Mat3& F);

}  // namespace ricochet
