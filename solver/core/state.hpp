// The state of a run at t_n that every scheme advances and every observer reads: time and step,
// displacements, velocities, accelerations, forces and the work accounts (docs/background.md,
// Central differences with a lumped mass, and Variable time step). The central-difference phases
// that advance it are schemes/central_difference.hpp's; the implicit scheme keeps the same fields.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "solver/core/force_totals.hpp"
#include "solver/core/loads.hpp"

namespace ricochet {

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

}  // namespace ricochet
