// The execution of a sweep's runs (harness/sweeps/sweep.hpp): each run is the subprocess
// `ricochet run BASE --set KEY=VALUE... [--threads N] --out FOLDER --quiet` (--threads as
// SweepPlan::threads() says; stdout to /dev/null, stderr to FOLDER/stderr.txt), `jobs` at a
// time, each repeated as the plan says; SIGINT, SIGTERM and SIGHUP are passed on to the running
// children. A finished run's record is filled from its summary.json (or marked failed, with the
// reason), and a progress line is printed after each run.
#pragma once

#include <chrono>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <vector>

#include "harness/sweeps/sweep_plan.hpp"

namespace ricochet {

class SweepExecution {
 public:
  using Clock = std::chrono::steady_clock;

  // `program`: the ricochet program to run; `start`: when the sweep started (for the elapsed
  // time); `done`: the runs already done when it starts (resumed ones), for the progress lines.
  SweepExecution(const SweepPlan& plan, std::vector<RunRecord>& records, const SweepOptions& options,
                 std::filesystem::path program, Clock::time_point start, std::size_t done);

  // Runs the runs of `queue`, each as soon as a job is free and its reference is done (in queue
  // order otherwise). A run's folder is emptied and its overrides.json written when it starts.
  // `on_done(i)` is called once run i is done, its record updated (state done; status, reason,
  // summary and timings, or status failed), before its progress line.
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
  std::size_t done_ = 0, session_runs_ = 0;
  double session_wall_ = 0.0;  // process wall time of the runs executed so far [s]
};

}  // namespace ricochet
