#include "solver/forces/internal_forces3.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include <omp.h>

#include "solver/forces/element_kernels3.hpp"
#include "solver/materials/stress3.hpp"

namespace ricochet {
namespace {

// The force pass of the 3D kernels (element_kernels3.hpp): the 2D ForcePass of
// internal_forces.cpp with 3x3 F and P and the 3D von Mises (stress3.hpp). kStress: 0 = no
// stresses, else 1 + the measure; kSample: a history sample or a field snapshot
// (StressTracking::samples()), every point's equivalents exact, with the arithmetic of
// von_mises_maxima() and cell_von_mises().
template <bool kEnergy_, int kStress, bool kSample>
struct ForcePass3 {
  static_assert(!kSample || kStress > 0, "a sample pass ranks the stresses too");
  static constexpr bool kEnergy = kEnergy_;
  static constexpr bool kPerPoint = kStress > 0;
  static constexpr bool kEveryPoint = kSample;
  static constexpr StressMeasure measure = static_cast<StressMeasure>(kStress > 0 ? kStress - 1 : 0);
  StressPeaks peaks;
  double threshold = 0.0;
  const std::uint8_t* contact_cell = nullptr;
  VonMisesRatio vm2;                 // the cell's largest so far (cells of several points)
  VonMises2 sampled{0.0, 0.0, 0.0};  // kSample: per measure, the largest so far [Pa^2]
  double cell_max = 0.0;             // kSample: the cell's largest of `measure` so far [Pa^2]
  double* cell_von_mises = nullptr;

  ForcePass3(const StressTracking* tracking, const ForceTotals& t)
      : peaks(t.stress),
        threshold(tracking ? tracking->threshold : 0.0),
        contact_cell(tracking ? tracking->contact_cell : nullptr),
        cell_von_mises(tracking ? tracking->cell_von_mises : nullptr) {}

  struct Response {
    Mat3 P;
  };
  void begin_element() {
    if constexpr (kStress) vm2 = VonMisesRatio{};
    if constexpr (kSample) cell_max = 0.0;
  }
  template <class Mat>
  EIGEN_ALWAYS_INLINE void screen(const Mat&, const LaneMat3& F, const LaneMat3& P, const double* det,
                                  double* may) const {
    von_mises_may_exceed_lanes<measure>(F, P, det, threshold, may);
  }
  template <int kPoints, class Mat, class Rows>
  EIGEN_ALWAYS_INLINE void point(const Mat&, const Mat3& F, double det_f, const Response& r, const Rows&, double,
                                 int cell, bool may) {
    if constexpr (kSample) {
      const std::array<VonMisesRatio, kStressMeasures> all = von_mises_ratios(F, r.P, det_f);
      for (int m = 0; m < kStressMeasures; ++m) sampled[m] = std::max(sampled[m], all[m].value());
      const VonMisesRatio x = all[static_cast<int>(measure)];
      cell_max = std::max(cell_max, x.value());
      if (may) rank<kPoints>(x, cell);
    } else if constexpr (kStress) {
      if (may) rank<kPoints>(von_mises_ratio(F, r.P, det_f, measure), cell);
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
void all_blocks(const Model3& model, const double* u, const double* v, double* f, const StressTracking* cc,
                ForceTotals& t, ForceScratch* scratch) {
  using Pass = ForcePass3<kEnergy, kStress, kSample>;
  if (!scratch) {
    for_each_block(model, [&](const auto& b, const auto& mat, auto viscous) {
      force_kernel<decltype(viscous)::value>(b, mat, u, v, DirectScatter3{f}, Pass(cc, t), t);
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
    visit_block(model, static_cast<BlockKind3>(k.kind), k.block, [&](const auto& b, const auto& mat, auto viscous) {
      force_kernel<decltype(viscous)::value>(b, mat, u, v, out, Pass(cc, tc), tc, k.begin, k.end);
    });
  };
  auto chunk = [&](long c) { chunk_into(c, ElementStore3{x.element_forces.data() + x.chunks[c].out}); };
  // Each node sums its cells' forces in the serial scatter's order, from 0 as f_int starts (an
  // entry's y and z are a row and two rows after its x: ElementStore3).
  auto gather = [&](int i) {
    double fx = 0.0, fy = 0.0, fz = 0.0;
    for (int p = x.node_offsets[i]; p < x.node_offsets[i + 1]; ++p) {
      const double* e = x.element_forces.data() + x.entries[p];
      fx += e[0];
      fy += e[kLanes];
      fz += e[2 * kLanes];
    }
    f[3 * i] = fx;
    f[3 * i + 1] = fy;
    f[3 * i + 2] = fz;
  };
  // As in 2D: no parallel region for a small model or one thread. On one thread the chunks add
  // their cells' forces straight into f instead (DirectScatter3), cell by cell in the order the
  // nodes' sums take them, so f is bit for bit the gathered one, and the totals still sum by
  // chunk; the store and the gather were a fifth of a step of the one-point hexahedron.
  if (x.chunks.size() >= kForceParallelChunks && omp_get_max_threads() > 1) {
#pragma omp parallel
    {
#pragma omp for schedule(static)
      for (long c = 0; c < chunks; ++c) chunk(c);
#pragma omp for schedule(static)
      for (int i = 0; i < nodes; ++i) gather(i);
    }
  } else {
    std::fill(f, f + model.num_dofs(), 0.0);
    for (long c = 0; c < chunks; ++c) chunk_into(c, DirectScatter3{f});
  }
  // The chunks' totals in chunk order; of equal peaks the first cell wins, as in the serial pass.
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

ForceTotals internal_forces(const Model3& model, const double* u, const double* v, double* f_int, bool with_energy,
                            const StressTracking* stress, ForceScratch* scratch) {
  if (!scratch) std::fill(f_int, f_int + model.num_dofs(), 0.0);  // the threaded pass overwrites it
  ForceTotals t;
  if (stress) t.stress.all = t.stress.interior = stress->threshold;  // only cells above it are ranked
  auto run = [&]<bool kEnergy, bool kSample>() {
    if (!stress) {
      if constexpr (!kSample) all_blocks<kEnergy, 0>(model, u, v, f_int, stress, t, scratch);
    } else if (stress->measure == StressMeasure::pk2) {
      all_blocks<kEnergy, 1 + static_cast<int>(StressMeasure::pk2), kSample>(model, u, v, f_int, stress, t, scratch);
    } else if (stress->measure == StressMeasure::kirchhoff) {
      all_blocks<kEnergy, 1 + static_cast<int>(StressMeasure::kirchhoff), kSample>(model, u, v, f_int, stress, t,
                                                                                  scratch);
    } else {
      all_blocks<kEnergy, 1 + static_cast<int>(StressMeasure::cauchy), kSample>(model, u, v, f_int, stress, t,
                                                                               scratch);
    }
  };
  if (stress && stress->samples())
    run.template operator()<true, true>();  // a sample is a monitor step: energies too (as 2D)
  else if (with_energy)
    run.template operator()<true, false>();
  else
    run.template operator()<false, false>();
  if (stress && stress->sampled_max) max_into(*stress->sampled_max, t.sampled);
  return t;
}

ForceScratch make_force_scratch(const Model3& model) {
  ForceScratch x;
  std::size_t out = 0;
  std::vector<std::vector<int>> node_entries(model.num_nodes());
  for (const BlockKind3 kind : kBlockKinds3)  // for_each_block's order
    for (std::size_t k = 0; k < model.num_blocks(kind); ++k)
      visit_block(model, kind, k, [&](const auto& b, const auto&, auto) {
        constexpr int N = std::decay_t<decltype(b)>::kNodes;
        for (std::size_t e0 = 0; e0 < b.conn.size(); e0 += kForceChunkCells)
          x.chunks.push_back({static_cast<int>(kind), k, e0, std::min(b.conn.size(), e0 + kForceChunkCells), out});
        for (std::size_t e = 0; e < b.conn.size(); ++e)
          for (int i = 0; i < N; ++i)
            node_entries[b.conn[e][i]].push_back(static_cast<int>(out + ElementStore3::entry<N>(e, i)));
        out += 3 * N * kLanes * b.num_batches();  // whole batches, the last one's padding too
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

// Calls fn(global cell, the cell's points' values, weights) for every cell in for_each_block's
// order: point(F, P, det F) at each integration point with F from the kernels' arithmetic
// (element_kernels3.hpp: the force pass's F, bit for bit) and P = mat.first_piola(F), and each
// point's reference volume. Cells of one point pass one value.
template <class Point, class Fn>
void for_each_cell_points(const Model3& model, const double* u, Point&& point, Fn&& fn) {
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
            std::array<decltype(point(F[0], F[0], 1.0)), 8> values;
            std::array<double, 8> vol;
            for (int q = 0; q < 8; ++q) {
              values[q] = point(F[q], mat.first_piola(F[q]), F[q].determinant());
              vol[q] = b.geom(e, Hex8Lanes::vol(q));
            }
            fn(cell, values.data(), vol.data(), 8);
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
            const auto value = point(F, mat.first_piola(F), F.determinant());
            fn(cell, &value, &vol, 1);
          }
        }
      });
}

// The cell's value: the largest over its points of the points' VonMises2.
template <class Fn>
void for_each_cell_stress(const Model3& model, const double* u, StressMeasure measure, bool all, Fn&& fn) {
  const int mi = static_cast<int>(measure);
  auto point = [&](const Mat3& F, const Mat3& P, double det_f) {
    if (all) return von_mises_squared(F, P, det_f);
    VonMises2 v{0.0, 0.0, 0.0};
    v[mi] = von_mises_ratio(F, P, det_f, measure).value();  // the one measure's work
    return v;
  };
  for_each_cell_points(model, u, point, [&](int cell, const VonMises2* values, const double*, int n) {
    VonMises2 vm2{0.0, 0.0, 0.0};
    for (int q = 0; q < n; ++q) max_into(vm2, values[q]);
    fn(cell, vm2);
  });
}

}  // namespace

void cell_von_mises(const Model3& model, const double* u, StressMeasure measure, double* out) {
  const int m = static_cast<int>(measure);
  for_each_cell_stress(model, u, measure, false, [&](int cell, const VonMises2& vm2) { out[cell] = std::sqrt(vm2[m]); });
}

void cell_tensors(const Model3& model, const double* u, double* cauchy, double* green_lagrange) {
  struct Tensors {
    SymTensor6 sigma, strain;
  };
  auto point = [](const Mat3& F, const Mat3& P, double det_f) {
    Tensors t;
    cauchy_and_green_lagrange(F, P, det_f, t.sigma, t.strain);
    return t;
  };
  // One point: its values; 2x2x2 points: the mean weighted by the points' reference volumes (the
  // cell's average by its own quadrature).
  for_each_cell_points(model, u, point, [&](int cell, const Tensors* values, const double* vol, int n) {
    double* s = cauchy + 6 * cell;
    double* g = green_lagrange + 6 * cell;
    if (n == 1) {
      for (int k = 0; k < 6; ++k) {
        s[k] = values[0].sigma[k];
        g[k] = values[0].strain[k];
      }
      return;
    }
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
  });
}

StressPeaks stress_peaks(const Model3& model, const double* u, const StressTracking& stress) {
  StressPeaks p;
  const int m = static_cast<int>(stress.measure);
  auto rank = [&](int cell, const VonMises2& vm2) {
    p.add(VonMisesRatio{vm2[m], 1.0}, cell, stress.contact_cell && stress.contact_cell[cell] != 0);
  };
  if (!stress.samples()) {
    for_each_cell_stress(model, u, stress.measure, false, rank);
    return p;
  }
  VonMises2 sampled{0.0, 0.0, 0.0};
  for_each_cell_stress(model, u, stress.measure, true, [&](int cell, const VonMises2& vm2) {
    rank(cell, vm2);
    max_into(sampled, vm2);
    if (stress.cell_von_mises) stress.cell_von_mises[cell] = std::sqrt(vm2[m]);
  });
  if (stress.sampled_max) max_into(*stress.sampled_max, sampled);
  return p;
}

VonMises2 von_mises_maxima(const Model3& model, const double* u) {
  VonMises2 m{0.0, 0.0, 0.0};
  for_each_cell_stress(model, u, StressMeasure::cauchy, true, [&](int, const VonMises2& vm2) { max_into(m, vm2); });
  for (double& x : m) x = std::sqrt(x);
  return m;
}

}  // namespace ricochet
