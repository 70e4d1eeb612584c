// `ricochet sweep SWEEP.toml`: runs every case of an expanded sweep (harness/sweeps/sweep_spec.hpp) as a
// subprocess `ricochet run`, one at a time (clean timings) or N in parallel, resumes an
// interrupted sweep, repeats runs for timing statistics, measures each run's errors against a
// reference run (harness/sweeps/reference_errors.hpp: the sweep's shared [reference] or its group's own),
// and keeps DIR/summary.csv, a complete table of the finished runs, up to date after every run.
// Formats and keys: docs/sweeps.md.
//
// With --shard K/N it runs only the runs of shard K of N, writing their run folders and its own
// DIR/shards/K-of-N/ (never DIR/summary.csv or DIR/sweep.json); --merge builds those two from the
// run folders of every shard (sweep_shard.hpp).
//
// The parts: sweep_plan.hpp (the runs, their folders and requests, what is already done),
// sweep_exec.hpp (the subprocesses, repeats, signals, progress), sweep_table.hpp (summary.csv),
// sweep_errors.hpp (each run's errors against its reference), sweep_shard.hpp (the shards'
// assignment, their manifests, and the merge); sweep.cpp puts them together and writes
// DIR/sweep.json.
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

// Shard K of N of a sweep (`--shard K/N`), 1 <= K <= N <= kMaxShards.
struct SweepShard {
  int k = 1, n = 1;
  std::string name() const { return std::to_string(k) + "-of-" + std::to_string(n); }  // its folder, DIR/shards/<name>
  std::string text() const { return "shard " + std::to_string(k) + " of " + std::to_string(n); }
};
inline constexpr int kMaxShards = 100000;  // N at most (a sweep has at most 100000 runs)

struct SweepOptions {
  std::filesystem::path out_dir;     // DIR (required)
  int jobs = 1;                      // runs at the same time, >= 1
  int repeat = 1;                    // times each run is repeated, >= 1
  // --threads N for every run (0 = all cores); empty: SweepPlan::threads() decides per run.
  std::optional<int> threads;
  bool force = false;                // rerun finished runs too
  bool quiet = false;                // no progress lines
  // Run only this shard's runs (sweep_shard.hpp), into DIR/runs/ and DIR/shards/K-of-N/.
  std::optional<SweepShard> shard;
  std::filesystem::path executable;  // the ricochet program to run; empty = /proc/self/exe
  std::ostream* log = nullptr;       // progress lines and notes; nullptr = std::cerr
  // How long to wait for a process that still writes a run folder (it holds its run.lock: a run
  // of an interrupted sweep) before stopping with an error [s].
  double writer_wait = 10.0;
};

struct SweepOutcome {
  std::size_t total = 0;     // runs in the sweep (with a shard: in the shard), reference runs included
  std::size_t resumed = 0;   // finished by an earlier invocation, not run again
  std::size_t executed = 0;  // run by this invocation
  std::size_t ok = 0, diverged = 0, failed = 0;  // over all runs (of the shard)
};

// `ricochet sweep SWEEP.toml [--out DIR] [--jobs N] [--threads N] [--repeat K] [--check GATES.toml]
// [--force] [--quiet] [--shard K/N | --merge | --slurm [--shards N] [--slurm-option OPT]... [--dry-run]]`.
struct SweepCommand {
  std::string file;        // SWEEP.toml
  std::string gates_file;  // --check GATES.toml; empty: no check
  SweepOptions options;    // an empty out_dir: results/<sweep name>
  bool merge = false;      // --merge: merge the shards' run folders (sweep_shard.hpp), run nothing
  // --slurm: submit the shards as a Slurm job array and the merge after them (sweep_slurm.hpp).
  bool slurm = false;
  std::optional<int> shards;               // --shards N: the array's tasks (default: one per run, at most 1000)
  std::vector<std::string> slurm_options;  // --slurm-option OPT: raw #SBATCH options, in order
  bool dry_run = false;                    // --dry-run: print the scripts, write and submit nothing
};

// Reads the sweep file (and the gate file, before any run), runs the sweep (or its shard, or
// merges it) and, with a gate file, checks its gates on DIR/summary.csv (lines on `out`, report
// DIR/gates-junit.xml). Returns 0 the sweep (shard) completed (diverged and failed runs are
// results) and every gate passed; 4 a gate failed (gates.hpp); with --merge, 3 runs are missing
// (merge_command). With --slurm it only checks the sweep and submits it (slurm_command), 0.
// Throws InputError for bad input (nothing written).
int run_command(const SweepCommand& c, std::ostream& out);

// What a sweep.json says about the invocation that wrote it (the keys before `runs`).
struct SweepJsonHead {
  std::filesystem::path out;      // DIR
  std::filesystem::path program;  // the executable that ran the runs
  Json jobs, threads;             // --jobs, --threads (null without it)
  int repeat = 1;
  bool force = false;
  std::string started_at;
  Json finished_at;               // null while running
  std::size_t resumed = 0;        // runs finished before, not run again
  Json counts;                    // {executed, ok, diverged, failed}; null while running
};

// DIR/sweep.json (docs/sweeps.md, "Output folder"): the sweep, `head`, the shared reference with
// its status and floor, and every run.
Json sweep_json(const SweepPlan& plan, const std::vector<RunRecord>& records, SweepTable& table, const SweepJsonHead& head);

// Runs a sweep: check_runs (sweep_plan.hpp) first (nothing is written on bad input), then the
// runs, writing DIR/sweep.json, DIR/runs/<id>/ and DIR/summary.csv; with options.shard only the
// shard's runs, writing DIR/runs/<id>/ of those and DIR/shards/K-of-N/ (shard.json, summary.csv
// without errors against references). Throws InputError for bad input and
// std::runtime_error if DIR cannot be written or the program cannot be started.
SweepOutcome run_sweep(const SweepSpec& spec, const std::vector<SweepRun>& runs, const SweepOptions& options);

}  // namespace ricochet
