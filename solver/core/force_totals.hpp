// What a pass of the internal forces gives back besides the forces, and its workspace: the
// energies, the smallest det F, the von Mises peaks of the stress measures (materials/stress.hpp
// computes the equivalents), and the threaded pass's scratch (forces/internal_forces.hpp). Plain
// data on the lowest floor, so that the state (core/state.hpp), the run's results and every
// folder above can hold them without including the force pass.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "solver/core/types.hpp"

namespace ricochet {

enum class StressMeasure { cauchy = 0, pk2 = 1, kirchhoff = 2 };
inline constexpr int kStressMeasures = 3;

inline const char* stress_measure_name(StressMeasure m) {
  switch (m) {
    case StressMeasure::pk2: return "pk2";
    case StressMeasure::kirchhoff: return "kirchhoff";
    default: return "cauchy";
  }
}

// Squared von Mises equivalents, indexed by StressMeasure [Pa^2].
using VonMises2 = std::array<double, kStressMeasures>;

inline void max_into(VonMises2& acc, const VonMises2& x) {
  for (int m = 0; m < kStressMeasures; ++m) acc[m] = std::max(acc[m], x[m]);
}

struct VonMisesRatio {
  double num = 0.0;  // [Pa^2]
  double den = 1.0;  // [-]
  double value() const { return num / den; }
};

inline bool ratio_greater(const VonMisesRatio& a, const VonMisesRatio& b) {
  return a.num * b.den > b.num * a.den;
}

// The largest squared equivalent of one measure over one evaluation of the internal forces,
// over all cells and over the interior cells (those without a node on a contact boundary),
// with the global cell index where each was reached (-1: none).
struct StressPeaks {
  double all = 0.0, interior = 0.0;  // [Pa^2]
  int all_cell = -1, interior_cell = -1;

  // Folds in one cell's squared equivalent (the max over its integration points), divided out
  // only when it is a new peak.
  void add(const VonMisesRatio& cell_vm2, int cell, bool on_contact_boundary) {
    if (cell_vm2.num > all * cell_vm2.den) {
      all = cell_vm2.value();
      all_cell = cell;
    }
    if (!on_contact_boundary && cell_vm2.num > interior * cell_vm2.den) {
      interior = cell_vm2.value();
      interior_cell = cell;
    }
  }
};

// What the force pass tracks of the stresses (stress.hpp).
struct StressTracking {
  const std::uint8_t* contact_cell = nullptr;  // per global cell, 1 on a contact boundary; never null
  StressMeasure measure = StressMeasure::cauchy;
  double threshold = 0.0;  // [Pa^2]: points that cannot exceed it are not ranked (0: rank all)
  // What a history sample or a field snapshot asks of the same pass (null: nothing), so that
  // it costs no second pass over the elements. Either makes every point's equivalents exact.
  VonMises2* sampled_max = nullptr;  // folds in, per measure, the largest squared equivalent over
                                     // every integration point [Pa^2]
  double* cell_von_mises = nullptr;  // per global cell (model.num_cells()), the von Mises of
                                     // `measure`, the largest over the cell's points [Pa]
  bool samples() const { return sampled_max != nullptr || cell_von_mises != nullptr; }
};

struct ForceTotals {
  double strain_energy = 0.0;     // sum vol * W(F) [J]; only when asked for
  double hourglass_energy = 0.0;  // stored 1/2 c q.q of stiffness-form hourglass control [J]; only when asked for
  double hourglass_power = 0.0;   // sum Q . qdot of viscous hourglass control [W]; always
  double min_jacobian = 1e300;    // smallest det F at any integration point [-]
  StressPeaks stress;             // only when asked for (StressTracking): the largest values above its
                                  // threshold (a cell index of -1: none above it)
  VonMises2 sampled{0.0, 0.0, 0.0};  // what StressTracking::sampled_max asked for, of this pass alone [Pa^2]
};

// The workspace of the threaded force pass, made once per model (make_force_scratch). The
// cells are cut into chunks of a fixed number of cells (whatever the number of threads); the
// chunks run in parallel and store each cell's nodal forces at the cell's place in
// element_forces (d N values per cell, d = Model<2>::kDim, the cells in the order of the
// for_each_block of element_kernels2.hpp, or element_kernels3.hpp for a Model<3>); then every node
// sums its entries in that order, the order in which a serial scatter adds them, and the
// chunks' totals are combined in chunk order. So the forces equal the serial pass's, and no
// result depends on the number of threads. One type for both dimensions, with a layout of
// element_forces per dimension: in 2D a cell's 2N values are contiguous, node I's x force at
// 2I and its y force at 2I + 1; the 3D layout (cells in batches of kLanes, a node's y and z
// forces kLanes and 2 kLanes after its x force) is described in internal_forces3.hpp.
struct ForceScratch {
  struct Chunk {
    int kind = 0;             // the block kind: a BlockKind (Model<2>) or BlockKind3 (Model<3>)
    std::size_t block = 0;    // index among the model's blocks of that kind
    std::size_t begin = 0, end = 0;  // the block's cells begin <= e < end
    std::size_t out = 0;      // offset of the block's first cell in element_forces
  };
  std::vector<Chunk> chunks;
  std::vector<int> node_offsets;  // num_nodes + 1: node i's entries are [node_offsets[i], node_offsets[i + 1])
  std::vector<int> entries;       // positions in element_forces of a node's x force, ascending (its y
                                  // force: + 1 in 2D; y and z in 3D: internal_forces3.hpp)
  std::vector<double> element_forces;
  std::vector<ForceTotals> totals;  // per chunk
};
inline constexpr std::size_t kForceChunkCells = 256;  // a multiple of kLanes (the vectorized kernels start batches at a chunk's start)
static_assert(kForceChunkCells % kLanes == 0);
// Below this many chunks the pass runs on one thread (the same arithmetic): a parallel region
// costs more than it saves on a small model.
inline constexpr std::size_t kForceParallelChunks = 4;

}  // namespace ricochet
