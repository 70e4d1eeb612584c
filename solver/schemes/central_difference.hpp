// Central-difference explicit integration with a lumped mass (docs/background.md, Central
// differences with a lumped mass, steps 1, 2, 5), with a step that may change from one step to
// the next (docs/background.md, Variable time step):
//   a_n = M^-1 (f_ext - f_int(u_n)),
//   v_{n+1/2} = v_{n-1/2} + dt_n a_n,   dt_n = (dt_{n-1/2} + dt_{n+1/2}) / 2,
//   u_{n+1} = u_n + dt_{n+1/2} v_{n+1/2},
// dt_{n+1/2} = t_{n+1} - t_n the step taken from t_n (State::dt) and dt_{n-1/2} the one that
// led to t_n (State::dt_prev). With a fixed step dt_n = dt_{n+1/2} = dt, bit for bit.
// The step is split into phases so a scheme can act between them (contact, from the next
// schemes on) and observers can read the state at t_n: evaluate() then update().
#pragma once

#include <vector>

#include "solver/core/loads.hpp"
#include "solver/core/state.hpp"
#include "solver/forces/internal_forces.hpp"

namespace ricochet {

// Allocates the state: u_0 = initial_displacement (or 0) with prescribed displacements
// imposed, v_0 = the model's initial velocities with prescribed velocities imposed, and the
// nodal loads.
// M is the model type (Model<2>, 2D; its dimension M::kDim sets the DOFs per node).
template <class M>
State initial_state(const M& model, const std::vector<PrescribedDof>& prescribed, double dt,
                    const Eigen::VectorXd& initial_displacement = {},
                    const std::vector<NodalLoad>& loads = {});

// Phase 1 of step n: f_int(u_n), free accelerations with the nodal loads F(t_n), then the
// prescribed DOFs' accelerations and the work of their reactions, accumulated by the
// trapezoidal rule in time (the rule under which 1/2 v_n^T M v_n changes by the work of the
// forces, to O(dt^2)). At n = 0 also sets v_{-1/2} = v_0 - dt_{-1/2}/2 a_0. Uses s.dt
// (dt_{n+1/2}): change it with set_step() before.
// With `stress` (internal_forces()) the pass also ranks the step's stresses. The force pass is
// the threaded one (s.force_scratch), on the OpenMP threads in force.
template <class M>
void evaluate(const M& model, const std::vector<PrescribedDof>& prescribed, State& s, bool with_energy,
              const StressTracking* stress = nullptr);

// Phase 2: v_{n+1/2} = v_{n-1/2} + dt_n a_n, u_{n+1} = u_n + dt_{n+1/2} v_{n+1/2},
// t_{n+1} = t_n + dt_{n+1/2}; dt_prev becomes dt.
void update(State& s);

// Fixed-step estimate: safety * min over cells of L_e / c_p (docs/background.md, Critical time
// step). [s]
inline double stable_time_step(const Model<2>& model, double safety) {
  return safety * model.critical_dt;
}

}  // namespace ricochet
