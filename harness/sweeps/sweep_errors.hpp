// The error columns of a sweep's runs (docs/sweeps.md, "Accuracy against cost"): each run
// compared with its reference run by compare_with_reference (harness/sweeps/reference_errors.hpp), and
// the shared reference's floor (its check run compared with it). Computed from the runs'
// summaries and history.csv files when first asked for, cached, and computed again when a
// reference runs again.
#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "harness/sweeps/reference_errors.hpp"
#include "harness/sweeps/sweep_plan.hpp"

namespace ricochet {

class SweepErrors {
 public:
  using Columns = std::vector<std::pair<std::string, std::string>>;  // column -> value

  // `measure` false: no errors are measured (a shard's own table, whose references may be
  // another shard's runs; the merge measures them), only reference_run and reference_kind.
  SweepErrors(const SweepPlan& plan, const std::vector<RunRecord>& records, bool measure = true);

  // Run i's error columns: reference_run, reference_kind, reference_dt (once the reference is
  // done), error_<metric> for each metric with a value, impulse_source, and for runs compared
  // with the shared reference floor_<metric>; empty for a run without a reference.
  const Columns& columns(std::size_t i);

  // The shared reference's uncertainty: its check run's errors against it, or nothing while
  // either has not finished (or the sweep has no check run).
  const std::optional<ReferenceMetrics>& floor();

  // Run i ran: when it is a reference, forgets its history and the errors of the runs compared
  // with it (a rerun shared reference or check run: every floor too). Returns those runs.
  std::vector<std::size_t> forget(std::size_t i);

 private:
  const HistoryTable* reference_history(std::size_t ref);
  RunOutputs outputs(std::size_t i, std::optional<HistoryTable>& history);
  void compute(std::size_t i);

  const SweepPlan& plan_;
  const std::vector<RunRecord>& records_;
  bool measure_ = true;
  std::vector<std::optional<Columns>> columns_;    // by run index
  std::map<std::size_t, HistoryTable> histories_;  // reference histories, by run index
  std::optional<ReferenceMetrics> floor_;          // the shared reference's check against it
};

}  // namespace ricochet
