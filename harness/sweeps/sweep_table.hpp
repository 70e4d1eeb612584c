// A sweep's summary.csv (docs/sweeps.md): one row per finished run, its swept values, its
// summary.json flattened into columns, its timings over the repeats and its errors against its
// reference (harness/sweeps/sweep_errors.hpp). SweepTable keeps the rows of a running sweep and writes
// the whole table again after every run.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "harness/outputs/json_io.hpp"
#include "harness/sweeps/sweep_errors.hpp"
#include "harness/sweeps/sweep_plan.hpp"

namespace ricochet {

// One summary.json value under its flattened name ("contact_iterations.mean"); arrays as compact
// JSON; `null` marks a JSON null (or empty object), whose column is dropped if another run has
// keys under the same name (e.g. "implicit" next to "implicit.theta").
struct FlatField {
  std::string name;
  std::string value;
  bool null = false;
};

// A summary.json object flattened in document order; the `status` key is left out (it is the
// table's own `status` column). Numbers are written as compact_json writes them (json_io.hpp).
std::vector<FlatField> flatten_summary(const Json& summary);

struct SummaryRow {
  std::string run_id, group, kind, status, reason;  // kind: "run", "reference" or "stability"
  std::vector<std::pair<std::string, std::string>> swept;  // case key -> value (display form)
  std::vector<FlatField> summary;                          // flattened summary.json; empty if failed
  std::vector<std::pair<std::string, std::string>> extra;  // tail column -> value
};

struct SummaryLayout {
  std::vector<std::string> swept;  // case-key columns, in this order (keys only rows have are appended)
  std::vector<std::string> tail;   // the last columns, in this order
};

// The table: run_id, group, kind, status, reason, the swept keys, the union of the summary
// columns in first-seen order (a later run's new key is placed next to its siblings), then the
// tail columns. A summary column whose name is taken by an earlier column is prefixed with
// "summary." (e.g. summary.scheme when `scheme` is swept). Fields are passed through csv_field.
std::string format_summary_csv(const std::vector<SummaryRow>& rows, const SummaryLayout& layout);

// format_summary_csv written with write_file_atomic.
void write_summary_csv(const std::filesystem::path& path, const std::vector<SummaryRow>& rows,
                       const SummaryLayout& layout);

// The summary.csv of a running sweep: the rows of its finished runs, each built once (and again
// when it, or the reference it is compared with, runs again).
class SweepTable {
 public:
  // The layout: the swept keys of the runs, then of the reference runs; the tail: repeats,
  // wall_seconds_min, wall_seconds_max, error_probe_<P> for each error probe, error_<metric>,
  // reference_run, reference_kind, reference_dt, impulse_source, with a check run
  // floor_<metric>, and with a stability group the search columns (stable_dt, unstable_dt,
  // estimate_dt, stable_over_estimate, outcome, converged, trials, unstable_reason).
  // `measure_errors` false: the error columns stay empty but for reference_run and
  // reference_kind (a shard's own table: SweepErrors).
  SweepTable(const SweepPlan& plan, const std::vector<RunRecord>& records, bool measure_errors = true);

  // Run i is done: its row, and those of the runs compared with it, are built again.
  void run_done(std::size_t i);
  // Writes the table of the runs that are done to `path`.
  void write(const std::filesystem::path& path);

  SweepErrors& errors() { return errors_; }

 private:
  const SummaryRow& row(std::size_t i);

  const SweepPlan& plan_;
  const std::vector<RunRecord>& records_;
  SweepErrors errors_;
  SummaryLayout layout_;
  std::vector<std::optional<SummaryRow>> rows_;  // by run index
};

}  // namespace ricochet
