// The element kernels, written once for both element passes: the forces of every step
// (internal_forces.cpp) and the implicit iteration matrix with the forces (tangent.cpp).
// Per element type, one kernel holds its formulation: the integration points (shape-function
// gradients dN/dX and volume weights, which carry the Gauss weights and the thickness:
// model.cpp), the kinematics at a point (gather -> F = I + ue^T dN/dX), the internal force
// fe = sum vol dN/dX P^T plus the Flanagan-Belytschko hourglass forces of one-point Q4, the
// scatter into f, the energies and the smallest det F. The pass supplies the material response
// at a point (first_piola, or first_piola_and_tangent for the tangent; plane stress and strain
// are inside the material law) and what it does besides the forces: stress tracking or the
// element matrix. element_kernel() goes cell by cell (the tangent); force_kernel(), below, is
// the same formulation on kLanes cells at once (the force pass).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <variant>

#include "solver/forces/internal_forces.hpp"
#include "solver/elements/kinematics.hpp"
#include "solver/materials/material_lanes.hpp"
#include "solver/model/model.hpp"

namespace ricochet {

// Where a kernel puts each cell's nodal forces fe (N x 2): added into the global array f
// (DirectScatter), or stored at the cell's place in a buffer of 2N values per cell
// (ElementStore: the threaded force pass, which sums them per node afterwards).
struct DirectScatter {
  double* f;
  template <int N>
  EIGEN_ALWAYS_INLINE void put(std::size_t, const std::array<int, N>& c, const Eigen::Matrix<double, N, 2>& fe) const {
    scatter<N>(f, c, fe);
  }
};
struct ElementStore {
  double* out;  // this block's first cell's entries
  static constexpr int kStride = 1;  // from an entry's x to its y
  // Cell e's node i's x among its block's entries; the entries of `cells` cells.
  template <int N>
  static constexpr std::size_t entry(std::size_t e, int i) {
    return 2 * N * e + 2 * i;
  }
  template <int N>
  static constexpr std::size_t size(std::size_t cells) {
    return 2 * N * cells;
  }
  template <int N>
  EIGEN_ALWAYS_INLINE void put(std::size_t e, const std::array<int, N>&, const Eigen::Matrix<double, N, 2>& fe) const {
    double* o = out + 2 * N * e;
    for (int i = 0; i < N; ++i) {
      o[2 * i] = fe(i, 0);
      o[2 * i + 1] = fe(i, 1);
    }
  }
};

// The 2D force pass's outputs (internal_forces.cpp). On one thread the threaded pass stores and
// gathers as on several, so that its forces are the same bits whatever the number of threads.
template <>
struct ForceOutput<2> {
  using Scatter = DirectScatter;
  using Store = ElementStore;
  static constexpr bool kScatterOnOneThread = false;
};

// The element kernels: element_kernel<kViscous>(block, material, u, v, out, pass, t, e0, e1)
// puts f_int(u, v) of the block's cells e0 <= e < e1 (all by default) through `out` and adds
// their totals into t (the strain energy and the
// stored hourglass energy only with Pass::kEnergy; the hourglass power; the smallest det F).
// `pass` is copied, so that its state stays in registers; it provides
//   static constexpr bool kEnergy
//   response(mat, F) -> r                 the material response at a point, r.P = P(F)
//   begin_element()                       before the pass's work on a cell
//   point<kPoints>(mat, F, det_f, r, dN/dX, vol, cell)   at each integration point, after
//                                         its force (kPoints: points per cell)
//   hourglass(gamma, c, viscous)          after the hourglass force (Q4 one-point)
//   end_element<kPoints>(e, cell)         after the scatter of the cell's forces
//   finish(t)                             after the block
// Each instantiation (element x material x pass) is its own function, so the material law
// inlines into its loop: instantiated inline into the block loop, four materials exhausted
// GCC's inlining budget and the force kernels ran 3x slower.
// Where each statement stands is part of the results and of the speed: it decides which
// products GCC fuses into FMAs in the energy sums (-march=native) and how the registers are
// allocated, so moving a statement can change the energies in the last bits or slow a kernel
// (bench/bench_element_forces.cpp).

// T3: constant gradients, one point.
template <bool kViscous, class Pass, class Mat, class Out>
[[gnu::noinline, gnu::flatten]] void element_kernel(const T3Block& b, const Mat& material, const double* u,
                                                    const double*, const Out& out, const Pass& pass_in,
                                                    ForceTotals& t, std::size_t e0 = 0,
                                                    std::size_t e1 = SIZE_MAX) {
  const Mat mat = material;  // a local copy: its constants cannot alias f, so they stay in registers
  Pass pass = pass_in;
  double energy = 0.0, min_j = t.min_jacobian;
  for (std::size_t e = e0, end = std::min(e1, b.conn.size()); e < end; ++e) {
    const T3Geom& g = b.geom[e];
    const Grad3 ue = gather<3>(u, b.conn[e]);
    const Mat2 F = deformation_gradient<3>(ue, g.dndx);
    const double det_f = F.determinant();
    min_j = std::min(min_j, det_f);
    const auto r = pass.response(mat, F);
    out.template put<3>(e, b.conn[e], g.vol * g.dndx * r.P.transpose());
    if constexpr (Pass::kEnergy) energy += g.vol * mat.energy_density(F);
    const int cell = b.first_cell + static_cast<int>(e);
    pass.begin_element();
    pass.template point<1>(mat, F, det_f, r, g.dndx, g.vol, cell);
    pass.template end_element<1>(e, cell);
  }
  t.strain_energy += energy;
  t.min_jacobian = min_j;
  pass.finish(t);
}

// Q4 2x2: the four Gauss points.
template <bool kViscous, class Pass, class Mat, class Out>
[[gnu::noinline, gnu::flatten]] void element_kernel(const Q4FullBlock& b, const Mat& material, const double* u,
                                                    const double*, const Out& out, const Pass& pass_in,
                                                    ForceTotals& t, std::size_t e0 = 0,
                                                    std::size_t e1 = SIZE_MAX) {
  const Mat mat = material;  // see above
  Pass pass = pass_in;
  double energy = 0.0, min_j = t.min_jacobian;
  for (std::size_t e = e0, end = std::min(e1, b.conn.size()); e < end; ++e) {
    const Q4FullGeom& g = b.geom[e];
    const Grad4 ue = gather<4>(u, b.conn[e]);
    const int cell = b.first_cell + static_cast<int>(e);
    Grad4 fe = Grad4::Zero();
    pass.begin_element();
    for (int q = 0; q < 4; ++q) {
      const Mat2 F = deformation_gradient<4>(ue, g.dndx[q]);
      const double det_f = F.determinant();
      min_j = std::min(min_j, det_f);
      const auto r = pass.response(mat, F);
      fe.noalias() += g.vol[q] * g.dndx[q] * r.P.transpose();
      if constexpr (Pass::kEnergy) energy += g.vol[q] * mat.energy_density(F);
      pass.template point<4>(mat, F, det_f, r, g.dndx[q], g.vol[q], cell);
    }
    out.template put<4>(e, b.conn[e], fe);
    pass.template end_element<4>(e, cell);
  }
  t.strain_energy += energy;
  t.min_jacobian = min_j;
  pass.finish(t);
}

// Q4 one-point: the mean gradients at the centroid, plus Flanagan-Belytschko hourglass forces
// q = sum_I gamma_I a_I, Q = c q, f_I += gamma_I Q (model.hpp), with a = v (viscous) or u.
template <bool kViscous, class Pass, class Mat, class Out>
[[gnu::noinline, gnu::flatten]] void element_kernel(const Q4HourglassBlock& b, const Mat& material,
                                                    const double* u, const double* v, const Out& out,
                                                    const Pass& pass_in, ForceTotals& t, std::size_t e0 = 0,
                                                    std::size_t e1 = SIZE_MAX) {
  const Mat mat = material;  // see above
  Pass pass = pass_in;
  double energy = 0.0, hg_energy = 0.0, hg_power = 0.0, min_j = t.min_jacobian;
  for (std::size_t e = e0, end = std::min(e1, b.conn.size()); e < end; ++e) {
    const Q4HourglassGeom& g = b.geom[e];
    const Grad4 ue = gather<4>(u, b.conn[e]);
    const Mat2 F = deformation_gradient<4>(ue, g.dndx);
    const double det_f = F.determinant();
    min_j = std::min(min_j, det_f);
    const auto r = pass.response(mat, F);
    Grad4 fe = g.vol * g.dndx * r.P.transpose();
    const int cell = b.first_cell + static_cast<int>(e);
    pass.begin_element();
    pass.template point<1>(mat, F, det_f, r, g.dndx, g.vol, cell);
    if constexpr (kViscous) {
      const Vec2 qdot = gather<4>(v, b.conn[e]).transpose() * g.gamma;
      const Vec2 Q = g.hourglass_coeff * qdot;
      fe.noalias() += g.gamma * Q.transpose();
      hg_power += Q.dot(qdot);
    } else {
      const Vec2 q = ue.transpose() * g.gamma;
      fe.noalias() += g.gamma * (g.hourglass_coeff * q).transpose();
      if constexpr (Pass::kEnergy) hg_energy += 0.5 * g.hourglass_coeff * q.squaredNorm();
    }
    pass.hourglass(g.gamma, g.hourglass_coeff, kViscous);
    out.template put<4>(e, b.conn[e], fe);
    pass.template end_element<1>(e, cell);
    if constexpr (Pass::kEnergy) energy += g.vol * mat.energy_density(F);
  }
  t.strain_energy += energy;
  t.hourglass_energy += hg_energy;
  t.hourglass_power += hg_power;
  t.min_jacobian = min_j;
  pass.finish(t);
}

// ---------------------------------------------------------------------------------------------
// The vectorized force kernels: force_kernel<kViscous>(block, material, u, v, out, pass, t, e0,
// e1) does what element_kernel does with the force pass, kLanes cells at a time, from the
// block's batches in structure-of-arrays form (ElementBlock::lane_conn, lane_geom): the gather,
// F, the material law (material_lanes.hpp) and the nodal forces run on all lanes at once; then,
// lane by lane in cell order, the forces go out and the pass's per-point work and the energy
// sums run, so every sum keeps the serial kernel's order. Each lane's arithmetic is the serial
// kernel's, Eigen's FMAs included (material_lanes.hpp): (vol dN/dX P^T)_ij =
// fma(vol dN_i1, P_j1, vol dN_i0 P_j0) for four-node cells and the first two rows of a
// triangle, the plain sum for its third row; sum_I gamma_I a_I is summed pairwise,
// (a_0 g_0 + a_2 g_2) + (a_1 g_1 + a_3 g_3). e0 is a multiple of kLanes (the threaded pass's
// chunks are); a last partial batch computes its padding lanes and drops them.
// The pass provides element_kernel's contract without response() and hourglass() (the kernel
// evaluates the law with first_piola_lanes and passes P as Pass::Response{P}), with point()
// taking one more argument, `may`, and:
//   kPerPoint                          whether point(), begin_element() and end_element() do
//                                      anything
//   screen(mat, F, P, det, may)        on all lanes of a point: may[l] = 1.0 where point()
//                                      has work (the cheap stress bound), else 0.0
//   kEveryPoint                        point() at every point, not only where may[l] = 1.0

namespace lanes {

template <int N>
struct Nodes {
  alignas(64) double x[N][kLanes];
  alignas(64) double y[N][kLanes];
};

template <int N>
EIGEN_ALWAYS_INLINE void gather(const double* a, const int* conn, Nodes<N>& n) {
  for (int i = 0; i < N; ++i)
#pragma omp simd
    for (int l = 0; l < kLanes; ++l) {
      const int c = conn[i * kLanes + l];
      n.x[i][l] = a[2 * c];
      n.y[i][l] = a[2 * c + 1];
    }
}

// F = I + ue^T dN/dX at a point whose gradients dN/dX (I, J) are at g[(2I + J) kLanes + l]
// (deformation_gradient's order).
template <int N>
EIGEN_ALWAYS_INLINE void deformation_gradient(const Nodes<N>& ue, const double* g, LaneMat2& F) {
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) {
    double f00 = 1.0, f01 = 0.0, f10 = 0.0, f11 = 1.0;
    for (int I = 0; I < N; ++I) {
      const double d0 = g[(2 * I) * kLanes + l], d1 = g[(2 * I + 1) * kLanes + l];
      f00 += ue.x[I][l] * d0;
      f10 += ue.y[I][l] * d0;
      f01 += ue.x[I][l] * d1;
      f11 += ue.y[I][l] * d1;
    }
    F.m00[l] = f00;
    F.m01[l] = f01;
    F.m10[l] = f10;
    F.m11[l] = f11;
  }
}

// fe += vol dN/dX P^T (kFirst: fe = ...). kFused: Eigen's FMA form (see above).
template <int N, bool kFirst>
EIGEN_ALWAYS_INLINE void add_point_forces(const double* g, const double* vol, const LaneMat2& P, Nodes<N>& fe) {
  for (int i = 0; i < N; ++i) {
    const bool fused = N == 4 || i < 2;
#pragma omp simd
    for (int l = 0; l < kLanes; ++l) {
      const double a0 = vol[l] * g[(2 * i) * kLanes + l], a1 = vol[l] * g[(2 * i + 1) * kLanes + l];
      const double x = fused ? std::fma(a1, P.m01[l], a0 * P.m00[l]) : a0 * P.m00[l] + a1 * P.m01[l];
      const double y = fused ? std::fma(a1, P.m11[l], a0 * P.m10[l]) : a0 * P.m10[l] + a1 * P.m11[l];
      if constexpr (kFirst) {
        fe.x[i][l] = x;
        fe.y[i][l] = y;
      } else {
        fe.x[i][l] = fe.x[i][l] + x;
        fe.y[i][l] = fe.y[i][l] + y;
      }
    }
  }
}

template <int N>
EIGEN_ALWAYS_INLINE Eigen::Matrix<double, N, 2> lane_rows(const Nodes<N>& n, int l) {
  Eigen::Matrix<double, N, 2> m;
  for (int i = 0; i < N; ++i) {
    m(i, 0) = n.x[i][l];
    m(i, 1) = n.y[i][l];
  }
  return m;
}

// Whether any of the n values is non-zero.
EIGEN_ALWAYS_INLINE bool any(const double* x, int n) {
  double s = 0.0;
#pragma omp simd reduction(+ : s)
  for (int i = 0; i < n; ++i) s += x[i];
  return s != 0.0;
}

EIGEN_ALWAYS_INLINE void min_into(double* min_j, const double* det) {
#pragma omp simd
  for (int l = 0; l < kLanes; ++l) min_j[l] = std::min(min_j[l], det[l]);
}

}  // namespace lanes

// T3 and Q4 2x2: kQ points per cell (T3: 1, its gradients and volume the cell's).
template <bool kViscous, class Pass, class Mat, class Out, int N, class Geom>
[[gnu::noinline, gnu::flatten]] void force_kernel(const ElementBlock<N, Geom>& b, const Mat& material,
                                                  const double* u, const double*, const Out& out,
                                                  const Pass& pass_in, ForceTotals& t, std::size_t e0 = 0,
                                                  std::size_t e1 = SIZE_MAX) {
  constexpr int kQ = std::is_same_v<Geom, Q4FullGeom> ? 4 : 1;
  constexpr int kPointValues = 2 * N + 1;  // a point's gradients and volume in lane_geom
  const Mat mat = material;  // see element_kernel
  Pass pass = pass_in;
  double energy = 0.0;
  alignas(64) double min_j[kLanes];
  std::fill(min_j, min_j + kLanes, t.min_jacobian);
  LaneMat2 F[kQ], P[kQ];
  alignas(64) double det[kQ][kLanes];
  alignas(64) double may[kQ][kLanes] = {};  // 1: the pass's point() has work (screen)
  const std::size_t end = std::min(e1, b.conn.size());
  for (std::size_t e = e0; e < end; e += kLanes) {
    const double* g = b.batch_geom(e / kLanes);
    lanes::Nodes<N> ue, fe;
    lanes::gather<N>(u, b.batch_conn(e / kLanes), ue);
    for (int q = 0; q < kQ; ++q) {
      const double* gq = g + q * kPointValues * kLanes;
      lanes::deformation_gradient<N>(ue, gq, F[q]);
      determinant_lanes(F[q], det[q]);
      lanes::min_into(min_j, det[q]);
      first_piola_lanes(mat, F[q], P[q]);
      if constexpr (Pass::kPerPoint) pass.screen(mat, F[q], P[q], det[q], may[q]);
      if (q == 0)
        lanes::add_point_forces<N, true>(gq, gq + 2 * N * kLanes, P[q], fe);
      else
        lanes::add_point_forces<N, false>(gq, gq + 2 * N * kLanes, P[q], fe);
    }
    const int n = static_cast<int>(std::min<std::size_t>(kLanes, end - e));
    // The pass's per-cell work only in a batch where some point has any (most batches of a
    // step have none: the points are below the run's stress peak so far).
    const bool per_point = Pass::kPerPoint && (Pass::kEveryPoint || lanes::any(may[0], kQ * kLanes));
    for (int l = 0; l < n; ++l) {
      const std::size_t c = e + l;
      const int cell = b.first_cell + static_cast<int>(c);
      if (per_point) {
        pass.begin_element();
        for (int q = 0; q < kQ; ++q)
          if (Pass::kEveryPoint || may[q][l] != 0.0)
            pass.template point<kQ>(mat, F[q].lane(l), det[q][l], typename Pass::Response{P[q].lane(l)}, nullptr,
                                    g[(q * kPointValues + 2 * N) * kLanes + l], cell, may[q][l] != 0.0);
      }
      if constexpr (Pass::kEnergy)
        for (int q = 0; q < kQ; ++q) energy += g[(q * kPointValues + 2 * N) * kLanes + l] * mat.energy_density(F[q].lane(l));
      out.template put<N>(c, b.conn[c], lanes::lane_rows<N>(fe, l));
      if (per_point) pass.template end_element<kQ>(c, cell);
    }
  }
  t.strain_energy += energy;
  t.min_jacobian = *std::min_element(min_j, min_j + kLanes);
  pass.finish(t);
}

// Q4 one-point with Flanagan-Belytschko hourglass control (element_kernel's third kernel).
template <bool kViscous, class Pass, class Mat, class Out>
[[gnu::noinline, gnu::flatten]] void force_kernel(const Q4HourglassBlock& b, const Mat& material, const double* u,
                                                  const double* v, const Out& out, const Pass& pass_in,
                                                  ForceTotals& t, std::size_t e0 = 0, std::size_t e1 = SIZE_MAX) {
  const Mat mat = material;  // see element_kernel
  Pass pass = pass_in;
  double energy = 0.0, hg_energy = 0.0, hg_power = 0.0;
  alignas(64) double min_j[kLanes];
  std::fill(min_j, min_j + kLanes, t.min_jacobian);
  LaneMat2 F, P;
  alignas(64) double det[kLanes], qx[kLanes], qy[kLanes], Qx[kLanes], Qy[kLanes];
  alignas(64) double may[kLanes] = {};
  const std::size_t end = std::min(e1, b.conn.size());
  for (std::size_t e = e0; e < end; e += kLanes) {
    const double* g = b.batch_geom(e / kLanes);
    const double* gamma = g + 8 * kLanes;
    const double* vol = g + 12 * kLanes;
    const double* coeff = g + 13 * kLanes;
    const int* conn = b.batch_conn(e / kLanes);
    lanes::Nodes<4> ue, fe;
    lanes::gather<4>(u, conn, ue);
    lanes::deformation_gradient<4>(ue, g, F);
    determinant_lanes(F, det);
    lanes::min_into(min_j, det);
    first_piola_lanes(mat, F, P);
    if constexpr (Pass::kPerPoint) pass.screen(mat, F, P, det, may);
    lanes::add_point_forces<4, true>(g, vol, P, fe);
    // q = sum_I gamma_I a_I, Q = c q, f_I += gamma_I Q.
    lanes::Nodes<4> va;
    if constexpr (kViscous) lanes::gather<4>(v, conn, va);
    const lanes::Nodes<4>& a = kViscous ? va : ue;
#pragma omp simd
    for (int l = 0; l < kLanes; ++l) {
      const double g0 = gamma[l], g1 = gamma[kLanes + l], g2 = gamma[2 * kLanes + l], g3 = gamma[3 * kLanes + l];
      qx[l] = (a.x[0][l] * g0 + a.x[2][l] * g2) + (a.x[1][l] * g1 + a.x[3][l] * g3);
      qy[l] = (a.y[0][l] * g0 + a.y[2][l] * g2) + (a.y[1][l] * g1 + a.y[3][l] * g3);
      Qx[l] = coeff[l] * qx[l];
      Qy[l] = coeff[l] * qy[l];
    }
    for (int i = 0; i < 4; ++i)
#pragma omp simd
      for (int l = 0; l < kLanes; ++l) {
        fe.x[i][l] = fe.x[i][l] + gamma[i * kLanes + l] * Qx[l];
        fe.y[i][l] = fe.y[i][l] + gamma[i * kLanes + l] * Qy[l];
      }
    const int n = static_cast<int>(std::min<std::size_t>(kLanes, end - e));
    const bool per_point = Pass::kPerPoint && (Pass::kEveryPoint || lanes::any(may, kLanes));  // see above
    for (int l = 0; l < n; ++l) {
      const std::size_t c = e + l;
      const int cell = b.first_cell + static_cast<int>(c);
      if (per_point) {
        pass.begin_element();
        if (Pass::kEveryPoint || may[l] != 0.0)
          pass.template point<1>(mat, F.lane(l), det[l], typename Pass::Response{P.lane(l)}, nullptr, vol[l], cell,
                                 may[l] != 0.0);
      }
      if constexpr (kViscous)
        hg_power += Qx[l] * qx[l] + Qy[l] * qy[l];
      else if constexpr (Pass::kEnergy)
        hg_energy += 0.5 * coeff[l] * (qx[l] * qx[l] + qy[l] * qy[l]);
      out.template put<4>(c, b.conn[c], lanes::lane_rows<4>(fe, l));
      if (per_point) pass.template end_element<1>(c, cell);
      if constexpr (Pass::kEnergy) energy += vol[l] * mat.energy_density(F.lane(l));
    }
  }
  t.strain_energy += energy;
  t.hourglass_energy += hg_energy;
  t.hourglass_power += hg_power;
  t.min_jacobian = *std::min_element(min_j, min_j + kLanes);
  pass.finish(t);
}

// For every cell: add(point(material, F, P, det F), reference volume [m^3], points) at each of
// its integration points, F at the point and P = mat.first_piola(F), then done(global cell,
// points), `points` the cell's number of integration points as a std::integral_constant (so that
// a one-point cell's reduction compiles to nothing). For the stress passes of
// internal_forces_impl.hpp, which reduce the points of a cell as they come (no array of values). The one-point cells (Q4 with hourglass control, T3)
// first, then the Q4 with 2x2 points.
template <class Point, class Add, class Done>
void for_each_cell_points(const Model<2>& model, const double* u, Point&& point, Add&& add, Done&& done) {
  for (const BlockKind kind : {BlockKind::q4_hourglass, BlockKind::t3, BlockKind::q4_full})
    for (std::size_t k = 0; k < model.num_blocks(kind); ++k)
      visit_block(model, kind, k, [&](const auto& b, const auto& mat, auto) {
        constexpr int N = std::tuple_size_v<typename std::decay_t<decltype(b.conn)>::value_type>;
        for (std::size_t e = 0; e < b.conn.size(); ++e) {
          const int cell = b.first_cell + static_cast<int>(e);
          if constexpr (std::is_same_v<std::decay_t<decltype(b)>, Q4FullBlock>) {
            const Grad4 ue = gather<4>(u, b.conn[e]);
            for (int q = 0; q < 4; ++q) {
              const Mat2 F = deformation_gradient<4>(ue, b.geom[e].dndx[q]);
              add(point(mat, F, mat.first_piola(F), F.determinant()), b.geom[e].vol[q], std::integral_constant<int, 4>{});
            }
            done(cell, std::integral_constant<int, 4>{});
          } else {
            const Mat2 F = deformation_gradient<N>(gather<N>(u, b.conn[e]), b.geom[e].dndx);
            add(point(mat, F, mat.first_piola(F), F.determinant()), b.geom[e].vol, std::integral_constant<int, 1>{});
            done(cell, std::integral_constant<int, 1>{});
          }
        }
      });
}

}  // namespace ricochet
