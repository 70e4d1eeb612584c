// Observers of the state at t_n (after evaluate()): energies, momentum, stresses, probes.
#pragma once

#include "solver/core/loads.hpp"
#include "solver/core/state.hpp"

namespace ricochet {

struct Energies {
  double kinetic = 0.0;         // 1/2 v_n^T M v_n [J]
  double strain = 0.0;          // sum vol W(F) [J]
  double hourglass = 0.0;       // stored (stiffness form) + dissipated (viscous form) [J]
  double external_work = 0.0;   // body forces + prescribed-DOF reactions + nodal loads [J]
  double friction_dissipation = 0.0;  // [J]
  // kinetic + strain + hourglass [J]
  double total() const { return kinetic + strain + hourglass; }
};

// Needs the force totals of an evaluate() with energy. u0 is the initial displacement.
template <class M>
Energies observe_energies(const M& model, const State& s, const Eigen::VectorXd& u0);

// sum_I m_I v_n,I [kg m/s]
template <class M>
Eigen::Matrix<double, M::kDim, 1> linear_momentum(const M& model, const State& s);

// |E(t) + D(t) - E_0 - W_ext(t)| / E_ref with E(t) the total above, D the friction dissipation,
// E_ref = max(E_0, |W_ext| seen so far); 0 when E_ref is 0. [-]
double energy_error(const Energies& e, double initial_energy, double reference_energy);

}  // namespace ricochet
