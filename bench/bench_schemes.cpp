// Whole runs of the paper's oblique-plate case (cases/oblique_plate.toml, mu = 0, 3 ms) per
// scheme, mesh and time step: the cells of the paper's Table 1 that the schemes can run.
// Measures the wall time of run_case (time loop, observers and sampling; case reading, model
// building and output writing excluded) in seconds, as the manual time of one iteration; run
// with --benchmark_repetitions to get medians. Not part of the CTest smoke test (seconds each).
// One thread unless the name ends in /threads:2 (RunSettings::threads), so that the series
// stay comparable whatever the machine's core count.
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "bench_common.hpp"
#include "harness/input/case_setup.hpp"

namespace ricochet::bench {
namespace {

void scheme_run(benchmark::State& state, const std::string& scheme, const std::string& mesh,
                const std::string& dt, int threads) {
  const CaseSpec spec = read_case(std::string(RICOCHET_SOURCE_DIR) + "/cases/oblique_plate.toml",
                                  {"scheme=" + scheme, "mesh=" + mesh, "time.dt=" + dt});
  PreparedCase pc = prepare_case(spec);
  pc.settings.threads = threads;
  for (auto _ : state) {
    const RunResult r = run_case(pc);
    if (r.status != RunStatus::ok) fail(state, "run " + scheme + " " + mesh + " " + dt + ": " + r.reason);
    state.SetIterationTime(r.timing.wall_seconds);
    state.counters["element_steps_per_second"] = r.timing.element_steps_per_second;
    state.counters["energy_error_max"] = r.energy_error_max;
  }
}

void register_all() {
  struct Cell {
    const char* scheme;
    const char* mesh;
    const char* dt;
    int threads = 1;
  };
  const std::vector<Cell> cells = {
      {"semi_explicit", "M1", "1e-5"}, {"semi_explicit", "M1", "1e-6"}, {"semi_explicit", "M2", "1e-6"},
      {"implicit", "M1", "1e-4"},      {"implicit", "M1", "1e-5"},      {"implicit", "M1", "1e-6"},
      {"implicit", "M2", "1e-4"},      {"implicit", "M2", "1e-5"},      {"implicit", "M2", "1e-6"},
      {"explicit_penalty", "M2", "auto"}, {"semi_explicit", "M2", "1e-6", 2}};
  for (const Cell& c : cells) {
    const std::string name = std::string("scheme_run/") + c.scheme + "/" + c.mesh + "/dt" + c.dt +
                             (c.threads > 1 ? "/threads:" + std::to_string(c.threads) : "");
    benchmark::RegisterBenchmark(name.c_str(),
                                 [c](benchmark::State& st) { scheme_run(st, c.scheme, c.mesh, c.dt, c.threads); })
        ->UseManualTime()
        ->Iterations(1)
        ->Unit(benchmark::kSecond);
  }
}

const int registered = (register_all(), 0);

}  // namespace
}  // namespace ricochet::bench
