// The force pass and the stress passes of both dimensions, written once over Model<D>
// (internal_forces.hpp). What differs by dimension is in the dimension's kernel header, which
// the including unit includes first: the kernels, how a cell's forces go out (ForceOutput<D>:
// added into f, or stored for the threaded pass's gather) and where a point's F comes from in a
// stress pass (for_each_cell_points): element_kernels2.hpp, element_kernels3.hpp. Each
// dimension is instantiated in units of its own, so that the kernels, the heaviest sources of
// the solver, compile in parallel: internal_forces2.cpp and internal_forces3.cpp hold the passes
// (RICOCHET_FORCE_PASSES), and the force pass's kernels are split by stress measure over
// force_pass{2,3}_{plain,pk2,kirchhoff,cauchy}.cpp (RICOCHET_FORCE_PASS_VARIANTS), which
// RICOCHET_FORCE_PASS_EXTERN keeps the passes' unit from instantiating again. As one unit the 3D
// kernels took 200 s of a Release build and 427 s under the sanitizers, the build's longest
// path on two cores.
#pragma once

#include "solver/forces/internal_forces.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <tuple>
#include <type_traits>

#include <omp.h>

#include "solver/materials/material_lanes.hpp"
#include "solver/materials/material_lanes3.hpp"
#include "solver/materials/stress.hpp"

namespace ricochet {
// Named, not anonymous: the units of RICOCHET_FORCE_PASS_VARIANTS instantiate all_blocks for
// the passes' unit.
namespace force_passes {

// The von Mises functions under one name: the 2D ones take the material (its plane mode decides
// the out-of-plane stress), the 3D ones do not need it.
template <StressMeasure kMeasure, class Mat>
EIGEN_ALWAYS_INLINE void may_exceed(const Mat& mat, const LaneMat2& F, const LaneMat2& P, const double* det,
                                    double threshold, double* may) {
  von_mises_may_exceed_lanes<kMeasure>(mat, F, P, det, threshold, may);
}
template <StressMeasure kMeasure, class Mat>
EIGEN_ALWAYS_INLINE void may_exceed(const Mat&, const LaneMat3& F, const LaneMat3& P, const double* det,
                                    double threshold, double* may) {
  von_mises_may_exceed_lanes<kMeasure>(F, P, det, threshold, may);
}
template <class Mat>
EIGEN_ALWAYS_INLINE VonMisesRatio ratio(const Mat& mat, const Mat2& F, const Mat2& P, double det_f, StressMeasure m) {
  return von_mises_ratio(mat, F, P, det_f, m);
}
template <class Mat>
EIGEN_ALWAYS_INLINE VonMisesRatio ratio(const Mat&, const Mat3& F, const Mat3& P, double det_f, StressMeasure m) {
  return von_mises_ratio(F, P, det_f, m);
}
template <class Mat>
EIGEN_ALWAYS_INLINE std::array<VonMisesRatio, kStressMeasures> ratios(const Mat& mat, const Mat2& F, const Mat2& P,
                                                                      double det_f) {
  return von_mises_ratios(mat, F, P, det_f);
}
template <class Mat>
EIGEN_ALWAYS_INLINE std::array<VonMisesRatio, kStressMeasures> ratios(const Mat&, const Mat3& F, const Mat3& P,
                                                                      double det_f) {
  return von_mises_ratios(F, P, det_f);
}
template <class Mat>
VonMises2 squared(const Mat& mat, const Mat2& F, const Mat2& P, double det_f) {
  return von_mises_squared(mat, F, P, det_f);
}
template <class Mat>
VonMises2 squared(const Mat&, const Mat3& F, const Mat3& P, double det_f) {
  return von_mises_squared(F, P, det_f);
}
template <class Mat>
void tensors(const Mat& mat, const Mat2& F, const Mat2& P, double det_f, SymTensor6& sigma, SymTensor6& strain) {
  cauchy_and_green_lagrange(mat, F, P, det_f, sigma, strain);
}
template <class Mat>
void tensors(const Mat&, const Mat3& F, const Mat3& P, double det_f, SymTensor6& sigma, SymTensor6& strain) {
  cauchy_and_green_lagrange(F, P, det_f, sigma, strain);
}

// The force pass, run by force_kernel() (element_kernels2.hpp, element_kernels3.hpp), which
// evaluates P at each point on lanes; with kStress (0 = no stresses, else 1 + the measure, so
// that each measure's kernel is its own), the von Mises peak of each cell over its points above
// the threshold. With kSample (a history sample or a field snapshot: StressTracking::samples())
// every point's equivalents are exact and the pass also fills sampled_max and cell_von_mises,
// with the arithmetic of von_mises_maxima() and cell_von_mises(), so the values are theirs.
template <int D, bool kEnergy_, int kStress, bool kSample>
struct ForcePass {
  static_assert(!kSample || kStress > 0, "a sample pass ranks the stresses too");
  using MatD = Eigen::Matrix<double, D, D>;
  static constexpr bool kEnergy = kEnergy_;
  static constexpr bool kPerPoint = kStress > 0;
  static constexpr bool kEveryPoint = kSample;  // point() at every point, not only where screen() allows
  static constexpr StressMeasure measure = static_cast<StressMeasure>(kStress > 0 ? kStress - 1 : 0);
  StressPeaks peaks;
  double threshold = 0.0;
  const std::uint8_t* contact_cell = nullptr;
  VonMisesRatio vm2;                 // the cell's largest so far (cells of several points)
  VonMises2 sampled{0.0, 0.0, 0.0};  // kSample: per measure, the largest so far [Pa^2]
  double cell_max = 0.0;             // kSample: the cell's largest of `measure` so far [Pa^2]
  double* cell_von_mises = nullptr;

  ForcePass(const StressTracking* tracking, const ForceTotals& t)
      : peaks(t.stress),
        threshold(tracking ? tracking->threshold : 0.0),
        contact_cell(tracking ? tracking->contact_cell : nullptr),
        cell_von_mises(tracking ? tracking->cell_von_mises : nullptr) {}

  struct Response {  // the point's P, from the kernel's first_piola_lanes
    MatD P;
  };
  void begin_element() {
    if constexpr (kStress) vm2 = VonMisesRatio{};
    if constexpr (kSample) cell_max = 0.0;
  }
  // Which of kLanes points may exceed the threshold (the cheap bound, on all lanes at once).
  template <class Mat, class LaneMat>
  EIGEN_ALWAYS_INLINE void screen(const Mat& mat, const LaneMat& F, const LaneMat& P, const double* det,
                                  double* may) const {
    may_exceed<measure>(mat, F, P, det, threshold, may);
  }
  // A point that may exceed the threshold (`may`, from screen()), or with kSample every point.
  // One-point cells are ranked by their point; cells of several points by the largest of
  // their points, at the end of the cell.
  template <int kPoints, class Mat, class Rows>
  EIGEN_ALWAYS_INLINE void point(const Mat& mat, const MatD& F, double det_f, const Response& r, const Rows&,
                                 double, int cell, bool may) {
    if constexpr (kSample) {
      // Every measure exactly (as von_mises_squared), the run's own as a ratio for the ranking.
      const std::array<VonMisesRatio, kStressMeasures> all = ratios(mat, F, r.P, det_f);
      for (int m = 0; m < kStressMeasures; ++m) sampled[m] = std::max(sampled[m], all[m].value());
      const VonMisesRatio x = all[static_cast<int>(measure)];
      cell_max = std::max(cell_max, x.value());
      if (may) rank<kPoints>(x, cell);
    } else if constexpr (kStress) {
      if (may) rank<kPoints>(ratio(mat, F, r.P, det_f, measure), cell);
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

template <bool kEnergy, int kStress, bool kSample = false, int D>
void all_blocks(const Model<D>& model, const double* u, const double* v, double* f, const StressTracking* cc,
                ForceTotals& t, ForceScratch* scratch) {
  using Pass = ForcePass<D, kEnergy, kStress, kSample>;
  using Out = ForceOutput<D>;
  if (!scratch) {
    for_each_block(model, [&](const auto& b, const auto& mat, auto viscous) {
      force_kernel<decltype(viscous)::value>(b, mat, u, v, typename Out::Scatter{f}, Pass(cc, t), t);
    });
    return;
  }
  ForceScratch& x = *scratch;
  const long chunks = static_cast<long>(x.chunks.size());
  const int nodes = model.num_nodes();
  const ForceTotals start = t;  // every chunk starts from the pass's initial totals
  // Chunk c's cells, their totals from `start` into x.totals[c], their forces through `out`.
  auto chunk_into = [&](long c, const auto& out) {
    const ForceScratch::Chunk& k = x.chunks[c];
    ForceTotals& tc = x.totals[c];
    tc = start;
    visit_block(model, static_cast<typename Model<D>::Kind>(k.kind), k.block,
                [&](const auto& b, const auto& mat, auto viscous) {
                  force_kernel<decltype(viscous)::value>(b, mat, u, v, out, Pass(cc, tc), tc, k.begin, k.end);
                });
  };
  auto chunk = [&](long c) { chunk_into(c, typename Out::Store{x.element_forces.data() + x.chunks[c].out}); };
  // Each node sums its cells' forces in the serial scatter's order, from 0 as f_int starts (an
  // entry's components are Out::Store::kStride apart).
  auto gather = [&](int i) {
    double fi[D] = {};
    for (int p = x.node_offsets[i]; p < x.node_offsets[i + 1]; ++p) {
      const double* e = x.element_forces.data() + x.entries[p];
      for (int k = 0; k < D; ++k) fi[k] += e[k * Out::Store::kStride];
    }
    for (int k = 0; k < D; ++k) f[D * i + k] = fi[k];
  };
  // The same arithmetic either way. No parallel region at all for a small model or one
  // thread: even a serialized region costs the OpenMP runtime an allocation. On one thread,
  // where Out::kScatterOnOneThread, the chunks add their cells' forces straight into f, cell by
  // cell in the order the nodes' sums take them, so f is bit for bit the gathered one and the
  // totals still sum by chunk (in 3D the store and the gather were a fifth of a step of the
  // one-point hexahedron).
  if (x.chunks.size() >= kForceParallelChunks && omp_get_max_threads() > 1) {
#pragma omp parallel
    {
#pragma omp for schedule(static)
      for (long c = 0; c < chunks; ++c) chunk(c);
#pragma omp for schedule(static)
      for (int i = 0; i < nodes; ++i) gather(i);
    }
  } else if constexpr (Out::kScatterOnOneThread) {
    std::fill(f, f + model.num_dofs(), 0.0);
    for (long c = 0; c < chunks; ++c) chunk_into(c, typename Out::Scatter{f});
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

// Calls fn(global cell, the cell's value): the largest over its integration points of
// point(material, F, P, det F), a VonMises2 (max_into combines the points).
template <int D, class Point, class Fn>
void for_each_cell_stress(const Model<D>& model, const double* u, Point&& point, Fn&& fn) {
  VonMises2 vm2{0.0, 0.0, 0.0};
  for_each_cell_points(
      model, u, point, [&](const VonMises2& value, double, auto) { max_into(vm2, value); },
      [&](int cell, auto) {
        fn(cell, vm2);
        vm2 = {0.0, 0.0, 0.0};
      });
}

// The point value with only `measure`'s entry filled (the others 0): one measure's work.
inline auto one_measure(StressMeasure measure) {
  return [measure](const auto& mat, const auto& F, const auto& P, double det_f) {
    VonMises2 v{0.0, 0.0, 0.0};
    v[static_cast<int>(measure)] = ratio(mat, F, P, det_f, measure).value();
    return v;
  };
}

inline const auto all_measures = [](const auto& mat, const auto& F, const auto& P, double det_f) {
  return squared(mat, F, P, det_f);
};

}  // namespace force_passes
using namespace force_passes;

template <int D>
ForceTotals internal_forces(const Model<D>& model, const double* u, const double* v, double* f_int, bool with_energy,
                            const StressTracking* stress, ForceScratch* scratch) {
  if (!scratch) std::fill(f_int, f_int + model.num_dofs(), 0.0);  // the threaded pass overwrites it
  ForceTotals t;
  if (stress) t.stress.all = t.stress.interior = stress->threshold;  // only cells above it are ranked
  // kStress: 0 = no stresses, else 1 + the measure, so that each measure's kernel is its own.
  // A sample pass always sums the energies (a sample is a monitor step): no kernels for the
  // sample without them.
  auto run = [&]<bool kEnergy, bool kSample>() {
    constexpr int kPk2 = 1 + static_cast<int>(StressMeasure::pk2);
    constexpr int kKirchhoff = 1 + static_cast<int>(StressMeasure::kirchhoff);
    constexpr int kCauchy = 1 + static_cast<int>(StressMeasure::cauchy);
    if (!stress) {
      if constexpr (!kSample) all_blocks<kEnergy, 0>(model, u, v, f_int, stress, t, scratch);
    } else if (stress->measure == StressMeasure::pk2) {
      all_blocks<kEnergy, kPk2, kSample>(model, u, v, f_int, stress, t, scratch);
    } else if (stress->measure == StressMeasure::kirchhoff) {
      all_blocks<kEnergy, kKirchhoff, kSample>(model, u, v, f_int, stress, t, scratch);
    } else {
      all_blocks<kEnergy, kCauchy, kSample>(model, u, v, f_int, stress, t, scratch);
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

template <int D>
ForceScratch make_force_scratch(const Model<D>& model) {
  using Store = typename ForceOutput<D>::Store;
  ForceScratch x;
  std::size_t out = 0;
  std::vector<std::vector<int>> node_entries(model.num_nodes());
  for (const auto kind : Model<D>::kKinds)  // for_each_block's order
    for (std::size_t k = 0; k < model.num_blocks(kind); ++k)
      visit_block(model, kind, k, [&](const auto& b, const auto&, auto) {
        constexpr int N = std::tuple_size_v<typename std::decay_t<decltype(b.conn)>::value_type>;
        for (std::size_t e0 = 0; e0 < b.conn.size(); e0 += kForceChunkCells)
          x.chunks.push_back({static_cast<int>(kind), k, e0, std::min(b.conn.size(), e0 + kForceChunkCells), out});
        for (std::size_t e = 0; e < b.conn.size(); ++e)
          for (int i = 0; i < N; ++i)
            node_entries[b.conn[e][i]].push_back(static_cast<int>(out + Store::template entry<N>(e, i)));
        out += Store::template size<N>(b.conn.size());
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

template <int D>
void cell_von_mises(const Model<D>& model, const double* u, StressMeasure measure, double* out) {
  const int m = static_cast<int>(measure);
  for_each_cell_stress(model, u, one_measure(measure), [&](int cell, const VonMises2& vm2) { out[cell] = std::sqrt(vm2[m]); });
}

template <int D>
void cell_tensors(const Model<D>& model, const double* u, double* cauchy, double* green_lagrange) {
  struct Tensors {
    SymTensor6 sigma, strain;
  };
  auto point = [](const auto& mat, const auto& F, const auto& P, double det_f) {
    Tensors t;
    tensors(mat, F, P, det_f, t.sigma, t.strain);
    return t;
  };
  // One point: its values; several points: the mean weighted by the points' reference volumes
  // (Gauss weight x det J0, x thickness in 2D), i.e. the cell's average by its own quadrature;
  // the plain mean of the four points for a parallelogram.
  std::array<Tensors, 8> values;  // a cell's points (at most 8, a hexahedron's)
  std::array<double, 8> vol;
  int n = 0;
  auto add = [&](const Tensors& t, double v, auto) {
    values[n] = t;
    vol[n++] = v;
  };
  auto done = [&](int cell, auto) {
    double* s = cauchy + 6 * cell;
    double* g = green_lagrange + 6 * cell;
    if (n == 1) {
      for (int k = 0; k < 6; ++k) {
        s[k] = values[0].sigma[k];
        g[k] = values[0].strain[k];
      }
    } else {
      SymTensor6 sigma{}, strain{};
      double volume = 0.0;
      for (int q = 0; q < n; ++q) {
        volume += vol[q];
        for (int k = 0; k < 6; ++k) {
          sigma[k] += vol[q] * values[q].sigma[k];
          strain[k] += vol[q] * values[q].strain[k];
        }
      }
      for (int k = 0; k < 6; ++k) {
        s[k] = sigma[k] / volume;
        g[k] = strain[k] / volume;
      }
    }
    n = 0;
  };
  for_each_cell_points(model, u, point, add, done);
}

template <int D>
StressPeaks stress_peaks(const Model<D>& model, const double* u, const StressTracking& stress) {
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

template <int D>
VonMises2 von_mises_maxima(const Model<D>& model, const double* u) {
  VonMises2 m{0.0, 0.0, 0.0};
  for_each_cell_stress(model, u, all_measures, [&](int, const VonMises2& vm2) { max_into(m, vm2); });
  for (double& x : m) x = std::sqrt(x);
  return m;
}

}  // namespace ricochet

// The explicit instantiations of dimension D, in namespace ricochet.
#define RICOCHET_FORCE_PASSES(D)                                                                                    \
  template ForceTotals internal_forces(const Model<D>&, const double*, const double*, double*, bool,                \
                                       const StressTracking*, ForceScratch*);                                       \
  template ForceScratch make_force_scratch(const Model<D>&);                                                        \
  template void cell_von_mises(const Model<D>&, const double*, StressMeasure, double*);                             \
  template void cell_tensors(const Model<D>&, const double*, double*, double*);                                     \
  template StressPeaks stress_peaks(const Model<D>&, const double*, const StressTracking&);                          \
  template VonMises2 von_mises_maxima(const Model<D>&, const double*);

// The force pass's kernels for one stress variant of dimension D (kStress as in all_blocks: 0
// for no stresses, else 1 + the measure), in namespace ricochet: with energies or without, and
// a sample pass's where there are stresses.
#define RICOCHET_FORCE_PASS_ALL_BLOCKS(PREFIX, D, kEnergy, kStress, kSample)                                      \
  PREFIX template void force_passes::all_blocks<kEnergy, kStress, kSample, D>(                                     \
      const Model<D>&, const double*, const double*, double*, const StressTracking*, ForceTotals&, ForceScratch*);
#define RICOCHET_FORCE_PASS_VARIANT_SET(PREFIX, D, kStress)                                                       \
  RICOCHET_FORCE_PASS_ALL_BLOCKS(PREFIX, D, false, kStress, false)                                                \
  RICOCHET_FORCE_PASS_ALL_BLOCKS(PREFIX, D, true, kStress, false)                                                 \
  RICOCHET_FORCE_PASS_ALL_BLOCKS(PREFIX, D, true, kStress, true)
#define RICOCHET_FORCE_PASS_VARIANTS(D, kStress) RICOCHET_FORCE_PASS_VARIANT_SET(, D, kStress)
#define RICOCHET_FORCE_PASS_PLAIN(D)                                                                              \
  RICOCHET_FORCE_PASS_ALL_BLOCKS(, D, false, 0, false)                                                            \
  RICOCHET_FORCE_PASS_ALL_BLOCKS(, D, true, 0, false)
// In the passes' unit: every variant is instantiated in its own unit.
#define RICOCHET_FORCE_PASS_EXTERN(D)                                                                             \
  RICOCHET_FORCE_PASS_ALL_BLOCKS(extern, D, false, 0, false)                                                      \
  RICOCHET_FORCE_PASS_ALL_BLOCKS(extern, D, true, 0, false)                                                       \
  RICOCHET_FORCE_PASS_VARIANT_SET(extern, D, 1 + static_cast<int>(StressMeasure::pk2))                            \
  RICOCHET_FORCE_PASS_VARIANT_SET(extern, D, 1 + static_cast<int>(StressMeasure::kirchhoff))                      \
  RICOCHET_FORCE_PASS_VARIANT_SET(extern, D, 1 + static_cast<int>(StressMeasure::cauchy))
