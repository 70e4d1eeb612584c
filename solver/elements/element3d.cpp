#include "solver/elements/element3d.hpp"

#include <algorithm>
#include <cmath>

namespace ricochet {
namespace {

// dN_a/dxi of the trilinear hexahedron at (xi, eta, zeta), N_a = (1 + s_a0 xi)(1 + s_a1 eta)
// (1 + s_a2 zeta) / 8 with the corner signs s_a = kHexCornerSigns[a]. Rows = corners.
Hex8Grad hex8_dn_dxi(double xi, double eta, double zeta) {
  Hex8Grad d;
  for (int a = 0; a < 8; ++a) {
    const double s0 = kHexCornerSigns[a][0], s1 = kHexCornerSigns[a][1], s2 = kHexCornerSigns[a][2];
    const double l0 = 1.0 + s0 * xi, l1 = 1.0 + s1 * eta, l2 = 1.0 + s2 * zeta;
    d(a, 0) = 0.125 * s0 * l1 * l2;
    d(a, 1) = 0.125 * s1 * l0 * l2;
    d(a, 2) = 0.125 * s2 * l0 * l1;
  }
  return d;
}

double hex8_shape(int a, double xi, double eta, double zeta) {
  return 0.125 * (1.0 + kHexCornerSigns[a][0] * xi) * (1.0 + kHexCornerSigns[a][1] * eta) *
         (1.0 + kHexCornerSigns[a][2] * zeta);
}

// Gauss point q of the 2x2x2 rule: the corner signs of corner q over sqrt 3.
Vec3 hex8_gauss_point(int q) {
  const double g = 1.0 / std::sqrt(3.0);
  return Vec3(g * kHexCornerSigns[q][0], g * kHexCornerSigns[q][1], g * kHexCornerSigns[q][2]);
}

// Mean gradients B = (1/V) sum_q vol_q dN/dX(q) and V = sum_q vol_q from the 2x2x2 geometry.
// Exact: int dN/dX dV = int dN/dxi adj(J) dxi, whose integrand is at most quadratic in each
// reference coordinate (adj J holds products of two columns of J, each free of its own
// coordinate), and the 2-point rule integrates cubics exactly. So V B_I = b_I = dV/dX_I, the
// Flanagan-Belytschko b of the exact volume.
void hex8_mean_gradients(const Hex8Geom& full, Hex8Grad& b_mean, double& volume) {
  b_mean.setZero();
  volume = 0.0;
  for (int q = 0; q < 8; ++q) {
    b_mean += full.vol[q] * full.dndx[q];
    volume += full.vol[q];
  }
  b_mean /= volume;
}

}  // namespace

Mat3 hex8_jacobian(const Hex8Nodes& x, int q) {
  const Vec3 p = hex8_gauss_point(q);
  return x * hex8_dn_dxi(p.x(), p.y(), p.z());
}

bool hex8_geometry(const Hex8Nodes& x, Hex8Geom& g) {
  for (int q = 0; q < 8; ++q) {
    const Vec3 p = hex8_gauss_point(q);
    const Hex8Grad dxi = hex8_dn_dxi(p.x(), p.y(), p.z());
    const Mat3 jac = x * dxi;  // J(i, j) = dX_i / dxi_j
    const double det = jac.determinant();
    if (!(det > 0.0) || !std::isfinite(det)) return false;
    g.dndx[q] = dxi * jac.inverse();
    g.vol[q] = det;  // Gauss weight 1
  }
  return true;
}

Hex8Hourglass hex8_hourglass_base() {
  Hex8Hourglass h;
  for (int a = 0; a < 8; ++a) {
    const double s0 = kHexCornerSigns[a][0], s1 = kHexCornerSigns[a][1], s2 = kHexCornerSigns[a][2];
    h(a, 0) = s1 * s2;
    h(a, 1) = s0 * s2;
    h(a, 2) = s0 * s1;
    h(a, 3) = s0 * s1 * s2;
  }
  return h;
}

bool hex8_one_point_geometry(const Hex8Nodes& x, const Material3& material, const HourglassControl& hourglass,
                             Hex8OnePointGeom& g) {
  Hex8Geom full;
  if (!hex8_geometry(x, full)) return false;
  hex8_mean_gradients(full, g.dndx, g.vol);
  // gamma_alpha = (h_alpha - B (X h_alpha)) / 8: B_i . X_j = delta_ij (the mean gradient of a
  // linear field is its gradient) and sum_I B_iI = 0, so gamma_alpha . X_j = 0 and
  // gamma_alpha . 1 = 0 (h_alpha . 1 = 0): no hourglass force from rigid or linear fields.
  const Hex8Hourglass h = hex8_hourglass_base();
  g.gamma = 0.125 * (h - g.dndx * (x * h));
  const double rho = material_density(material);
  const double cp = material_wave_speed(material);
  g.form = hourglass.form;
  g.hourglass_coeff = hourglass.form == HourglassForm::viscous
                          ? hourglass.coeff * rho * cp * std::cbrt(g.vol * g.vol)
                          : hourglass.coeff * rho * cp * cp * g.vol * g.dndx.squaredNorm() / 2.0;
  return true;
}

Hex8Matrix hex8_hourglass_matrix(const Hex8OnePointGeom& g) {
  const Eigen::Matrix<double, 8, 8> gg = g.hourglass_coeff * (g.gamma * g.gamma.transpose());
  Hex8Matrix H = Hex8Matrix::Zero();
  for (int a = 0; a < 8; ++a)
    for (int b = 0; b < 8; ++b)
      for (int i = 0; i < 3; ++i) H(3 * a + i, 3 * b + i) = gg(a, b);
  return H;
}

bool tet4_geometry(const Tet4Nodes& x, Tet4Geom& g) {
  Mat3 jac;
  jac.col(0) = x.col(1) - x.col(0);
  jac.col(1) = x.col(2) - x.col(0);
  jac.col(2) = x.col(3) - x.col(0);
  const double det = jac.determinant();
  if (!(det > 0.0) || !std::isfinite(det)) return false;
  Tet4Grad dxi;
  dxi << -1, -1, -1,  //
      1, 0, 0,        //
      0, 1, 0,        //
      0, 0, 1;
  g.dndx = dxi * jac.inverse();
  g.vol = det / 6.0;
  return true;
}

Eigen::Matrix<double, 8, 1> hex8_lumped_masses(const Hex8Nodes& x, double density) {
  Eigen::Matrix<double, 8, 1> m = Eigen::Matrix<double, 8, 1>::Zero();
  for (int q = 0; q < 8; ++q) {
    const Vec3 p = hex8_gauss_point(q);
    const double det = (x * hex8_dn_dxi(p.x(), p.y(), p.z())).determinant();
    for (int a = 0; a < 8; ++a) m(a) += density * det * hex8_shape(a, p.x(), p.y(), p.z());
  }
  return m;
}

Eigen::Vector4d tet4_lumped_masses(const Tet4Nodes& x, double density) {
  Mat3 jac;
  jac.col(0) = x.col(1) - x.col(0);
  jac.col(1) = x.col(2) - x.col(0);
  jac.col(2) = x.col(3) - x.col(0);
  return Eigen::Vector4d::Constant(density * jac.determinant() / 24.0);
}

double hex8_characteristic_length(const Hex8Nodes& x) {
  Hex8Geom full;
  if (!hex8_geometry(x, full)) return 0.0;
  Hex8Grad b_mean;
  double volume = 0.0;
  hex8_mean_gradients(full, b_mean, volume);
  // The smallest row-sum mass over rho: min_a sum_q vol_q N_a(q) (hex8_lumped_masses / rho).
  double m_min = 1e300;
  for (int a = 0; a < 8; ++a) {
    double m = 0.0;
    for (int q = 0; q < 8; ++q) {
      const Vec3 p = hex8_gauss_point(q);
      m += full.vol[q] * hex8_shape(a, p.x(), p.y(), p.z());
    }
    m_min = std::min(m_min, m);
  }
  // u^T K u <= V (lambda + 2 mu) (B:B) |u|^2 for the one-point element (lambda >= 0) and
  // u^T M u >= m_min |u|^2, so omega_max^2 <= rho c_p^2 V (B:B) / m_min and
  // Delta t = 2 / omega_max >= L_e / c_p with L_e = 2 sqrt(m_min / (rho V) / (B:B)); with equal
  // masses rho V / 8 this is Flanagan and Belytschko's 1 / sqrt(2 B:B).
  return 2.0 * std::sqrt(m_min / volume / b_mean.squaredNorm());
}

double tet4_characteristic_length(const Tet4Nodes& x) {
  Tet4Geom g;
  if (!tet4_geometry(x, g)) return 0.0;
  // omega_max^2 <= 4 c_p^2 sum_I |dN_I/dX|^2 (lumped masses rho V / 4), Delta t = 2 / omega_max.
  return 1.0 / std::sqrt(g.dndx.squaredNorm());
}

}  // namespace ricochet
