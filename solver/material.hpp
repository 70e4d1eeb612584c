// Hyperelastic materials behind one contract, chosen once per element block via std::variant:
//   double energy_density(F)   W(F), strain energy per unit reference volume [J/m^3]
//   Mat2   first_piola(F)      P = dW/dF, in-plane block of the first Piola-Kirchhoff stress [Pa]
//   OutOfPlane out_of_plane(F) the out-of-plane stretch F33 [-] and 2nd Piola-Kirchhoff S33 [Pa]
//   double wave_speed()        small-strain in-plane dilatational wave speed c_p [m/s]
//   double density             reference mass density rho [kg/m^3]
// F is the in-plane 2x2 deformation gradient. Plane strain fixes F33 = 1; plane stress
// eliminates F33 by S33 = 0, so W and P are the reduced 2D functions (P stays exactly dW/dF).
#pragma once

#include <cmath>
#include <variant>

#include "solver/types.hpp"

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
  OutOfPlane out_of_plane(const Mat2& F) const;
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
  OutOfPlane out_of_plane(const Mat2& F) const;
  double wave_speed() const;
};

using Material = std::variant<StVenantKirchhoff, NeoHookean>;

double material_density(const Material& m);
double material_wave_speed(const Material& m);

// Cauchy stress of the in-plane F and the von Mises equivalent of the full 3D state [Pa].
double von_mises(const Material& m, const Mat2& F);

}  // namespace ricochet
