#include "solver/internal_forces.hpp"

#include <algorithm>

#include "solver/kinematics.hpp"

namespace ricochet {
namespace {

// Each kernel instantiation (element x material x options) is its own function, so the
// material law inlines into its loop: instantiated inline into all_blocks, four materials
// exhausted GCC's inlining budget and the kernels ran 3x slower.

// Elements whose cells share one deformation gradient per integration point: T3 and Q4 2x2.
template <bool kEnergy, class Mat>
[[gnu::noinline]] void t3_forces(const T3Block& b, const Mat& mat, const double* u, double* f, ForceTotals& t) {
  double energy = 0.0, min_j = t.min_jacobian;
  for (std::size_t e = 0; e < b.conn.size(); ++e) {
    const T3Geom& g = b.geom[e];
    const Grad3 ue = gather<3>(u, b.conn[e]);
    const Mat2 F = deformation_gradient<3>(ue, g.dndx);
    min_j = std::min(min_j, F.determinant());
    const Mat2 P = mat.first_piola(F);
    scatter<3>(f, b.conn[e], g.vol * g.dndx * P.transpose());
    if constexpr (kEnergy) energy += g.vol * mat.energy_density(F);
  }
  t.strain_energy += energy;
  t.min_jacobian = min_j;
}

template <bool kEnergy, class Mat>
[[gnu::noinline]] void q4_full_forces(const Q4FullBlock& b, const Mat& mat, const double* u, double* f, ForceTotals& t) {
  double energy = 0.0, min_j = t.min_jacobian;
  for (std::size_t e = 0; e < b.conn.size(); ++e) {
    const Q4FullGeom& g = b.geom[e];
    const Grad4 ue = gather<4>(u, b.conn[e]);
    Grad4 fe = Grad4::Zero();
    for (int q = 0; q < 4; ++q) {
      const Mat2 F = deformation_gradient<4>(ue, g.dndx[q]);
      min_j = std::min(min_j, F.determinant());
      fe.noalias() += g.vol[q] * g.dndx[q] * mat.first_piola(F).transpose();
      if constexpr (kEnergy) energy += g.vol[q] * mat.energy_density(F);
    }
    scatter<4>(f, b.conn[e], fe);
  }
  t.strain_energy += energy;
  t.min_jacobian = min_j;
}

// One-point Q4 with Flanagan-Belytschko hourglass forces f_I = gamma_I Q, Q = c q.
template <bool kEnergy, bool kViscous, class Mat>
[[gnu::noinline]] void q4_hourglass_forces(const Q4HourglassBlock& b, const Mat& mat, const double* u,
                         const double* v, double* f, ForceTotals& t) {
  double energy = 0.0, hg_energy = 0.0, hg_power = 0.0, min_j = t.min_jacobian;
  for (std::size_t e = 0; e < b.conn.size(); ++e) {
    const Q4HourglassGeom& g = b.geom[e];
    const Grad4 ue = gather<4>(u, b.conn[e]);
    const Mat2 F = deformation_gradient<4>(ue, g.dndx);
    min_j = std::min(min_j, F.determinant());
    Grad4 fe = g.vol * g.dndx * mat.first_piola(F).transpose();
    if constexpr (kViscous) {
      const Vec2 qdot = gather<4>(v, b.conn[e]).transpose() * g.gamma;
      const Vec2 Q = g.hourglass_coeff * qdot;
      fe.noalias() += g.gamma * Q.transpose();
      hg_power += Q.dot(qdot);
    } else {
      const Vec2 q = ue.transpose() * g.gamma;
      fe.noalias() += g.gamma * (g.hourglass_coeff * q).transpose();
      if constexpr (kEnergy) hg_energy += 0.5 * g.hourglass_coeff * q.squaredNorm();
    }
    scatter<4>(f, b.conn[e], fe);
    if constexpr (kEnergy) energy += g.vol * mat.energy_density(F);
  }
  t.strain_energy += energy;
  t.hourglass_energy += hg_energy;
  t.hourglass_power += hg_power;
  t.min_jacobian = min_j;
}

template <bool kEnergy>
void all_blocks(const Model& model, const double* u, const double* v, double* f, ForceTotals& t) {
  for (const auto& b : model.q4_hourglass)
    std::visit(
        [&](const auto& mat) {
          if (b.form == HourglassForm::viscous)
            q4_hourglass_forces<kEnergy, true>(b, mat, u, v, f, t);
          else
            q4_hourglass_forces<kEnergy, false>(b, mat, u, v, f, t);
        },
        b.material);
  for (const auto& b : model.q4_full)
    std::visit([&](const auto& mat) { q4_full_forces<kEnergy>(b, mat, u, f, t); }, b.material);
  for (const auto& b : model.t3)
    std::visit([&](const auto& mat) { t3_forces<kEnergy>(b, mat, u, f, t); }, b.material);
}

}  // namespace

ForceTotals internal_forces(const Model& model, const double* u, const double* v, double* f_int,
                            bool with_energy) {
  std::fill(f_int, f_int + model.num_dofs(), 0.0);
  ForceTotals t;
  if (with_energy)
    all_blocks<true>(model, u, v, f_int, t);
  else
    all_blocks<false>(model, u, v, f_int, t);
  return t;
}

void cell_von_mises(const Model& model, const double* u, double* out) {
  for (const auto& b : model.q4_hourglass)
    for (std::size_t e = 0; e < b.conn.size(); ++e) {
      const Mat2 F = deformation_gradient<4>(gather<4>(u, b.conn[e]), b.geom[e].dndx);
      out[b.first_cell + e] = von_mises(b.material, F);
    }
  for (const auto& b : model.q4_full)
    for (std::size_t e = 0; e < b.conn.size(); ++e) {
      const Grad4 ue = gather<4>(u, b.conn[e]);
      double vm = 0.0;
      for (int q = 0; q < 4; ++q)
        vm = std::max(vm, von_mises(b.material, deformation_gradient<4>(ue, b.geom[e].dndx[q])));
      out[b.first_cell + e] = vm;
    }
  for (const auto& b : model.t3)
    for (std::size_t e = 0; e < b.conn.size(); ++e) {
      const Mat2 F = deformation_gradient<3>(gather<3>(u, b.conn[e]), b.geom[e].dndx);
      out[b.first_cell + e] = von_mises(b.material, F);
    }
}

}  // namespace ricochet
