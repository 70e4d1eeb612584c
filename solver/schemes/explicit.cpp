#include "solver/schemes/explicit.hpp"

#include "solver/contact/bipotential_contact.hpp"
#include "solver/contact/penalty_contact.hpp"
#include "solver/observers/run_monitor.hpp"
#include "solver/schemes/relaxation.hpp"
#include "solver/schemes/threads.hpp"

namespace ricochet {

RunResult run_explicit(const Model& model, const RunSettings& settings, const ProgressFn& progress) {
  // The whole run, set-up included, uses the run's thread count.
  const ThreadScope threads(settings.threads);
  RunResult result;
  result.threads = threads.threads();
  State s = initial_state(model, settings.prescribed, settings.dt, settings.initial_displacement, settings.loads);
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
  // A quasi-static start (relaxation.hpp): the scene relaxed under its t = 0 loads with this
  // scheme's steps and contact, then the clock starts from there.
  result.relaxed = settings.relaxation.enabled;
  const bool relaxed_ok =
      !result.relaxed ||
      relax_explicit_start(model, settings,
                           {with_contact && !penalty ? &bipotential : nullptr, with_contact && penalty ? &springs : nullptr},
                           s, result.relaxation);
  RunMonitor monitor(model, settings, result, contact);
  const long planned = monitor.planned_steps();
  if (!relaxed_ok) {
    monitor.diverge(s, "relaxation: " + result.relaxation.reason);
    monitor.finish(s);
    return result;
  }

  for (;;) {
    const long n = s.step;
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
    if (tracking) monitor.track_stress(s, s.forces.stress);
    if (observe) {
      if (!monitor.observe(s, kinetic0)) break;
      if (progress) progress(n, planned, s.time);
    }
    if (n == planned) break;
    if (with_contact) monitor.contact_step(s.time, s.dt);  // its forces act over [t_n, t_n+1]
    update(s);
  }
  monitor.finish(s);
  return result;
}

}  // namespace ricochet
