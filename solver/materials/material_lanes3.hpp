// The 3D material laws (material3d.hpp) on kLanes deformation gradients at once, for the 3D
// force kernels (element_kernels3.hpp): first_piola_lanes(mat, F, P) sets P = mat.first_piola(F)
// lane by lane with the same arithmetic, so the two give the same bits in a build without
// floating-point contraction (-ffp-contract=off, as ci/compare_results builds); with contraction
// the compiler may fuse a product into an addition differently in the two codes (a few ulps;
// tests/solver/forces/test_internal_forces3.cpp).
//
// St Venant-Kirchhoff's arithmetic is written once, in material3d.hpp (svk_first_piola3), and
// both first_piola() and the lanes run it: Eigen evaluates a 3 x 3 product in an order and with
// fused multiply-adds of its own choosing (measured: neither p0 + (p1 + p2) nor (p0 + p1) + p2
// for every entry), which a lane loop cannot follow. Neo-Hookean is written out per lane from
// material3d.cpp's entrywise formula (its logarithm stays scalar: the C library has no vector
// log that gives the scalar function's bits); Blatz-Ko and Mooney-Rivlin call their scalar law
// per lane, as in 2D (material_lanes.hpp).
#pragma once

#include <algorithm>
#include <cmath>

#include "solver/materials/material3d.hpp"
#include "solver/materials/stress.hpp"

// Complete unrolling of a loop of constant trip count inside a lane loop (`#pragma omp simd`):
// GCC vectorizes a lane loop only if its body is straight-line code by then, and its own
// unrolling heuristics stop short of these bodies (the 3D kernels' 8 points, 24 coefficients).
#define RICOCHET_UNROLL _Pragma("GCC unroll 128")

namespace ricochet {

// kLanes 3x3 matrices side by side: m[3 i + j][l] is entry (i, j) of lane l.
struct LaneMat3 {
  alignas(64) double m[9][kLanes];

  Mat3 lane(int l) const {
    Mat3 a;
    RICOCHET_UNROLL
    for (int i = 0; i < 3; ++i)
      RICOCHET_UNROLL
      for (int j = 0; j < 3; ++j) a(i, j) = m[3 * i + j][l];
    return a;
  }
  void set(int l, const Mat3& a) {
    RICOCHET_UNROLL
    for (int i = 0; i < 3; ++i)
      RICOCHET_UNROLL
      for (int j = 0; j < 3; ++j) m[3 * i + j][l] = a(i, j);
  }
};

// The per-lane arithmetic below reads and writes through pointers with a stride S: a lane
// loop passes &a[0][l] of lane-major arrays (S = kLanes), so that every access is a[k][l] of an
// array outside the loop and the loop vectorizes (a local array inside a `#pragma omp simd` body
// is privatized per lane, and GCC 12 then gives up on the loop); one cell passes plain arrays
// (S = 1). Loops inside are unrolled (RICOCHET_UNROLL) for the same reason.

// det F as Eigen's 3x3 determinant (Determinant.h): F00 (F11 F22 - F12 F21) - F01 (F10 F22 -
// F12 F20) + F02 (F10 F21 - F11 F20), from the nine entries (row-major, f[S k]).
template <int S>
EIGEN_ALWAYS_INLINE double determinant3(const double* f) {
  auto F = [&](int k) { return f[S * k]; };
  return F(0) * (F(4) * F(8) - F(5) * F(7)) - F(1) * (F(3) * F(8) - F(5) * F(6)) + F(2) * (F(3) * F(7) - F(4) * F(6));
}

EIGEN_ALWAYS_INLINE void determinant_lanes(const LaneMat3& F, double* det) {
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) det[l] = determinant3<kLanes>(&F.m[0][l]);
}

// Any 3D law: its scalar law, lane by lane.
template <class Mat>
EIGEN_ALWAYS_INLINE void first_piola_lanes(const Mat& mat, const LaneMat3& F, LaneMat3& P) {
  for (int l = 0; l < kLanes; ++l) P.set(l, mat.first_piola(F.lane(l)));
}

// St Venant-Kirchhoff: material3d.hpp's svk_first_piola3, the arithmetic of first_piola().
template <int S>
EIGEN_ALWAYS_INLINE void first_piola_lane(const StVenantKirchhoff3& mat, const double* f, double* p) {
  svk_first_piola3<S>(mat.lambda, mat.shear_modulus, f, p);
}

EIGEN_ALWAYS_INLINE void first_piola_lanes(const StVenantKirchhoff3& mat, const LaneMat3& F, LaneMat3& P) {
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) first_piola_lane<kLanes>(mat, &F.m[0][l], &P.m[0][l]);
}

// Neo-Hookean (material3d.cpp): H = cof F, J = F00 H00 + F01 H01 + F02 H02,
// P = mu F + ((lambda ln J - mu) / J) H.
template <int S>
EIGEN_ALWAYS_INLINE void cofactor3(const double* f, double* h) {
  auto F = [&](int k) { return f[S * k]; };
  h[S * 0] = F(4) * F(8) - F(5) * F(7);
  h[S * 1] = F(5) * F(6) - F(3) * F(8);
  h[S * 2] = F(3) * F(7) - F(4) * F(6);
  h[S * 3] = F(7) * F(2) - F(8) * F(1);
  h[S * 4] = F(8) * F(0) - F(6) * F(2);
  h[S * 5] = F(6) * F(1) - F(7) * F(0);
  h[S * 6] = F(1) * F(5) - F(2) * F(4);
  h[S * 7] = F(2) * F(3) - F(0) * F(5);
  h[S * 8] = F(0) * F(4) - F(1) * F(3);
}

EIGEN_ALWAYS_INLINE void first_piola_lanes(const NeoHookean3& mat, const LaneMat3& F, LaneMat3& P) {
  alignas(64) double j[kLanes], s[kLanes];
  LaneMat3 H;
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) {
    cofactor3<kLanes>(&F.m[0][l], &H.m[0][l]);
    j[l] = F.m[0][l] * H.m[0][l] + F.m[1][l] * H.m[1][l] + F.m[2][l] * H.m[2][l];
  }
  for (int l = 0; l < kLanes; ++l) s[l] = (mat.lambda * std::log(j[l]) - mat.shear_modulus) / j[l];
  const double mu = mat.shear_modulus;
#pragma omp simd
  for (int l = 0; l < kLanes; ++l)
    RICOCHET_UNROLL
    for (int k = 0; k < 9; ++k) P.m[k][l] = mu * F.m[k][l] + s[l] * H.m[k][l];
}

// von_mises_may_exceed (stress.hpp) on all lanes for measure kMeasure: may[l] = 1.0 where the
// point of lane l can exceed `threshold` [Pa^2], else 0.0. The same arithmetic as the scalar
// bound, which is conservative by 0.1 % anyway: a point that passes gets its exact value from
// the scalar code.
template <StressMeasure kMeasure>
EIGEN_ALWAYS_INLINE void von_mises_may_exceed_lanes(const LaneMat3& F, const LaneMat3& P, const double* det,
                                                    double threshold, double* may) {
  if (!(threshold > 0.0)) {
    std::fill(may, may + kLanes, 1.0);
    return;
  }
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) {
    double ff = 0.0, pp = 0.0;
    RICOCHET_UNROLL
    for (int k = 0; k < 9; ++k) {
      ff += F.m[k][l] * F.m[k][l];
      pp += P.m[k][l] * P.m[k][l];
    }
    const double j2 = det[l] * det[l];
    bool exceeds;
    if constexpr (kMeasure == StressMeasure::pk2)
      exceeds = 0.5005 * (pp * ff * ff) > threshold * j2;
    else if constexpr (kMeasure == StressMeasure::kirchhoff)
      exceeds = 1.5015 * (pp * ff) > threshold;
    else
      exceeds = 1.5015 * (pp * ff) > threshold * j2;
    may[l] = exceeds ? 1.0 : 0.0;
  }
}

}  // namespace ricochet
