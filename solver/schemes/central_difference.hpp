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

#include "solver/elements/internal_forces.hpp"

namespace ricochet {

// A prescribed DOF: either a constant velocity, or a displacement reached linearly over
// `ramp` seconds (ramp = 0: imposed from t = 0), u(t) = value * min(1, t / ramp).
struct PrescribedDof {
  enum class Kind { velocity, displacement };
  int dof = 0;
  Kind kind = Kind::velocity;
  double value = 0.0;  // [m/s] or [m]
  double ramp = 0.0;   // [s]

  double displacement_at(double t) const {
    return ramp > 0.0 && t < ramp ? value * t / ramp : value;
  }
};

// A nodal force on one DOF that is switched on at `start` and ramped up linearly over `ramp`
// seconds (ramp = 0: a step at `start`): F(t) = value * clamp((t - start) / ramp, 0, 1), and 0
// before `start` (case key [[loads]], docs/case-format.md). Its work is accumulated in
// State::load_work.
struct NodalLoad {
  int dof = 0;
  double value = 0.0;  // [N]
  double start = 0.0;  // [s]
  double ramp = 0.0;   // [s]

  double force_at(double t) const {
    if (t < start) return 0.0;
    return ramp > 0.0 && t < start + ramp ? value * (t - start) / ramp : value;
  }
  // Constant from t = 0 on (the loads a quasi-static start relaxes under, and that do not end
  // a body's rest: summary.json `drift`).
  bool constant() const { return start <= 0.0 && ramp <= 0.0; }
};

// A loaded DOF of a run: its load, and what the trapezoidal work rule needs of the last step.
struct LoadedDof {
  NodalLoad load;
  double force_last = 0.0;  // F at the last evaluate() [N]
  double u_last = 0.0;      // u of that DOF then [m]
};

struct State {
  long step = 0;
  double time = 0.0;     // t_n [s]
  double dt = 0.0;       // dt_{n+1/2}, the step from t_n to t_n+1 [s]
  double dt_prev = 0.0;  // dt_{n-1/2}, the step that led to t_n (= dt at n = 0) [s]
  // t_n = time_base + (step - step_base) dt: the time and step at the last change of dt
  // (set_step), so that a fixed step keeps t_n = n dt.
  double time_base = 0.0;  // [s]
  long step_base = 0;
  Eigen::VectorXd u;       // u_n [m]
  Eigen::VectorXd v_half;  // v_{n-1/2} (v_0 before the first evaluate) [m/s]
  Eigen::VectorXd a;       // a_n after evaluate() [m/s^2]
  Eigen::VectorXd f_int;   // f_int(u_n) [N]
  Eigen::VectorXd f_ext;   // body forces M g [N], constant
  double hourglass_dissipation = 0.0;  // work of viscous hourglass forces so far [J]
  double reaction_work = 0.0;          // work of the prescribed-DOF reactions up to t_n [J]
  double reaction_power = 0.0;         // sum R v_n of the last evaluate() [W]
  // Time-dependent nodal loads (empty: none) and their work up to t_n, by the trapezoidal rule
  // in displacement, sum 1/2 (F_{k-1} + F_k) . (u_k - u_{k-1}): the rule under which a constant
  // load's work is F . (u_n - u_0), as for gravity.
  std::vector<LoadedDof> loads;
  double load_work = 0.0;  // [J]
  ForceTotals forces;                  // totals of the last evaluate()
  ForceScratch force_scratch;          // the threaded force pass's workspace (internal_forces.hpp)
};

// Allocates the state: u_0 = initial_displacement (or 0) with prescribed displacements
// imposed, v_0 = the model's initial velocities with prescribed velocities imposed, and the
// nodal loads.
// M is the model type (Model, 2D; its dimension M::kDim sets the DOFs per node).
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

// Makes dt the step from t_n, dt_{n+1/2} (before evaluate() of step n); at n = 0 also dt_{-1/2}.
inline void set_step(State& s, double dt) {
  s.time_base = s.time;
  s.step_base = s.step;
  s.dt = dt;
  if (s.step == 0) s.dt_prev = dt;
}

// dt_n = (dt_{n-1/2} + dt_{n+1/2}) / 2: the time over which a_n changes the velocity,
// v_{n+1/2} - v_{n-1/2} = dt_n a_n [s]. dt itself for a fixed step.
inline double velocity_step(const State& s) { return 0.5 * (s.dt_prev + s.dt); }

// Velocity at t_n, v_n = v_{n-1/2} + dt_{n-1/2}/2 a_n, of one DOF (valid after evaluate()):
// v_{n+1} - v_n = dt_{n+1/2} (a_n + a_{n+1}) / 2, the trapezoidal rule over each step.
inline double velocity_at_step(const State& s, int dof) {
  return s.v_half[dof] + 0.5 * s.dt_prev * s.a[dof];
}

// Fixed-step estimate: safety * min over cells of L_e / c_p (docs/background.md, Critical time
// step). [s]
inline double stable_time_step(const Model& model, double safety) {
  return safety * model.critical_dt;
}

}  // namespace ricochet
