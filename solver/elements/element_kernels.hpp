// The element kernels, written once for both element passes: the forces of every step
// (internal_forces.cpp) and the implicit iteration matrix with the forces (tangent.cpp).
// Per element type, one kernel holds its formulation: the integration points (shape-function
// gradients dN/dX and volume weights, which carry the Gauss weights and the thickness:
// model.cpp), the kinematics at a point (gather -> F = I + ue^T dN/dX), the internal force
// fe = sum vol dN/dX P^T plus the Flanagan-Belytschko hourglass forces of one-point Q4, the
// scatter into f, the energies and the smallest det F. The pass supplies the material response
// at a point (first_piola, or first_piola_and_tangent for the tangent; plane stress and strain
// are inside the material law) and what it does besides the forces: stress tracking or the
// element matrix.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <variant>

#include "solver/elements/internal_forces.hpp"
#include "solver/elements/kinematics.hpp"
#include "solver/model/model.hpp"

namespace ricochet {

// Calls fn(block, material, std::bool_constant<viscous hourglass control>) for block k of
// `kind`, with its material's own type (the constant is false for the blocks without
// hourglass control).
template <class Fn>
void visit_block(const Model& model, BlockKind kind, std::size_t k, Fn&& fn) {
  switch (kind) {
    case BlockKind::q4_hourglass: {
      const Q4HourglassBlock& b = model.q4_hourglass[k];
      std::visit(
          [&](const auto& mat) {
            if (b.form == HourglassForm::viscous)
              fn(b, mat, std::true_type{});
            else
              fn(b, mat, std::false_type{});
          },
          b.material);
      return;
    }
    case BlockKind::q4_full:
      std::visit([&](const auto& mat) { fn(model.q4_full[k], mat, std::false_type{}); }, model.q4_full[k].material);
      return;
    case BlockKind::t3:
      std::visit([&](const auto& mat) { fn(model.t3[k], mat, std::false_type{}); }, model.t3[k].material);
      return;
  }
}

// visit_block for every element block, in the order every pass sums f_int (kBlockKinds).
template <class Fn>
void for_each_block(const Model& model, Fn&& fn) {
  for (const BlockKind kind : kBlockKinds)
    for (std::size_t k = 0; k < model.num_blocks(kind); ++k) visit_block(model, kind, k, fn);
}

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
  template <int N>
  EIGEN_ALWAYS_INLINE void put(std::size_t e, const std::array<int, N>&, const Eigen::Matrix<double, N, 2>& fe) const {
    double* o = out + 2 * N * e;
    for (int i = 0; i < N; ++i) {
      o[2 * i] = fe(i, 0);
      o[2 * i + 1] = fe(i, 1);
    }
  }
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

}  // namespace ricochet
