// The execution of a sweep's runs (harness/sweeps/sweep.hpp): each run is the subprocess
// `ricochet run BASE --set KEY=VALUE... [--threads N] --out FOLDER --quiet` (--threads as
// SweepPlan::threads() says; stdout to /dev/null, stderr to FOLDER/stderr.txt), or for a
// stability group's search `ricochet stability BASE --set ... --out FOLDER --quiet [options]`,
// `jobs` at a time, each repeated as the plan says. Each run process is in its own process group and dies
// with the sweep (SIGKILL when the sweep ends, whatever ends it: PR_SET_PDEATHSIG), and holds
// its folder's lock, RUN/run.lock, for its whole life (RunFolderLock). SIGINT, SIGTERM and
// SIGHUP are passed on to the running runs' groups; the sweep waits up to 5 s for them to end
// before it ends by the same signal. A finished run's record is filled from its summary.json
// (a search's from its stability.json), or marked failed with the reason (and that failure kept in
// the run folder as failure.json, for a merge: sweep_shard.hpp), and a progress line is printed
// after each run.
#pragma once

#include <chrono>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <iosfwd>
#include <string>
#include <vector>

#include "harness/sweeps/sweep_plan.hpp"

namespace ricochet {

// The lock of a run folder: an flock on FOLDER/run.lock. The sweep takes it before it empties the
// folder and starts the run, and each of the run's processes inherits it (the same open file),
// so it is held as long as the sweep or any process of the run lives, and the kernel drops it
// when they have all ended (no stale lock after a crash or SIGKILL). A sweep never writes into,
// or starts a run in, a folder whose lock another process holds. The file itself holds the pid of
// the last run process started in the folder (for the messages), and is never removed.
class RunFolderLock {
 public:
  // Creates FOLDER and FOLDER/run.lock if missing and locks it. If another process holds it,
  // writes one line "WHO: FOLDER: still being written by process PID ...; waiting up to ..." to
  // `log`, and waits up to `wait` seconds for it; then throws std::runtime_error, one line
  // naming the folder and the process.
  RunFolderLock(const std::filesystem::path& folder, double wait, std::ostream& log, const std::string& who);
  RunFolderLock(RunFolderLock&& o) noexcept;
  RunFolderLock& operator=(RunFolderLock&& o) noexcept;
  RunFolderLock(const RunFolderLock&) = delete;
  RunFolderLock& operator=(const RunFolderLock&) = delete;
  ~RunFolderLock();  // releases it (the run's processes may still hold it)

  int fd() const { return fd_; }
  // Writes `pid` (the run process just started) into run.lock.
  void record(long pid);
  // Removes everything in the folder but run.lock.
  void clear_folder() const;

 private:
  std::filesystem::path folder_;
  int fd_ = -1;
};

// A failed run's record in its folder, FOLDER/failure.json: {"run_id", "status": "failed",
// "reason", "written_at"}, written with a temporary file and a rename. A run folder holds
// summary.json (finished), failure.json (failed) or neither (not finished); resume reruns a
// failed run as before, and a merge reads the failure from it (read_failure).
void write_failure(const std::filesystem::path& folder, const std::string& run_id, const std::string& reason);

// The reason of a failed run from FOLDER/failure.json, if it is there, is a failure record of
// run `run_id` and is valid (status "failed", a string reason); else nothing.
std::optional<std::string> read_failure(const std::filesystem::path& folder, const std::string& run_id);

class SweepExecution {
 public:
  using Clock = std::chrono::steady_clock;

  // `program`: the ricochet program to run; `start`: when the sweep started (for the elapsed
  // time); `done`: the runs already done when it starts (resumed ones), for the progress lines,
  // which count the runs in the plan's scope (a shard's runs).
  SweepExecution(const SweepPlan& plan, std::vector<RunRecord>& records, const SweepOptions& options,
                 std::filesystem::path program, Clock::time_point start, std::size_t done);

  // Runs the runs of `queue`, each as soon as a job is free and its reference is done (in queue
  // order otherwise). A run's folder is locked (RunFolderLock, waiting up to
  // SweepOptions::writer_wait), emptied and its overrides.json written when it starts. Must be
  // called from a thread that lives until it returns (the runs die with the thread that started
  // them); if it throws, the runs it started are killed and reaped first.
  // `on_done(i)` is called once run i is done, its record updated (state done; status, reason,
  // summary and timings, or status failed), before its progress line. A failed run's folder gets
  // failure.json (write_failure) before its lock is released.
  void run(std::vector<std::size_t> queue, const std::function<void(std::size_t)>& on_done);

 private:
  struct Task;

  void start(Task& t);
  void begin(std::size_t i, std::vector<Task>& active);
  void finish(Task& t, int wait_status);
  void progress(const Task& t);

  const SweepPlan& plan_;
  std::vector<RunRecord>& records_;
  const SweepOptions& options_;
  std::filesystem::path program_;
  std::ostream* log_;
  Clock::time_point start_;
  std::size_t total_ = 0;  // runs in the plan's scope
  std::size_t done_ = 0, session_runs_ = 0;
  double session_wall_ = 0.0;  // process wall time of the runs executed so far [s]
};

}  // namespace ricochet
