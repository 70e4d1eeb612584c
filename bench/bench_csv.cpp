// Reading CSV: parse_csv() and parse_csv_number() (harness/outputs/csv_reader.hpp) on a table
// the size of a long run's history.csv, 2401 rows x 34 columns of numbers written as
// history.csv writes them (%.17g). docs/architecture.md quotes this figure as the reason the
// reader stays our own.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "harness/outputs/csv_reader.hpp"

namespace {

std::string history_like_table(int rows, int columns) {
  std::string text;
  for (int c = 0; c < columns; ++c) text += (c ? ",column_" : "column_") + std::to_string(c);
  text += '\n';
  char buf[32];
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      std::snprintf(buf, sizeof buf, "%.17g", std::sin(0.37 * r + 1.1 * c) * std::pow(10.0, c % 9 - 4));
      if (c) text += ',';
      text += buf;
    }
    text += '\n';
  }
  return text;
}

void BM_CsvRead(benchmark::State& state) {
  const std::string text = history_like_table(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  std::size_t numbers = 0;
  for (auto _ : state) {
    const ricochet::CsvTable t = ricochet::parse_csv(text, "history.csv");
    numbers = 0;
    for (const auto& row : t.rows)
      for (const auto& cell : row) numbers += ricochet::parse_csv_number(cell).has_value();
    benchmark::DoNotOptimize(numbers);
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations()) * static_cast<std::int64_t>(text.size()));
  state.counters["bytes"] = static_cast<double>(text.size());
  state.counters["numbers"] = static_cast<double>(numbers);
}
BENCHMARK(BM_CsvRead)->Name("csv_read/history")->Args({2401, 34})->Unit(benchmark::kMillisecond);

}  // namespace
