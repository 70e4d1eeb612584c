// The plan of a sweep (harness/sweeps/sweep.hpp): its runs with their folders, how often each runs,
// the order they start in, and each run's identity: the request (overrides.json) a finished run
// must match to be reused, so that an interrupted or repeated sweep resumes instead of
// rerunning. Also the per-run record that execution, the table and sweep.json share.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "harness/outputs/json_io.hpp"
#include "harness/sweeps/sweep_spec.hpp"

namespace ricochet {

struct SweepOptions;

// What is known about one run of the sweep.
struct RunRecord {
  enum class State { pending, active, done } state = State::pending;
  bool resumed = false;             // finished by an earlier invocation
  std::string status, reason;       // ok / diverged / failed, and why (empty for ok runs)
  std::optional<Json> summary;      // the run's summary.json (the last repeat's); a stability
                                    // search's stability.json
  std::vector<double> wall, cpu;    // per repeat, from the summaries [s]
};

class SweepPlan {
 public:
  // Hashes each run's base case (its text, FNV-1a), so that editing one base case reruns only
  // the runs made from it, and the mesh files each run's case reads (run_identity.hpp); takes
  // the build identity of the program that runs them (SweepOptions::executable).
  SweepPlan(const SweepSpec& spec, const std::vector<SweepRun>& runs, const SweepOptions& options);

  const SweepSpec& spec() const { return spec_; }
  const std::vector<SweepRun>& runs() const { return runs_; }
  const SweepRun& run(std::size_t i) const { return runs_[i]; }
  std::size_t size() const { return runs_.size(); }
  // The index of run `id` (which must exist).
  std::size_t index(const std::string& id) const { return index_.at(id); }

  // DIR/runs/<id>.
  std::filesystem::path folder(std::size_t i) const;
  // How often run i runs: --repeat K times; a reference run and a stability search once (its errors are the point, its
  // timing is not compared with anything).
  int repeats(std::size_t i) const;
  // The outputs of repeat k (from 1) of run i: its folder, or folder/repeat-k when it repeats.
  std::filesystem::path repeat_dir(std::size_t i, int k) const;
  // The text of the run's overrides.json: its id, base case and the base's hash, its overrides,
  // its number of repeats, the hashes of the mesh files its case reads (`meshes_fnv1a`) and the
  // program's build identity (`program_build`); for a stability search also `kind` and its
  // search options. Not its threads: they change the timings only, never the
  // results, so a sweep resumed with another --jobs or --threads (or `threads` values) reuses
  // its finished runs; each run's summary.json records the threads it used.
  std::string request(std::size_t i) const;
  // The `--threads` given to run i's `ricochet run`: the sweep's --threads if set; else 1 when
  // the run's overrides (the sweep file's `set`, `cross`, `reference`) do not set `threads`:
  // a sweep's runs are timed and compared, and one thread each keeps their timings from
  // depending on what else holds the cores; else none (the sweep file's `threads` decides).
  std::optional<int> threads(std::size_t i) const;

  // The runs this invocation may read, run and table: every run, or with set_scope only the
  // runs of one shard (`ricochet sweep --shard K/N`). The runs outside it belong to other
  // processes: their folders are neither read nor written.
  void set_scope(std::vector<bool> in_scope) { scope_ = std::move(in_scope); }
  bool in_scope(std::size_t i) const { return scope_.empty() || scope_[i]; }
  std::size_t scope_size() const;

  // The pending runs in scope in the order they are started: reference runs first, so that runs
  // compared with them find them finished.
  std::vector<std::size_t> queue(const std::vector<RunRecord>& records) const;
  // A run waits for its reference when the reference is in scope; a reference run (the shared
  // reference's check run) does not: its errors are computed again when the reference finishes.
  // A reference outside the scope (another shard's) holds nothing back: a run does not need its
  // reference to run, only its errors do, and the merge measures them (sweep_shard.hpp).
  bool startable(std::size_t i, const std::vector<RunRecord>& records) const;

  // The sweep definition's fingerprint: FNV-1a (64 bits, 16 hex digits) of every run's request
  // (above), in the sweep's order. Two invocations with the same fingerprint run the same runs
  // with the same identities; it changes with the runs, their overrides, their base cases' text,
  // their mesh files, the program's build and --repeat, not with --jobs, --threads or the output
  // folder.
  std::string definition() const;

  // Whether run i was finished by an earlier invocation: its overrides.json matches the request
  // and every repeat left a readable, valid summary.json (summary_problem), or for a stability
  // search its folder has a readable, valid stability.json (stability_problem); then `record` is
  // filled from them. A summary.json that is there but unreadable or invalid makes the run not
  // finished, and `note` says which file and why ("PATH: wall_seconds: expected ..."); else
  // `note` is empty.
  bool load_finished(std::size_t i, RunRecord& record, std::string& note) const;

 private:
  const SweepSpec& spec_;
  const std::vector<SweepRun>& runs_;
  const SweepOptions& options_;
  std::map<std::string, std::size_t> index_;
  std::map<std::filesystem::path, std::string> base_hash_;  // FNV-1a of each base case's text
  std::vector<Json> mesh_hashes_;  // per run: {mesh file: FNV-1a of its bytes, or null} (run_identity.hpp)
  // per run: an external scheme's adapter files (the arguments of its command that are files:
  // the adapter script, the program) with the FNV-1a of their bytes; null for ricochet's schemes
  std::vector<Json> adapter_hashes_;
  std::string build_id_;           // program_build_id of the program that runs the runs
  std::vector<bool> scope_;                                  // empty: every run
};

// What is wrong with a run's summary.json for a sweep, in one line naming the key ("wall_seconds:
// expected a number >= 0, got \"x\""); empty if nothing. Checked: the keys the sweep itself
// reads: `status` ("ok" or "diverged"), `diverged` (an object with a string `reason` when
// diverged, else null), `wall_seconds` and `cpu_seconds` (finite numbers >= 0), `steps` and
// `elements` (integers >= 0), `dt` (a finite number > 0). The other keys are copied to
// summary.csv as they are, and the error columns skip what they cannot read.
std::string summary_problem(const Json& summary);

// What is wrong with a stability search's stability.json for a sweep, in one line naming the key;
// empty if nothing. `ricochet stability` writes it last (atomically, after every trial), so a
// valid one marks a finished search. Checked: the keys the table reads: `outcome` (one of the
// outcomes of docs/stability.md), `converged` (a boolean), `estimate` (a finite number > 0),
// `largest_stable_dt` and `smallest_unstable_dt` (null or a finite number > 0), `runs` (an
// integer >= 0) and `trials` (an array).
std::string stability_problem(const Json& report);

// Fills a finished search's record from its stability.json: status ok (the search finished,
// whatever its outcome), no reason.
void set_stability_finished(RunRecord& record, Json report);

// Fills status, reason and summary from a finished run's summary.json (a status other than ok
// or diverged counts as diverged).
void set_finished(RunRecord& record, Json summary);

// The number `key` of a summary, else `fallback`.
double json_number(const Json& summary, std::string_view key, double fallback);
// The string `key` of a summary as it is, a number as summary.csv shows it; else empty.
std::string json_text(const Json& summary, std::string_view key);

// Validates every run's case (read_case of the run's base with its overrides) and, for every run
// compared with a reference (and every reference run), its error probe. Throws InputError
// "SWEEP:LINE: KEY: run ID: <the case's one-line error>".
void check_runs(const SweepSpec& spec, const std::vector<SweepRun>& runs);

// FNV-1a (64 bits) of a text, and as 16 hex digits.
std::uint64_t fnv1a(std::string_view text);
std::string fnv1a_hex(std::string_view text);

// The whole text of a file; empty if it cannot be read.
std::string read_text(const std::filesystem::path& path);

}  // namespace ricochet
