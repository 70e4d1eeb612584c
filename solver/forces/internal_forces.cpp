#include "solver/forces/internal_forces.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <tuple>
#include <type_traits>

#include <omp.h>

#include "solver/forces/element_kernels.hpp"

namespace ricochet {
namespace {

// The force pass, run by force_kernel() (element_kernels.hpp), which evaluates P at each point
// on lanes; with kStress (0 = no stresses, else 1 + the measure, so that each measure's kernel
// is its own), the von
// Mises peak of each cell over its points above the threshold. With kSample (a history sample
// or a field snapshot: StressTracking::samples()) every point's equivalents are exact and the
// pass also fills sampled_max and cell_von_mises, with the arithmetic of von_mises_maxima()
// and cell_von_mises(), so the values are theirs.
template <bool kEnergy_, int kStress, bool kSample>
struct ForcePass {
  static_assert(!kSample || kStress > 0, "a sample pass ranks the stresses too");
  static constexpr bool kEnergy = kEnergy_;
  static constexpr bool kPerPoint = kStress > 0;
  static constexpr bool kEveryPoint = kSample;  // point() at every point, not only where screen() allows
  static constexpr StressMeasure measure = static_cast<StressMeasure>(kStress > 0 ? kStress - 1 : 0);
  StressPeaks peaks;
  double threshold = 0.0;
  const std::uint8_t* contact_cell = nullptr;
  VonMisesRatio vm2;  // the cell's largest so far (cells of several points)
  VonMises2 sampled{0.0, 0.0, 0.0};  // kSample: per measure, the largest so far [Pa^2]
  double cell_max = 0.0;             // kSample: the cell's largest of `measure` so far [Pa^2]
  double* cell_von_mises = nullptr;

  ForcePass(const StressTracking* tracking, const ForceTotals& t)
      : peaks(t.stress),
        threshold(tracking ? tracking->threshold : 0.0),
        contact_cell(tracking ? tracking->contact_cell : nullptr),
        cell_von_mises(tracking ? tracking->cell_von_mises : nullptr) {}

  struct Response {  // the point's P, from the kernel's first_piola_lanes
    Mat2 P;
  };
  void begin_element() {
    if constexpr (kStress) vm2 = VonMisesRatio{};
    if constexpr (kSample) cell_max = 0.0;
  }
  // Which of kLanes points may exceed the threshold (the cheap bound, on all lanes at once).
  template <class Mat>
  EIGEN_ALWAYS_INLINE void screen(const Mat& mat, const LaneMat2& F, const LaneMat2& P, const double* det,
                                  double* may) const {
    von_mises_may_exceed_lanes<measure>(mat, F, P, det, threshold, may);
  }
  // A point that may exceed the threshold (`may`, from screen()), or with kSample every point.
  // One-point cells are ranked by their point; cells of several points by the largest of
  // their points, at the end of the cell.
  template <int kPoints, class Mat, class Rows>
  EIGEN_ALWAYS_INLINE void point(const Mat& mat, const Mat2& F, double det_f, const Response& r, const Rows&,
                                 double, int cell, bool may) {
    if constexpr (kSample) {
      // Every measure exactly (as von_mises_squared), the run's own as a ratio for the ranking.
      const std::array<VonMisesRatio, kStressMeasures> all = von_mises_ratios(mat, F, r.P, det_f);
      for (int m = 0; m < kStressMeasures; ++m) sampled[m] = std::max(sampled[m], all[m].value());
      const VonMisesRatio x = all[static_cast<int>(measure)];
      cell_max = std::max(cell_max, x.value());
      if (may) rank<kPoints>(x, cell);
    } else if constexpr (kStress) {
      if (may) rank<kPoints>(von_mises_ratio(mat, F, r.P, det_f, measure), cell);
    }
  }
  template <int kPoints>
  EIGEN_ALWAYS_INLINE void rank(const VonMisesRatio& x, int cell) {
    if constexpr (kPoints == 1)
      peaks.add(x, cell, contact_cell[cell] != 0);
    else if (ratio_greater(x, vm2))
      vm2 = x;
  }
  template <int kPoints>
  void end_element(std::size_t, int cell) {
    if constexpr (kStress && kPoints > 1) {
      if (vm2.num > 0.0) peaks.add(vm2, cell, contact_cell[cell] != 0);
    }
    if constexpr (kSample) {
      if (cell_von_mises) cell_von_mises[cell] = std::sqrt(cell_max);
    }
  }
  void finish(ForceTotals& t) const {
    t.stress = peaks;
    if constexpr (kSample) max_into(t.sampled, sampled);
  }
};

template <bool kEnergy, int kStress, bool kSample = false>
void all_blocks(const Model& model, const double* u, const double* v, double* f, const StressTracking* cc,
                ForceTotals& t, ForceScratch* scratch) {
  if (!scratch) {
    for_each_block(model, [&](const auto& b, const auto& mat, auto viscous) {
      force_kernel<decltype(viscous)::value>(b, mat, u, v, DirectScatter{f}, ForcePass<kEnergy, kStress, kSample>(cc, t),
                                               t);
    });
    return;
  }
  ForceScratch& x = *scratch;
  const long chunks = static_cast<long>(x.chunks.size());
  const int nodes = model.num_nodes();
  const ForceTotals start = t;  // every chunk starts from the pass's initial totals
  auto chunk = [&](long c) {
    const ForceScratch::Chunk& k = x.chunks[c];
    ForceTotals& tc = x.totals[c];
    tc = start;
    visit_block(model, static_cast<BlockKind>(k.kind), k.block, [&](const auto& b, const auto& mat, auto viscous) {
      force_kernel<decltype(viscous)::value>(b, mat, u, v, ElementStore{x.element_forces.data() + k.out},
                                               ForcePass<kEnergy, kStress, kSample>(cc, tc), tc, k.begin, k.end);
    });
  };
  // Each node sums its cells' forces in the serial scatter's order, from 0 as f_int starts.
  auto gather = [&](int i) {
    double fx = 0.0, fy = 0.0;
    for (int p = x.node_offsets[i]; p < x.node_offsets[i + 1]; ++p) {
      fx += x.element_forces[x.entries[p]];
      fy += x.element_forces[x.entries[p] + 1];
    }
    f[2 * i] = fx;
    f[2 * i + 1] = fy;
  };
  // The same arithmetic either way. No parallel region at all for a small model or one
  // thread: even a serialized region costs the OpenMP runtime an allocation.
  if (x.chunks.size() >= kForceParallelChunks && omp_get_max_threads() > 1) {
#pragma omp parallel
    {
#pragma omp for schedule(static)
      for (long c = 0; c < chunks; ++c) chunk(c);
#pragma omp for schedule(static)
      for (int i = 0; i < nodes; ++i) gather(i);
    }
  } else {
    for (long c = 0; c < chunks; ++c) chunk(c);
    for (int i = 0; i < nodes; ++i) gather(i);
  }
  // The chunks' totals in chunk order; a peak is taken only if strictly larger, so that of
  // equal values the first cell wins, as in the serial pass.
  for (const ForceTotals& c : x.totals) {
    t.strain_energy += c.strain_energy;
    t.hourglass_energy += c.hourglass_energy;
    t.hourglass_power += c.hourglass_power;
    t.min_jacobian = std::min(t.min_jacobian, c.min_jacobian);
    if (c.stress.all_cell >= 0 && c.stress.all > t.stress.all) {
      t.stress.all = c.stress.all;
      t.stress.all_cell = c.stress.all_cell;
    }
    if (c.stress.interior_cell >= 0 && c.stress.interior > t.stress.interior) {
      t.stress.interior = c.stress.interior;
      t.stress.interior_cell = c.stress.interior_cell;
    }
    max_into(t.sampled, c.sampled);
  }
}

}  // namespace

ForceTotals internal_forces(const Model& model, const double* u, const double* v, double* f_int,
                            bool with_energy, const StressTracking* stress, ForceScratch* scratch) {
  if (!scratch) std::fill(f_int, f_int + model.num_dofs(), 0.0);  // the threaded pass overwrites it
  ForceTotals t;
  if (stress) t.stress.all = t.stress.interior = stress->threshold;  // only cells above it are ranked
  // kStress: 0 = no stresses, else 1 + the measure, so that each measure's kernel is its own.
  // A sample pass always sums the energies (a sample is a monitor step): no kernels for the
  // sample without them.
  auto run = [&]<bool kEnergy, bool kSample>() {
    if (!stress) {
      if constexpr (!kSample) all_blocks<kEnergy, 0>(model, u, v, f_int, stress, t, scratch);
    } else if (stress->measure == StressMeasure::pk2) {
      all_blocks<kEnergy, 1 + static_cast<int>(StressMeasure::pk2), kSample>(model, u, v, f_int, stress, t, scratch);
    } else if (stress->measure == StressMeasure::kirchhoff) {
      all_blocks<kEnergy, 1 + static_cast<int>(StressMeasure::kirchhoff), kSample>(model, u, v, f_int, stress, t, scratch);
    } else {
      all_blocks<kEnergy, 1 + static_cast<int>(StressMeasure::cauchy), kSample>(model, u, v, f_int, stress, t, scratch);
    }
  };
  if (stress && stress->samples())
    run.template operator()<true, true>();  // energies too: see above
  else if (with_energy)
    run.template operator()<true, false>();
  else
    run.template operator()<false, false>();
  if (stress && stress->sampled_max) max_into(*stress->sampled_max, t.sampled);
  return t;
}

ForceScratch make_force_scratch(const Model& model) {
  ForceScratch x;
  std::size_t out = 0;
  std::vector<std::vector<int>> node_entries(model.num_nodes());
  for (const BlockKind kind : kBlockKinds)  // for_each_block's order
    for (std::size_t k = 0; k < model.num_blocks(kind); ++k)
      visit_block(model, kind, k, [&](const auto& b, const auto&, auto) {
        constexpr int N = std::tuple_size_v<typename std::decay_t<decltype(b.conn)>::value_type>;
        for (std::size_t e0 = 0; e0 < b.conn.size(); e0 += kForceChunkCells)
          x.chunks.push_back({static_cast<int>(kind), k, e0, std::min(b.conn.size(), e0 + kForceChunkCells), out});
        for (std::size_t e = 0; e < b.conn.size(); ++e)
          for (int i = 0; i < N; ++i) node_entries[b.conn[e][i]].push_back(static_cast<int>(out + 2 * N * e + 2 * i));
        out += 2 * N * b.conn.size();
      });
  if (out > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw std::length_error("make_force_scratch: too many element-force entries for int indices");
  x.node_offsets.assign(1, 0);
  for (const auto& l : node_entries) {
    x.entries.insert(x.entries.end(), l.begin(), l.end());
    x.node_offsets.push_back(static_cast<int>(x.entries.size()));
  }
  x.element_forces.assign(out, 0.0);
  x.totals.resize(x.chunks.size());
  return x;
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

void cell_tensors(const Model& model, const double* u, double* cauchy, double* green_lagrange) {
  auto store = [&](int cell, const SymTensor6& sigma, const SymTensor6& strain) {
    for (int k = 0; k < 6; ++k) {
      cauchy[6 * cell + k] = sigma[k];
      green_lagrange[6 * cell + k] = strain[k];
    }
  };
  // One-point cells (Q4 with hourglass control, T3): the centroid's values.
  auto one_point = [&]<int N>(const auto& blocks) {
    for (const auto& b : blocks)
      std::visit(
          [&](const auto& mat) {
            for (std::size_t e = 0; e < b.conn.size(); ++e) {
              const Mat2 F = deformation_gradient<N>(gather<N>(u, b.conn[e]), b.geom[e].dndx);
              SymTensor6 sigma, strain;
              cauchy_and_green_lagrange(mat, F, mat.first_piola(F), F.determinant(), sigma, strain);
              store(b.first_cell + static_cast<int>(e), sigma, strain);
            }
          },
          b.material);
  };
  one_point.template operator()<4>(model.q4_hourglass);
  one_point.template operator()<3>(model.t3);
  // Q4 with 2x2 points: the mean over the points weighted by their volumes (Gauss weight x det J0
  // x thickness), i.e. the cell's average by its own quadrature; the plain mean of the four
  // points for a parallelogram.
  for (const auto& b : model.q4_full)
    std::visit(
        [&](const auto& mat) {
          for (std::size_t e = 0; e < b.conn.size(); ++e) {
            const Grad4 ue = gather<4>(u, b.conn[e]);
            SymTensor6 sigma{}, strain{};
            double volume = 0.0;
            for (int q = 0; q < 4; ++q) {
              const Mat2 F = deformation_gradient<4>(ue, b.geom[e].dndx[q]);
              SymTensor6 sq, eq;
              cauchy_and_green_lagrange(mat, F, mat.first_piola(F), F.determinant(), sq, eq);
              const double w = b.geom[e].vol[q];
              volume += w;
              for (int k = 0; k < 6; ++k) {
                sigma[k] += w * sq[k];
                strain[k] += w * eq[k];
              }
            }
            for (int k = 0; k < 6; ++k) {
              sigma[k] /= volume;
              strain[k] /= volume;
            }
            store(b.first_cell + static_cast<int>(e), sigma, strain);
          }
        },
        b.material);
}

StressPeaks stress_peaks(const Model& model, const double* u, const StressTracking& stress) {
  StressPeaks p;
  const int m = static_cast<int>(stress.measure);
  auto rank = [&](int cell, const VonMises2& vm2) {
    p.add(VonMisesRatio{vm2[m], 1.0}, cell, stress.contact_cell && stress.contact_cell[cell] != 0);
  };
  if (!stress.samples()) {
    for_each_cell_stress(model, u, one_measure(stress.measure), rank);
    return p;
  }
  VonMises2 sampled{0.0, 0.0, 0.0};
  for_each_cell_stress(model, u, all_measures, [&](int cell, const VonMises2& vm2) {
    rank(cell, vm2);
    max_into(sampled, vm2);
    if (stress.cell_von_mises) stress.cell_von_mises[cell] = std::sqrt(vm2[m]);
  });
  if (stress.sampled_max) max_into(*stress.sampled_max, sampled);
  return p;
}

VonMises2 von_mises_maxima(const Model& model, const double* u) {
  VonMises2 m{0.0, 0.0, 0.0};
  for_each_cell_stress(model, u, all_measures, [&](int, const VonMises2& vm2) { max_into(m, vm2); });
  for (double& x : m) x = std::sqrt(x);
  return m;
}

}  // namespace ricochet
