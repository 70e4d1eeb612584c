// The time step for every scheme and command (docs/background.md, Critical time step): the
// stable step of a model under a run's contact method, decided once; and for the explicit loop
// the variable step that follows the current configuration (StepControl; docs/background.md,
// Variable time step).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "solver/schemes/run_types.hpp"

namespace ricochet {

// The critical step (safety 1) of a model under a run's contact method [s], the one rule the
// automatic step (safety x this) and the stability search use: the elements' estimate
// model.critical_dt (min L_e / c_p), and with penalty contact the combined limit of elements
// and springs, 1 / sqrt(1 / dt_e^2 + 1 / dt_p^2) (penalty_combined_critical_dt). With penalty
// contact, `penalty_critical_dt` (if not null) receives the springs' own limit dt_p (+infinity
// without springs); it is left alone otherwise. Penalty springs of `settings.penalty.soft`
// depend on settings.penalty.soft_dt, which must be set.
template <class M>
double critical_time_step(const M& model, const RunSettings& settings, double* penalty_critical_dt = nullptr);

// The variable time step of the explicit loop (RunSettings::dt_update_interval = N > 0). At the
// top of step n, before evaluate(): when t_n has reached end_time the run is over; otherwise,
// every N steps (n = 0, N, 2N, ...), the step becomes
//   dt = dt_safety x critical(u_n),   critical = 1 / sqrt(1 / dt_e^2 + 1 / dt_p^2),
// dt_e = min over cells of L_e(X + u_n) / c_p: the characteristic lengths of
// model.critical_dt (q4_characteristic_length, t3_characteristic_length) in the current
// configuration, with the material's small-strain wave speed c_p of t = 0; dt_p the penalty
// springs' limit, whose stiffness does not change (dt_p = +infinity without springs: dt_e).
// The undeformed configuration gives the automatic step of prepare_case() bit for bit. A step
// that would pass end_time is shortened to end on it. A recomputed step below
// dt_min_ratio x the initial step (or a cell with L_e <= 0) is a failure the loop reports as a
// divergence. With N = 0 it leaves the step alone and only ends the run after ceil(end/dt)
// steps, as the fixed-step loop does. Allocates nothing after construction.
template <class M>
class StepControlT {
 public:
  StepControlT(const M& model, const RunSettings& settings, double spring_critical_dt);

  bool variable() const { return interval_ > 0; }

  // The critical step (safety 1) of the configuration u (2n) [s]; `cell`, if not null, gets the
  // global cell that sets dt_e (the first in cell order on ties). 0 if a cell has L_e <= 0
  // (inverted). With `parallel`, on the OpenMP threads in force; the result is the same.
  double critical(const Eigen::VectorXd& u, int* cell = nullptr, bool parallel = false) const;

  // At the top of step s.step (variable step only): false when t_n has reached end_time (the
  // state is the run's last, and s.time is set to end_time exactly). Otherwise sets the step
  // from t_n (set_step) and returns true.
  bool begin_step(State& s);

  // Why the last recomputed step was refused (below the floor, or an inverted cell); empty if
  // it was not. The step then stays the previous one, for the loop to report the state.
  const std::string& failure() const { return failure_; }

  // Steps to the end: n + ceil((end - t_n) / dt) at the last recomputation (an estimate for
  // progress output); ceil(end / dt) for a fixed step.
  long planned_steps() const { return planned_; }

  // Into the run's result: dt_update_interval, dt_min, dt_max, dt_updates, dt_floor.
  void report(RunResult& r) const;

 private:
  const M& model_;
  int interval_ = 0;
  double safety_ = 0.9, end_ = 0.0, dt0_ = 0.0, floor_ = 0.0;
  double spring_dt_ = 0.0;
  std::array<std::vector<double>, 3> wave_speed_;  // per block of each BlockKind, c_p [m/s]
  std::array<std::vector<double>, 3> inv_c2_;      // 1 / c_p^2 [s^2/m^2]
  mutable std::vector<double> position_;           // critical()'s scratch: X + u (2n) [m]
  double dt_min_ = 0.0, dt_max_ = 0.0;
  long updates_ = 0, planned_ = 0;
  bool landed_ = false;  // the step just taken was shortened to end on end_time
  std::string failure_;
};

template <>
double StepControlT<Model<2>>::critical(const Eigen::VectorXd& u, int* cell, bool parallel) const;
template <>
double StepControlT<Model<3>>::critical(const Eigen::VectorXd& u, int* cell, bool parallel) const;
using StepControl = StepControlT<Model<2>>;

}  // namespace ricochet
