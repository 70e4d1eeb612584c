// ricochet_bench: Google Benchmark's usual command line. Exits non-zero when a benchmark
// reported an error (an invalid result) or when the filter selected no benchmark, so the
// CTest smoke test fails on a broken benchmark.
#include <benchmark/benchmark.h>

#include "bench/bench_common.hpp"

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  const std::size_t ran = benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return ran > 0 && ricochet::bench::failure_count() == 0 ? 0 : 1;
}
