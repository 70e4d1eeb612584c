// The material laws on kLanes deformation gradients at once, for the vectorized force kernels
// (element_kernels2.hpp): first_piola_lanes(mat, F, P) sets P = mat.first_piola(F) lane by lane,
// with the same arithmetic, so the two give the same bits.
//
// "The same arithmetic" includes Eigen's own fused multiply-adds: Eigen evaluates the 2x2
// product F S with FMA instructions (F S)_ij = fma(F_i1, S_1j, F_i0 S_0j) on a CPU that has
// them, whatever -ffp-contract says, so the lane code calls std::fma there. On such a CPU
// std::fma is one instruction and the loops vectorize; the tests compare both paths
// (tests/solver/forces/test_element_lanes.cpp).
//
// St Venant-Kirchhoff and neo-Hookean are written out per lane (the neo-Hookean logarithms
// and the plane-stress iteration stay scalar: the C library has no vector log or exp that
// gives the scalar functions' bits); Blatz-Ko and Mooney-Rivlin call their scalar law per lane.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "solver/materials/material.hpp"
#include "solver/materials/stress.hpp"

namespace ricochet {

// kLanes 2x2 matrices side by side: m00[l] is entry (0, 0) of lane l.
struct LaneMat2 {
  alignas(64) double m00[kLanes];
  alignas(64) double m01[kLanes];
  alignas(64) double m10[kLanes];
  alignas(64) double m11[kLanes];

  Mat2 lane(int l) const {
    Mat2 m;
    m << m00[l], m01[l], m10[l], m11[l];
    return m;
  }
  void set(int l, const Mat2& m) {
    m00[l] = m(0, 0);
    m01[l] = m(0, 1);
    m10[l] = m(1, 0);
    m11[l] = m(1, 1);
  }
};

// det F per lane, as Eigen's 2x2 determinant: F00 F11 - F10 F01.
EIGEN_ALWAYS_INLINE void determinant_lanes(const LaneMat2& F, double* det) {
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) det[l] = F.m00[l] * F.m11[l] - F.m10[l] * F.m01[l];
}

// Any material: its scalar law, lane by lane.
template <class Mat>
EIGEN_ALWAYS_INLINE void first_piola_lanes(const Mat& mat, const LaneMat2& F, LaneMat2& P) {
  for (int l = 0; l < kLanes; ++l) P.set(l, mat.first_piola(F.lane(l)));
}

// St Venant-Kirchhoff: E = (F^T F - I)/2, S = lambda tr(E) I + 2 mu E, P = F S.
EIGEN_ALWAYS_INLINE void first_piola_lanes(const StVenantKirchhoff& mat, const LaneMat2& F, LaneMat2& P) {
  const double mu2 = 2.0 * mat.shear_modulus, lambda = mat.lambda;
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) {
    const double a = F.m00[l], b = F.m01[l], c = F.m10[l], d = F.m11[l];
    const double e00 = 0.5 * ((a * a + c * c) - 1.0), e11 = 0.5 * ((b * b + d * d) - 1.0);
    const double e01 = 0.5 * (b * a + d * c), e10 = 0.5 * (a * b + c * d);
    const double ltr = lambda * (e00 + e11);
    const double s00 = mu2 * e00 + ltr, s11 = mu2 * e11 + ltr, s01 = mu2 * e01, s10 = mu2 * e10;
    P.m00[l] = std::fma(b, s10, a * s00);
    P.m01[l] = std::fma(b, s11, a * s01);
    P.m10[l] = std::fma(d, s10, c * s00);
    P.m11[l] = std::fma(d, s11, c * s01);
  }
}

// Neo-Hookean: P = mu F + (lambda ln J - mu) F^-T, ln J = ln det F + ln C33 / 2.
EIGEN_ALWAYS_INLINE void first_piola_lanes(const NeoHookean& mat, const LaneMat2& F, LaneMat2& P) {
  alignas(64) double j2[kLanes], beta[kLanes];
  determinant_lanes(F, j2);
  for (int l = 0; l < kLanes; ++l) {
    const double log_j = std::log(j2[l]) + 0.5 * mat.log_c33(std::log(j2[l]));
    beta[l] = mat.lambda * log_j - mat.shear_modulus;
  }
  const double mu = mat.shear_modulus;
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) {
    const double a = F.m00[l], b = F.m01[l], c = F.m10[l], d = F.m11[l];
    P.m00[l] = mu * a + beta[l] * (d / j2[l]);
    P.m01[l] = mu * b + beta[l] * (-c / j2[l]);
    P.m10[l] = mu * c + beta[l] * (-b / j2[l]);
    P.m11[l] = mu * d + beta[l] * (a / j2[l]);
  }
}

// von_mises_may_exceed (stress.hpp) lane by lane, for measure kMeasure: may[l] = 1.0 where
// the point of lane l can exceed `threshold` [Pa^2], else 0.0. The bound is conservative by
// 0.1 %, so a last-bit difference between the lane and the scalar arithmetic decides nothing:
// a point that passes gets its exact value from the scalar code.
template <StressMeasure kMeasure, class Mat>
EIGEN_ALWAYS_INLINE void von_mises_may_exceed_lanes(const Mat& mat, const LaneMat2& F, const LaneMat2& P,
                                                    const double* det, double threshold, double* may) {
  for (int l = 0; l < kLanes; ++l)
    may[l] = von_mises_may_exceed(mat, F.lane(l), P.lane(l), det[l], kMeasure, threshold) ? 1.0 : 0.0;
}

// St Venant-Kirchhoff: the out-of-plane state in closed form (material.hpp), no call.
template <StressMeasure kMeasure>
EIGEN_ALWAYS_INLINE void von_mises_may_exceed_lanes(const StVenantKirchhoff& mat, const LaneMat2& F,
                                                    const LaneMat2& P, const double* det, double threshold,
                                                    double* may) {
  if (!(threshold > 0.0)) {
    std::fill(may, may + kLanes, 1.0);
    return;
  }
  const bool strain = mat.plane == PlaneMode::strain;
  const double lambda_3d = strain ? mat.lambda_3d : 0.0, e33 = strain ? 0.0 : mat.e33_per_trace;
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) {
    const double a = F.m00[l], b = F.m01[l], c = F.m10[l], d = F.m11[l];
    const double ff = a * a + c * c + b * b + d * d;
    const double pf = (P.m00[l] * P.m00[l] + P.m10[l] * P.m10[l] + P.m01[l] * P.m01[l] + P.m11[l] * P.m11[l]) * ff;
    const double tr = 0.5 * (ff - 2.0);         // tr E (in-plane)
    const double s33 = lambda_3d * tr;          // S33: 0 in plane stress
    const double f33_2 = 1.0 + 2.0 * e33 * tr;  // F33^2: 1 in plane strain
    const double j2 = det[l] * det[l];
    double bound, limit;
    if constexpr (kMeasure == StressMeasure::pk2) {
      const double ds = det[l] * s33;
      bound = 1.5015 * (pf + ds * ds);
      limit = threshold * j2;
    } else {
      const double t33 = f33_2 * s33;
      bound = 1.5015 * (pf + t33 * t33);
      limit = kMeasure == StressMeasure::kirchhoff ? threshold : threshold * j2 * f33_2;
    }
    may[l] = bound > limit ? 1.0 : 0.0;
  }
}

}  // namespace ricochet
