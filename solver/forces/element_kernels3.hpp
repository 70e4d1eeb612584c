// The 3D force kernels (docs/three-dimensions.md, "The 3D model and force pass"): the
// formulations of element3d.hpp (hexahedron with 2x2x2 points, one-point hexahedron with
// Flanagan-Belytschko hourglass control, tetrahedron) on kLanes cells at once, from the blocks'
// structure-of-arrays geometry (model.hpp, blocks3.hpp), as the 2D force_kernel() of element_kernels2.hpp:
// gather, F at each point, the material law on all lanes (material_lanes3.hpp), the nodal
// forces; then lane by lane in cell order the forces go out and the pass's per-point work and
// the energy sums run, so every sum keeps the serial order.
//
// The tetrahedron computes element3d.hpp's formulas, F = I + u dN/dX and f = (vol P) dN/dX^T, with
// its sums in a fixed order ((p0 + p1) + (p2 + p3) and p0 + (p1 + p2); Eigen picks its own order
// and fused multiply-adds, so the two agree to round-off). The hexahedra reorganize the
// arithmetic, to fewer operations and less geometry, into the exact same formulas (equal to
// element3d.hpp to round-off; tests/solver/forces/test_internal_forces3.cpp):
//
// - The trilinear field u = sum_a N_a u_a in the monomials 1, xi, eta, zeta, eta zeta, xi zeta,
//   xi eta, xi eta zeta (kHexMonomialSigns): u = 1/8 sum_m c_m m(xi), c_m = sum_a s_am u_a, the
//   Walsh-Hadamard transform of the corner values, 24 additions a component by butterflies
//   (hadamard_forward below). Its inverse is the same butterflies (hadamard_inverse).
// - 2x2x2 points: 8 du/dxi at a point from c: d/dxi of the monomials at (xi, eta, zeta) =
//   (+-g, +-g, +-g), g = 1/sqrt 3, e.g. 8 du/dxi = c_xi + g eta^ c_xieta + g zeta^ c_xizeta
//   + 1/3 eta^ zeta^ c_xietazeta (eta^ = +-1 the point's sign), four values per component and
//   direction shared by the point pairs (reference_gradients); F = I + (8 du/dxi) K with
//   K = J^-1 / 8 per point; the forces f_a = sum_q vol_q P_q dN_a/dX(q)^T = sum_q G_q
//   8 dN_a/dxi(q)^T with G_q = vol_q P_q K_q^T, whose monomial coefficients (the transpose of
//   the gradients, reference_forces) give f by the inverse transform. Per point: 27 + 27
//   multiply-adds instead of 72 + 72, and 10 geometry values instead of 25.
// - One point: H = u B = sum_m c_m Bh_m^T with Bh_m = 1/8 sum_a s_am B_a (B_a = sum_m s_am Bh_m);
//   the hourglass modes q_alpha = u gamma_alpha with gamma_alpha = (h_alpha - B X h_alpha)/8
//   (element3d.hpp) are q_alpha = (c_{4+alpha} - H xh_alpha) / 8, xh_alpha = X h_alpha, and the
//   forces V P B^T + Q gamma^T = (V P - R) B^T + Q h^T / 8 with R = sum_alpha Q_alpha xh_alpha^T / 8,
//   whose coefficients are (V P - R) Bh_m^T plus Q_alpha / 8 on the hourglass monomials: no
//   gamma (32 values a cell) is stored or multiplied. The viscous form does the same with v.
//
// Each kernel is `[[gnu::noinline, gnu::flatten]]` per (element, material, pass), as in 2D, so
// the law inlines into its loop. The pass provides element_kernels2.hpp's contract for
// force_kernel() (kEnergy, kPerPoint, kEveryPoint, Response{P}, begin_element(), screen(mat, F,
// P, det, may), point<kPoints>(mat, F, det, response, nullptr, vol, cell, may),
// end_element<kPoints>(e, cell), finish(t)) with 3x3 F and P.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <variant>

#include "solver/forces/internal_forces.hpp"
#include "solver/materials/material_lanes3.hpp"
#include "solver/model/model.hpp"

namespace ricochet {

// ---------------------------------------------------------------------------------------------
// The cells' arithmetic, one lane at a time. Every function indexes its arrays with [], so it
// takes a plain pointer (one cell's own arrays, stride 1) or a Strided accessor (a batch's
// lane-major arrays: lane_in(&a[0][l])[k] reads a[k][l]). A lane loop must see every
// access as a[k][l] of an array outside it: GCC 12 privatizes a local array of a
// `#pragma omp simd` body per lane and then gives up on the loop, so the lane loops call these
// functions with accessors and keep their own temporaries inside them. Nodal values come through
// an accessor x(i, a), component i of node a: StridedNodes over a batch's gathered values
// (lanes3::Nodes; reading the flat DOF array inside the lane loop instead, GCC's emulated
// gathers, measured 3-8 % slower on this project's machine), CellNodes over one cell's array.
// The kernels below and the one-cell functions after them run the same functions, so the same
// bits.
namespace hex8wh {

// a[k] = p[S k].
template <int S, class T>
struct Strided {
  T* p;
  EIGEN_ALWAYS_INLINE T& operator[](int k) const { return p[S * k]; }
};
// A batch's lane-major array seen from lane l: lane_in(&a[0][l])[k] is a[k][l].
EIGEN_ALWAYS_INLINE Strided<kLanes, const double> lane_in(const double* p) { return {p}; }
EIGEN_ALWAYS_INLINE Strided<kLanes, double> lane_out(double* p) { return {p}; }
// The same array from entry n on.
template <class T>
EIGEN_ALWAYS_INLINE T* shifted(T* p, int n) {
  return p + n;
}
template <int S, class T>
EIGEN_ALWAYS_INLINE Strided<S, T> shifted(const Strided<S, T>& a, int n) {
  return {a.p + S * n};
}

// Nodal values u[S (N i + a)]: a batch's gathered values (lanes3::Nodes, from &v[0][0][l],
// S = kLanes) or one cell's (S = 1).
template <int N, int S>
struct StridedNodes {
  const double* u;
  EIGEN_ALWAYS_INLINE double operator()(int i, int a) const { return u[S * (N * i + a)]; }
};
template <int N>
using CellNodes = StridedNodes<N, 1>;

// Corner (VTK order) at the bit pattern k = b_xi + 2 b_eta + 4 b_zeta (bit 1: sign +1), and the
// monomial (kHexMonomialSigns order) whose odd variables are the bits of k.
inline constexpr int kCornerOfBits[8] = {0, 1, 3, 2, 4, 5, 7, 6};
inline constexpr int kMonomialOfBits[8] = {0, 1, 2, 6, 3, 5, 4, 7};
inline constexpr double kG = 0.57735026918962576451;      // 1/sqrt 3, the Gauss points' coordinate
inline constexpr double kThird = 0.33333333333333333333;  // 1/3 = g^2

// c_m = sum_a s_am x(i, a) for the monomials m = 0..7 (c a local array): butterflies over
// xi, eta, zeta (the stages as counted loops: GCC unrolls `1 << stage`, not `b <<= 1`), each pair
// (minus, plus) -> (plus + minus, plus - minus).
template <class X>
EIGEN_ALWAYS_INLINE void hadamard_forward(const X& x, int i, double* c) {
  double y[8];
  RICOCHET_UNROLL
  for (int k = 0; k < 8; ++k) y[k] = x(i, kCornerOfBits[k]);
  RICOCHET_UNROLL
  for (int stage = 0; stage < 3; ++stage)
    RICOCHET_UNROLL
    for (int k = 0; k < 8; ++k)
      if (const int b = 1 << stage; !(k & b)) {
        const double lo = y[k], hi = y[k + b];
        y[k] = hi + lo;
        y[k + b] = hi - lo;
      }
  RICOCHET_UNROLL
  for (int k = 0; k < 8; ++k) c[kMonomialOfBits[k]] = y[k];
}

// x[a] = sum_m s_am c_m (c a local array): the butterflies (even, odd) -> (even - odd, even + odd).
template <class O>
EIGEN_ALWAYS_INLINE void hadamard_inverse(const double* c, O x) {
  double y[8];
  RICOCHET_UNROLL
  for (int k = 0; k < 8; ++k) y[k] = c[kMonomialOfBits[k]];
  RICOCHET_UNROLL
  for (int stage = 0; stage < 3; ++stage)
    RICOCHET_UNROLL
    for (int k = 0; k < 8; ++k)
      if (const int b = 1 << stage; !(k & b)) {
        const double even = y[k], odd = y[k + b];
        y[k] = even - odd;
        y[k + b] = even + odd;
      }
  RICOCHET_UNROLL
  for (int k = 0; k < 8; ++k) x[kCornerOfBits[k]] = y[k];
}

// The coefficients of the three components of nodal values x: c[8 i + m].
template <class X>
EIGEN_ALWAYS_INLINE void hadamard_forward3(const X& x, double* c) {
  RICOCHET_UNROLL
  for (int i = 0; i < 3; ++i) hadamard_forward(x, i, c + 8 * i);
}

// For derivative direction K: the monomial of each other variable's mixed term and the other two
// variables (o1 < o2). d/dxi: xi eta (6) with eta, xi zeta (5) with zeta; d/deta: xi eta (6)
// with xi, eta zeta (4) with zeta; d/dzeta: xi zeta (5) with xi, eta zeta (4) with eta.
inline constexpr int kMixed[3][2] = {{6, 5}, {6, 4}, {5, 4}};
inline constexpr int kOther[3][2] = {{1, 2}, {0, 2}, {0, 1}};

// 8 du_i/dxi_K at the 2x2x2 points from the nodal values u(i, a): h[9 q + 3 i + K] at point q
// (next to corner q). With c the coefficients, A = c_K, B = g c_(K o1), C = g c_(K o2),
// D = c_xietazeta / 3, the value at the signs (s1, s2) of the other two variables is
// A + s1 B + s2 C + s1 s2 D: (A + D) +- (B + C) for s1 = s2, (A - D) +- (B - C) otherwise.
template <class X, class H>
EIGEN_ALWAYS_INLINE void reference_gradients(const X& u, H h) {
  double c[24];
  hadamard_forward3(u, c);
  RICOCHET_UNROLL
  for (int i = 0; i < 3; ++i)
    RICOCHET_UNROLL
    for (int K = 0; K < 3; ++K) {
      const double a = c[8 * i + 1 + K], b = kG * c[8 * i + kMixed[K][0]], cc = kG * c[8 * i + kMixed[K][1]];
      const double d = kThird * c[8 * i + 7];
      const double apd = a + d, amd = a - d, bpc = b + cc, bmc = b - cc;
      const double pp = apd + bpc, mm = apd - bpc, pm = amd + bmc, mp = amd - bmc;
      RICOCHET_UNROLL
      for (int q = 0; q < 8; ++q) {
        const int s1 = kHexCornerSigns[q][kOther[K][0]], s2 = kHexCornerSigns[q][kOther[K][1]];
        h[9 * q + 3 * i + K] = s1 > 0 ? (s2 > 0 ? pp : pm) : (s2 > 0 ? mp : mm);
      }
    }
}

// The point pair of each (s1, s2) for direction K: the two points (sign of K -1, then +1) whose
// other two signs are (s1, s2), indexed [K][2 (s1 > 0) + (s2 > 0)][0 or 1].
inline constexpr std::array<std::array<std::array<int, 2>, 4>, 3> kPairs = [] {
  std::array<std::array<std::array<int, 2>, 4>, 3> p{};
  for (int K = 0; K < 3; ++K)
    for (int q = 0; q < 8; ++q) {
      const int s1 = kHexCornerSigns[q][kOther[K][0]], s2 = kHexCornerSigns[q][kOther[K][1]];
      p[K][2 * (s1 > 0) + (s2 > 0)][kHexCornerSigns[q][K] > 0] = q;
    }
  return p;
}();

// The transpose of reference_gradients: from G (g[9 q + 3 i + K], the points' vol P K^T), the
// nodal forces f[8 i + a] = sum_q sum_K G_iK(q) 8 dN_a/dxi_K(q). For each (i, K): the pair
// sums S(s1, s2), then sum S, g sum s1 S, g sum s2 S, 1/3 sum s1 s2 S onto the monomials K,
// (K o1), (K o2), xi eta zeta (the mixed ones get two directions' terms, xi eta zeta three,
// added in the order of K), and the nodal values by hadamard_inverse.
template <class G, class O>
EIGEN_ALWAYS_INLINE void reference_forces(G g, O f) {
  RICOCHET_UNROLL
  for (int i = 0; i < 3; ++i) {
    double t[3][4];  // per K: sum, o1 term, o2 term, o1 o2 term
    RICOCHET_UNROLL
    for (int K = 0; K < 3; ++K) {
      double s[4];  // S(-,-), S(-,+), S(+,-), S(+,+)
      RICOCHET_UNROLL
      for (int k = 0; k < 4; ++k) s[k] = g[9 * kPairs[K][k][0] + 3 * i + K] + g[9 * kPairs[K][k][1] + 3 * i + K];
      const double a = s[3] + s[0], b = s[2] + s[1], c = s[3] - s[0], d = s[2] - s[1];
      t[K][0] = a + b;
      t[K][1] = kG * (c + d);
      t[K][2] = kG * (c - d);
      t[K][3] = kThird * (a - b);
    }
    double fh[8];
    fh[0] = 0.0;
    fh[1] = t[0][0];
    fh[2] = t[1][0];
    fh[3] = t[2][0];
    fh[6] = t[0][1] + t[1][1];  // xi eta: d/dxi's eta term, d/deta's xi term
    fh[5] = t[0][2] + t[2][1];  // xi zeta: d/dxi's zeta term, d/dzeta's xi term
    fh[4] = t[1][2] + t[2][2];  // eta zeta: d/deta's zeta term, d/dzeta's eta term
    fh[7] = (t[0][3] + t[1][3]) + t[2][3];
    hadamard_inverse(fh, shifted(f, 8 * i));
  }
}

// F = I + h k at a point: f[3 i + J] = delta_iJ + (h_i0 k_0J + h_i1 k_1J + h_i2 k_2J) (h = 8 du/dxi,
// k = J^-1 / 8, both row-major).
template <class H, class KM, class F>
EIGEN_ALWAYS_INLINE void deformation_gradient(H h, KM k, F f) {
  RICOCHET_UNROLL
  for (int i = 0; i < 3; ++i)
    RICOCHET_UNROLL
    for (int J = 0; J < 3; ++J)
      f[3 * i + J] = (i == J ? 1.0 : 0.0) + (h[3 * i] * k[J] + h[3 * i + 1] * k[3 + J] + h[3 * i + 2] * k[6 + J]);
}

// G = (vol P) K^T at a point: g[3 i + K] = vP_i0 k_K0 + vP_i1 k_K1 + vP_i2 k_K2.
template <class P, class KM, class G>
EIGEN_ALWAYS_INLINE void point_force_coefficients(P p, double vol, KM k, G g) {
  RICOCHET_UNROLL
  for (int i = 0; i < 3; ++i) {
    const double v0 = vol * p[3 * i], v1 = vol * p[3 * i + 1], v2 = vol * p[3 * i + 2];
    RICOCHET_UNROLL
    for (int K = 0; K < 3; ++K) g[3 * i + K] = v0 * k[3 * K] + v1 * k[3 * K + 1] + v2 * k[3 * K + 2];
  }
}

// One point: H = sum_{m=1..7} c_m Bh_m^T, h[3 i + J] = sum_m c[8 i + m] bh[3 (m - 1) + J] in the
// order of m (c and h local arrays; bh the geometry's first values).
template <class B>
EIGEN_ALWAYS_INLINE void mean_gradient(const double* c, B bh, double* h) {
  RICOCHET_UNROLL
  for (int i = 0; i < 3; ++i)
    RICOCHET_UNROLL
    for (int J = 0; J < 3; ++J) {
      double s = c[8 * i + 1] * bh[J];
      RICOCHET_UNROLL
      for (int m = 2; m < 8; ++m) s += c[8 * i + m] * bh[3 * (m - 1) + J];
      h[3 * i + J] = s;
    }
}

// One point: F = I + u B from the nodal displacements u(i, a) and the geometry
// (Hex8OnePointLanes): f[3 i + J]; H = u B itself in h[3 i + J] (h = nullptr: not kept, as the
// viscous form, whose hourglass modes take v B instead).
template <class X, class Gm, class H, class F>
EIGEN_ALWAYS_INLINE void one_point_gradient(const X& u, Gm geom, H h, F f) {
  double c[24], hl[9];
  hadamard_forward3(u, c);
  mean_gradient(c, geom, hl);
  RICOCHET_UNROLL
  for (int n = 0; n < 9; ++n) {
    if constexpr (!std::is_same_v<H, std::nullptr_t>) h[n] = hl[n];
    f[n] = (n % 4 == 0 ? 1.0 : 0.0) + hl[n];
  }
}

// One point with hourglass control, after the law: from P (p), the hourglass field's nodal
// values a(i, n) (u for the stiffness form, v for the viscous one) and for the stiffness form
// H = u B (hu, from one_point_gradient), the geometry (Hex8OnePointLanes): the nodal forces
// f[8 i + a] and sum Q . q, returned (the power of the viscous form, twice the stored energy of
// the stiffness form). With c the coefficients of a and Ha = a B: 8 q_alpha = c_(4 + alpha) -
// Ha xh_alpha, Q_alpha / 8 = (c / 64)(8 q_alpha); T = vol P - R, R_iJ = sum_alpha (Q_alpha / 8)_i
// xh_alpha,J; the coefficients T Bh_m^T plus Q_alpha / 8 on the hourglass monomials, then
// hadamard_inverse.
template <bool kViscous, class P, class X, class H, class Gm, class O>
EIGEN_ALWAYS_INLINE double one_point_forces(P p, const X& a, H hu, Gm geom, O f) {
  using L = Hex8OnePointLanes;
  double c[24], ha[9];
  hadamard_forward3(a, c);
  if constexpr (kViscous) {
    mean_gradient(c, geom, ha);
  } else {
    RICOCHET_UNROLL
    for (int n = 0; n < 9; ++n) ha[n] = hu[n];
  }
  const double c64 = geom[L::kCoeff64], vol = geom[L::kVol];
  double q8[12], Q8[12];
  double work = 0.0;
  RICOCHET_UNROLL
  for (int i = 0; i < 3; ++i)
    RICOCHET_UNROLL
    for (int al = 0; al < 4; ++al) {
      q8[4 * i + al] = c[8 * i + 4 + al] - (ha[3 * i] * geom[L::xh(al, 0)] + ha[3 * i + 1] * geom[L::xh(al, 1)] +
                                            ha[3 * i + 2] * geom[L::xh(al, 2)]);
      Q8[4 * i + al] = c64 * q8[4 * i + al];
      work += Q8[4 * i + al] * q8[4 * i + al];
    }
  RICOCHET_UNROLL
  for (int i = 0; i < 3; ++i) {
    double tm[3];
    RICOCHET_UNROLL
    for (int J = 0; J < 3; ++J)
      tm[J] = vol * p[3 * i + J] - ((Q8[4 * i] * geom[L::xh(0, J)] + Q8[4 * i + 1] * geom[L::xh(1, J)]) +
                                    (Q8[4 * i + 2] * geom[L::xh(2, J)] + Q8[4 * i + 3] * geom[L::xh(3, J)]));
    double fh[8];
    fh[0] = 0.0;
    RICOCHET_UNROLL
    for (int m = 1; m < 8; ++m)
      fh[m] = tm[0] * geom[L::bh(m, 0)] + tm[1] * geom[L::bh(m, 1)] + tm[2] * geom[L::bh(m, 2)];
    RICOCHET_UNROLL
    for (int al = 0; al < 4; ++al) fh[4 + al] += Q8[4 * i + al];
    hadamard_inverse(fh, shifted(f, 8 * i));
  }
  return work;
}

// The tetrahedron as element3d.hpp: F = I + u dN/dX, F_iJ = delta + ((u_i0 d_0J + u_i1 d_1J) +
// (u_i2 d_2J + u_i3 d_3J)) (geometry Tet4Lanes).
template <class X, class Gm, class F>
EIGEN_ALWAYS_INLINE void tet4_deformation_gradient(const X& U, Gm geom, F f) {
  auto D = [&](int a, int J) { return geom[Tet4Lanes::dndx(a, J)]; };
  RICOCHET_UNROLL
  for (int i = 0; i < 3; ++i)
    RICOCHET_UNROLL
    for (int J = 0; J < 3; ++J)
      f[3 * i + J] = (i == J ? 1.0 : 0.0) + ((U(i, 0) * D(0, J) + U(i, 1) * D(1, J)) + (U(i, 2) * D(2, J) + U(i, 3) * D(3, J)));
}

// f = (vol P) dN/dX^T: f_ia = (vol P)_i0 d_a0 + ((vol P)_i1 d_a1 + (vol P)_i2 d_a2) (f[4 i + a]).
template <class P, class Gm, class O>
EIGEN_ALWAYS_INLINE void tet4_forces(P p, Gm geom, O f) {
  auto D = [&](int a, int J) { return geom[Tet4Lanes::dndx(a, J)]; };
  const double vol = geom[Tet4Lanes::kVol];
  RICOCHET_UNROLL
  for (int i = 0; i < 3; ++i) {
    const double v0 = vol * p[3 * i], v1 = vol * p[3 * i + 1], v2 = vol * p[3 * i + 2];
    RICOCHET_UNROLL
    for (int a = 0; a < 4; ++a) f[4 * i + a] = v0 * D(a, 0) + (v1 * D(a, 1) + v2 * D(a, 2));
  }
}

}  // namespace hex8wh

// ---------------------------------------------------------------------------------------------
// The deformation gradients of one cell, with the kernels' arithmetic (the same bits as the
// force pass's F): for the stress passes and field tensors (internal_forces3.cpp).

// A block's geometry of cell e, as a plain array (stride 1).
template <int N, class Layout>
std::array<double, Layout::kValues> cell_lane_values(const ElementBlock3<N, Layout>& b, std::size_t e) {
  std::array<double, Layout::kValues> g;
  for (int j = 0; j < Layout::kValues; ++j) g[j] = b.geom(e, j);
  return g;
}

// Nodal values ue (3 x N) as u[N i + a], the kernels' order.
template <int N>
std::array<double, 3 * N> component_major(const Nodes3<N>& ue) {
  std::array<double, 3 * N> u;
  for (int i = 0; i < 3; ++i)
    for (int a = 0; a < N; ++a) u[N * i + a] = ue(i, a);
  return u;
}

inline Mat3 row_major(const double* f) {
  Mat3 F;
  for (int i = 0; i < 3; ++i)
    for (int J = 0; J < 3; ++J) F(i, J) = f[3 * i + J];
  return F;
}

// Hexahedron 2x2x2: F at the 8 points from the nodal displacements ue (3 x 8).
inline void hex8_point_gradients(const Hex8Block& b, std::size_t e, const Hex8Nodes& ue, std::array<Mat3, 8>& F) {
  const std::array<double, 24> u = component_major<8>(ue);
  const std::array<double, Hex8Lanes::kValues> g = cell_lane_values(b, e);
  double h[72];
  hex8wh::reference_gradients(hex8wh::CellNodes<8>{u.data()}, h);
  for (int q = 0; q < 8; ++q) {
    double f[9];
    hex8wh::deformation_gradient(h + 9 * q, g.data() + Hex8Lanes::k(q, 0, 0), f);
    F[q] = row_major(f);
  }
}

// One-point hexahedron: F at the centroid.
inline Mat3 hex8_one_point_gradient(const Hex8OnePointBlock& b, std::size_t e, const Hex8Nodes& ue) {
  const std::array<double, 24> u = component_major<8>(ue);
  const std::array<double, Hex8OnePointLanes::kValues> g = cell_lane_values(b, e);
  double h[9], f[9];
  hex8wh::one_point_gradient(hex8wh::CellNodes<8>{u.data()}, g.data(), h, f);
  return row_major(f);
}

// Tetrahedron: F = I + u dN/dX, as element3d.hpp.
inline Mat3 tet4_gradient(const Tet4Block& b, std::size_t e, const Tet4Nodes& ue) {
  const std::array<double, 12> u = component_major<4>(ue);
  const std::array<double, Tet4Lanes::kValues> g = cell_lane_values(b, e);
  double f[9];
  hex8wh::tet4_deformation_gradient(hex8wh::CellNodes<4>{u.data()}, g.data(), f);
  return row_major(f);
}

// A cell's nodal values (3 x N) of a flat DOF array (3n, interleaved).
template <int N>
inline Nodes3<N> gather3(const double* a, const std::array<int, N>& c) {
  Nodes3<N> e;
  for (int i = 0; i < N; ++i)
    for (int k = 0; k < 3; ++k) e(k, i) = a[3 * c[i] + k];
  return e;
}

// ---------------------------------------------------------------------------------------------
// Where a kernel puts a batch's nodal forces (the record fe, lanes 0 <= l < n are the cells e,
// e + 1, ...): added into the global array f cell by cell (DirectScatter3), or stored whole in
// the threaded pass's buffer (ElementStore3).
namespace lanes3 {

template <int N>
struct Nodes {
  alignas(64) double v[3][N][kLanes];  // component, node, lane
};

template <int N>
EIGEN_ALWAYS_INLINE void gather(const double* a, const int* conn, Nodes<N>& n) {
  RICOCHET_UNROLL
  for (int i = 0; i < N; ++i)
#pragma omp simd
    for (int l = 0; l < kLanes; ++l) {
      const int c = conn[i * kLanes + l];
      n.v[0][i][l] = a[3 * c];
      n.v[1][i][l] = a[3 * c + 1];
      n.v[2][i][l] = a[3 * c + 2];
    }
}

// gather() of two fields at the same nodes (the viscous one-point hexahedron's u and v) in one
// loop: GCC emulates the gathers with scalar loads, and reads each node index out of the vector
// of indices into a register; here it does so once for both fields, not once per field (7 % of
// the viscous kernel's instructions).
template <int N>
EIGEN_ALWAYS_INLINE void gather2(const double* a, const double* b, const int* conn, Nodes<N>& na, Nodes<N>& nb) {
  RICOCHET_UNROLL
  for (int i = 0; i < N; ++i)
#pragma omp simd
    for (int l = 0; l < kLanes; ++l) {
      const int c = conn[i * kLanes + l];
      na.v[0][i][l] = a[3 * c];
      na.v[1][i][l] = a[3 * c + 1];
      na.v[2][i][l] = a[3 * c + 2];
      nb.v[0][i][l] = b[3 * c];
      nb.v[1][i][l] = b[3 * c + 1];
      nb.v[2][i][l] = b[3 * c + 2];
    }
}

EIGEN_ALWAYS_INLINE void min_into(double* min_j, const double* det) {
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) min_j[l] = std::min(min_j[l], det[l]);
}

// Whether any of the n values is non-zero.
EIGEN_ALWAYS_INLINE bool any(const double* x, int n) {
  double s = 0.0;
#pragma omp simd reduction(+ : s)
  for (int i = 0; i < n; ++i) s += x[i];
  return s != 0.0;
}

}  // namespace lanes3

struct DirectScatter3 {
  double* f;
  template <int N>
  EIGEN_ALWAYS_INLINE void put(std::size_t e, const std::array<int, N>* conn, const lanes3::Nodes<N>& fe,
                               int n) const {
    for (int l = 0; l < n; ++l) {
      RICOCHET_UNROLL
      for (int a = 0; a < N; ++a) {
        double* p = f + 3 * conn[e + l][a];
        p[0] += fe.v[0][a][l];
        p[1] += fe.v[1][a][l];
        p[2] += fe.v[2][a][l];
      }
    }
  }
};
// The buffer holds a block's batches whole (make_force_scratch pads a block to whole batches):
// per batch 3N rows of kLanes values, row 3 a + k for component k of node a, lane l in column
// l. So a batch goes out as 3N row copies (vector loads and stores), where one value per cell
// and entry went out before; cell e's node a, component k is at 3N (e - e % kLanes) +
// (3 a + k) kLanes + e % kLanes (ElementStore3::entry).
struct ElementStore3 {
  double* out;  // this block's first batch
  static constexpr int kStride = kLanes;  // from an entry's x to its y, and its y to its z
  // The entries of `cells` cells, in whole batches.
  template <int N>
  static constexpr std::size_t size(std::size_t cells) {
    return 3 * N * kLanes * ((cells + kLanes - 1) / kLanes);
  }
  template <int N>
  static constexpr std::size_t entry(std::size_t e, int a) {
    return 3 * N * (e - e % kLanes) + 3 * a * kLanes + e % kLanes;
  }
  template <int N>
  EIGEN_ALWAYS_INLINE void put(std::size_t e, const std::array<int, N>*, const lanes3::Nodes<N>& fe, int) const {
    double* o = out + 3 * N * e;  // e: the batch's first cell, a multiple of kLanes
    RICOCHET_UNROLL
    for (int a = 0; a < N; ++a)
      RICOCHET_UNROLL
      for (int k = 0; k < 3; ++k)
#pragma omp simd
        for (int l = 0; l < kLanes; ++l) o[(3 * a + k) * kLanes + l] = fe.v[k][a][l];
  }
};

// The 3D force pass's outputs (internal_forces.cpp). On one thread the threaded pass adds its
// chunks' forces straight into f, the same bits as the store and the gather.
template <>
struct ForceOutput<3> {
  using Scatter = DirectScatter3;
  using Store = ElementStore3;
  static constexpr bool kScatterOnOneThread = true;
};

// A batch row is kLanes = 8 doubles, one 512-bit vector. Where the target has AVX-512
// (-march=native on such a machine), the kernels ask GCC for 512-bit vectors, one instruction a
// row where its default (256-bit, for the clock of older AVX-512 cores) takes two; the arithmetic
// of each lane is the same. Elsewhere it is empty.
#if defined(__AVX512F__) && defined(__GNUC__) && !defined(__clang__)
#define RICOCHET_KERNEL_VECTORS gnu::target("prefer-vector-width=512")
#else
#define RICOCHET_KERNEL_VECTORS
#endif

// ---------------------------------------------------------------------------------------------
// The kernels: force_kernel<kViscous>(block, material, u, v, out, pass, t, e0, e1) puts f_int(u,
// v) of the block's cells e0 <= e < e1 (all by default; e0 a multiple of kLanes) through `out`
// and adds their totals into t. A last partial batch computes its padding lanes; DirectScatter3
// drops them, ElementStore3 stores them in the block's padding.

// Tetrahedron: element3d.hpp's tet4_forces on lanes.
template <bool kViscous, class Pass, class Mat, class Out>
[[gnu::noinline, gnu::flatten, RICOCHET_KERNEL_VECTORS]] void force_kernel(
    const Tet4Block& b, const Mat& material, const double* u, const double*, const Out& out, const Pass& pass_in,
    ForceTotals& t, std::size_t e0 = 0, std::size_t e1 = SIZE_MAX) {
  const Mat mat = material;  // a local copy: its constants cannot alias f (element_kernels2.hpp)
  Pass pass = pass_in;
  double energy = 0.0;
  alignas(64) double min_j[kLanes];
  std::fill(min_j, min_j + kLanes, t.min_jacobian);
  LaneMat3 F, P;
  alignas(64) double det[kLanes];
  alignas(64) double may[kLanes] = {};
  const std::size_t end = std::min(e1, b.conn.size());
  for (std::size_t e = e0; e < end; e += kLanes) {
    const double* g = b.batch_geom(e / kLanes);
    lanes3::Nodes<4> ue, fe;
    lanes3::gather<4>(u, b.batch_conn(e / kLanes), ue);
#pragma omp simd
    for (int l = 0; l < kLanes; ++l)
      hex8wh::tet4_deformation_gradient(hex8wh::StridedNodes<4, kLanes>{&ue.v[0][0][l]}, hex8wh::lane_in(g + l),
                                        hex8wh::lane_out(&F.m[0][l]));
    determinant_lanes(F, det);
    first_piola_lanes(mat, F, P);
#pragma omp simd
    for (int l = 0; l < kLanes; ++l)
      hex8wh::tet4_forces(hex8wh::lane_in(&P.m[0][l]), hex8wh::lane_in(g + l), hex8wh::lane_out(&fe.v[0][0][l]));
    lanes3::min_into(min_j, det);
    if constexpr (Pass::kPerPoint) pass.screen(mat, F, P, det, may);
    const double* vol = g + Tet4Lanes::kVol * kLanes;
    const int n = static_cast<int>(std::min<std::size_t>(kLanes, end - e));
    out.template put<4>(e, b.conn.data(), fe, n);
    const bool per_point = Pass::kPerPoint && (Pass::kEveryPoint || lanes3::any(may, kLanes));
    for (int l = 0; l < n; ++l) {
      const std::size_t c = e + l;
      const int cell = b.first_cell + static_cast<int>(c);
      if constexpr (Pass::kEnergy) energy += vol[l] * mat.energy_density(F.lane(l));
      if (per_point) {
        pass.begin_element();
        if (Pass::kEveryPoint || may[l] != 0.0)
          pass.template point<1>(mat, F.lane(l), det[l], typename Pass::Response{P.lane(l)}, nullptr, vol[l], cell,
                                 may[l] != 0.0);
        pass.template end_element<1>(c, cell);
      }
    }
  }
  t.strain_energy += energy;
  t.min_jacobian = *std::min_element(min_j, min_j + kLanes);
  pass.finish(t);
}

// Hexahedron, 2x2x2 points.
template <bool kViscous, class Pass, class Mat, class Out>
[[gnu::noinline, gnu::flatten, RICOCHET_KERNEL_VECTORS]] void force_kernel(
    const Hex8Block& b, const Mat& material, const double* u, const double*, const Out& out, const Pass& pass_in,
    ForceTotals& t, std::size_t e0 = 0, std::size_t e1 = SIZE_MAX) {
  const Mat mat = material;  // see above
  Pass pass = pass_in;
  double energy = 0.0;
  alignas(64) double min_j[kLanes];
  std::fill(min_j, min_j + kLanes, t.min_jacobian);
  LaneMat3 F[8], P[8];
  alignas(64) double h[72][kLanes];   // 8 du/dxi at the points, [9 q + 3 i + K]
  alignas(64) double gq[72][kLanes];  // G = vol P K^T at the points, [9 q + 3 i + K]
  alignas(64) double det[8][kLanes];
  alignas(64) double may[8][kLanes] = {};
  const std::size_t end = std::min(e1, b.conn.size());
  for (std::size_t e = e0; e < end; e += kLanes) {
    const double* g = b.batch_geom(e / kLanes);
    lanes3::Nodes<8> ue, fe;
    lanes3::gather<8>(u, b.batch_conn(e / kLanes), ue);
#pragma omp simd
    for (int l = 0; l < kLanes; ++l)
      hex8wh::reference_gradients(hex8wh::StridedNodes<8, kLanes>{&ue.v[0][0][l]}, hex8wh::lane_out(&h[0][l]));
    for (int q = 0; q < 8; ++q) {
      const double* gk = g + Hex8Lanes::k(q, 0, 0) * kLanes;
      const double* vol = g + Hex8Lanes::vol(q) * kLanes;
#pragma omp simd
      for (int l = 0; l < kLanes; ++l)
        hex8wh::deformation_gradient(hex8wh::lane_in(&h[9 * q][l]), hex8wh::lane_in(gk + l), hex8wh::lane_out(&F[q].m[0][l]));
      determinant_lanes(F[q], det[q]);
      first_piola_lanes(mat, F[q], P[q]);
#pragma omp simd
      for (int l = 0; l < kLanes; ++l)
        hex8wh::point_force_coefficients(hex8wh::lane_in(&P[q].m[0][l]), vol[l], hex8wh::lane_in(gk + l),
                                         hex8wh::lane_out(&gq[9 * q][l]));
      lanes3::min_into(min_j, det[q]);
      if constexpr (Pass::kPerPoint) pass.screen(mat, F[q], P[q], det[q], may[q]);
    }
#pragma omp simd
    for (int l = 0; l < kLanes; ++l) hex8wh::reference_forces(hex8wh::lane_in(&gq[0][l]), hex8wh::lane_out(&fe.v[0][0][l]));
    const int n = static_cast<int>(std::min<std::size_t>(kLanes, end - e));
    out.template put<8>(e, b.conn.data(), fe, n);
    const bool per_point = Pass::kPerPoint && (Pass::kEveryPoint || lanes3::any(may[0], 8 * kLanes));
    for (int l = 0; l < n; ++l) {
      const std::size_t c = e + l;
      const int cell = b.first_cell + static_cast<int>(c);
      if constexpr (Pass::kEnergy)
        for (int q = 0; q < 8; ++q) energy += g[Hex8Lanes::vol(q) * kLanes + l] * mat.energy_density(F[q].lane(l));
      if (per_point) {
        pass.begin_element();
        for (int q = 0; q < 8; ++q)
          if (Pass::kEveryPoint || may[q][l] != 0.0)
            pass.template point<8>(mat, F[q].lane(l), det[q][l], typename Pass::Response{P[q].lane(l)}, nullptr,
                                   g[Hex8Lanes::vol(q) * kLanes + l], cell, may[q][l] != 0.0);
        pass.template end_element<8>(c, cell);
      }
    }
  }
  t.strain_energy += energy;
  t.min_jacobian = *std::min_element(min_j, min_j + kLanes);
  pass.finish(t);
}

// One-point hexahedron with Flanagan-Belytschko hourglass control (see the top of the file).
template <bool kViscous, class Pass, class Mat, class Out>
[[gnu::noinline, gnu::flatten, RICOCHET_KERNEL_VECTORS]] void force_kernel(
    const Hex8OnePointBlock& b, const Mat& material, const double* u, const double* v, const Out& out,
    const Pass& pass_in, ForceTotals& t, std::size_t e0 = 0, std::size_t e1 = SIZE_MAX) {
  using L = Hex8OnePointLanes;
  const Mat mat = material;  // see above
  Pass pass = pass_in;
  double energy = 0.0, hg_energy = 0.0, hg_power = 0.0;
  alignas(64) double min_j[kLanes];
  std::fill(min_j, min_j + kLanes, t.min_jacobian);
  LaneMat3 F, P;
  alignas(64) double hu[9][kLanes];  // H = u B (the stiffness form's hourglass modes use it)
  alignas(64) double det[kLanes], work[kLanes];
  alignas(64) double may[kLanes] = {};
  const std::size_t end = std::min(e1, b.conn.size());
  for (std::size_t e = e0; e < end; e += kLanes) {
    const double* g = b.batch_geom(e / kLanes);
    const int* conn = b.batch_conn(e / kLanes);
    lanes3::Nodes<8> ue, ve, fe;
    if constexpr (kViscous)
      lanes3::gather2<8>(u, v, conn, ue, ve);
    else
      lanes3::gather<8>(u, conn, ue);
#pragma omp simd
    for (int l = 0; l < kLanes; ++l) {
      if constexpr (kViscous)
        hex8wh::one_point_gradient(hex8wh::StridedNodes<8, kLanes>{&ue.v[0][0][l]}, hex8wh::lane_in(g + l), nullptr,
                                   hex8wh::lane_out(&F.m[0][l]));
      else
        hex8wh::one_point_gradient(hex8wh::StridedNodes<8, kLanes>{&ue.v[0][0][l]}, hex8wh::lane_in(g + l),
                                   hex8wh::lane_out(&hu[0][l]), hex8wh::lane_out(&F.m[0][l]));
    }
    determinant_lanes(F, det);
    first_piola_lanes(mat, F, P);
#pragma omp simd
    for (int l = 0; l < kLanes; ++l)
      work[l] = hex8wh::one_point_forces<kViscous>(
          hex8wh::lane_in(&P.m[0][l]), hex8wh::StridedNodes<8, kLanes>{kViscous ? &ve.v[0][0][l] : &ue.v[0][0][l]},
          hex8wh::lane_in(&hu[0][l]), hex8wh::lane_in(g + l), hex8wh::lane_out(&fe.v[0][0][l]));
    lanes3::min_into(min_j, det);
    if constexpr (Pass::kPerPoint) pass.screen(mat, F, P, det, may);
    const int n = static_cast<int>(std::min<std::size_t>(kLanes, end - e));
    out.template put<8>(e, b.conn.data(), fe, n);
    const bool per_point = Pass::kPerPoint && (Pass::kEveryPoint || lanes3::any(may, kLanes));
    for (int l = 0; l < n; ++l) {
      const std::size_t c = e + l;
      const int cell = b.first_cell + static_cast<int>(c);
      if constexpr (kViscous)
        hg_power += work[l];
      else if constexpr (Pass::kEnergy)
        hg_energy += 0.5 * work[l];
      if constexpr (Pass::kEnergy) energy += g[L::kVol * kLanes + l] * mat.energy_density(F.lane(l));
      if (per_point) {
        pass.begin_element();
        if (Pass::kEveryPoint || may[l] != 0.0)
          pass.template point<1>(mat, F.lane(l), det[l], typename Pass::Response{P.lane(l)}, nullptr,
                                 g[L::kVol * kLanes + l], cell, may[l] != 0.0);
        pass.template end_element<1>(c, cell);
      }
    }
  }
  t.strain_energy += energy;
  t.hourglass_energy += hg_energy;
  t.hourglass_power += hg_power;
  t.min_jacobian = *std::min_element(min_j, min_j + kLanes);
  pass.finish(t);
}

// For every cell in for_each_block's order: add(point(material, F, P, det F), reference volume,
// points) at each integration point, with F from the kernels' arithmetic (element_kernels3.hpp:
// the force pass's F, bit for bit) and P = mat.first_piola(F), then done(global cell, points):
// the contract of the 2D for_each_cell_points (element_kernels2.hpp).
template <class Point, class Add, class Done>
void for_each_cell_points(const Model<3>& model, const double* u, Point&& point, Add&& add, Done&& done) {
  for (const BlockKind3 kind : kBlockKinds3)
    for (std::size_t k = 0; k < model.num_blocks(kind); ++k)
      visit_block(model, kind, k, [&](const auto& b, const auto& mat, auto) {
        using Block = std::decay_t<decltype(b)>;
        for (std::size_t e = 0; e < b.conn.size(); ++e) {
          const int cell = b.first_cell + static_cast<int>(e);
          const Nodes3<Block::kNodes> ue = gather3<Block::kNodes>(u, b.conn[e]);
          if constexpr (std::is_same_v<Block, Hex8Block>) {
            std::array<Mat3, 8> F;
            hex8_point_gradients(b, e, ue, F);
            for (int q = 0; q < 8; ++q)
              add(point(mat, F[q], mat.first_piola(F[q]), F[q].determinant()), b.geom(e, Hex8Lanes::vol(q)),
                  std::integral_constant<int, 8>{});
            done(cell, std::integral_constant<int, 8>{});
          } else {
            Mat3 F;
            double vol;
            if constexpr (std::is_same_v<Block, Tet4Block>) {
              F = tet4_gradient(b, e, ue);
              vol = b.geom(e, Tet4Lanes::kVol);
            } else {
              F = hex8_one_point_gradient(b, e, ue);
              vol = b.geom(e, Hex8OnePointLanes::kVol);
            }
            add(point(mat, F, mat.first_piola(F), F.determinant()), vol, std::integral_constant<int, 1>{});
            done(cell, std::integral_constant<int, 1>{});
          }
        }
      });
}

}  // namespace ricochet
