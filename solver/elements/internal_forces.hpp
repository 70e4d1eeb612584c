// Internal nodal forces f_int(u) of every element block: gather -> F = I + ue^T dN/dX -> P(F)
// -> fe = vol dN/dX P^T -> scatter. Flat DOF arrays: u, v, f are 2n, interleaved (x0, y0, x1..).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "solver/model/model.hpp"
#include "solver/materials/stress.hpp"

namespace ricochet {

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
// element_forces (d N values per cell, d = Model::kDim, the cells in the order of the
// for_each_block of element_kernels.hpp, or element_kernels3.hpp for a Model3); then every node
// sums its entries in that order, the order in which a serial scatter adds them, and the
// chunks' totals are combined in chunk order. So the forces equal the serial pass's, and no
// result depends on the number of threads. One type for both dimensions, with a layout of
// element_forces per dimension: in 2D a cell's 2N values are contiguous, node I's x force at
// 2I and its y force at 2I + 1; the 3D layout (cells in batches of kLanes, a node's y and z
// forces kLanes and 2 kLanes after its x force) is described in internal_forces3.hpp.
struct ForceScratch {
  struct Chunk {
    int kind = 0;             // the block kind: a BlockKind (Model) or BlockKind3 (Model3)
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

ForceScratch make_force_scratch(const Model& model);

// Overwrites f_int. `v` (2n) is the velocity the viscous hourglass forces use.
// With `with_energy` the strain and stored hourglass energies are summed as well. With
// `stress` the pass also ranks the von Mises equivalents of stress->measure at every
// integration point above stress->threshold (ForceTotals::stress; the cost:
// bench/bench_element_forces.cpp), and fills what stress->sampled_max and
// stress->cell_von_mises ask for (the values von_mises_maxima() and cell_von_mises() give).
// With `scratch` (from make_force_scratch(model)) the pass is the threaded one: it uses the
// OpenMP threads in force (RunSettings::threads, ThreadScope) and gives the same results for
// any number of them. The energies then sum per chunk, so they may differ from the serial
// pass's in the last bits.
ForceTotals internal_forces(const Model& model, const double* u, const double* v, double* f_int,
                            bool with_energy, const StressTracking* stress = nullptr,
                            ForceScratch* scratch = nullptr);

// Largest von Mises stress of `measure` over each cell's integration points, per global cell
// [Pa]. `out` has model.num_cells() entries.
void cell_von_mises(const Model& model, const double* u, StressMeasure measure, double* out);

// The Cauchy stress [Pa] and the Green-Lagrange strain [-] of each cell at u, as symmetric
// tensors in VTK order (XX, YY, ZZ, XY, YZ, XZ; cauchy_and_green_lagrange(), stress.hpp): 6
// values per global cell in `cauchy` and `green_lagrange` (6 model.num_cells() each). A cell's
// value is the mean over its integration points weighted by their reference volumes (one-point
// cells: the centroid's value). For field snapshots only: a pass of its own over the elements.
void cell_tensors(const Model& model, const double* u, double* cauchy, double* green_lagrange);

// The peaks internal_forces() tracks, by a stress pass alone (for the implicit scheme, whose
// force passes are Newton iterates), and in the same pass what stress.sampled_max and
// stress.cell_von_mises ask for. `contact_cell` null: no cell is on a contact boundary.
StressPeaks stress_peaks(const Model& model, const double* u, const StressTracking& stress);

// The largest von Mises stress of each measure over all cells and integration points [Pa].
VonMises2 von_mises_maxima(const Model& model, const double* u);

}  // namespace ricochet
