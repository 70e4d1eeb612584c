// `ricochet sweep SWEEP.toml`: runs every case of an expanded sweep (harness/sweep_spec.hpp) as a
// subprocess `ricochet run`, one at a time (clean timings) or N in parallel, resumes an
// interrupted sweep, repeats runs for timing statistics, measures each run's errors against a
// reference run (harness/reference_errors.hpp: the sweep's shared [reference] or its group's own),
// and keeps DIR/summary.csv, a complete table of the finished runs, up to date after every run.
// Formats and keys: docs/sweeps.md.
#pragma once

#include <cstddef>
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "harness/json_io.hpp"
#include "harness/reference_errors.hpp"
#include "harness/sweep_spec.hpp"

namespace ricochet {

// The `sweep` command: args are the words after `sweep`:
//   SWEEP.toml [--out DIR] [--jobs N] [--repeat K] [--check GATES.toml] [--force] [--quiet]
// Returns the exit status: 0 the sweep completed (diverged and failed runs are results) and,
// with --check, every gate passed; 4 a gate failed (gates.hpp; report DIR/gates-junit.xml);
// 2 bad input, gate file included (one line "ricochet: ..." on stderr, nothing written);
// 1 any other error.
int sweep_command(const std::vector<std::string>& args);

// The usage text of the sweep command (several lines, ending in '\n').
const char* sweep_usage();

struct SweepOptions {
  std::filesystem::path out_dir;     // DIR (required)
  int jobs = 1;                      // runs at the same time, >= 1
  int repeat = 1;                    // times each run is repeated, >= 1
  bool force = false;                // rerun finished runs too
  bool quiet = false;                // no progress lines
  std::filesystem::path executable;  // the ricochet program to run; empty = /proc/self/exe
  std::ostream* log = nullptr;       // progress lines; nullptr = std::cerr
};

struct SweepOutcome {
  std::size_t total = 0;     // runs in the sweep, reference runs included
  std::size_t resumed = 0;   // finished by an earlier invocation, not run again
  std::size_t executed = 0;  // run by this invocation
  std::size_t ok = 0, diverged = 0, failed = 0;  // over all runs
};

// Validates every run's case (read_case of the run's base with its overrides) and, for every run
// compared with a reference (and every reference run), its error probe. Throws InputError
// "SWEEP:LINE: KEY: run ID: <the case's one-line error>".
void check_runs(const SweepSpec& spec, const std::vector<SweepRun>& runs);

// Runs a sweep: check_runs first (nothing is written on bad input), then the runs, writing
// DIR/sweep.json, DIR/runs/<id>/ and DIR/summary.csv. Throws InputError for bad input and
// std::runtime_error if DIR cannot be written or the program cannot be started.
SweepOutcome run_sweep(const SweepSpec& spec, const std::vector<SweepRun>& runs, const SweepOptions& options);

// --- summary.csv ------------------------------------------------------------------------------

// One summary.json value under its flattened name ("contact_iterations.mean"); arrays as compact
// JSON; `null` marks a JSON null (or empty object), whose column is dropped if another run has
// keys under the same name (e.g. "implicit" next to "implicit.theta").
struct FlatField {
  std::string name;
  std::string value;
  bool null = false;
};

// A summary.json object flattened in document order; the `status` key is left out (it is the
// table's own `status` column).
std::vector<FlatField> flatten_summary(const Json& summary);

struct SummaryRow {
  std::string run_id, group, kind, status, reason;  // kind: "run" or "reference"
  std::vector<std::pair<std::string, std::string>> swept;  // case key -> value (display form)
  std::vector<FlatField> summary;                          // flattened summary.json; empty if failed
  std::vector<std::pair<std::string, std::string>> extra;  // tail column -> value
};

struct SummaryLayout {
  std::vector<std::string> swept;  // case-key columns, in this order (keys only rows have are appended)
  std::vector<std::string> tail;   // the last columns, in this order
};

// The table: run_id, group, kind, status, reason, the swept keys, the union of the summary
// columns in first-seen order (a later run's new key is placed next to its siblings), then the
// tail columns. A summary column whose name is taken by an earlier column is prefixed with
// "summary." (e.g. summary.scheme when `scheme` is swept). Fields are passed through csv_field.
std::string format_summary_csv(const std::vector<SummaryRow>& rows, const SummaryLayout& layout);

// format_summary_csv written with write_file_atomic.
void write_summary_csv(const std::filesystem::path& path, const std::vector<SummaryRow>& rows,
                       const SummaryLayout& layout);

}  // namespace ricochet
