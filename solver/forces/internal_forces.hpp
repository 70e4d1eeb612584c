// Internal nodal forces f_int(u) of every element block: gather -> F = I + ue^T dN/dX -> P(F)
// -> fe = vol dN/dX P^T -> scatter. Flat DOF arrays: u, v, f are 2n, interleaved (x0, y0, x1..).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "solver/model/model.hpp"
#include "solver/core/force_totals.hpp"
#include "solver/materials/stress.hpp"

namespace ricochet {

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
