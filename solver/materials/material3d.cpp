#include "solver/materials/material3d.hpp"

#include <cmath>

#include "solver/materials/material.hpp"  // lame_from_young_poisson
#include "solver/materials/stress.hpp"    // adjugate

namespace ricochet {

namespace {

// cof F = J F^-T, the transpose of stress.hpp's adjugate.
Mat3 cofactor(const Mat3& F) { return adjugate(F).transpose(); }

// det F by the first row of F and of its cofactor matrix.
double determinant(const Mat3& F, const Mat3& H) {
  return F(0, 0) * H(0, 0) + F(0, 1) * H(0, 1) + F(0, 2) * H(0, 2);
}

// The St Venant-Kirchhoff S = lambda tr(E) I + 2 mu E.
Mat3 svk_pk2(const Mat3& F, double lambda, double mu) {
  const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
  Mat3 S = (2.0 * mu) * E;
  S.diagonal().array() += lambda * E.trace();
  return S;
}

// Kronecker delta as a double.
constexpr double delta(int a, int b) { return a == b ? 1.0 : 0.0; }

}  // namespace

// ------------------------------------------------------------------- St Venant-Kirchhoff

StVenantKirchhoff3 StVenantKirchhoff3::make(double young, double poisson, double density) {
  const Lame l = lame_from_young_poisson(young, poisson);
  return {l.lambda, l.shear_modulus, density};
}

double StVenantKirchhoff3::energy_density(const Mat3& F) const {
  const Mat3 E = 0.5 * (F.transpose() * F - Mat3::Identity());
  const double tr = E.trace();
  return 0.5 * lambda * tr * tr + shear_modulus * E.squaredNorm();
}

Mat3 StVenantKirchhoff3::first_piola(const Mat3& F) const {
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> f = F;
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> p;
  svk_first_piola3<1>(lambda, shear_modulus, f.data(), p.data());
  return p;
}

void StVenantKirchhoff3::first_piola_and_tangent(const Mat3& F, Mat3& P, Mat9& A) const {
  const double mu = shear_modulus;
  const Mat3 S = svk_pk2(F, lambda, mu);
  P = first_piola(F);  // the same bits as first_piola()'s (S above is for A)
  const Mat3 b = F * F.transpose();
  // A(iJ, kL) = delta_ik S_JL + lambda F_iJ F_kL + mu (F_iL F_kJ + b_ik delta_JL).
  for (int i = 0; i < 3; ++i)
    for (int J = 0; J < 3; ++J)
      for (int k = 0; k < 3; ++k)
        for (int L = 0; L < 3; ++L)
          A(3 * i + J, 3 * k + L) = delta(i, k) * S(J, L) + lambda * F(i, J) * F(k, L) +
                                    mu * (F(i, L) * F(k, J) + b(i, k) * delta(J, L));
}

// ---------------------------------------------------------------------------- neo-Hookean

NeoHookean3 NeoHookean3::make(double young, double poisson, double density) {
  const Lame l = lame_from_young_poisson(young, poisson);
  return {l.lambda, l.shear_modulus, density};
}

double NeoHookean3::energy_density(const Mat3& F) const {
  const double log_j = std::log(determinant(F, cofactor(F)));
  const double mu = shear_modulus;
  return 0.5 * mu * (F.squaredNorm() - 3.0) - mu * log_j + 0.5 * lambda * log_j * log_j;
}

Mat3 NeoHookean3::first_piola(const Mat3& F) const {
  const Mat3 H = cofactor(F);
  const double j = determinant(F, H);
  // P = mu F + (lambda ln J - mu) G with G = H / J.
  return shear_modulus * F + ((lambda * std::log(j) - shear_modulus) / j) * H;
}

void NeoHookean3::first_piola_and_tangent(const Mat3& F, Mat3& P, Mat9& A) const {
  const double mu = shear_modulus;
  const Mat3 H = cofactor(F);
  const double j = determinant(F, H);
  const double beta = lambda * std::log(j) - mu;
  P = mu * F + (beta / j) * H;  // the expression of first_piola()
  const Mat3 G = H / j;
  // A(iJ, kL) = mu delta_ik delta_JL + lambda G_iJ G_kL - beta G_iL G_kJ.
  for (int i = 0; i < 3; ++i)
    for (int J = 0; J < 3; ++J)
      for (int k = 0; k < 3; ++k)
        for (int L = 0; L < 3; ++L)
          A(3 * i + J, 3 * k + L) = mu * delta(i, k) * delta(J, L) + lambda * G(i, J) * G(k, L) -
                                    beta * G(i, L) * G(k, J);
}

// ---------------------------------------------------------------------------------- Blatz-Ko

BlatzKo3 BlatzKo3::make(double shear_modulus, double density) {
  return {shear_modulus, shear_modulus, density};
}

double BlatzKo3::energy_density(const Mat3& F) const {
  const Mat3 H = cofactor(F);
  const double j = determinant(F, H);
  // tr C^-1 = |G|^2 = |H|^2 / J^2.
  return 0.5 * shear_modulus * (H.squaredNorm() / (j * j) + 2.0 * j - 5.0);
}

Mat3 BlatzKo3::first_piola(const Mat3& F) const {
  const Mat3 H = cofactor(F);
  const Mat3 G = H / determinant(F, H);
  // P = mu (J G - G G^T G), J G = H.
  return shear_modulus * (H - G * (G.transpose() * G));
}

void BlatzKo3::first_piola_and_tangent(const Mat3& F, Mat3& P, Mat9& A) const {
  const double mu = shear_modulus;
  const Mat3 H = cofactor(F);
  const double j = determinant(F, H);
  const Mat3 G = H / j;
  const Mat3 gtg = G.transpose() * G;  // C^-1
  const Mat3 M = G * gtg;              // G G^T G
  P = mu * (H - M);                    // the expression of first_piola()
  const Mat3 ggt = G * G.transpose();  // b^-1
  // A(iJ, kL) = mu [J (G_iJ G_kL - G_iL G_kJ) + G_iL M_kJ + M_iL G_kJ + (G G^T)_ik (G^T G)_JL].
  for (int i = 0; i < 3; ++i)
    for (int J = 0; J < 3; ++J)
      for (int k = 0; k < 3; ++k)
        for (int L = 0; L < 3; ++L)
          A(3 * i + J, 3 * k + L) =
              mu * (j * (G(i, J) * G(k, L) - G(i, L) * G(k, J)) + G(i, L) * M(k, J) +
                    M(i, L) * G(k, J) + ggt(i, k) * gtg(J, L));
}

// ------------------------------------------------------------------ invariants (I1, I2, J)

namespace {

// (I1, I2, J) and cof F of one F.
struct Invariants3 {
  Mat3 H;
  double i1, i2, j;
};

Invariants3 invariants3(const Mat3& F) {
  Invariants3 v;
  v.H = cofactor(F);
  v.i1 = F.squaredNorm();
  v.i2 = v.H.squaredNorm();  // I2 of C = tr cof C = |cof F|^2
  v.j = determinant(F, v.H);
  return v;
}

// P = W_1 2 F + W_2 2 (I1 F - F C) + W_J H; fc = F C.
Mat3 invariant_piola(const Mat3& F, const Invariants3& v, const Mat3& fc,
                     const InvariantDerivatives3& d) {
  return (2.0 * d.w1) * F + (2.0 * d.w2) * (v.i1 * F - fc) + d.wj * v.H;
}

Mat3 invariant_piola_and_tangent(const Mat3& F, const Invariants3& v,
                                 const InvariantDerivatives3& d, Mat9& A) {
  const Mat3 C = F.transpose() * F;
  const Mat3 b = F * F.transpose();
  const Mat3 fc = F * C;
  const Mat3 g1 = 2.0 * F;
  const Mat3 g2 = 2.0 * (v.i1 * F - fc);
  const Mat3& gj = v.H;
  const double ij = 1.0 / v.j;
  for (int i = 0; i < 3; ++i)
    for (int J = 0; J < 3; ++J)
      for (int k = 0; k < 3; ++k)
        for (int L = 0; L < 3; ++L) {
          const double dd = delta(i, k) * delta(J, L);
          const double d2i1 = 2.0 * dd;
          const double d2i2 = 2.0 * (2.0 * F(i, J) * F(k, L) + v.i1 * dd - delta(i, k) * C(J, L) -
                                     b(i, k) * delta(J, L) - F(i, L) * F(k, J));
          const double d2j = (v.H(i, J) * v.H(k, L) - v.H(i, L) * v.H(k, J)) * ij;
          A(3 * i + J, 3 * k + L) =
              d.w1 * d2i1 + d.w2 * d2i2 + d.wj * d2j + d.w11 * g1(i, J) * g1(k, L) +
              d.w22 * g2(i, J) * g2(k, L) + d.wjj * gj(i, J) * gj(k, L) +
              d.w12 * (g1(i, J) * g2(k, L) + g2(i, J) * g1(k, L)) +
              d.w1j * (g1(i, J) * gj(k, L) + gj(i, J) * g1(k, L)) +
              d.w2j * (g2(i, J) * gj(k, L) + gj(i, J) * g2(k, L));
        }
  return invariant_piola(F, v, fc, d);
}

}  // namespace

Mat3 invariant_piola3(const Mat3& F, const InvariantDerivatives3& d) {
  const Mat3 fc = F * (F.transpose() * F);
  return invariant_piola(F, invariants3(F), fc, d);
}

void invariant_piola_and_tangent3(const Mat3& F, const InvariantDerivatives3& d, Mat3& P,
                                  Mat9& A) {
  P = invariant_piola_and_tangent(F, invariants3(F), d, A);
}

// ----------------------------------------------------------------------------- Mooney-Rivlin

MooneyRivlin3 MooneyRivlin3::make(double c10, double c01, double bulk_modulus, double density) {
  MooneyRivlin3 m;
  m.c10 = c10;
  m.c01 = c01;
  m.bulk_modulus = bulk_modulus;
  m.shear_modulus = 2.0 * (c10 + c01);
  m.lambda = bulk_modulus - 2.0 * m.shear_modulus / 3.0;
  m.density = density;
  return m;
}

InvariantDerivatives3 MooneyRivlin3::derivatives(double i1, double i2, double j) const {
  const double jm13 = 1.0 / std::cbrt(j), jm23 = jm13 * jm13, jm43 = jm23 * jm23;
  const double ij = 1.0 / j;
  const double a1 = c10 * jm23, a2 = c01 * jm43;  // W_1, W_2
  InvariantDerivatives3 d;
  d.w1 = a1;
  d.w2 = a2;
  d.wj = (-2.0 / 3.0 * a1 * i1 - 4.0 / 3.0 * a2 * i2) * ij + bulk_modulus * (j - 1.0);
  d.w1j = -2.0 / 3.0 * a1 * ij;
  d.w2j = -4.0 / 3.0 * a2 * ij;
  d.wjj = (10.0 / 9.0 * a1 * i1 + 28.0 / 9.0 * a2 * i2) * ij * ij + bulk_modulus;
  return d;
}

double MooneyRivlin3::energy_density(const Mat3& F) const {
  const Invariants3 v = invariants3(F);
  const double jm13 = 1.0 / std::cbrt(v.j), jm23 = jm13 * jm13, jm43 = jm23 * jm23;
  return c10 * (jm23 * v.i1 - 3.0) + c01 * (jm43 * v.i2 - 3.0) +
         0.5 * bulk_modulus * (v.j - 1.0) * (v.j - 1.0);
}

Mat3 MooneyRivlin3::first_piola(const Mat3& F) const {
  const Invariants3 v = invariants3(F);
  const Mat3 fc = F * (F.transpose() * F);
  return invariant_piola(F, v, fc, derivatives(v.i1, v.i2, v.j));
}

void MooneyRivlin3::first_piola_and_tangent(const Mat3& F, Mat3& P, Mat9& A) const {
  const Invariants3 v = invariants3(F);
  P = invariant_piola_and_tangent(F, v, derivatives(v.i1, v.i2, v.j), A);
}

// ------------------------------------------------------------------------------ the variant

double material_density(const Material3& m) {
  return std::visit([](const auto& x) { return x.density; }, m);
}

double material_wave_speed(const Material3& m) {
  return std::visit([](const auto& x) { return x.wave_speed(); }, m);
}

Mat9 material_tangent(const Material3& m, const Mat3& F) {
  return std::visit(
      [&F](const auto& x) {
        Mat3 P;
        Mat9 A;
        x.first_piola_and_tangent(F, P, A);
        return A;
      },
      m);
}

}  // namespace ricochet
