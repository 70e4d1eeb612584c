#include "solver/schemes/explicit.hpp"

#include <limits>

#include "solver/contact/bipotential_contact.hpp"
#include "solver/contact/penalty_contact.hpp"
#include "solver/schemes/central_difference.hpp"
#include "solver/schemes/run_monitor.hpp"
#include "solver/schemes/relaxation.hpp"
#include "solver/schemes/threads.hpp"
#include "solver/schemes/time_step.hpp"

namespace ricochet {

template <class M>
RunResult run_explicit(const M& model, const RunSettings& settings, const ProgressFn& progress) {
  constexpr int D = M::kDim;
  const auto& obstacles = obstacles_of(settings, model);
  // The whole run, set-up included, uses the run's thread count.
  ThreadScope threads(settings.threads, settings.adapt_threads);
  RunResult result;
  result.timing.threads = threads.threads();
  result.timing.threads_min = threads.threads_min();
  State s = initial_state(model, settings.prescribed, settings.dt, settings.initial_displacement, settings.loads);
  // E_0 from the initial conditions themselves: the reconstructed v_0 of step 0 already holds
  // half of any contact impulse of the first step.
  const double kinetic0 = 0.5 * s.v_half.cwiseAbs2().dot(model.mass);
  // The contact solve of the run's method; the contact set (candidates, frames, observables) is
  // the same for both.
  const bool penalty = settings.contact_method == RunSettings::ContactMethod::penalty;
  BipotentialContactT<D> bipotential;
  PenaltyContactT<D> springs;
  if (penalty)
    springs = make_penalty_contact(model, obstacles, settings.friction, settings.prescribed, settings.penalty,
                                   settings.body_pairs);
  else
    bipotential = make_bipotential_contact(model, obstacles, settings.friction, settings.prescribed,
                                           settings.body_pairs);
  const ContactSetT<D>& contact = penalty ? springs.set : bipotential.set;
  const bool with_contact = !contact.candidates.empty();
  // A quasi-static start (relaxation.hpp): the scene relaxed under its t = 0 loads with this
  // scheme's steps and contact, then the clock starts from there.
  result.relaxed = settings.relaxation.enabled;
  const bool relaxed_ok =
      !result.relaxed ||
      relax_explicit_start(model, settings,
                           {with_contact && !penalty ? &bipotential : nullptr, with_contact && penalty ? &springs : nullptr},
                           s, result.relaxation);
  RunMonitorT<M> monitor(model, settings, result, contact);
  // The variable step (settings.dt_update_interval > 0; time_step.hpp): the springs' limit
  // enters it as it entered the first step.
  StepControlT<M> steps(model, settings,
                    penalty ? penalty_critical_dt(model, springs) : std::numeric_limits<double>::infinity());
  if (!relaxed_ok) {
    monitor.diverge(s, "relaxation: " + result.relaxation.reason);
    monitor.finish(s);
    return result;
  }

  // What a history row at t_n holds (docs/outputs.md, History semantics). The bi-potential
  // reactions solved in step n -> n+1 are the reactions at t_{n+1} (Cros et al. 2010, Eq. (3):
  // R_{t+dt}). So the row at t_n is observed before they are solved: it holds u_n, the contact
  // results up to t_n, and v_n = v_{n-1/2} + dt/2 a_n with a_n the accelerations of the forces
  // at t_n, the reactions at t_n (solved in the step before) included; the t = 0 row is the
  // initial state. (The free accelerations are kept in `a_free` and put back, bit for bit, for
  // the contact solve.) The penalty springs' forces are forces of the configuration u_n, like
  // f_int: the row at t_n is observed after them.
  Eigen::VectorXd a_free = Eigen::VectorXd::Zero(s.a.size());
  auto observe_row = [&](long n) {
    const bool reactions = !penalty && !contact.active.empty();
    if (reactions) {
      a_free = s.a;
      add_reaction_accelerations(model, bipotential, s);
    }
    const bool ok = monitor.observe(s, kinetic0);
    if (reactions) s.a = a_free;
    if (!ok) return false;
    if (progress) progress(n, steps.planned_steps(), s.time);
    return true;
  };
  for (;;) {
    threads.adapt();
    const long n = s.step;
    if (steps.variable()) monitor.plan_step(s, !steps.begin_step(s));
    const bool observe = monitor.is_monitor_step(n);
    const StressTracking* tracking = monitor.stress_tracking(n);
    evaluate(model, settings.prescribed, s, observe, tracking);
    if (!(s.forces.min_jacobian > 0.0)) {
      monitor.diverge(s, "inverted element (det F = " + std::to_string(s.forces.min_jacobian) + ")");
      break;
    }
    if (!steps.failure().empty()) {
      monitor.diverge(s, steps.failure());
      break;
    }
    if (tracking) monitor.track_stress(s, s.forces.stress);
    if (penalty) {
      if (with_contact) penalty_phase(model, obstacles, springs, s);
      if (observe && !observe_row(n)) break;
      if (monitor.is_last_step(n)) break;
    } else {
      if (observe && !observe_row(n)) break;
      if (monitor.is_last_step(n)) break;
      if (with_contact) contact_phase(model, obstacles, settings.contact, bipotential, s);
    }
    // Its forces act over [t_n, t_n+1] and change the velocity over dt_n.
    if (with_contact) monitor.contact_step(s.time, s.dt, velocity_step(s));
    update(s);
  }
  monitor.finish(s);
  steps.report(result);
  result.timing.threads_min = threads.threads_min();
  return result;
}

template RunResult run_explicit<Model<2>>(const Model<2>&, const RunSettings&, const ProgressFn&);
template RunResult run_explicit<Model<3>>(const Model<3>&, const RunSettings&, const ProgressFn&);

}  // namespace ricochet
