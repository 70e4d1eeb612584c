// The stability search (`ricochet stability`): the largest stable time step of a case's scheme
// on its mesh, found by bracketing and bisection over whole runs, next to the theoretical estimate
// of docs/background.md, Critical time step (model.critical_dt, min L_e / c_p; for the explicit
// penalty scheme the combined element and spring limit). Criterion, algorithm and output keys:
// docs/stability.md.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "harness/input/case_setup.hpp"
#include "harness/outputs/json_io.hpp"

namespace ricochet {

struct StabilityOptions {
  double tolerance = 0.01;     // stop when hi / lo - 1 <= tolerance [-]
  int max_runs = 30;           // cap on the number of trial runs
  double energy_bound = 0.1;   // a stable run keeps energy_error_max <= this [-]
  std::optional<double> end_time;  // shortens (or lengthens) time.end of every trial [s]
  double cap_factor = 1e3;     // no trial above cap_factor x the estimate (nor above time.end)
  double floor_factor = 1e-3;  // no trial below floor_factor x the estimate
};

// One trial run at a fixed time step.
struct StabilityTrial {
  double dt = 0.0;                // [s]
  bool stable = false;            // the criterion: status ok and energy_error_max <= bound
  RunStatus status = RunStatus::ok;
  std::string reason;             // why unstable ("" when stable): the divergence, or the energy rule
  double energy_error_max = 0.0;  // [-]
  // The signed energy balance (total + friction dissipation - E_0 - external work) over the
  // reference energy, from the history samples: its largest value (energy gained, >= 0) and
  // its smallest (energy lost, <= 0). Tells growth (instability) from dissipation (accuracy).
  double energy_gain_max = 0.0, energy_loss_max = 0.0;  // [-]
  long steps = 0, planned_steps = 0;
  double wall_seconds = 0.0;      // time loop [s]
};

enum class StabilityOutcome {
  bracketed,             // lo stable, hi unstable (converged says whether hi/lo - 1 <= tolerance)
  no_unstable_up_to_cap, // every trial up to the cap was stable (e.g. an implicit scheme)
  no_stable_down_to_floor,  // every trial down to the floor was unstable
  run_limit,             // max_runs reached before any bracket was found
};

struct StabilityResult {
  double critical_dt = 0.0;          // model.critical_dt, the elements' estimate [s]
  double penalty_critical_dt = 0.0;  // the contact springs' limit [s]; 0 if none
  double estimate = 0.0;             // the estimate the search starts from [s]
  double cap = 0.0, floor = 0.0;     // search range [s]
  double end_time = 0.0;             // time.end of the trials [s]
  StabilityOutcome outcome = StabilityOutcome::run_limit;
  bool converged = false;            // bracketed and hi / lo - 1 <= tolerance
  std::optional<double> lo;          // largest stable dt tried [s]
  std::optional<double> hi;          // smallest unstable dt tried [s]
  std::vector<StabilityTrial> trials;  // in the order run
};

// The estimate the search starts from: model.critical_dt, or for the explicit penalty scheme
// with obstacles 1 / sqrt(1/dt_e^2 + 1/dt_p^2) (docs/case-format.md, [time]) [s].
double stability_estimate(const PreparedCase& pc);

// The case as one trial runs it: a copy with time.dt = dt (fixed, never recomputed), time.end = opt.end_time
// if given, and no field snapshots.
PreparedCase stability_trial_case(const PreparedCase& pc, double dt, const StabilityOptions& opt);

// Applies the criterion to a finished run.
StabilityTrial judge_trial(const RunResult& r, const StabilityOptions& opt);

// Runs the case once at time step dt (stability_trial_case) and applies the criterion.
StabilityTrial stability_trial(const PreparedCase& pc, double dt, const StabilityOptions& opt);

// Called after each trial with the trial, the case it ran and its full result.
using StabilityTrialFn =
    std::function<void(const StabilityTrial&, const PreparedCase& trial_case, const RunResult&)>;

// The search: from the estimate, doubling (while stable) or halving (while unstable) to a
// bracket, then bisection in log space (the geometric mean) until hi / lo - 1 <= tolerance,
// at most opt.max_runs trials in all. `on_trial` (may be empty) is called after each trial.
// Throws InputError for options out of range (check_stability_options).
StabilityResult find_stable_dt(const PreparedCase& pc, const StabilityOptions& opt,
                               const StabilityTrialFn& on_trial = {});

// Throws InputError naming the option when one is out of range.
void check_stability_options(const StabilityOptions& opt);

// The stability.json document (docs/stability.md).
Json stability_report(const PreparedCase& pc, const StabilityOptions& opt, const StabilityResult& r);

// One line: case, scheme, mesh, the estimate, lo, hi, lo / estimate and the number of runs.
std::string stability_summary_line(const PreparedCase& pc, const StabilityResult& r);

// `ricochet stability CASE.toml [--set KEY=VALUE]... [--threads N] [--out DIR] [--tolerance REL]
//  [--max-runs N] [--end TIME] [--energy-bound E] [--quiet]`.
struct StabilityCommand {
  std::string case_file;
  std::vector<std::string> sets;  // --set KEY=VALUE, in order
  std::optional<int> threads;     // --threads N: replaces the case key `threads` of every trial
  std::string out_dir;            // empty: nothing written
  StabilityOptions options;
  bool quiet = false;             // no per-trial lines on stderr
};

// Prints the summary line (and, unless quiet, one line per trial on stderr); writes
// DIR/stability.json and DIR/trials/NN/ when out_dir is set. Returns the exit status: 0 bracket
// found, 4 no bracket (no stable dt down to the floor, or max_runs reached first), 5 no unstable
// dt up to the cap. Throws InputError for bad input (nothing written), anything else when an
// output cannot be written.
int run_command(const StabilityCommand& c);

}  // namespace ricochet
