#include "harness/stability/stability.hpp"

#include "harness/input/run_plan.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "harness/outputs/atomic_file.hpp"
#include "harness/input/input_error.hpp"
#include "harness/outputs/run_outputs.hpp"
#include "solver/schemes/time_step.hpp"

namespace ricochet {
namespace {

const char* status_name(RunStatus s) { return s == RunStatus::ok ? "ok" : "diverged"; }

const char* outcome_name(StabilityOutcome o) {
  switch (o) {
    case StabilityOutcome::bracketed: return "bracketed";
    case StabilityOutcome::no_unstable_up_to_cap: return "no_unstable_up_to_cap";
    case StabilityOutcome::no_stable_down_to_floor: return "no_stable_down_to_floor";
    case StabilityOutcome::run_limit: return "run_limit";
  }
  return "?";
}

std::string fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

bool uses_penalty_estimate(const PreparedCase& pc) {
  return pc.spec.scheme == Scheme::explicit_penalty && std::isfinite(pc.penalty_critical_dt) &&
         pc.penalty_critical_dt > 0.0;
}

// "diverged" or "energy rule": what made the trial at dt unstable.
std::string unstable_by(const StabilityResult& r, double dt) {
  for (const StabilityTrial& t : r.trials)
    if (t.dt == dt) return t.status == RunStatus::diverged ? "diverged" : "energy rule";
  return "?";
}

}  // namespace

void check_stability_options(const StabilityOptions& o) {
  auto bad = [](const std::string& what) { throw InputError("ricochet stability: " + what); };
  if (!(o.tolerance > 0.0 && o.tolerance <= 10.0))
    bad("--tolerance: expected a number in (0, 10]; got " + fmt("%g", o.tolerance));
  if (o.max_runs < 1 || o.max_runs > 10000)
    bad("--max-runs: expected an integer in 1 ... 10000; got " + std::to_string(o.max_runs));
  if (!(o.energy_bound > 0.0) || !std::isfinite(o.energy_bound))
    bad("--energy-bound: expected a number > 0; got " + fmt("%g", o.energy_bound));
  if (o.end_time && !(*o.end_time > 0.0 && std::isfinite(*o.end_time)))
    bad("--end: expected a time > 0 [s]; got " + fmt("%g", *o.end_time));
  if (!(o.cap_factor >= 1.0) || !std::isfinite(o.cap_factor)) bad("cap factor must be >= 1");
  if (!(o.floor_factor > 0.0 && o.floor_factor <= 1.0)) bad("floor factor must be in (0, 1]");
}

double stability_estimate(const PreparedCase& pc) {
  return with_model(pc, [&](const auto& m) {
    return uses_penalty_estimate(pc) ? critical_time_step(m, pc.settings) : m.critical_dt;
  });
}

PreparedCase stability_trial_case(const PreparedCase& pc, double dt, const StabilityOptions& opt) {
  PreparedCase t = pc;
  t.settings.dt = dt;
  t.spec.dt = dt;
  t.settings.dt_update_interval = 0;  // a trial's step is fixed
  t.spec.dt_update_interval = 0;
  if (opt.end_time) {
    t.settings.end_time = *opt.end_time;
    t.spec.end_time = *opt.end_time;
  }
  t.settings.field_times.clear();
  t.spec.field_times.clear();
  return t;
}

StabilityTrial judge_trial(const RunResult& r, const StabilityOptions& opt) {
  StabilityTrial t;
  t.dt = r.dt;
  t.status = r.status;
  t.energy_error_max = r.energy_error_max;
  t.steps = r.steps;
  t.planned_steps = r.planned_steps;
  const History& h = r.history;
  if (h.rows() > 0) {
    try {
      const std::size_t ct = h.column("total_energy"), cd = h.column("friction_dissipation"),
                        cw = h.column("external_work");
      double reference = std::abs(r.initial_energy);
      for (std::size_t row = 0; row < h.rows(); ++row) {
        const double w = h.at(row, cw);
        reference = std::max(reference, std::abs(w));
        if (!(reference > 0.0)) continue;
        const double b = (h.at(row, ct) + h.at(row, cd) - r.initial_energy - w) / reference;
        if (!std::isfinite(b)) continue;
        t.energy_gain_max = std::max(t.energy_gain_max, b);
        t.energy_loss_max = std::min(t.energy_loss_max, b);
      }
    } catch (const std::out_of_range&) {
      // a history without the energy columns: gain and loss stay 0
    }
  }
  t.wall_seconds = r.timing.wall_seconds;
  if (r.status != RunStatus::ok) {
    t.stable = false;
    t.reason = "diverged: " + r.reason;
  } else if (!(r.energy_error_max <= opt.energy_bound)) {  // NaN counts as unbounded
    t.stable = false;
    t.reason = "energy error " + fmt("%.3g", r.energy_error_max) + " > bound " + fmt("%g", opt.energy_bound);
  } else {
    t.stable = true;
  }
  return t;
}

StabilityTrial stability_trial(const PreparedCase& pc, double dt, const StabilityOptions& opt) {
  const PreparedCase t = stability_trial_case(pc, dt, opt);
  return judge_trial(run_case(t), opt);
}

StabilityResult find_stable_dt(const PreparedCase& pc, const StabilityOptions& opt,
                               const StabilityTrialFn& on_trial) {
  check_stability_options(opt);
  StabilityResult res;
  res.critical_dt = with_model(pc, [](const auto& m) { return m.critical_dt; });
  res.penalty_critical_dt = uses_penalty_estimate(pc) ? pc.penalty_critical_dt : 0.0;
  res.estimate = stability_estimate(pc);
  res.end_time = opt.end_time.value_or(pc.settings.end_time);
  // A step longer than the run is one step of the run: the search stops there.
  res.cap = std::min(opt.cap_factor * res.estimate, res.end_time);
  res.floor = std::min(opt.floor_factor * res.estimate, res.cap);
  // The trial of the shortest step plans the most steps and rows: the search stays in the
  // case's limits (harness/input/run_plan.hpp) if it does.
  check_run_plan(stability_trial_case(pc, res.floor, opt));

  auto budget_left = [&] { return static_cast<int>(res.trials.size()) < opt.max_runs; };
  auto trial = [&](double dt) {
    const PreparedCase tc = stability_trial_case(pc, dt, opt);
    const RunResult r = run_case(tc);
    StabilityTrial t = judge_trial(r, opt);
    t.dt = dt;  // exactly the requested value
    res.trials.push_back(t);
    if (on_trial) on_trial(res.trials.back(), tc, r);
    return t.stable;
  };

  // Bracket: start at the estimate, double while stable, halve while unstable.
  const double dt0 = std::min(res.estimate, res.cap);
  if (trial(dt0)) {
    res.lo = dt0;
    while (!res.hi) {
      if (*res.lo >= res.cap) {
        res.outcome = StabilityOutcome::no_unstable_up_to_cap;
        return res;
      }
      if (!budget_left()) {
        res.outcome = StabilityOutcome::run_limit;
        return res;
      }
      const double next = std::min(2.0 * *res.lo, res.cap);
      if (trial(next)) res.lo = next; else res.hi = next;
    }
  } else {
    res.hi = dt0;
    while (!res.lo) {
      if (*res.hi <= res.floor) {
        res.outcome = StabilityOutcome::no_stable_down_to_floor;
        return res;
      }
      if (!budget_left()) {
        res.outcome = StabilityOutcome::run_limit;
        return res;
      }
      const double next = std::max(0.5 * *res.hi, res.floor);
      if (trial(next)) res.lo = next; else res.hi = next;
    }
  }

  // Bisection in log space: the geometric mean halves log(hi/lo) with every trial.
  res.outcome = StabilityOutcome::bracketed;
  while (*res.hi / *res.lo - 1.0 > opt.tolerance && budget_left()) {
    const double mid = std::sqrt(*res.lo * *res.hi);
    if (trial(mid)) res.lo = mid; else res.hi = mid;
  }
  res.converged = *res.hi / *res.lo - 1.0 <= opt.tolerance;
  return res;
}

Json stability_report(const PreparedCase& pc, const StabilityOptions& opt, const StabilityResult& r) {
  Json j = case_identity(pc);
  with_model(pc, [&](const auto& m) {
    j["nodes"] = m.num_nodes();
    j["elements"] = m.num_cells();
  });
  j["critical_dt"] = r.critical_dt;
  j["penalty_critical_dt"] = r.penalty_critical_dt > 0.0 ? Json(r.penalty_critical_dt) : Json();
  j["estimate"] = r.estimate;
  j["estimate_rule"] = r.penalty_critical_dt > 0.0 ? "1/sqrt(1/critical_dt^2 + 1/penalty_critical_dt^2)"
                                                   : "critical_dt = min L_e/c_p";
  j["end_time"] = r.end_time;

  Json crit = Json::object();
  crit["status"] = "ok";
  crit["energy_error_max_bound"] = opt.energy_bound;
  crit["energy_growth_limit"] = pc.settings.energy_growth_limit;
  crit["rule"] = "stable iff the run ends with status ok (no inverted element, finite energies, total energy <= "
                 "energy_growth_limit x reference) and energy_error_max <= energy_error_max_bound";
  j["criterion"] = crit;

  Json search = Json::object();
  search["tolerance"] = opt.tolerance;
  search["max_runs"] = opt.max_runs;
  search["cap"] = r.cap;
  search["floor"] = r.floor;
  j["search"] = search;

  j["outcome"] = outcome_name(r.outcome);
  j["converged"] = r.converged;
  j["largest_stable_dt"] = r.lo ? Json(*r.lo) : Json();
  j["smallest_unstable_dt"] = r.hi ? Json(*r.hi) : Json();
  j["unstable_by"] = r.hi ? Json(unstable_by(r, *r.hi)) : Json();
  j["stable_over_estimate"] = r.lo ? Json(*r.lo / r.estimate) : Json();
  j["unstable_over_estimate"] = r.hi ? Json(*r.hi / r.estimate) : Json();
  j["bracket_width"] = r.lo && r.hi ? Json(*r.hi / *r.lo - 1.0) : Json();
  j["runs"] = static_cast<long>(r.trials.size());

  Json trials = Json::array();
  for (const StabilityTrial& t : r.trials) {
    Json q = Json::object();
    q["dt"] = t.dt;
    q["dt_over_estimate"] = t.dt / r.estimate;
    q["stable"] = t.stable;
    q["status"] = status_name(t.status);
    q["reason"] = t.reason;
    q["energy_error_max"] = t.energy_error_max;
    q["energy_gain_max"] = t.energy_gain_max;
    q["energy_loss_max"] = t.energy_loss_max;
    q["steps"] = t.steps;
    q["planned_steps"] = t.planned_steps;
    q["wall_seconds"] = t.wall_seconds;
    trials.push_back(q);
  }
  j["trials"] = trials;
  j["build"] = build_info();
  j["written_at"] = utc_now();
  return j;
}

std::string stability_summary_line(const PreparedCase& pc, const StabilityResult& r) {
  std::string s = pc.spec.name + ": " + scheme_name(pc.spec.scheme) + " " + joined_bodies(pc.spec, false) + " " +
                  joined_bodies(pc.spec, true) + "  estimate " + fmt("%.4g", r.estimate) + " s";
  auto ratio = [&](double dt) { return fmt("%.4g", dt) + " s (" + fmt("%.4g", dt / r.estimate) + " x)"; };
  switch (r.outcome) {
    case StabilityOutcome::bracketed:
      s += "  largest stable " + ratio(*r.lo) + "  smallest unstable " + ratio(*r.hi) + " [" +
           unstable_by(r, *r.hi) + "]  width " +
           fmt("%.2g", 100.0 * (*r.hi / *r.lo - 1.0)) + " %";
      if (!r.converged) s += " (tolerance not reached)";
      break;
    case StabilityOutcome::no_unstable_up_to_cap:
      s += "  no unstable dt up to " + ratio(r.cap);
      break;
    case StabilityOutcome::no_stable_down_to_floor:
      s += "  no stable dt down to " + ratio(r.floor);
      break;
    case StabilityOutcome::run_limit:
      s += "  no bracket within the run limit";
      if (r.lo) s += "; largest stable " + ratio(*r.lo);
      if (r.hi) s += "; smallest unstable " + ratio(*r.hi);
      break;
  }
  return s + "  " + std::to_string(r.trials.size()) + " runs";
}

int run_command(const StabilityCommand& c) {
  const StabilityOptions& opt = c.options;
  const std::string& out_dir = c.out_dir;
  const bool quiet = c.quiet;
  check_stability_options(opt);

  CaseSpec spec = read_case(c.case_file, c.sets);
  if (c.threads) spec.threads = *c.threads;
  if (spec.scheme == Scheme::external)
    throw InputError(c.case_file + ": scheme: \"" + spec.external.name + "\" is an external scheme; the stability "
                     "search runs ricochet's own schemes: sweep the external scheme's time step instead (docs/peers.md)");
  const PreparedCase pc = prepare_case(spec);

  namespace fs = std::filesystem;
  const fs::path dir(out_dir);
  if (!out_dir.empty()) {  // an earlier search's results must not describe this one
    fs::remove(dir / "stability.json");
    fs::remove_all(dir / "trials");
  }
  const double estimate = stability_estimate(pc);
  int index = 0;
  const StabilityResult res = find_stable_dt(
      pc, opt, [&](const StabilityTrial& t, const PreparedCase& tc, const RunResult& r) {
        ++index;
        if (!quiet)
          std::fprintf(stderr, "  trial %2d: dt %.5g s (%.4g x estimate): %s%s%s  energy_error_max %.3g (gain %.3g, loss %.3g)  %ld/%ld steps  %.3g s\n",
                       index, t.dt, t.dt / estimate, t.stable ? "stable" : "UNSTABLE", t.stable ? "" : " - ",
                       t.reason.c_str(), t.energy_error_max, t.energy_gain_max, -t.energy_loss_max, t.steps,
                       t.planned_steps, t.wall_seconds);
        if (!out_dir.empty()) {
          char name[16];
          std::snprintf(name, sizeof name, "%02d", index);
          write_run_outputs(dir / "trials" / name, tc, r);
        }
      });
  if (!out_dir.empty()) write_file_atomic(dir / "stability.json", dump_json(stability_report(pc, opt, res)));
  std::printf("%s%s\n", stability_summary_line(pc, res).c_str(), out_dir.empty() ? "" : ("  -> " + out_dir).c_str());
  switch (res.outcome) {
    case StabilityOutcome::bracketed: return 0;
    case StabilityOutcome::no_unstable_up_to_cap: return 5;
    default: return 4;
  }
}

}  // namespace ricochet
