// What every scheme's time loop shares: the sampling schedule, the observers at monitor
// steps, divergence checks, history rows and field snapshots, timing. A scheme loop calls
// is_monitor_step(n) to know whether to compute energies, then observe(...) at those steps.
#pragma once

#include <chrono>
#include <cstdint>
#include <ctime>
#include <vector>

#include "solver/contact/contact_set.hpp"
#include "solver/schemes/run_types.hpp"

namespace ricochet {

// What the angular momentum is in dimension D: its z component in 2D, the vector in 3D
// [kg m^2/s].
template <int D>
struct MonitorSpace;
template <>
struct MonitorSpace<2> {
  using Angular = double;
  static double zero_angular() { return 0.0; }
};
template <>
struct MonitorSpace<3> {
  using Angular = Vec3;
  static Vec3 zero_angular() { return Vec3::Zero(); }
};

// M is the model type (Model<2> in 2D).
template <class M>
class RunMonitorT {
 public:
  // `contact` is the scheme's contact set (no candidates: no contact), read at every observation:
  // its candidates' penetration, its observables, and at the end its run totals.
  RunMonitorT(const M& model, const RunSettings& settings, RunResult& result, const ContactSetT<M::kDim>& contact);

  long planned_steps() const { return planned_; }
  bool is_monitor_step(long n) const;

  // Variable step (RunSettings::dt_update_interval > 0), where the schedule is by time: at the
  // top of every step, once the step from t_n is set in s.dt, whether the state at t_n is a
  // history sample or a field snapshot. A time T goes to the step nearest it, t_n with
  // T < t_n + dt/2 (half-way ties to the later step, as the fixed step's rounding does); the
  // run's last state (`last`: t_n = end_time, no step follows) is always a sample and takes the
  // field times up to end_time. With a fixed step the schedule is of step indices, made once,
  // and this is not called.
  void plan_step(const State& s, bool last);
  // The run's last step: the planned one (fixed step), or the one plan_step() was told.
  bool is_last_step(long n) const;

  // At a monitor step: energies from s (after an evaluate with energy), divergence checks,
  // the history row and field snapshot when scheduled. Returns false if the run diverged.
  // `kinetic0` is the kinetic energy of the initial conditions (used at n = 0).
  bool observe(const State& s, double kinetic0);

  // What the force pass of step n ranks (internal_forces()): the run's stress measure, the
  // cells with a node on a contact boundary (a contact candidate node, or a boundary node of a
  // body pair's master body), and as threshold the run's interior peak so far (only a new peak
  // matters), except at history samples, whose row holds the step's own peak (threshold 0).
  // At a history sample it also asks for every measure's maximum (summary's
  // von_mises_sampled_max), at a field snapshot for the cells' values: the observers are
  // computed in the step's own pass over the elements, none of their own.
  // Null when the step needs no stresses (RunSettings::stress_every_step false, neither a
  // sample nor a field snapshot).
  const StressTracking* stress_tracking(long n);

  // Every step that stress_tracking(n) answered, after the pass and before observe(): folds
  // the peaks of the state s (t_n) into the run's maxima, and keeps what the pass sampled.
  // A scheme must call both at every step (observe() throws std::logic_error otherwise).
  void track_stress(const State& s, const StressPeaks& peaks);

  // Every step whose contact forces (the contact set's last step) act over [t_begin, t_begin + dt]:
  // accumulates the contact impulses (force x impulse_dt: the time over which the forces change
  // the velocity, dt_n of central_difference.hpp; dt for a fixed step), the first and last
  // contact times and the time in contact.
  void contact_step(double t_begin, double dt, double impulse_dt);
  void contact_step(double t_begin, double dt) { contact_step(t_begin, dt, dt); }

  // Records a divergence found by the scheme itself (e.g. det F <= 0, a failed solve).
  void diverge(const State& s, std::string reason);

  // End of the run: timings, steps, and the contact set's run totals.
  void finish(const State& s);

 private:
  // The largest node displacement from u0_ (RunResult::displacement_max, drift_max).
  void track_displacement(const State& s);
  // A field snapshot of the state s (t_n): u, v_n, the cells' tensors and the nodes' contact
  // data (contact_fields()); the von Mises values are the caller's. Snapshot steps only.
  FieldSnapshot snapshot(const State& s) const;
  // The nodes' contact force, gap and status from what the contact set holds now.
  void contact_fields(const State& s, FieldSnapshot& f) const;

  const M& model_;
  const RunSettings& settings_;
  RunResult& result_;
  const ContactSetT<M::kDim>& contact_;
  long planned_ = 0;
  // Fixed step: the next history sample's step (-1: none left), made by next_sample() from
  // sample_k_; and the field snapshots' steps (a list: their number is bounded by the case).
  long next_sample_step_ = 0;
  long sample_k_ = 0;
  bool every_step_ = false;
  void next_sample();
  std::vector<long> field_steps_;
  std::size_t next_field_ = 0;
  bool sample_at(long n) const;
  bool field_at(long n) const;
  // Variable step: the schedule by time (plan_step).
  bool variable_ = false;
  std::vector<double> field_times_;  // ascending, up to end_time [s]
  long next_sample_k_ = 0;           // the next sample time is next_sample_k_ x sample_interval
  long planned_step_ = -1;           // the step plan_step() was last called for
  bool planned_sample_ = false, planned_field_ = false, planned_last_ = false;
  long monitor_every_ = 1;
  Eigen::VectorXd u0_;
  double reference_energy_ = 0.0;  // max(E_0, |W_ext|): the energy-error denominator
  double input_energy_ = 0.0;      // max over time of E_0 + |W_ext|: the growth reference
  std::vector<std::uint8_t> contact_cell_;
  StressTracking tracking_;
  StressPeaks last_peaks_;  // of the last track_stress()
  VonMises2 sampled_vm2_{0.0, 0.0, 0.0};  // a sample's maxima per measure [Pa^2]
  std::vector<double> field_cells_;       // a field snapshot's von Mises per cell [Pa]
  long tracked_step_ = -1;                // the step stress_tracking() was last asked for
  long sampled_step_ = -1;                // the step whose sample or field values are held
  std::chrono::steady_clock::time_point wall0_;
  std::clock_t cpu0_;
};
using RunMonitor = RunMonitorT<Model<2>>;

}  // namespace ricochet
