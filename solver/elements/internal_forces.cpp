#include "solver/elements/internal_forces.hpp"

#include <algorithm>
#include <cmath>

#include "solver/elements/kinematics.hpp"

namespace ricochet {
namespace {

// Each kernel instantiation (element x material x options) is its own function, so the
// material law inlines into its loop: instantiated inline into all_blocks, four materials
// exhausted GCC's inlining budget and the kernels ran 3x slower.

// Elements whose cells share one deformation gradient per integration point: T3 and Q4 2x2.
template <bool kEnergy, int kStress, class Mat>
[[gnu::noinline, gnu::flatten]] void t3_forces(const T3Block& b, const Mat& material, const double* u, double* f,
                                             const StressTracking* tracking, ForceTotals& t) {
  const Mat mat = material;  // a local copy: its constants cannot alias f, so they stay in registers
  double energy = 0.0, min_j = t.min_jacobian;
  StressPeaks peaks = t.stress;
  constexpr StressMeasure measure = static_cast<StressMeasure>(kStress > 0 ? kStress - 1 : 0);
  const double threshold = tracking ? tracking->threshold : 0.0;
  const std::uint8_t* contact_cell = tracking ? tracking->contact_cell : nullptr;
  for (std::size_t e = 0; e < b.conn.size(); ++e) {
    const T3Geom& g = b.geom[e];
    const Grad3 ue = gather<3>(u, b.conn[e]);
    const Mat2 F = deformation_gradient<3>(ue, g.dndx);
    const double det_f = F.determinant();
    min_j = std::min(min_j, det_f);
    const Mat2 P = mat.first_piola(F);
    scatter<3>(f, b.conn[e], g.vol * g.dndx * P.transpose());
    if constexpr (kEnergy) energy += g.vol * mat.energy_density(F);
    if constexpr (kStress) {
      if (von_mises_may_exceed(mat, F, P, det_f, measure, threshold)) {
        const int cell = b.first_cell + static_cast<int>(e);
        peaks.add(von_mises_ratio(mat, F, P, det_f, measure), cell, contact_cell[cell] != 0);
      }
    }
  }
  t.strain_energy += energy;
  t.min_jacobian = min_j;
  t.stress = peaks;
}

template <bool kEnergy, int kStress, class Mat>
[[gnu::noinline, gnu::flatten]] void q4_full_forces(const Q4FullBlock& b, const Mat& material, const double* u, double* f,
                                                  const StressTracking* tracking, ForceTotals& t) {
  const Mat mat = material;  // a local copy: its constants cannot alias f, so they stay in registers
  double energy = 0.0, min_j = t.min_jacobian;
  StressPeaks peaks = t.stress;
  constexpr StressMeasure measure = static_cast<StressMeasure>(kStress > 0 ? kStress - 1 : 0);
  const double threshold = tracking ? tracking->threshold : 0.0;
  const std::uint8_t* contact_cell = tracking ? tracking->contact_cell : nullptr;
  for (std::size_t e = 0; e < b.conn.size(); ++e) {
    const Q4FullGeom& g = b.geom[e];
    const Grad4 ue = gather<4>(u, b.conn[e]);
    Grad4 fe = Grad4::Zero();
    [[maybe_unused]] VonMisesRatio vm2;
    for (int q = 0; q < 4; ++q) {
      const Mat2 F = deformation_gradient<4>(ue, g.dndx[q]);
      const double det_f = F.determinant();
      min_j = std::min(min_j, det_f);
      const Mat2 P = mat.first_piola(F);
      fe.noalias() += g.vol[q] * g.dndx[q] * P.transpose();
      if constexpr (kEnergy) energy += g.vol[q] * mat.energy_density(F);
      if constexpr (kStress) {
        if (von_mises_may_exceed(mat, F, P, det_f, measure, threshold)) {
          const VonMisesRatio r = von_mises_ratio(mat, F, P, det_f, measure);
          if (ratio_greater(r, vm2)) vm2 = r;
        }
      }
    }
    scatter<4>(f, b.conn[e], fe);
    if constexpr (kStress) {
      if (vm2.num > 0.0) {
        const int cell = b.first_cell + static_cast<int>(e);
        peaks.add(vm2, cell, contact_cell[cell] != 0);
      }
    }
  }
  t.strain_energy += energy;
  t.min_jacobian = min_j;
  t.stress = peaks;
}

// One-point Q4 with Flanagan-Belytschko hourglass forces f_I = gamma_I Q, Q = c q.
template <bool kEnergy, int kStress, bool kViscous, class Mat>
[[gnu::noinline, gnu::flatten]] void q4_hourglass_forces(const Q4HourglassBlock& b, const Mat& material, const double* u,
                                                       const double* v, double* f, const StressTracking* tracking,
                                                       ForceTotals& t) {
  const Mat mat = material;  // a local copy: its constants cannot alias f, so they stay in registers
  double energy = 0.0, hg_energy = 0.0, hg_power = 0.0, min_j = t.min_jacobian;
  StressPeaks peaks = t.stress;
  constexpr StressMeasure measure = static_cast<StressMeasure>(kStress > 0 ? kStress - 1 : 0);
  const double threshold = tracking ? tracking->threshold : 0.0;
  const std::uint8_t* contact_cell = tracking ? tracking->contact_cell : nullptr;
  for (std::size_t e = 0; e < b.conn.size(); ++e) {
    const Q4HourglassGeom& g = b.geom[e];
    const Grad4 ue = gather<4>(u, b.conn[e]);
    const Mat2 F = deformation_gradient<4>(ue, g.dndx);
    const double det_f = F.determinant();
    min_j = std::min(min_j, det_f);
    const Mat2 P = mat.first_piola(F);
    Grad4 fe = g.vol * g.dndx * P.transpose();
    if constexpr (kStress) {
      if (von_mises_may_exceed(mat, F, P, det_f, measure, threshold)) {
        const int cell = b.first_cell + static_cast<int>(e);
        peaks.add(von_mises_ratio(mat, F, P, det_f, measure), cell, contact_cell[cell] != 0);
      }
    }
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
  t.stress = peaks;
}

template <bool kEnergy, int kStress>
void all_blocks(const Model& model, const double* u, const double* v, double* f, const StressTracking* cc,
                ForceTotals& t) {
  for (const auto& b : model.q4_hourglass)
    std::visit(
        [&](const auto& mat) {
          if (b.form == HourglassForm::viscous)
            q4_hourglass_forces<kEnergy, kStress, true>(b, mat, u, v, f, cc, t);
          else
            q4_hourglass_forces<kEnergy, kStress, false>(b, mat, u, v, f, cc, t);
        },
        b.material);
  for (const auto& b : model.q4_full)
    std::visit([&](const auto& mat) { q4_full_forces<kEnergy, kStress>(b, mat, u, f, cc, t); }, b.material);
  for (const auto& b : model.t3)
    std::visit([&](const auto& mat) { t3_forces<kEnergy, kStress>(b, mat, u, f, cc, t); }, b.material);
}

}  // namespace

ForceTotals internal_forces(const Model& model, const double* u, const double* v, double* f_int,
                            bool with_energy, const StressTracking* stress) {
  std::fill(f_int, f_int + model.num_dofs(), 0.0);
  ForceTotals t;
  if (stress) t.stress.all = t.stress.interior = stress->threshold;  // only cells above it are ranked
  // kStress: 0 = no stresses, else 1 + the measure, so that each measure's kernel is its own.
  auto run = [&]<bool kEnergy>() {
    if (!stress)
      all_blocks<kEnergy, 0>(model, u, v, f_int, stress, t);
    else if (stress->measure == StressMeasure::pk2)
      all_blocks<kEnergy, 1 + static_cast<int>(StressMeasure::pk2)>(model, u, v, f_int, stress, t);
    else if (stress->measure == StressMeasure::kirchhoff)
      all_blocks<kEnergy, 1 + static_cast<int>(StressMeasure::kirchhoff)>(model, u, v, f_int, stress, t);
    else
      all_blocks<kEnergy, 1 + static_cast<int>(StressMeasure::cauchy)>(model, u, v, f_int, stress, t);
  };
  if (with_energy)
    run.template operator()<true>();
  else
    run.template operator()<false>();
  return t;
}

namespace {

// Calls fn(global cell, the cell's value): the largest over its integration points of
// point(material, F, P, det F), a VonMises2 (max_into combines the points).
template <class Point, class Fn>
void for_each_cell_stress(const Model& model, const double* u, Point&& point, Fn&& fn) {
  // One-point cells (Q4 with hourglass control, T3): F at the centroid.
  auto one_point = [&]<int N>(const auto& blocks) {
    for (const auto& b : blocks)
      std::visit(
          [&](const auto& mat) {
            for (std::size_t e = 0; e < b.conn.size(); ++e) {
              const Mat2 F = deformation_gradient<N>(gather<N>(u, b.conn[e]), b.geom[e].dndx);
              fn(b.first_cell + static_cast<int>(e), point(mat, F, mat.first_piola(F), F.determinant()));
            }
          },
          b.material);
  };
  one_point.template operator()<4>(model.q4_hourglass);
  one_point.template operator()<3>(model.t3);
  for (const auto& b : model.q4_full)
    std::visit(
        [&](const auto& mat) {
          for (std::size_t e = 0; e < b.conn.size(); ++e) {
            const Grad4 ue = gather<4>(u, b.conn[e]);
            VonMises2 vm2{0.0, 0.0, 0.0};
            for (int q = 0; q < 4; ++q) {
              const Mat2 F = deformation_gradient<4>(ue, b.geom[e].dndx[q]);
              max_into(vm2, point(mat, F, mat.first_piola(F), F.determinant()));
            }
            fn(b.first_cell + static_cast<int>(e), vm2);
          }
        },
        b.material);
}

// The point value with only `measure`'s entry filled (the others 0): one measure's work.
auto one_measure(StressMeasure measure) {
  return [measure](const auto& mat, const Mat2& F, const Mat2& P, double det_f) {
    VonMises2 v{0.0, 0.0, 0.0};
    v[static_cast<int>(measure)] = von_mises_ratio(mat, F, P, det_f, measure).value();
    return v;
  };
}

const auto all_measures = [](const auto& mat, const Mat2& F, const Mat2& P, double det_f) {
  return von_mises_squared(mat, F, P, det_f);
};

}  // namespace

void cell_von_mises(const Model& model, const double* u, StressMeasure measure, double* out) {
  const int m = static_cast<int>(measure);
  for_each_cell_stress(model, u, one_measure(measure), [&](int cell, const VonMises2& vm2) { out[cell] = std::sqrt(vm2[m]); });
}

StressPeaks stress_peaks(const Model& model, const double* u, const StressTracking& stress) {
  StressPeaks p;
  const int m = static_cast<int>(stress.measure);
  for_each_cell_stress(model, u, one_measure(stress.measure), [&](int cell, const VonMises2& vm2) {
    p.add(VonMisesRatio{vm2[m], 1.0}, cell, stress.contact_cell && stress.contact_cell[cell] != 0);
  });
  return p;
}

VonMises2 von_mises_maxima(const Model& model, const double* u) {
  VonMises2 m{0.0, 0.0, 0.0};
  for_each_cell_stress(model, u, all_measures, [&](int, const VonMises2& vm2) { max_into(m, vm2); });
  for (double& x : m) x = std::sqrt(x);
  return m;
}

}  // namespace ricochet
