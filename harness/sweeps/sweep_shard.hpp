// Sharded sweeps (docs/sweeps.md, "Sharded sweeps"): `ricochet sweep FILE --shard K/N` runs the
// runs of shard K of N into the usual DIR/runs/<id>/ and its own DIR/shards/K-of-N/ (shard.lock,
// shard.json, summary.csv), and `ricochet sweep FILE --merge` builds DIR/summary.csv and
// DIR/sweep.json from the run folders, as a sweep without --shard would have written them, with
// the errors against references measured across the shards.
//
// The assignment: the runs ordered by the FNV-1a hash of their run id (ties: the sweep's order)
// and dealt out in turn, so that it depends on the run ids and N only (never on what is done),
// each shard gets floor(T/N) or ceil(T/N) runs, and a shard's runs are spread over the sweep's
// groups and crossed values.
//
// The locks (flock): a sweep without --shard holds DIR/sweep.lock exclusively; a shard holds it
// shared plus DIR/shards/K-of-N/shard.lock exclusively; a merge holds it shared plus
// DIR/merge.lock exclusively. So shards run side by side (on several hosts, if the shared file
// system has flock), a merge may run beside them, a shard never runs twice at once, and a sweep
// without --shard never runs beside shards or a merge.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "harness/sweeps/sweep.hpp"

namespace ricochet {

// `--merge`'s exit status when runs are missing (not run, interrupted, still running, or from
// another sweep definition).
inline constexpr int kExitIncomplete = 3;

// The value of --shard, "K/N" with integers 1 <= K <= N <= kMaxShards. Throws InputError, one line
// "ricochet sweep: --shard: expected K/N ...; got 'TEXT'".
SweepShard parse_shard(const std::string& text);

// The shard (1 ... n) of each run, by the assignment above.
std::vector<int> shard_assignment(const std::vector<SweepRun>& runs, int n);
// Which runs belong to `shard` (SweepPlan::set_scope).
std::vector<bool> shard_scope(const std::vector<SweepRun>& runs, const SweepShard& shard);

// DIR/shards/K-of-N.
std::filesystem::path shard_folder(const std::filesystem::path& out_dir, const SweepShard& shard);

// An flock on `file` (created if missing), exclusive or shared, without waiting: its open file
// descriptor (close-on-exec, so that no run inherits it), or -1 if another process holds a
// conflicting lock. Throws std::runtime_error if the file cannot be opened.
int try_lock_file(const std::filesystem::path& file, bool exclusive);

// A run of the sweep that a merge could not take.
struct MissingRun {
  std::size_t index = 0;
  std::string id;
  std::string why;      // "not run", "interrupted ...", "being written by process P ...", or why
                        // its folder is from another sweep definition
  bool foreign = false;  // its folder holds a run of another sweep definition (refused)
  int shard = 0, shards = 0;  // its shard K of N, when the shards' manifests give N; else 0
};

struct MergeOutcome {
  std::size_t total = 0;                         // runs in the sweep
  std::size_t ok = 0, diverged = 0, failed = 0;  // the merged runs
  std::vector<MissingRun> missing;               // in the sweep's order
  bool complete() const { return missing.empty(); }
};

// `ricochet sweep FILE --merge`: check_runs first (nothing written on bad input), then reads every
// run folder of the sweep under its run.lock (without waiting: a folder being written is a missing
// run), and writes DIR/summary.csv (the finished runs, their errors against their references) and
// DIR/sweep.json (with a `merge` object: the definition, the shards' manifests, the missing and
// failed runs). Lists the failed and the missing runs on options.log (even with quiet), and per
// shard with missing runs the command that reruns it. A run folder whose overrides.json is not
// what this sweep would write (another sweep file, base case, --repeat) is refused: missing, never
// merged. Throws InputError for bad input (options.jobs, threads, force or shard set; no folder
// DIR) and std::runtime_error if DIR cannot be written or a sweep without --shard runs in it.
MergeOutcome merge_sweep(const SweepSpec& spec, const std::vector<SweepRun>& runs, const SweepOptions& options);

}  // namespace ricochet
