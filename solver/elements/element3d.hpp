// The 3D element kernels, one element at a time (docs/three-dimensions.md, "Elements in 3D"):
// the 8-node hexahedron with 2x2x2 Gauss points, the one-point hexahedron with
// Flanagan-Belytschko hourglass control, and the 4-node tetrahedron, in the total-Lagrangian
// form of the 2D kernels (element_kernels2.hpp): F = I + sum_a u_a (x) dN_a/dX at each point,
// the material response P(F) (and A = dP/dF), nodal forces f_a = sum_points vol P dN_a/dX, the
// strain energy sum vol W(F), the smallest det F; the element matrix K = sum vol B^T A B. Plus
// what the model needs of each cell once: the reference geometry (gradients, volumes,
// hourglass vectors and coefficient), the lumped masses and the critical-step length.
// The 3D model (model.hpp, blocks3.hpp) builds its geometry, masses and critical lengths with these; the 3D
// force pass (element_kernels3.hpp) runs the same formulations on batches of cells, equal to
// these kernels to round-off; no scheme uses them yet (docs/three-dimensions.md, Not wired in
// yet).
//
// Element arrays: positions, displacements, velocities and forces are 3 x N (column a = node a,
// VTK corner order, mesh.hpp). As a flat column-major vector the degrees of freedom run
// (x0, y0, z0, x1, ...): DOF 3a + i, the row and column order of the element matrices.
// Gradients are N x 3 (row a = dN_a/dX), as the 2D kernels' Grad4 (N x 2).
// Sign convention (the 2D one): f is the internal force, f = dE/du for the stored energy E (the
// element pushes its nodes with -f); K = df/du.
//
// The kernels (templates on the material law, each law inlined into its instantiation as in
// 2D) allocate nothing and make no virtual call: fixed-size Eigen objects and scalars only. The
// Material3 overloads dispatch once per call with std::visit.
#pragma once

#include <algorithm>
#include <array>
#include <concepts>
#include <variant>

#include "solver/materials/material3d.hpp"
#include "solver/elements/hourglass.hpp"
#include "solver/core/types.hpp"

namespace ricochet {

template <int N>
using Nodes3 = Eigen::Matrix<double, 3, N>;  // column a = node a [m] or [m/s] or [N]
template <int N>
using NodeGrad3 = Eigen::Matrix<double, N, 3>;  // row a = dN_a/dX [1/m]
template <int N>
using ElementMatrix3 = Eigen::Matrix<double, 3 * N, 3 * N>;  // DOF 3a + i

using Hex8Nodes = Nodes3<8>;
using Tet4Nodes = Nodes3<4>;
using Hex8Grad = NodeGrad3<8>;
using Tet4Grad = NodeGrad3<4>;
using Hex8Matrix = ElementMatrix3<8>;  // 24 x 24
using Tet4Matrix = ElementMatrix3<4>;  // 12 x 12
using Hex8Hourglass = Eigen::Matrix<double, 8, 4>;  // column alpha = gamma_alpha

// Corner signs of the reference cube [-1, 1]^3 in VTK order: corner a at (xi_a, eta_a, zeta_a).
inline constexpr std::array<std::array<int, 3>, 8> kHexCornerSigns = {
    {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}}};

// What a kernel sums over its points (the 3D ForceTotals of internal_forces.hpp).
struct ElementTotals3 {
  double strain_energy = 0.0;     // sum vol W(F) [J] (0 with kEnergy = false)
  double hourglass_energy = 0.0;  // stiffness form: stored 1/2 c sum_alpha |q_alpha|^2 [J]
  double hourglass_power = 0.0;   // viscous form: sum_alpha Q_alpha . qdot_alpha >= 0 [W],
                                  // dissipated; the caller integrates it over time
  double min_jacobian = 1e300;    // smallest det F at the element's points [-]
};

// ---------------------------------------------------------------------------------------------
// Reference geometry, computed once per cell (element3d.cpp). Each builder returns false (and
// leaves g unusable) where a Jacobian determinant at a point it uses is <= 0 or not finite;
// a hexahedron folded at a corner but positive at its points passes (the model checks
// hex_corner_quality(), mesh.hpp, as 2D build_model checks q4_corner_quality()).

// 2x2x2 Gauss points at (xi, eta, zeta) = (s_a / sqrt 3) for the corner signs s_a of corner a
// (point q next to corner q), weight 1: dN/dX = dN/dxi J^-1 and vol = det J (J = dX/dxi).
struct Hex8Geom {
  std::array<Hex8Grad, 8> dndx;
  std::array<double, 8> vol;  // [m^3], sum = the cell's volume
};
bool hex8_geometry(const Hex8Nodes& x, Hex8Geom& g);

// J = dX/dxi at the 2x2x2 Gauss point q, the matrix hex8_geometry() inverts (the same arithmetic,
// so the same bits): the 3D model stores J^-1 and det J per point instead of dN/dX (model.hpp, blocks3.hpp).
Mat3 hex8_jacobian(const Hex8Nodes& x, int q);

// One point: the mean ("uniform strain") gradients B = (1/V) int dN/dX dV = b / V with
// b_iI = dV/dX_iI (Flanagan & Belytschko 1981), V the volume, the hourglass vectors
// gamma_alpha = (h_alpha - B (X h_alpha)) / 8 (hex8_hourglass_base(), X the 3 x 8 corners),
// and the hourglass coefficient c of HourglassControl carried to 3D:
//   viscous:   c = coeff rho c_p V^(2/3)          [kg/s]
//   stiffness: c = coeff rho c_p^2 V (B:B) / 2    [N/m]
struct Hex8OnePointGeom {
  Hex8Grad dndx;            // B [1/m]
  Hex8Hourglass gamma;      // [-]
  double vol = 0.0;         // V [m^3]
  double hourglass_coeff = 0.0;  // c
  HourglassForm form = HourglassForm::viscous;
};
bool hex8_one_point_geometry(const Hex8Nodes& x, const Material3& material, const HourglassControl& hourglass,
                             Hex8OnePointGeom& g);

// The four hourglass base vectors of the hexahedron in VTK corner order (columns): the
// products eta zeta, xi zeta, xi eta, xi eta zeta of the corner signs (Flanagan & Belytschko
// 1981; orthogonal to each other and to the linear polynomials 1, xi, eta, zeta on the corners).
Hex8Hourglass hex8_hourglass_base();

// Constant gradients dN/dX = dN/dxi J^-1 with N0 = 1 - xi - eta - zeta, N1 = xi, N2 = eta,
// N3 = zeta, so J = [X1 - X0, X2 - X0, X3 - X0]; vol = det J / 6.
struct Tet4Geom {
  Tet4Grad dndx;
  double vol = 0.0;  // [m^3]
};
bool tet4_geometry(const Tet4Nodes& x, Tet4Geom& g);

// Row-sum lumped masses [kg]: m_a = rho int N_a dV, for the hexahedron by the 2x2x2 points
// (exact: N_a det J is at most cubic in each reference coordinate), rho V / 4 for a
// tetrahedron. They sum to rho V.
Eigen::Matrix<double, 8, 1> hex8_lumped_masses(const Hex8Nodes& x, double density);
Eigen::Vector4d tet4_lumped_masses(const Tet4Nodes& x, double density);

// Critical-step lengths, Delta t = L_e / c_p [m] (docs/three-dimensions.md, Elements in 3D):
//   hexahedron (both integrations): L_e = sqrt(8 m_min / (rho V)) V / sqrt(2 sum_I b_I . b_I)
//     = 2 sqrt(m_min / (rho V) / (B:B)), the Flanagan-Belytschko bound omega_max^2 <= 8 c_p^2 B:B
//     of the one-point element with equal masses rho V / 8, for the row-sum masses
//     (m_min the smallest); h / sqrt 3 for a cube of side h, 1 / sqrt(sum_j 1 / L_j^2) for a box;
//   tetrahedron: L_e = 1 / sqrt(sum_I |dN_I/dX|^2) = 1 / sqrt(sum_I 1 / h_I^2), h_I the altitude
//     over the face opposite corner I: omega_max^2 <= 4 c_p^2 sum_I |dN_I/dX|^2 for the lumped
//     tetrahedron (lambda >= 0); h / 2 for a regular tetrahedron of altitude h.
// A cell whose geometry builder fails gives 0.
double hex8_characteristic_length(const Hex8Nodes& x);
double tet4_characteristic_length(const Tet4Nodes& x);

// ---------------------------------------------------------------------------------------------
// The kernels.

// A 3D law: the members of the material3d.hpp contract the kernels use.
template <class M>
concept Law3 = requires(const M& m, const Mat3& F, Mat3& P, Mat9& A) {
  { m.energy_density(F) } -> std::convertible_to<double>;
  { m.first_piola(F) } -> std::convertible_to<Mat3>;
  m.first_piola_and_tangent(F, P, A);
};

namespace element3d {

// F = I + u dN/dX = I + sum_a u_a (x) dN_a/dX.
template <int N>
EIGEN_ALWAYS_INLINE Mat3 deformation_gradient(const Nodes3<N>& u, const NodeGrad3<N>& dn) {
  Mat3 F = Mat3::Identity();
  F.noalias() += u * dn;
  return F;
}

// K += w B^T A B for one point, with B the 9 x 3N matrix of dF/du, B(3i + J, 3a + k) =
// delta_ik dN_a/dX_J (so vec(dF) = B du in A's row order 3i + J). Written by blocks:
// K(3a + i, 3b + k) += w sum_J sum_L dN_a/dX_J A(3i + J, 3k + L) dN_b/dX_L.
template <int N>
EIGEN_ALWAYS_INLINE void add_point_stiffness(const NodeGrad3<N>& dn, double w, const Mat9& A,
                                             ElementMatrix3<N>& K) {
  for (int a = 0; a < N; ++a) {
    // Wa(i, 3k + L) = w sum_J dN_a/dX_J A(3i + J, 3k + L)
    Eigen::Matrix<double, 3, 9> Wa;
    for (int i = 0; i < 3; ++i)
      Wa.row(i) = (w * dn(a, 0)) * A.row(3 * i) + (w * dn(a, 1)) * A.row(3 * i + 1) + (w * dn(a, 2)) * A.row(3 * i + 2);
    for (int b = 0; b < N; ++b)
      for (int k = 0; k < 3; ++k)
        K.template block<3, 1>(3 * a, 3 * b + k).noalias() += Wa.template middleCols<3>(3 * k) * dn.row(b).transpose();
  }
}

// One point's forces, energy and det F: f += vol P dN^T.
template <bool kEnergy, int N, class Mat>
EIGEN_ALWAYS_INLINE void point_forces(const Mat& mat, const Nodes3<N>& u, const NodeGrad3<N>& dn, double vol,
                                      Nodes3<N>& f, ElementTotals3& t) {
  const Mat3 F = deformation_gradient<N>(u, dn);
  t.min_jacobian = std::min(t.min_jacobian, F.determinant());
  const Mat3 P = mat.first_piola(F);
  f.noalias() += (vol * P) * dn.transpose();
  if constexpr (kEnergy) t.strain_energy += vol * mat.energy_density(F);
}

// The same with A = dP/dF: K += vol B^T A B.
template <bool kEnergy, int N, class Mat>
EIGEN_ALWAYS_INLINE void point_forces_and_stiffness(const Mat& mat, const Nodes3<N>& u, const NodeGrad3<N>& dn,
                                                    double vol, Nodes3<N>& f, ElementMatrix3<N>& K,
                                                    ElementTotals3& t) {
  const Mat3 F = deformation_gradient<N>(u, dn);
  t.min_jacobian = std::min(t.min_jacobian, F.determinant());
  Mat3 P;
  Mat9 A;
  mat.first_piola_and_tangent(F, P, A);
  f.noalias() += (vol * P) * dn.transpose();
  add_point_stiffness<N>(dn, vol, A, K);
  if constexpr (kEnergy) t.strain_energy += vol * mat.energy_density(F);
}

// Adds the Flanagan-Belytschko hourglass forces of one-point hexahedron g for the field a (u for
// the stiffness form, v for the viscous one): q = a gamma (3 x 4, column alpha = q_alpha),
// Q = c q, f += Q gamma^T; the stored energy 1/2 c |q|^2 or the power Q : qdot.
template <bool kEnergy>
EIGEN_ALWAYS_INLINE void add_hourglass_forces(const Hex8OnePointGeom& g, const Hex8Nodes& a, Hex8Nodes& f,
                                              ElementTotals3& t) {
  const Eigen::Matrix<double, 3, 4> q = a * g.gamma;
  const Eigen::Matrix<double, 3, 4> Q = g.hourglass_coeff * q;
  f.noalias() += Q * g.gamma.transpose();
  if (g.form == HourglassForm::viscous)
    t.hourglass_power += (Q.array() * q.array()).sum();
  else if constexpr (kEnergy)
    t.hourglass_energy += 0.5 * (Q.array() * q.array()).sum();
}

}  // namespace element3d

// Hexahedron, 2x2x2 points: f (overwritten) and the totals at displacement u.
template <bool kEnergy = true, Law3 Mat>
ElementTotals3 hex8_forces(const Hex8Geom& g, const Mat& mat, const Hex8Nodes& u, Hex8Nodes& f) {
  ElementTotals3 t;
  f.setZero();
  for (int q = 0; q < 8; ++q) element3d::point_forces<kEnergy, 8>(mat, u, g.dndx[q], g.vol[q], f, t);
  return t;
}

// Hexahedron, 2x2x2 points: f and K = df/du = sum vol B^T A B (overwritten), the totals.
template <bool kEnergy = true, Law3 Mat>
ElementTotals3 hex8_stiffness(const Hex8Geom& g, const Mat& mat, const Hex8Nodes& u, Hex8Nodes& f, Hex8Matrix& K) {
  ElementTotals3 t;
  f.setZero();
  K.setZero();
  for (int q = 0; q < 8; ++q)
    element3d::point_forces_and_stiffness<kEnergy, 8>(mat, u, g.dndx[q], g.vol[q], f, K, t);
  return t;
}

// One-point hexahedron with hourglass control: f = V P(F) B^T + c (a gamma) gamma^T with
// F = I + u B, a = v (viscous form) or u (stiffness form).
template <bool kEnergy = true, Law3 Mat>
ElementTotals3 hex8_one_point_forces(const Hex8OnePointGeom& g, const Mat& mat, const Hex8Nodes& u,
                                     const Hex8Nodes& v, Hex8Nodes& f) {
  ElementTotals3 t;
  f.setZero();
  element3d::point_forces<kEnergy, 8>(mat, u, g.dndx, g.vol, f, t);
  element3d::add_hourglass_forces<kEnergy>(g, g.form == HourglassForm::viscous ? v : u, f, t);
  return t;
}

// The hourglass matrix c sum_alpha gamma_alpha gamma_alpha^T on each displacement component:
// H(3a + i, 3b + k) = delta_ik c (gamma gamma^T)(a, b). It is df/du of the stiffness form's
// hourglass forces, and df/dv (the damping matrix) of the viscous form's.
Hex8Matrix hex8_hourglass_matrix(const Hex8OnePointGeom& g);

// One-point hexahedron: f at (u, v) as hex8_one_point_forces, K = df/du = V B^T A B (+ the
// hourglass matrix for the stiffness form) and C = df/dv (the hourglass matrix for the viscous
// form, else 0), the totals.
template <bool kEnergy = true, Law3 Mat>
ElementTotals3 hex8_one_point_stiffness(const Hex8OnePointGeom& g, const Mat& mat, const Hex8Nodes& u,
                                        const Hex8Nodes& v, Hex8Nodes& f, Hex8Matrix& K, Hex8Matrix& C) {
  ElementTotals3 t;
  f.setZero();
  K.setZero();
  element3d::point_forces_and_stiffness<kEnergy, 8>(mat, u, g.dndx, g.vol, f, K, t);
  element3d::add_hourglass_forces<kEnergy>(g, g.form == HourglassForm::viscous ? v : u, f, t);
  if (g.form == HourglassForm::viscous) {
    C = hex8_hourglass_matrix(g);
  } else {
    K += hex8_hourglass_matrix(g);
    C.setZero();
  }
  return t;
}

// Tetrahedron: f (overwritten) and the totals.
template <bool kEnergy = true, Law3 Mat>
ElementTotals3 tet4_forces(const Tet4Geom& g, const Mat& mat, const Tet4Nodes& u, Tet4Nodes& f) {
  ElementTotals3 t;
  f.setZero();
  element3d::point_forces<kEnergy, 4>(mat, u, g.dndx, g.vol, f, t);
  return t;
}

// Tetrahedron: f and K = vol B^T A B (overwritten), the totals.
template <bool kEnergy = true, Law3 Mat>
ElementTotals3 tet4_stiffness(const Tet4Geom& g, const Mat& mat, const Tet4Nodes& u, Tet4Nodes& f, Tet4Matrix& K) {
  ElementTotals3 t;
  f.setZero();
  K.setZero();
  element3d::point_forces_and_stiffness<kEnergy, 4>(mat, u, g.dndx, g.vol, f, K, t);
  return t;
}

// The same kernels on a Material3: one std::visit per call, then the law's instantiation.
template <bool kEnergy = true>
ElementTotals3 hex8_forces(const Hex8Geom& g, const Material3& m, const Hex8Nodes& u, Hex8Nodes& f) {
  return std::visit([&](const auto& law) { return hex8_forces<kEnergy>(g, law, u, f); }, m);
}
template <bool kEnergy = true>
ElementTotals3 hex8_stiffness(const Hex8Geom& g, const Material3& m, const Hex8Nodes& u, Hex8Nodes& f,
                              Hex8Matrix& K) {
  return std::visit([&](const auto& law) { return hex8_stiffness<kEnergy>(g, law, u, f, K); }, m);
}
template <bool kEnergy = true>
ElementTotals3 hex8_one_point_forces(const Hex8OnePointGeom& g, const Material3& m, const Hex8Nodes& u,
                                     const Hex8Nodes& v, Hex8Nodes& f) {
  return std::visit([&](const auto& law) { return hex8_one_point_forces<kEnergy>(g, law, u, v, f); }, m);
}
template <bool kEnergy = true>
ElementTotals3 hex8_one_point_stiffness(const Hex8OnePointGeom& g, const Material3& m, const Hex8Nodes& u,
                                        const Hex8Nodes& v, Hex8Nodes& f, Hex8Matrix& K, Hex8Matrix& C) {
  return std::visit([&](const auto& law) { return hex8_one_point_stiffness<kEnergy>(g, law, u, v, f, K, C); }, m);
}
template <bool kEnergy = true>
ElementTotals3 tet4_forces(const Tet4Geom& g, const Material3& m, const Tet4Nodes& u, Tet4Nodes& f) {
  return std::visit([&](const auto& law) { return tet4_forces<kEnergy>(g, law, u, f); }, m);
}
template <bool kEnergy = true>
ElementTotals3 tet4_stiffness(const Tet4Geom& g, const Material3& m, const Tet4Nodes& u, Tet4Nodes& f,
                              Tet4Matrix& K) {
  return std::visit([&](const auto& law) { return tet4_stiffness<kEnergy>(g, law, u, f, K); }, m);
}

}  // namespace ricochet
