// The timed loop of the explicit-step benchmarks (bench_explicit_step.cpp, 2D; explicit_step3
// in bench_element_forces3.cpp, 3D): evaluate() then update() per iteration from the state
// `start`, which is restored (timer paused) every kResetEvery steps so a long run never leaves
// the small-strain regime however many iterations the library picks. Returns the last state.
#pragma once

#include <vector>

#include <benchmark/benchmark.h>

#include "solver/schemes/central_difference.hpp"

namespace ricochet::bench {

inline constexpr long kResetEvery = 1000;

template <class M>
State time_explicit_steps(benchmark::State& state, const M& model, const std::vector<PrescribedDof>& prescribed,
                          const State& start) {
  State s = start;
  long since_reset = 0;
  for (auto _ : state) {
    if (since_reset == kResetEvery) {
      state.PauseTiming();
      s = start;
      since_reset = 0;
      state.ResumeTiming();
    }
    evaluate(model, prescribed, s, /*with_energy=*/false);
    update(s);
    ++since_reset;
    benchmark::DoNotOptimize(s.u.data());
    benchmark::ClobberMemory();
  }
  return s;
}

}  // namespace ricochet::bench
