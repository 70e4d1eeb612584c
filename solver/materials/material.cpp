#include "solver/materials/material.hpp"

#include <cmath>

namespace ricochet {

Lame lame_from_young_poisson(double young, double poisson) {
  return {young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson)),
          young / (2.0 * (1.0 + poisson))};
}

StVenantKirchhoff StVenantKirchhoff::make(double young, double poisson, double density,
                                          PlaneMode plane) {
  const Lame l = lame_from_young_poisson(young, poisson);
  StVenantKirchhoff m;
  m.lambda_3d = l.lambda;
  m.shear_modulus = l.shear_modulus;
  m.e33_per_trace = -l.lambda / (l.lambda + 2.0 * l.shear_modulus);
  m.lambda = plane == PlaneMode::stress
                 ? 2.0 * l.lambda * l.shear_modulus / (l.lambda + 2.0 * l.shear_modulus)
                 : l.lambda;
  m.density = density;
  m.plane = plane;
  return m;
}

NeoHookean NeoHookean::make(double young, double poisson, double density, PlaneMode plane) {
  const Lame l = lame_from_young_poisson(young, poisson);
  return {l.lambda, l.shear_modulus, density, plane};
}

double NeoHookean::log_c33(double log_j2) const {
  if (plane == PlaneMode::strain) return 0.0;
  // S33 = 0  <=>  h(s) = mu (e^s - 1) + lambda (log_j2 + s/2) = 0, s = ln C33; h' > 0, h'' > 0.
  const double mu = shear_modulus;
  double s = -lambda * log_j2 / (mu + 0.5 * lambda);
  for (int it = 0; it < 30; ++it) {
    const double es = std::exp(s);
    const double h = mu * (es - 1.0) + lambda * (log_j2 + 0.5 * s);
    const double ds = h / (mu * es + 0.5 * lambda);
    s -= ds;
    if (std::abs(ds) < 1e-15 * (1.0 + std::abs(s))) break;
  }
  return s;
}

OutOfPlane NeoHookean::out_of_plane(const Mat2& F) const {
  const double log_j2 = std::log(F.determinant());
  if (plane == PlaneMode::strain) return {1.0, lambda * log_j2};
  return {std::exp(0.5 * log_c33(log_j2)), 0.0};
}

double NeoHookean::wave_speed() const {
  const double lam = plane == PlaneMode::stress
                         ? 2.0 * lambda * shear_modulus / (lambda + 2.0 * shear_modulus)
                         : lambda;
  return std::sqrt((lam + 2.0 * shear_modulus) / density);
}

void invariant_piola_and_tangent(const Mat2& F, const InvariantDerivatives& d, Mat2& P,
                                 Eigen::Matrix4d& A) {
  const Eigen::Vector4d f(F(0, 0), F(0, 1), F(1, 0), F(1, 1));
  const Eigen::Vector4d k(F(1, 1), -F(1, 0), -F(0, 1), F(0, 0));  // vec cof F
  P(0, 0) = 2.0 * d.wn * f[0] + d.wj * k[0];
  P(0, 1) = 2.0 * d.wn * f[1] + d.wj * k[1];
  P(1, 0) = 2.0 * d.wn * f[2] + d.wj * k[2];
  P(1, 1) = 2.0 * d.wn * f[3] + d.wj * k[3];
  const Eigen::Matrix4d fk = f * k.transpose();
  A.noalias() = (4.0 * d.wnn) * (f * f.transpose()) + (2.0 * d.wnj) * (fk + fk.transpose()) +
                d.wjj * (k * k.transpose());
  A.diagonal().array() += 2.0 * d.wn;
  A(0, 3) += d.wj;
  A(3, 0) += d.wj;
  A(1, 2) -= d.wj;
  A(2, 1) -= d.wj;
}

namespace {

double plane_wave_speed(double lambda, double mu, double density, PlaneMode plane) {
  const double lam = plane == PlaneMode::stress ? 2.0 * lambda * mu / (lambda + 2.0 * mu) : lambda;
  return std::sqrt((lam + 2.0 * mu) / density);
}

}  // namespace

// ---------------------------------------------------------------------------------- Blatz-Ko

BlatzKo BlatzKo::make(double shear_modulus, double density, PlaneMode plane) {
  return {shear_modulus, shear_modulus, density, plane};
}

InvariantDerivatives BlatzKo::derivatives(const Mat2& F) const {
  // W = mu/2 (n/j^2 + g(j) - k): plane strain g = 2 j, k = 4; plane stress g = 3 j^(2/3), k = 5.
  const double mu = shear_modulus;
  const double n = F.squaredNorm(), j = F.determinant();
  const double ij = 1.0 / j, ij2 = ij * ij, ij3 = ij2 * ij;
  InvariantDerivatives d;
  d.wn = 0.5 * mu * ij2;
  d.wnj = -mu * ij3;
  d.wjj = 3.0 * mu * n * ij3 * ij;
  if (plane == PlaneMode::stress) {
    const double jm13 = 1.0 / std::cbrt(j);  // g'/2 = j^(-1/3), g''/2 = -j^(-4/3)/3
    d.wj = mu * (jm13 - n * ij3);
    d.wjj -= mu * jm13 * ij / 3.0;
  } else {
    d.wj = mu * (1.0 - n * ij3);
  }
  return d;
}

double BlatzKo::energy_density(const Mat2& F) const {
  const double n = F.squaredNorm(), j = F.determinant();
  if (plane == PlaneMode::stress) {
    const double cj = std::cbrt(j);
    return 0.5 * shear_modulus * (n / (j * j) + 3.0 * cj * cj - 5.0);
  }
  return 0.5 * shear_modulus * (n / (j * j) + 2.0 * j - 4.0);
}

Mat2 BlatzKo::first_piola(const Mat2& F) const {
  Mat2 P;
  Eigen::Matrix4d A;
  first_piola_and_tangent(F, P, A);
  return P;
}

void BlatzKo::first_piola_and_tangent(const Mat2& F, Mat2& P, Eigen::Matrix4d& A) const {
  invariant_piola_and_tangent(F, derivatives(F), P, A);
}

Eigen::Matrix4d BlatzKo::tangent(const Mat2& F) const {
  Mat2 P;
  Eigen::Matrix4d A;
  first_piola_and_tangent(F, P, A);
  return A;
}

OutOfPlane BlatzKo::out_of_plane(const Mat2& F) const {
  const double j = F.determinant();
  // S33 = mu (J / C33 - 1 / C33^2); plane strain C33 = 1, J = j.
  if (plane == PlaneMode::strain) return {1.0, shear_modulus * (j - 1.0)};
  return {1.0 / std::cbrt(j), 0.0};  // C33 = j^(-2/3)
}

double BlatzKo::wave_speed() const {
  return plane_wave_speed(lambda, shear_modulus, density, plane);
}

// ------------------------------------------------------------------------------ Mooney-Rivlin

MooneyRivlin MooneyRivlin::make(double c10, double c01, double bulk_modulus, double density,
                                PlaneMode plane) {
  MooneyRivlin m;
  m.c10 = c10;
  m.c01 = c01;
  m.bulk_modulus = bulk_modulus;
  m.shear_modulus = 2.0 * (c10 + c01);
  m.lambda = bulk_modulus - 2.0 * m.shear_modulus / 3.0;
  m.density = density;
  m.plane = plane;
  return m;
}

// With lambda3 = F33 = e^t: J = j e^t, I1 = n + e^2t, I2 = j^2 + n e^2t, so W is a sum of
// monomials in (n, j, e^t):
//   m1 = c10 n j^(-2/3) e^(-2t/3), m2 = c10 j^(-2/3) e^(4t/3),
//   m3 = c01 j^(2/3) e^(-4t/3),    m4 = c01 n j^(-4/3) e^(2t/3),
// plus kappa/2 (J - 1)^2 - 3 (c10 + c01).
MooneyRivlin::Terms MooneyRivlin::terms(double n, double j, double t) const {
  const double cj = std::cbrt(j), j23 = cj * cj, jm23 = 1.0 / j23, jm43 = jm23 * jm23;
  const double e = t == 0.0 ? 1.0 : std::exp(t / 3.0), e2 = e * e, e4 = e2 * e2;
  const double q1 = c10 * jm23 / e2, q4 = c01 * jm43 * e2;
  const double m1 = n * q1, m2 = c10 * jm23 * e4, m3 = c01 * j23 / e4, m4 = n * q4;
  const double J = j * e2 * e, k = bulk_modulus;
  const double vj = k * (J - 1.0) * J;           // J dVol/dJ
  const double vjj = k * (2.0 * J - 1.0) * J;    // J d(J dVol/dJ)/dJ
  const double ij = 1.0 / j;
  Terms r;
  r.w = (m1 + m2) + (m3 + m4) - 3.0 * (c10 + c01) + 0.5 * k * (J - 1.0) * (J - 1.0);
  r.wn = q1 + q4;
  r.wnj = (-2.0 / 3.0 * q1 - 4.0 / 3.0 * q4) * ij;
  r.wnt = 2.0 / 3.0 * (q4 - q1);
  r.wj = (-2.0 / 3.0 * (m1 + m2) + 2.0 / 3.0 * m3 - 4.0 / 3.0 * m4 + vj) * ij;
  r.wjj = (10.0 / 9.0 * (m1 + m2) - 2.0 / 9.0 * m3 + 28.0 / 9.0 * m4 + k * J * J) * ij * ij;
  r.wjt = (4.0 / 9.0 * m1 - 8.0 / 9.0 * (m2 + m3 + m4) + vjj) * ij;
  r.wt = -2.0 / 3.0 * m1 + 4.0 / 3.0 * m2 - 4.0 / 3.0 * m3 + 2.0 / 3.0 * m4 + vj;
  r.wtt = 4.0 / 9.0 * (m1 + m4) + 16.0 / 9.0 * (m2 + m3) + vjj;
  return r;
}

double MooneyRivlin::log_stretch33(double n, double j) const {
  if (plane == PlaneMode::strain) return 0.0;
  // dW/dt = 0, bracketed Newton: dW/dt -> -inf as t -> -inf (c10 + c01 > 0) and +inf as
  // t -> +inf (kappa > 0). Start from the small-strain solution t = -lambda/(lambda+2mu) ln j.
  const double cj = std::cbrt(j), j23 = cj * cj, jm23 = 1.0 / j23, jm43 = jm23 * jm23;
  const double k = bulk_modulus;
  const double a1 = c10 * n * jm23, a2 = c10 * jm23, a3 = c01 * j23, a4 = c01 * n * jm43;
  double t = -lambda * std::log(j) / (lambda + 2.0 * shear_modulus);
  double lo = -40.0, hi = 40.0;
  for (int it = 0; it < 200; ++it) {
    const double e = std::exp(t / 3.0), e2 = e * e, e4 = e2 * e2;
    const double m1 = a1 / e2, m2 = a2 * e4, m3 = a3 / e4, m4 = a4 * e2;
    const double J = j * e2 * e;
    const double g = -2.0 / 3.0 * m1 + 4.0 / 3.0 * m2 - 4.0 / 3.0 * m3 + 2.0 / 3.0 * m4 +
                     k * (J - 1.0) * J;
    const double gp = 4.0 / 9.0 * (m1 + m4) + 16.0 / 9.0 * (m2 + m3) + k * (2.0 * J - 1.0) * J;
    if (g == 0.0) break;
    (g < 0.0 ? lo : hi) = t;
    double tn = t - g / gp;
    if (!(gp > 0.0) || !(tn > lo && tn < hi)) tn = 0.5 * (lo + hi);
    const double step = tn - t;
    t = tn;
    if (std::abs(step) < 1e-15 * (1.0 + std::abs(t)) || hi - lo < 1e-15 * (1.0 + std::abs(t)))
      break;
  }
  return t;
}

double MooneyRivlin::energy_density(const Mat2& F) const {
  const double n = F.squaredNorm(), j = F.determinant();
  return terms(n, j, log_stretch33(n, j)).w;
}

Mat2 MooneyRivlin::first_piola(const Mat2& F) const {
  const double n = F.squaredNorm(), j = F.determinant();
  const Terms r = terms(n, j, log_stretch33(n, j));
  Mat2 P;
  P << 2.0 * r.wn * F(0, 0) + r.wj * F(1, 1), 2.0 * r.wn * F(0, 1) - r.wj * F(1, 0),
      2.0 * r.wn * F(1, 0) - r.wj * F(0, 1), 2.0 * r.wn * F(1, 1) + r.wj * F(0, 0);
  return P;
}

void MooneyRivlin::first_piola_and_tangent(const Mat2& F, Mat2& P, Eigen::Matrix4d& A) const {
  const double n = F.squaredNorm(), j = F.determinant();
  const Terms r = terms(n, j, log_stretch33(n, j));
  InvariantDerivatives d{r.wn, r.wj, 0.0, r.wnj, r.wjj};
  if (plane == PlaneMode::stress) {
    // t(n, j) from W_t = 0: the reduced second derivatives are Schur complements.
    const double it = 1.0 / r.wtt;
    d.wnn -= r.wnt * r.wnt * it;
    d.wnj -= r.wnt * r.wjt * it;
    d.wjj -= r.wjt * r.wjt * it;
  }
  invariant_piola_and_tangent(F, d, P, A);
}

Eigen::Matrix4d MooneyRivlin::tangent(const Mat2& F) const {
  Mat2 P;
  Eigen::Matrix4d A;
  first_piola_and_tangent(F, P, A);
  return A;
}

OutOfPlane MooneyRivlin::out_of_plane(const Mat2& F) const {
  const double n = F.squaredNorm(), j = F.determinant();
  if (plane == PlaneMode::strain) return {1.0, terms(n, j, 0.0).wt};  // S33 = W_t / C33
  return {std::exp(log_stretch33(n, j)), 0.0};
}

double MooneyRivlin::wave_speed() const {
  return plane_wave_speed(lambda, shear_modulus, density, plane);
}

double material_density(const Material& m) {
  return std::visit([](const auto& x) { return x.density; }, m);
}

double material_wave_speed(const Material& m) {
  return std::visit([](const auto& x) { return x.wave_speed(); }, m);
}

Eigen::Matrix4d material_tangent(const Material& m, const Mat2& F) {
  return std::visit([&F](const auto& x) { return x.tangent(F); }, m);
}

double von_mises(const Material& m, const Mat2& F, StressMeasure measure) {
  return std::visit(
      [&](const auto& mat) {
        return std::sqrt(von_mises_ratio(mat, F, mat.first_piola(F), F.determinant(), measure).value());
      },
      m);
}

}  // namespace ricochet
