// The threads of a run (solver/schemes/threads.hpp): resolve_threads() and ThreadScope, and that
// every scheme's run uses RunSettings::threads while it runs, restores the caller's count,
// records the count in RunResult::threads, and gives bitwise the same results for 1 and 2 threads,
// the variable step's included.
#include <gtest/gtest.h>

#include <omp.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "harness/input/case_setup.hpp"
#include "solver/forces/internal_forces.hpp"
#include "solver/schemes/threads.hpp"

namespace fs = std::filesystem;
using namespace ricochet;

namespace {

// A block thrown obliquely onto a rigid line with friction: contact, sticking and sliding within
// the run, so every part of a step (forces, contact, stress peaks) is exercised.
const std::string kCase = R"(name = "block"
mesh = "m"
[meshes.m]
generator = "rectangle"
width = 0.1
height = 0.05
nx = 8
ny = 4
origin = [-0.05, 0.0005]
[[bodies]]
name = "b"
velocity = [2.0, -5.0]
[bodies.material]
young = 1e8
poisson = 0.3
density = 1000.0
[[obstacles]]
point = [0.0, 0.0]
normal = [0.0, 1.0]
friction = 0.3
[time]
end = 1e-3
dt = 1e-5
[output]
interval = 1e-4
[[output.probes]]
name = "P"
point = [0.05, 0.0005]
)";

// The team count of a parallel region started here.
int region_threads() {
  int n = 0;
#pragma omp parallel
  {
#pragma omp single
    n = omp_get_num_threads();
  }
  return n;
}

// Restores the test process's OpenMP count after each test.
class Threads : public ::testing::Test {
 protected:
  void SetUp() override { before_ = omp_get_max_threads(); }
  void TearDown() override { omp_set_num_threads(before_); }
  int before_ = 1;
};

}  // namespace

TEST_F(Threads, ResolveGivesAllCoresForZeroAndTheCountOtherwise) {
  EXPECT_EQ(resolve_threads(0), omp_get_num_procs());
  EXPECT_EQ(resolve_threads(1), 1);
  EXPECT_EQ(resolve_threads(3), 3);  // as given, even above the number of cores
  EXPECT_EQ(resolve_threads(kMaxThreads), kMaxThreads);
  EXPECT_EQ(resolve_threads(kMaxThreads + 1), kMaxThreads);
  EXPECT_THROW(resolve_threads(-1), std::invalid_argument);
}

TEST_F(Threads, ScopeSetsTheCountAndRestoresTheOneBefore) {
  omp_set_num_threads(3);
  {
    const ThreadScope scope(2);
    EXPECT_EQ(scope.threads(), 2);
    EXPECT_EQ(omp_get_max_threads(), 2);
    EXPECT_EQ(region_threads(), 2);
    {
      const ThreadScope inner(0);
      EXPECT_EQ(inner.threads(), omp_get_num_procs());
      EXPECT_EQ(omp_get_max_threads(), omp_get_num_procs());
    }
    EXPECT_EQ(omp_get_max_threads(), 2);
  }
  EXPECT_EQ(omp_get_max_threads(), 3);
  EXPECT_THROW(ThreadScope(-2), std::invalid_argument);
  EXPECT_EQ(omp_get_max_threads(), 3);
}

// Each scheme with threads = 1 and 2: the count in force inside the run (seen from the progress
// callback, which the loop calls at its monitor steps), the recorded count, the caller's count
// afterwards, and the results bit for bit.
// The small block runs the force pass on one thread whatever the count (fewer cells than
// kForceParallelChunks chunks); the fine variants (64 x 20 cells of each formulation, in the
// explicit schemes, whose force pass is the threaded one) run its chunks in parallel.
TEST_F(Threads, EveryRunUsesItsThreadsAndResultsDoNotDependOnThem) {
  const fs::path file = fs::temp_directory_path() / ("ricochet_threads_" + std::to_string(getpid()) + ".toml");
  std::ofstream(file) << kCase;
  struct Variant {
    const char* scheme;
    std::vector<std::string> set;
  };
  const std::vector<std::string> fine = {"meshes.m.nx=64", "meshes.m.ny=20", "time.end=3e-4", "time.dt=2e-6"};
  // The variable step, recomputed every step on the run's threads (StepControl::critical).
  const std::vector<std::string> variable = {"meshes.m.nx=64", "meshes.m.ny=20", "time.end=3e-4", "time.dt=auto",
                                             "time.dt_update_interval=1"};
  auto with = [&](std::vector<std::string> a, const std::vector<std::string>& b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
  };
  const std::vector<Variant> variants = {
      {"explicit_penalty", {}},
      {"semi_explicit", {}},
      {"implicit", {}},
      {"semi_explicit", fine},
      {"explicit_penalty", with(fine, {"bodies[0].element=q4_hourglass"})},
      {"semi_explicit", with(fine, {"meshes.m.cells=tri"})},
      {"semi_explicit", variable},
      {"explicit_penalty", with(variable, {"meshes.m.cells=tri"})},
  };
  for (const Variant& variant : variants) {
    const char* scheme = variant.scheme;
    SCOPED_TRACE(std::string(scheme) + (variant.set.empty() ? "" : ", " + variant.set.back()));
    const PreparedCase base =
        prepare_case(read_case(file.string(), with({std::string("scheme=") + scheme}, variant.set)));
    if (!variant.set.empty()) {
      EXPECT_GE(static_cast<std::size_t>(base.model<2>().num_cells()), kForceParallelChunks * kForceChunkCells);
    }
    std::vector<RunResult> results;
    for (const int threads : {1, 2}) {
      PreparedCase pc = base;
      pc.settings.threads = threads;
      pc.settings.adapt_threads = false;  // the count itself is under test, whatever the load
      omp_set_num_threads(5);
      std::vector<int> inside;
      results.push_back(run_case(pc, [&](long, long, double) { inside.push_back(omp_get_max_threads()); }));
      const RunResult& r = results.back();
      EXPECT_EQ(omp_get_max_threads(), 5) << "the caller's count is restored";
      EXPECT_EQ(r.timing.threads, threads);
      ASSERT_FALSE(inside.empty());
      for (const int n : inside) EXPECT_EQ(n, threads);
      ASSERT_EQ(r.status, RunStatus::ok) << r.reason;
      EXPECT_GT(r.contact.steps, 0) << "the block must reach the line";
    }
    const RunResult &a = results[0], &b = results[1];
    ASSERT_EQ(a.history.columns, b.history.columns);
    ASSERT_EQ(a.history.values.size(), b.history.values.size());
    EXPECT_EQ(std::memcmp(a.history.values.data(), b.history.values.data(), a.history.values.size() * sizeof(double)), 0)
        << "history differs between 1 and 2 threads";
    EXPECT_EQ(std::memcmp(&a.stress.von_mises_max, &b.stress.von_mises_max, sizeof(double)), 0);
    EXPECT_EQ(std::memcmp(&a.friction_dissipation, &b.friction_dissipation, sizeof(double)), 0);
    EXPECT_EQ(a.steps, b.steps);
    EXPECT_EQ(a.dt_min, b.dt_min);
  }
  fs::remove(file);
}

// The default (0) is every core.
TEST_F(Threads, DefaultRunUsesEveryCore) {
  const fs::path file = fs::temp_directory_path() / ("ricochet_threads_default_" + std::to_string(getpid()) + ".toml");
  std::ofstream(file) << kCase;
  const PreparedCase pc = prepare_case(read_case(file.string(), {"scheme=semi_explicit", "time.end=1e-4"}));
  fs::remove(file);
  EXPECT_EQ(pc.settings.threads, 0);
  EXPECT_EQ(run_case(pc).timing.threads, omp_get_num_procs());
}

namespace {

// `n` child processes that spin on a core each until the object goes: the "other processes
// holding the cores" of a shared machine.
class BusyProcesses {
 public:
  explicit BusyProcesses(int n) {
    for (int i = 0; i < n; ++i) {
      const pid_t pid = fork();
      if (pid == 0) {
        for (;;) asm volatile("");  // spin: an empty asm keeps the loop a side effect
      }
      if (pid > 0) pids_.push_back(pid);
    }
    usleep(50000);  // let the scheduler spread them
  }
  ~BusyProcesses() {
    for (const pid_t pid : pids_) kill(pid, SIGKILL);
    for (const pid_t pid : pids_) waitpid(pid, nullptr, 0);
  }
  std::size_t size() const { return pids_.size(); }

 private:
  std::vector<pid_t> pids_;
};

}  // namespace

// Processes that never block are runnable at every look: each sample counts them all.
TEST_F(Threads, OtherRunnableTasksCountsBusyProcesses) {
  if (other_runnable_tasks({}) < 0) GTEST_SKIP() << "no /proc/loadavg: the count is not available here";
  const BusyProcesses busy(2);
  ASSERT_EQ(busy.size(), 2u);
  for (int i = 0; i < 20; ++i) {
    EXPECT_GE(other_runnable_tasks({}), 2);
    usleep(2000);
  }
}

// With a busy process on every core, an adapting run gives its second thread up (threads_min
// = 1) and its results are those of the fixed counts bit for bit; a run with adapt_threads =
// false keeps its two threads throughout.
TEST_F(Threads, AdaptingRunGivesThreadsUpWhileOthersHoldTheCores) {
  if (other_runnable_tasks({}) < 0) GTEST_SKIP() << "no /proc/loadavg: the count is not available here";
  const fs::path file = fs::temp_directory_path() / ("ricochet_threads_adapt_" + std::to_string(getpid()) + ".toml");
  std::ofstream(file) << kCase;
  const PreparedCase base = prepare_case(read_case(
      file.string(), {"scheme=semi_explicit", "meshes.m.nx=64", "meshes.m.ny=20", "time.end=3e-4", "time.dt=2e-6"}));
  fs::remove(file);
  PreparedCase fixed = base;
  fixed.settings.threads = 2;
  fixed.settings.adapt_threads = false;
  const RunResult reference = run_case(fixed);
  ASSERT_EQ(reference.status, RunStatus::ok) << reference.reason;

  const BusyProcesses busy(omp_get_num_procs());
  PreparedCase adapting = base;
  adapting.settings.threads = 2;
  std::vector<int> inside;
  const RunResult r = run_case(adapting, [&](long, long, double) { inside.push_back(omp_get_max_threads()); });
  ASSERT_EQ(r.status, RunStatus::ok) << r.reason;
  EXPECT_EQ(r.timing.threads, 2);
  EXPECT_EQ(r.timing.threads_min, 1);
  ASSERT_FALSE(inside.empty());
  EXPECT_EQ(inside.front(), 1) << "the load is read before the first step";
  ASSERT_EQ(r.history.values.size(), reference.history.values.size());
  EXPECT_EQ(std::memcmp(r.history.values.data(), reference.history.values.data(),
                        r.history.values.size() * sizeof(double)),
            0);

  std::vector<int> fixed_inside;
  const RunResult f = run_case(fixed, [&](long, long, double) { fixed_inside.push_back(omp_get_max_threads()); });
  EXPECT_EQ(f.timing.threads_min, 2);
  for (const int n : fixed_inside) EXPECT_EQ(n, 2);
}
