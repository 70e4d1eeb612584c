#include "solver/material.hpp"

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
  m.lambda = plane == PlaneMode::stress
                 ? 2.0 * l.lambda * l.shear_modulus / (l.lambda + 2.0 * l.shear_modulus)
                 : l.lambda;
  m.density = density;
  m.plane = plane;
  return m;
}

OutOfPlane StVenantKirchhoff::out_of_plane(const Mat2& F) const {
  const double tr = 0.5 * (F.squaredNorm() - 2.0);  // tr E (in-plane)
  if (plane == PlaneMode::strain) return {1.0, lambda_3d * tr};
  // S33 = lambda3 (tr + E33) + 2 mu E33 = 0.
  const double e33 = -lambda_3d * tr / (lambda_3d + 2.0 * shear_modulus);
  return {std::sqrt(1.0 + 2.0 * e33), 0.0};
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

double material_density(const Material& m) {
  return std::visit([](const auto& x) { return x.density; }, m);
}

double material_wave_speed(const Material& m) {
  return std::visit([](const auto& x) { return x.wave_speed(); }, m);
}

Eigen::Matrix4d material_tangent(const Material& m, const Mat2& F) {
  return std::visit([&F](const auto& x) { return x.tangent(F); }, m);
}

double von_mises(const Material& m, const Mat2& F) {
  return std::visit(
      [&F](const auto& mat) {
        const Mat2 P = mat.first_piola(F);
        const OutOfPlane o = mat.out_of_plane(F);
        const double j = F.determinant() * o.stretch;
        const Mat2 s = P * F.transpose() / j;  // in-plane Cauchy stress
        const double s33 = o.stretch * o.stretch * o.pk2 / j;
        const double d1 = s(0, 0) - s(1, 1), d2 = s(1, 1) - s33, d3 = s33 - s(0, 0);
        const double shear = 0.5 * (s(0, 1) + s(1, 0));
        return std::sqrt(0.5 * (d1 * d1 + d2 * d2 + d3 * d3) + 3.0 * shear * shear);
      },
      m);
}

}  // namespace ricochet
