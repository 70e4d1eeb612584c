// The threads of a run: how many OpenMP threads the element loops of one run may use, and the
// scope that sets that count for the run. The schemes' run functions (run_explicit,
// run_implicit) open a ThreadScope from RunSettings::threads; the kernels only use
// `#pragma omp parallel` and so take the count from it. Results do not depend on the count:
// the threaded loops are written to be bitwise identical for any number of threads.
//
// On a machine shared with other work the count adapts (RunSettings::adapt_threads, on by
// default): OpenMP's threads spin-wait at every barrier, and a thread whose partner has lost its
// core to another process spins for nothing. Measured on 2 cores beside two busy processes, the
// plate on M2 at dt = 1e-6 s took 8.8 x longer on two threads than on one (46 s against 0.42 s
// once, x110). So the scope counts the cores that other processes hold, at the start and then
// every kAdaptInterval of the run, and runs on the cores left (at least one, at most the
// requested count): fewer threads at once when others arrive, more again only when the cores
// have been free at two checks in a row (docs/performance.md, Threads on a shared machine).
#pragma once

#include <chrono>
#include <vector>

namespace ricochet {

// The largest thread count a run accepts (case key `threads`, `--threads`).
inline constexpr int kMaxThreads = 256;

// How often an adapting scope looks at the load again.
inline constexpr std::chrono::milliseconds kAdaptInterval{100};

// The threads a run with setting `requested` may use: 0 = every core this process may run on
// (omp_get_num_procs(), which honours the CPU affinity mask); n >= 1 = n, capped at
// kMaxThreads. OMP_NUM_THREADS does not change it: the run's setting decides. Throws
// std::invalid_argument for a negative count.
int resolve_threads(int requested);

// The machine's load as seen from this process: runnable tasks of other processes, from the
// kernel's count of runnable tasks (/proc/loadavg) less this process's own runnable threads
// (`own_tids`: the OpenMP team's thread ids; the calling thread always counts). -1 when the
// counts cannot be read (not Linux): the scope then keeps the requested count.
int other_runnable_tasks(const std::vector<int>& own_tids);

// While it lives, OpenMP parallel regions started by this thread use threads_now() threads
// (omp_set_num_threads); the count in force before is restored when it ends. One run, one scope.
class ThreadScope {
 public:
  // `adapt`: fit the count to the cores other processes leave free (above); false: always the
  // resolved `requested` (benchmarks and tests that must run a given count).
  explicit ThreadScope(int requested, bool adapt = false);
  ~ThreadScope();
  ThreadScope(const ThreadScope&) = delete;
  ThreadScope& operator=(const ThreadScope&) = delete;

  // Once per time step: every kAdaptInterval, count the load again and set the team size. No
  // allocation; a few small reads of /proc at most ten times a second.
  void adapt() {
    if (adapting_ && std::chrono::steady_clock::now() >= next_check_) refit();
  }

  int threads() const { return threads_; }          // the ceiling: resolve_threads(requested)
  int threads_now() const { return now_; }          // the team size in force
  int threads_min() const { return min_used_; }     // the smallest team size the run used

 private:
  void refit();

  int threads_;
  int previous_;
  bool adapting_;
  int now_;
  int min_used_;
  int free_streak_ = 0;  // checks in a row that found more free cores than now_
  int cores_;            // cores this process may run on (omp_get_num_procs)
  std::vector<int> tids_;  // the team's thread ids, for other_runnable_tasks
  std::chrono::steady_clock::time_point next_check_;
};

}  // namespace ricochet
