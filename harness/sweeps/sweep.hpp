// `ricochet sweep SWEEP.toml`: runs every case of an expanded sweep (harness/sweeps/sweep_spec.hpp) as a
// subprocess `ricochet run`, one at a time (clean timings) or N in parallel, resumes an
// interrupted sweep, repeats runs for timing statistics, measures each run's errors against a
// reference run (harness/sweeps/reference_errors.hpp: the sweep's shared [reference] or its group's own),
// and keeps DIR/summary.csv, a complete table of the finished runs, up to date after every run.
// Formats and keys: docs/sweeps.md.
//
// The parts: sweep_plan.hpp (the runs, their folders and requests, what is already done),
// sweep_exec.hpp (the subprocesses, repeats, signals, progress), sweep_table.hpp (summary.csv),
// sweep_errors.hpp (each run's errors against its reference); sweep.cpp puts them together and
// writes DIR/sweep.json.
#pragma once

#include <cstddef>
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "harness/sweeps/reference_errors.hpp"
#include "harness/sweeps/sweep_plan.hpp"
#include "harness/sweeps/sweep_spec.hpp"
#include "harness/sweeps/sweep_table.hpp"

namespace ricochet {

inline constexpr int kMaxSweepJobs = 1024;  // --jobs at most

struct SweepOptions {
  std::filesystem::path out_dir;     // DIR (required)
  int jobs = 1;                      // runs at the same time, >= 1
  int repeat = 1;                    // times each run is repeated, >= 1
  // --threads N for every run (0 = all cores); empty: SweepPlan::threads() decides per run.
  std::optional<int> threads;
  bool force = false;                // rerun finished runs too
  bool quiet = false;                // no progress lines
  std::filesystem::path executable;  // the ricochet program to run; empty = /proc/self/exe
  std::ostream* log = nullptr;       // progress lines and notes; nullptr = std::cerr
  // How long to wait for a process that still writes a run folder (it holds its run.lock: a run
  // of an interrupted sweep) before stopping with an error [s].
  double writer_wait = 10.0;
};

struct SweepOutcome {
  std::size_t total = 0;     // runs in the sweep, reference runs included
  std::size_t resumed = 0;   // finished by an earlier invocation, not run again
  std::size_t executed = 0;  // run by this invocation
  std::size_t ok = 0, diverged = 0, failed = 0;  // over all runs
};

// `ricochet sweep SWEEP.toml [--out DIR] [--jobs N] [--threads N] [--repeat K] [--check GATES.toml]
// [--force] [--quiet]`.
struct SweepCommand {
  std::string file;        // SWEEP.toml
  std::string gates_file;  // --check GATES.toml; empty: no check
  SweepOptions options;    // an empty out_dir: results/<sweep name>
};

// Reads the sweep file (and the gate file, before any run), runs the sweep and, with a gate
// file, checks its gates on DIR/summary.csv (lines on `out`, report DIR/gates-junit.xml).
// Returns 0 the sweep completed (diverged and failed runs are results) and every gate passed;
// 4 a gate failed (gates.hpp). Throws InputError for bad input (nothing written).
int run_command(const SweepCommand& c, std::ostream& out);

// Runs a sweep: check_runs (sweep_plan.hpp) first (nothing is written on bad input), then the
// runs, writing DIR/sweep.json, DIR/runs/<id>/ and DIR/summary.csv. Throws InputError for bad input and
// std::runtime_error if DIR cannot be written or the program cannot be started.
SweepOutcome run_sweep(const SweepSpec& spec, const std::vector<SweepRun>& runs, const SweepOptions& options);

}  // namespace ricochet
