// The threads of a run: how many OpenMP threads the element loops of one run may use, and the
// scope that sets that count for the run. The schemes' run functions (run_explicit,
// run_implicit) open a ThreadScope from RunSettings::threads; the kernels only use
// `#pragma omp parallel` and so take the count from it. Results do not depend on the count:
// the threaded loops are written to be bitwise identical for any number of threads.
#pragma once

namespace ricochet {

// The largest thread count a run accepts (case key `threads`, `--threads`).
inline constexpr int kMaxThreads = 256;

// The threads a run with setting `requested` uses: 0 = every core this process may run on
// (omp_get_num_procs(), which honours the CPU affinity mask); n >= 1 = n, capped at
// kMaxThreads. OMP_NUM_THREADS does not change it: the run's setting decides. Throws
// std::invalid_argument for a negative count.
int resolve_threads(int requested);

// While it lives, OpenMP parallel regions started by this thread use threads() threads
// (omp_set_num_threads); the count in force before is restored when it ends. One run, one scope.
class ThreadScope {
 public:
  explicit ThreadScope(int requested);
  ~ThreadScope();
  ThreadScope(const ThreadScope&) = delete;
  ThreadScope& operator=(const ThreadScope&) = delete;

  int threads() const { return threads_; }

 private:
  int threads_;
  int previous_;
};

}  // namespace ricochet
