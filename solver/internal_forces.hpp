// Internal nodal forces f_int(u) of every element block: gather -> F = I + ue^T dN/dX -> P(F)
// -> fe = vol dN/dX P^T -> scatter. Flat DOF arrays: u, v, f are 2n, interleaved (x0, y0, x1..).
#pragma once

#include "solver/model.hpp"

namespace ricochet {

struct ForceTotals {
  double strain_energy = 0.0;     // sum vol * W(F) [J]; only when asked for
  double hourglass_energy = 0.0;  // stored 1/2 c q.q of stiffness-form hourglass control [J]; only when asked for
  double hourglass_power = 0.0;   // sum Q . qdot of viscous hourglass control [W]; always
  double min_jacobian = 1e300;    // smallest det F at any integration point [-]
};

// Overwrites f_int. `v` (2n) is the velocity the viscous hourglass forces use.
// With `with_energy` the strain and stored hourglass energies are summed as well.
ForceTotals internal_forces(const Model& model, const double* u, const double* v, double* f_int,
                            bool with_energy);

// Largest von Mises (Cauchy) stress over each cell's integration points, per global cell [Pa].
// `out` has model.num_cells() entries.
void cell_von_mises(const Model& model, const double* u, double* out);

}  // namespace ricochet
