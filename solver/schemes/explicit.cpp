#include "solver/schemes/explicit.hpp"

#include <limits>

#include "solver/contact/bipotential_contact.hpp"
#include "solver/contact/penalty_contact.hpp"
#include "solver/observers/run_monitor.hpp"
#include "solver/schemes/threads.hpp"
#include "solver/schemes/time_step.hpp"

namespace ricochet {

RunResult run_explicit(const Model& model, const RunSettings& settings, const ProgressFn& progress) {
  // The whole run, set-up included, uses the run's thread count.
  const ThreadScope threads(settings.threads);
  RunResult result;
  result.threads = threads.threads();
  State s = initial_state(model, settings.prescribed, settings.dt, settings.initial_displacement);
  // E_0 from the initial conditions themselves: the reconstructed v_0 of step 0 already holds
  // half of any contact impulse of the first step.
  const double kinetic0 = 0.5 * s.v_half.cwiseAbs2().dot(model.mass);
  // The contact solve of the run's method; the contact set (candidates, frames, observables) is
  // the same for both.
  const bool penalty = settings.contact_method == RunSettings::ContactMethod::penalty;
  BipotentialContact bipotential;
  PenaltyContact springs;
  if (penalty)
    springs = make_penalty_contact(model, settings.obstacles, settings.friction, settings.prescribed,
                                   settings.penalty, settings.body_pairs);
  else
    bipotential = make_bipotential_contact(model, settings.obstacles, settings.friction, settings.prescribed,
                                           settings.body_pairs);
  const ContactSet& contact = penalty ? springs.set : bipotential.set;
  const bool with_contact = !contact.candidates.empty();
  RunMonitor monitor(model, settings, result, contact);
  // The variable step (settings.dt_update_interval > 0; time_step.hpp): the springs' limit
  // enters it as it entered the first step.
  StepControl steps(model, settings,
                    penalty ? penalty_critical_dt(model, springs) : std::numeric_limits<double>::infinity());

  for (;;) {
    const long n = s.step;
    if (steps.variable()) monitor.plan_step(s, !steps.begin_step(s));
    const bool observe = monitor.is_monitor_step(n);
    const StressTracking* tracking = monitor.stress_tracking(n);
    evaluate(model, settings.prescribed, s, observe, tracking);
    if (with_contact) {
      if (penalty)
        penalty_phase(model, settings.obstacles, springs, s);
      else
        contact_phase(model, settings.obstacles, settings.contact, bipotential, s);
    }
    if (!(s.forces.min_jacobian > 0.0)) {
      monitor.diverge(s, "inverted element (det F = " + std::to_string(s.forces.min_jacobian) + ")");
      break;
    }
    if (!steps.failure().empty()) {
      monitor.diverge(s, steps.failure());
      break;
    }
    if (tracking) monitor.track_stress(s, s.forces.stress);
    if (observe) {
      if (!monitor.observe(s, kinetic0)) break;
      if (progress) progress(n, steps.planned_steps(), s.time);
    }
    if (monitor.is_last_step(n)) break;
    // Its forces act over [t_n, t_n+1] and change the velocity over dt_n.
    if (with_contact) monitor.contact_step(s.time, s.dt, velocity_step(s));
    update(s);
  }
  monitor.finish(s);
  steps.report(result);
  return result;
}

}  // namespace ricochet
