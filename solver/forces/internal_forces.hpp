// Internal nodal forces f_int(u) of every element block of a Model<D>, and the stress passes:
// gather -> F = I + ue^T dN/dX -> P(F) -> fe = vol dN/dX P^T -> scatter. Written once for both
// dimensions (internal_forces.cpp), instantiated for D = 2 and 3. Flat DOF arrays: u, v, f are
// D n, interleaved (x0, y0, [z0,] x1, ...). The kernels: element_kernels2.hpp,
// element_kernels3.hpp; the von Mises equivalents: stress.hpp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "solver/core/force_totals.hpp"
#include "solver/materials/stress.hpp"
#include "solver/model/model.hpp"

namespace ricochet {

// How the force pass of dimension D puts out a cell's forces: Scatter (added into f), Store (at
// the cell's place in the threaded pass's buffer; Store::entry, Store::size, Store::kStride), and
// whether the threaded pass on one thread scatters directly (kScatterOnOneThread). Defined
// beside the dimension's kernels: element_kernels2.hpp, element_kernels3.hpp.
template <int D>
struct ForceOutput;

// The threaded pass's workspace: chunks of kForceChunkCells cells of the blocks in
// for_each_block's order, D N element-force values per cell in the layout of the dimension's
// ForceOutput<D>::Store.
template <int D>
ForceScratch make_force_scratch(const Model<D>& model);

// Overwrites f_int. `v` (D n) is the velocity the viscous hourglass forces use.
// With `with_energy` the strain and stored hourglass energies are summed as well; the hourglass
// power and the smallest det F always. With `stress` the pass also ranks the von Mises
// equivalents of stress->measure at every integration point above stress->threshold
// (ForceTotals::stress; the cost: bench/bench_element_forces.cpp), and fills what
// stress->sampled_max and stress->cell_von_mises ask for (the values von_mises_maxima() and
// cell_von_mises() give). With `scratch` (from make_force_scratch(model)) the pass is the
// threaded one: it uses the OpenMP threads in force (RunSettings::threads, ThreadScope) and gives
// the same results for any number of them. The energies then sum per chunk, so they may differ
// from the serial pass's in the last bits.
template <int D>
ForceTotals internal_forces(const Model<D>& model, const double* u, const double* v, double* f_int, bool with_energy,
                            const StressTracking* stress = nullptr, ForceScratch* scratch = nullptr);

// Largest von Mises stress of `measure` over each cell's integration points, per global cell
// [Pa]. `out` has model.num_cells() entries.
template <int D>
void cell_von_mises(const Model<D>& model, const double* u, StressMeasure measure, double* out);

// The Cauchy stress [Pa] and the Green-Lagrange strain [-] of each cell at u, as symmetric
// tensors in VTK order (XX, YY, ZZ, XY, YZ, XZ; cauchy_and_green_lagrange()): 6 values per
// global cell in `cauchy` and `green_lagrange` (6 model.num_cells() each). A cell's value is the
// mean over its integration points weighted by their reference volumes (one-point cells: the
// centroid's value). For field snapshots only: a pass of its own over the elements.
template <int D>
void cell_tensors(const Model<D>& model, const double* u, double* cauchy, double* green_lagrange);

// The peaks internal_forces() tracks, by a stress pass alone (for the implicit scheme, whose
// force passes are Newton iterates), and in the same pass what stress.sampled_max and
// stress.cell_von_mises ask for. `contact_cell` null: no cell is on a contact boundary.
template <int D>
StressPeaks stress_peaks(const Model<D>& model, const double* u, const StressTracking& stress);

// The largest von Mises stress of each measure over all cells and integration points [Pa].
template <int D>
VonMises2 von_mises_maxima(const Model<D>& model, const double* u);

}  // namespace ricochet
