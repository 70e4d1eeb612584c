// Hyperelastic materials behind one contract, chosen once per element block via std::variant:
//   double energy_density(F)   W(F), strain energy per unit reference volume [J/m^3]
//   Mat2   first_piola(F)      P = dW/dF, in-plane block of the first Piola-Kirchhoff stress [Pa]
//   OutOfPlane out_of_plane(F) the out-of-plane stretch F33 [-] and 2nd Piola-Kirchhoff S33 [Pa]
//   double wave_speed()        small-strain in-plane dilatational wave speed c_p [m/s]
//   double density             reference mass density rho [kg/m^3]
//   Matrix4d tangent(F)        A = dP/dF, the consistent tangent of the (reduced) law [Pa],
//                              indexed A(2*i + J, 2*k + L) = dP_iJ / dF_kL (i, k spatial and
//                              J, L material indices in 0..1). Hyperelastic, so A = A^T.
//   first_piola_and_tangent(F, P, A)  P and A in one pass (for assembly); P equals
//                              first_piola(F) up to round-off (written out in scalars, a few ulps)
// F is the in-plane 2x2 deformation gradient. Plane strain fixes F33 = 1; plane stress
// eliminates F33 by S33 = 0, so W and P are the reduced 2D functions (P stays exactly dW/dF)
// and A includes the dependence of the eliminated F33 on F.
#pragma once

#include <cmath>
#include <variant>

#include "solver/materials/stress.hpp"
#include "solver/core/types.hpp"

namespace ricochet {

struct OutOfPlane {
  double stretch = 1.0;  // F33 [-]
  double pk2 = 0.0;      // S33 [Pa]
};

// Lame constants of (E, nu) [Pa]; lambda is the 3D value.
struct Lame {
  double lambda;
  double shear_modulus;
};
Lame lame_from_young_poisson(double young, double poisson);

// St Venant-Kirchhoff: W = lambda/2 tr(E)^2 + mu E:E with E = (F^T F - I)/2. In plane stress
// lambda is replaced by the reduced 2lambda*mu/(lambda+2mu), which is exact for this law.
struct StVenantKirchhoff {
  double lambda = 0.0;         // 2D (plane-reduced) first Lame constant [Pa]
  double lambda_3d = 0.0;      // 3D first Lame constant [Pa]
  double shear_modulus = 0.0;  // [Pa]
  double density = 0.0;        // [kg/m^3]
  PlaneMode plane = PlaneMode::strain;
  double e33_per_trace = 0.0;  // plane stress: E33 / tr E = -lambda3 / (lambda3 + 2 mu) [-]

  static StVenantKirchhoff make(double young, double poisson, double density, PlaneMode plane);

  double energy_density(const Mat2& F) const {
    const Mat2 E = 0.5 * (F.transpose() * F - Mat2::Identity());
    const double tr = E.trace();
    return 0.5 * lambda * tr * tr + shear_modulus * E.squaredNorm();
  }
  Mat2 first_piola(const Mat2& F) const {
    const Mat2 E = 0.5 * (F.transpose() * F - Mat2::Identity());
    Mat2 S = (2.0 * shear_modulus) * E;
    S.diagonal().array() += lambda * E.trace();
    return F * S;
  }
  // A_ik(J, L) = delta_ik S_JL + lambda F_iJ F_kL + mu (b_ik delta_JL + F_iL F_kJ), b = F F^T.
  // With f = (F00, F01, F10, F11) = (a, b, c, d) (index 2i + J): mu F_iL F_kJ is mu f f^T
  // except at the entries (0,3), (1,2) (and mirrors), where it differs by -mu det F, +mu det F.
  // Written out in scalars: Eigen's 2x2 temporaries make GCC store F and P piecewise and reload
  // them as vectors (store-forwarding stalls), which cost 25 % of the assembly time.
  EIGEN_ALWAYS_INLINE void first_piola_and_tangent(const Mat2& F, Mat2& P,
                                                   Eigen::Matrix4d& A) const {
    const double a = F(0, 0), b = F(0, 1), c = F(1, 0), d = F(1, 1);
    const double mu = shear_modulus;
    // E = (F^T F - I)/2, S = lambda tr(E) I + 2 mu E, P = F S.
    const double e00 = 0.5 * (a * a + c * c - 1.0), e11 = 0.5 * (b * b + d * d - 1.0);
    const double e01 = 0.5 * (a * b + c * d);
    const double ltr = lambda * (e00 + e11);
    const double s00 = 2.0 * mu * e00 + ltr, s11 = 2.0 * mu * e11 + ltr, s01 = 2.0 * mu * e01;
    P(0, 0) = a * s00 + b * s01;
    P(0, 1) = a * s01 + b * s11;
    P(1, 0) = c * s00 + d * s01;
    P(1, 1) = c * s01 + d * s11;
    const double lm = lambda + mu;
    const double b00 = mu * (a * a + b * b), b01 = mu * (a * c + b * d);
    const double b11 = mu * (c * c + d * d);
    const double mj = mu * (a * d - b * c);
    A(0, 0) = lm * a * a + s00 + b00;
    A(1, 1) = lm * b * b + s11 + b00;
    A(2, 2) = lm * c * c + s00 + b11;
    A(3, 3) = lm * d * d + s11 + b11;
    A(0, 1) = A(1, 0) = lm * a * b + s01;
    A(2, 3) = A(3, 2) = lm * c * d + s01;
    A(0, 2) = A(2, 0) = lm * a * c + b01;
    A(1, 3) = A(3, 1) = lm * b * d + b01;
    A(0, 3) = A(3, 0) = lm * a * d - mj;
    A(1, 2) = A(2, 1) = lm * b * c + mj;
  }
  Eigen::Matrix4d tangent(const Mat2& F) const {
    Mat2 P;
    Eigen::Matrix4d A;
    first_piola_and_tangent(F, P, A);
    return A;
  }
  OutOfPlane out_of_plane(const Mat2& F) const {
    const double tr = 0.5 * (F(0, 0) * F(0, 0) + F(1, 0) * F(1, 0) + F(0, 1) * F(0, 1) + F(1, 1) * F(1, 1) - 2.0);  // tr E (in-plane), in scalars
    if (plane == PlaneMode::strain) return {1.0, lambda_3d * tr};
    return {std::sqrt(stretch33_squared(F)), 0.0};
  }
  // F33^2 = 1 + 2 E33 without the square root; in plane stress S33 = lambda3 (tr + E33) +
  // 2 mu E33 = 0 gives E33 = -lambda3 tr / (lambda3 + 2 mu).
  double stretch33_squared(const Mat2& F) const {
    if (plane == PlaneMode::strain) return 1.0;
    // tr E (in-plane), in scalars (stress.hpp, squared_norm)
    const double tr = 0.5 * (F(0, 0) * F(0, 0) + F(1, 0) * F(1, 0) + F(0, 1) * F(0, 1) + F(1, 1) * F(1, 1) - 2.0);
    return 1.0 + 2.0 * e33_per_trace * tr;
  }
  double wave_speed() const { return std::sqrt((lambda + 2.0 * shear_modulus) / density); }
};

// Compressible neo-Hookean: W = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2 (3D invariants).
// Plane stress solves S33 = 0 for C33 by a scalar Newton iteration in ln C33 (convex, so it
// converges monotonically after the first step).
struct NeoHookean {
  double lambda = 0.0;         // 3D first Lame constant [Pa]
  double shear_modulus = 0.0;  // [Pa]
  double density = 0.0;        // [kg/m^3]
  PlaneMode plane = PlaneMode::strain;

  static NeoHookean make(double young, double poisson, double density, PlaneMode plane);

  // ln C33 for a given in-plane F (0 in plane strain).
  double log_c33(double log_j2) const;

  double energy_density(const Mat2& F) const {
    const double log_j2 = std::log(F.determinant());
    const double s = log_c33(log_j2);
    const double log_j = log_j2 + 0.5 * s;
    return 0.5 * shear_modulus * (F.squaredNorm() + std::exp(s) - 3.0) - shear_modulus * log_j +
           0.5 * lambda * log_j * log_j;
  }
  Mat2 first_piola(const Mat2& F) const {
    const double j2 = F.determinant();
    const double log_j = std::log(j2) + 0.5 * log_c33(std::log(j2));
    // F^-T of a 2x2 matrix, written out.
    Mat2 f_inv_t;
    f_inv_t << F(1, 1), -F(1, 0), -F(0, 1), F(0, 0);
    f_inv_t /= j2;
    return shear_modulus * F + (lambda * log_j - shear_modulus) * f_inv_t;
  }
  // With G = F^-T, beta = lambda ln J - mu and d ln J / dF = (1 + s'/2) G:
  // A_ik(J, L) = mu delta_ik delta_JL + lambda (1 + s'/2) G_iJ G_kL - beta G_iL G_kJ, where
  // s' = ds/d(ln J2) = -lambda / (mu e^s + lambda/2) in plane stress (implicit function of
  // S33 = 0) and 0 in plane strain. With g = (G00, G01, G10, G11) (index 2i + J), G_iL G_kJ is
  // g g^T except at the entries (0,3), (1,2) (and mirrors), where it differs by -det G, +det G.
  EIGEN_ALWAYS_INLINE void first_piola_and_tangent(const Mat2& F, Mat2& P,
                                                   Eigen::Matrix4d& A) const {
    const double j2 = F.determinant();
    const double log_j2 = std::log(j2);
    const double s = log_c33(log_j2);
    const double log_j = log_j2 + 0.5 * s;
    Mat2 f_inv_t;
    f_inv_t << F(1, 1), -F(1, 0), -F(0, 1), F(0, 0);
    f_inv_t /= j2;
    const double mu = shear_modulus;
    const double beta = lambda * log_j - mu;
    P = mu * F + beta * f_inv_t;
    // lambda (1 + s'/2) = lambda mu e^s / (mu e^s + lambda/2), and S33 = 0 gives
    // mu e^s = mu - lambda ln J (= -beta) without another exp.
    double lam = lambda;
    if (plane == PlaneMode::stress) {
      const double mes = -beta;
      lam = lambda * mes / (mes + 0.5 * lambda);
    }
    const double p = f_inv_t(0, 0), q = f_inv_t(0, 1), r = f_inv_t(1, 0), w = f_inv_t(1, 1);
    const double lb = lam - beta, bj = beta / j2;  // bj = beta det G
    A(0, 0) = lb * p * p + mu;
    A(1, 1) = lb * q * q + mu;
    A(2, 2) = lb * r * r + mu;
    A(3, 3) = lb * w * w + mu;
    A(0, 1) = A(1, 0) = lb * p * q;
    A(0, 2) = A(2, 0) = lb * p * r;
    A(1, 3) = A(3, 1) = lb * q * w;
    A(2, 3) = A(3, 2) = lb * r * w;
    A(0, 3) = A(3, 0) = lb * p * w + bj;
    A(1, 2) = A(2, 1) = lb * q * r - bj;
  }
  Eigen::Matrix4d tangent(const Mat2& F) const {
    Mat2 P;
    Eigen::Matrix4d A;
    first_piola_and_tangent(F, P, A);
    return A;
  }
  OutOfPlane out_of_plane(const Mat2& F) const;
  double wave_speed() const;
};

// Derivatives of a reduced in-plane energy W(n, j) with n = |F|^2 = tr(F^T F) and j = det F
// (for plane stress, the out-of-plane unknown already eliminated, i.e. the second derivatives
// are the Schur complements). P = 2 W_n F + W_j cof F and
// A = 2 W_n I + W_j d2j/dF2 + 4 W_nn f f^T + 2 W_nj (f k^T + k f^T) + W_jj k k^T with
// f = vec F, k = vec cof F (index 2i + J) and d2j/dF2 the constant +-1 matrix of det.
struct InvariantDerivatives {
  double wn = 0.0, wj = 0.0, wnn = 0.0, wnj = 0.0, wjj = 0.0;
};
void invariant_piola_and_tangent(const Mat2& F, const InvariantDerivatives& d, Mat2& P,
                                 Eigen::Matrix4d& A);

// Blatz-Ko foam rubber (the f = 0 form, Feng, Magnain & Cros 2006):
//   W = mu/2 (I2/I3 + 2 sqrt(I3) - 5) = mu/2 (tr C^-1 + 2 J - 5)   (3D invariants of C).
// Small-strain limit: shear modulus mu, Poisson's ratio 1/4 (lambda = mu, E = 2.5 mu).
// Plane strain (C33 = 1): W = mu/2 (|F|^2/j^2 + 2 j - 4), j = det F.
// Plane stress: S33 = mu (J/C33 - 1/C33^2) = 0 has the unique closed-form root C33 = j^(-2/3)
// for every j > 0, so W = mu/2 (|F|^2/j^2 + 3 j^(2/3) - 5) exactly (no iteration).
struct BlatzKo {
  double shear_modulus = 0.0;  // mu [Pa]
  double lambda = 0.0;         // small-strain 3D first Lame constant (= mu) [Pa]
  double density = 0.0;        // [kg/m^3]
  PlaneMode plane = PlaneMode::strain;

  static BlatzKo make(double shear_modulus, double density, PlaneMode plane);

  InvariantDerivatives derivatives(const Mat2& F) const;
  double energy_density(const Mat2& F) const;
  Mat2 first_piola(const Mat2& F) const;
  void first_piola_and_tangent(const Mat2& F, Mat2& P, Eigen::Matrix4d& A) const;
  Eigen::Matrix4d tangent(const Mat2& F) const;
  OutOfPlane out_of_plane(const Mat2& F) const;
  double wave_speed() const;
};

// Compressible Mooney-Rivlin with isochoric invariants (3D):
//   W = c10 (J^(-2/3) I1 - 3) + c01 (J^(-4/3) I2 - 3) + kappa/2 (J - 1)^2.
// Small-strain limit: mu = 2 (c10 + c01), bulk modulus kappa, lambda = kappa - 2 mu / 3.
// Plane strain: F33 = 1. Plane stress: S33 = 0 solved for t = ln F33 by a bracketed Newton
// iteration at every evaluation. A root always exists (c10 + c01 > 0, kappa > 0); every root
// with J >= 1/4 is a strict minimum in F33 (W'' - 2/3 W' > 0 there), so the root is unique
// unless some root has J < 1/4 (only seen for in-plane area ratios det F < ~0.3 with large
// kappa/c01 and strong distortion) - see docs/case-format.md.
struct MooneyRivlin {
  double c10 = 0.0;            // [Pa]
  double c01 = 0.0;            // [Pa]
  double bulk_modulus = 0.0;   // kappa [Pa]
  double shear_modulus = 0.0;  // small-strain mu = 2 (c10 + c01) [Pa]
  double lambda = 0.0;         // small-strain 3D first Lame constant kappa - 2 mu / 3 [Pa]
  double density = 0.0;        // [kg/m^3]
  PlaneMode plane = PlaneMode::strain;

  static MooneyRivlin make(double c10, double c01, double bulk_modulus, double density,
                           PlaneMode plane);

  // W and its derivatives in (n, j, t) with n = |F|^2, j = det F, t = ln F33.
  struct Terms {
    double w, wn, wj, wt, wnj, wjj, wnt, wjt, wtt;
  };
  Terms terms(double n, double j, double t) const;
  // t = ln F33: 0 in plane strain, the root of dW/dt = 0 (S33 = 0) in plane stress.
  double log_stretch33(double n, double j) const;

  double energy_density(const Mat2& F) const;
  Mat2 first_piola(const Mat2& F) const;
  void first_piola_and_tangent(const Mat2& F, Mat2& P, Eigen::Matrix4d& A) const;
  Eigen::Matrix4d tangent(const Mat2& F) const;
  OutOfPlane out_of_plane(const Mat2& F) const;
  double wave_speed() const;
};

using Material = std::variant<StVenantKirchhoff, NeoHookean, BlatzKo, MooneyRivlin>;

double material_density(const Material& m);
double material_wave_speed(const Material& m);
// A = dP/dF of the material at F, indexed A(2*i + J, 2*k + L) = dP_iJ / dF_kL [Pa].
Eigen::Matrix4d material_tangent(const Material& m, const Mat2& F);

// The von Mises equivalent of the full 3D stress state at F, of `measure` (stress.hpp: the one
// formula the force pass and the fields use) [Pa].
double von_mises(const Material& m, const Mat2& F, StressMeasure measure = StressMeasure::cauchy);

}  // namespace ricochet
