#include "solver/elements/internal_forces.hpp"

#include <algorithm>
#include <cmath>

#include "solver/elements/element_kernels.hpp"

namespace ricochet {
namespace {

// The force pass (element_kernels.hpp): P = first_piola(F) at each point and, with kStress
// (0 = no stresses, else 1 + the measure, so that each measure's kernel is its own), the von
// Mises peak of each cell over its points above the threshold.
template <bool kEnergy_, int kStress>
struct ForcePass {
  static constexpr bool kEnergy = kEnergy_;
  static constexpr StressMeasure measure = static_cast<StressMeasure>(kStress > 0 ? kStress - 1 : 0);
  StressPeaks peaks;
  double threshold = 0.0;
  const std::uint8_t* contact_cell = nullptr;
  VonMisesRatio vm2;  // the cell's largest so far (cells of several points)

  ForcePass(const StressTracking* tracking, const ForceTotals& t)
      : peaks(t.stress),
        threshold(tracking ? tracking->threshold : 0.0),
        contact_cell(tracking ? tracking->contact_cell : nullptr) {}

  struct Response {
    Mat2 P;
  };
  template <class Mat>
  EIGEN_ALWAYS_INLINE Response response(const Mat& mat, const Mat2& F) const {
    return {mat.first_piola(F)};
  }
  void begin_element() {
    if constexpr (kStress) vm2 = VonMisesRatio{};
  }
  // One-point cells are ranked by their point; cells of several points by the largest of
  // their points, at the end of the cell.
  template <int kPoints, class Mat, class Rows>
  EIGEN_ALWAYS_INLINE void point(const Mat& mat, const Mat2& F, double det_f, const Response& r, const Rows&,
                                 double, int cell) {
    if constexpr (kStress) {
      if (von_mises_may_exceed(mat, F, r.P, det_f, measure, threshold)) {
        if constexpr (kPoints == 1) {
          peaks.add(von_mises_ratio(mat, F, r.P, det_f, measure), cell, contact_cell[cell] != 0);
        } else {
          const VonMisesRatio x = von_mises_ratio(mat, F, r.P, det_f, measure);
          if (ratio_greater(x, vm2)) vm2 = x;
        }
      }
    }
  }
  template <class Gamma>
  void hourglass(const Gamma&, double, bool) {}
  template <int kPoints>
  void end_element(std::size_t, int cell) {
    if constexpr (kStress && kPoints > 1) {
      if (vm2.num > 0.0) peaks.add(vm2, cell, contact_cell[cell] != 0);
    }
  }
  void finish(ForceTotals& t) const { t.stress = peaks; }
};

template <bool kEnergy, int kStress>
void all_blocks(const Model& model, const double* u, const double* v, double* f, const StressTracking* cc,
                ForceTotals& t) {
  for_each_block(model, [&](const auto& b, const auto& mat, auto viscous) {
    element_kernel<decltype(viscous)::value>(b, mat, u, v, f, ForcePass<kEnergy, kStress>(cc, t), t);
  });
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
