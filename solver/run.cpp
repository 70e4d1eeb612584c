#include "solver/run.hpp"

#include <algorithm>
#include <stdexcept>

#include "solver/run_monitor.hpp"

namespace ricochet {

std::size_t History::column(const std::string& name) const {
  const auto it = std::find(columns.begin(), columns.end(), name);
  if (it == columns.end()) throw std::out_of_range("no history column '" + name + "'");
  return static_cast<std::size_t>(it - columns.begin());
}

double critical_time_step(const Model& model, const RunSettings& settings, double* penalty_critical) {
  const bool contact = !settings.obstacles.empty() || !settings.body_pairs.empty();
  if (settings.contact_method != RunSettings::ContactMethod::penalty || !contact) return model.critical_dt;
  const PenaltyState springs = make_penalty_state(model, settings.obstacles, settings.friction, settings.prescribed,
                                                  settings.penalty, settings.body_pairs);
  if (penalty_critical) *penalty_critical = penalty_critical_dt(model, springs);
  return penalty_combined_critical_dt(model, springs);
}

void copy_contact_totals(const ContactState& c, RunResult& r) {
  r.friction_dissipation = c.friction_dissipation;
  r.contact_work = c.contact_work;
  r.contact_steps = c.steps_with_contact;
  r.contact_sweeps_max = c.sweeps_max;
  r.contact_unconverged_steps = c.unconverged_steps;
  if (c.steps_with_contact > 0)
    r.contact_sweeps_mean = static_cast<double>(c.sweeps_total) / c.steps_with_contact;
}

void copy_contact_totals(const PenaltyState& c, RunResult& r) {
  r.friction_dissipation = c.friction_dissipation;
  r.contact_work = c.contact_work;
  r.contact_steps = c.steps_with_contact;
}

RunResult run_explicit(const Model& model, const RunSettings& settings, const ProgressFn& progress) {
  RunResult result;
  State s = initial_state(model, settings.prescribed, settings.dt, settings.initial_displacement);
  // E_0 from the initial conditions themselves: the reconstructed v_0 of step 0 already holds
  // half of any contact impulse of the first step.
  const double kinetic0 = 0.5 * s.v_half.cwiseAbs2().dot(model.mass);
  const bool penalty = settings.contact_method == RunSettings::ContactMethod::penalty;
  ContactState contact;
  PenaltyState springs;
  if (penalty)
    springs = make_penalty_state(model, settings.obstacles, settings.friction, settings.prescribed, settings.penalty,
                                 settings.body_pairs);
  else
    contact = make_contact_state(model, settings.obstacles, settings.friction, settings.prescribed, settings.body_pairs);
  const std::vector<ContactCandidate>& candidates = penalty ? springs.candidates : contact.candidates;
  const bool with_contact = !candidates.empty();
  const std::vector<Surface>& surfaces = penalty ? springs.surfaces : contact.surfaces;
  RunMonitor monitor(model, settings, result, with_contact ? &candidates : nullptr, &surfaces);
  const long planned = monitor.planned_steps();

  for (;;) {
    const long n = s.step;
    const bool observe = monitor.is_monitor_step(n);
    const StressTracking* tracking = monitor.stress_tracking(n);
    evaluate(model, settings.prescribed, s, observe, tracking);
    if (with_contact) {
      if (penalty)
        penalty_phase(model, settings.obstacles, springs, s);
      else
        contact_phase(model, settings.obstacles, settings.contact, contact, s);
    }
    if (!(s.forces.min_jacobian > 0.0)) {
      monitor.diverge(s, "inverted element (det F = " + std::to_string(s.forces.min_jacobian) + ")");
      break;
    }
    if (tracking) monitor.track_stress(s, s.forces.stress);
    if (observe) {
      if (!monitor.observe(s, penalty ? report(springs) : report(contact), kinetic0)) break;
      if (progress) progress(n, planned, s.time);
    }
    if (n == planned) break;
    if (with_contact) {
      if (penalty)
        monitor.contact_step(s.time, s.dt, springs.active_count, springs.normal_force, springs.tangential_force);
      else
        monitor.contact_step(s.time, s.dt, contact.active_count, contact.normal_force, contact.tangential_force);
    }
    update(s);
  }
  monitor.finish(s);
  if (penalty)
    copy_contact_totals(springs, result);
  else
    copy_contact_totals(contact, result);
  return result;
}

}  // namespace ricochet
