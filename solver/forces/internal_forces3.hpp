// The 3D force pass: internal nodal forces f_int(u, v) of every element block of a Model3,
// with the energies, the smallest det F and the stress tracking, and the 3D stress passes.
// The same functions, arguments and meanings as the 2D ones (internal_forces.hpp), as overloads
// on the model type, so that a scheme written as a template over the model calls the right one.
// Flat DOF arrays: u, v, f are 3n, interleaved (x0, y0, z0, x1, ...). The kernels:
// element_kernels3.hpp; the 3D von Mises: stress3.hpp.
//
// The element matrices of the implicit scheme in 3D (its SystemMatrix with three DOFs per node)
// are not here yet: they will come as a tangent pass beside tangent.hpp, from element3d.hpp's
// hex8_stiffness, hex8_one_point_stiffness and tet4_stiffness on the geometry of
// cell_geometry() (model3.hpp), with its forces checked against this pass's.
#pragma once

#include "solver/forces/internal_forces.hpp"  // ForceTotals, StressTracking, ForceScratch
#include "solver/model/model3.hpp"

namespace ricochet {

// The threaded pass's workspace for a Model3 (ForceScratch, the 2D type: one State serves both
// dimensions): chunks of kForceChunkCells cells of the blocks in for_each_block's order, 3N
// element-force values per cell, a block's in whole batches of kLanes cells in the lane layout of
// element_kernels3.hpp's ElementStore3 (an entry's y and z values kLanes and 2 kLanes after its x).
ForceScratch make_force_scratch(const Model3& model);

// Overwrites f_int (3n). `v` (3n) is the velocity the viscous hourglass forces use. As the 2D
// internal_forces(): with `with_energy` the strain and stored hourglass energies are summed;
// the hourglass power and the smallest det F always; with `stress` the pass ranks the von
// Mises equivalents of stress->measure (stress3.hpp) above stress->threshold and fills what
// stress->sampled_max and stress->cell_von_mises ask for; with `scratch` (from
// make_force_scratch(model)) it is the threaded pass, whose results do not depend on the number
// of threads (its energies sum per chunk).
ForceTotals internal_forces(const Model3& model, const double* u, const double* v, double* f_int, bool with_energy,
                            const StressTracking* stress = nullptr, ForceScratch* scratch = nullptr);

// Largest von Mises stress of `measure` over each cell's integration points, per global cell
// [Pa]. `out` has model.num_cells() entries.
void cell_von_mises(const Model3& model, const double* u, StressMeasure measure, double* out);

// The Cauchy stress [Pa] and the Green-Lagrange strain [-] of each cell at u, symmetric tensors in
// VTK order (XX, YY, ZZ, XY, YZ, XZ): 6 values per global cell in `cauchy` and `green_lagrange`
// (6 model.num_cells() each). A cell's value is the mean over its integration points weighted by
// their reference volumes (one-point cells: the centroid's value).
void cell_tensors(const Model3& model, const double* u, double* cauchy, double* green_lagrange);

// The peaks internal_forces() tracks, by a stress pass alone, and what stress.sampled_max and
// stress.cell_von_mises ask for. `contact_cell` null: no cell is on a contact boundary.
StressPeaks stress_peaks(const Model3& model, const double* u, const StressTracking& stress);

// The largest von Mises stress of each measure over all cells and integration points [Pa].
VonMises2 von_mises_maxima(const Model3& model, const double* u);

}  // namespace ricochet
