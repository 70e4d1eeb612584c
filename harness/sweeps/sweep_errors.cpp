#include "harness/sweeps/sweep_errors.hpp"

#include <exception>

#include "harness/outputs/csv_writer.hpp"

namespace ricochet {
namespace {

std::string number_text(double x) {
  std::string s;
  append_number(s, x);
  return s;
}

}  // namespace

SweepErrors::SweepErrors(const SweepPlan& plan, const std::vector<RunRecord>& records, bool measure)
    : plan_(plan), records_(records), measure_(measure), columns_(plan.size()) {}

const HistoryTable* SweepErrors::reference_history(std::size_t ref) {
  auto it = histories_.find(ref);
  if (it != histories_.end()) return &it->second;
  try {
    return &histories_.emplace(ref, read_history_csv(plan_.folder(ref) / "history.csv")).first->second;
  } catch (const std::exception&) {
    return nullptr;
  }
}

// A finished run's outputs; `history` holds its history.csv if it could be read (a reference
// run's is cached instead).
RunOutputs SweepErrors::outputs(std::size_t i, std::optional<HistoryTable>& history) {
  RunOutputs o;
  const RunRecord& rec = records_[i];
  if (rec.state != RunRecord::State::done || !rec.summary) return o;
  o.summary = &*rec.summary;
  if (plan_.run(i).is_reference) {
    o.history = reference_history(i);
  } else {
    try {
      history = read_history_csv(plan_.folder(i) / "history.csv");
      o.history = &*history;
    } catch (const std::exception&) {
      // No history: the history metrics stay empty.
    }
  }
  return o;
}

const std::optional<ReferenceMetrics>& SweepErrors::floor() {
  const SweepReference& sr = plan_.spec().reference;
  if (floor_ || sr.check.empty()) return floor_;
  std::optional<HistoryTable> h1, h2;  // unused: both are reference runs, whose histories are cached
  const RunOutputs a = outputs(plan_.index(sr.check_id()), h1), b = outputs(plan_.index(sr.id()), h2);
  if (a.summary && b.summary) floor_ = compare_with_reference(a, b, sr.error_probe);
  return floor_;
}

void SweepErrors::compute(std::size_t i) {
  Columns& c = columns_[i].emplace();
  const SweepRun& run = plan_.run(i);
  if (run.reference_id.empty()) return;
  const std::size_t ref = plan_.index(run.reference_id);
  const RunRecord& rr = records_[ref];
  c.push_back({"reference_run", run.reference_id});
  c.push_back({"reference_kind", run.reference_kind});
  if (!measure_) return;
  if (rr.state == RunRecord::State::done && rr.summary) c.push_back({"reference_dt", json_text(*rr.summary, "dt")});
  if (!records_[i].summary) return;
  std::optional<HistoryTable> own, theirs;
  const RunOutputs a = outputs(i, own), b = outputs(ref, theirs);
  const ReferenceMetrics m = compare_with_reference(a, b, run.error_probe);
  for (const auto& [name, value] : metric_values(m, run.error_probe))
    if (value) c.push_back({"error_" + name, number_text(*value)});
  if (!m.impulse_source.empty()) c.push_back({"impulse_source", m.impulse_source});
  const SweepReference& sr = plan_.spec().reference;
  if (run.reference_kind == "shared")
    if (const auto& f = floor())
      for (const auto& [name, value] : metric_values(*f, sr.error_probe))
        if (value && has_floor(name)) c.push_back({"floor_" + name, number_text(*value)});
}

const SweepErrors::Columns& SweepErrors::columns(std::size_t i) {
  if (!columns_[i]) compute(i);
  return *columns_[i];
}

std::vector<std::size_t> SweepErrors::forget(std::size_t i) {
  std::vector<std::size_t> affected;
  const SweepRun& run = plan_.run(i);
  if (!run.is_reference) return affected;
  histories_.erase(i);
  const SweepReference& sr = plan_.spec().reference;
  const bool shared = sr.present && (run.id == sr.id() || run.id == sr.check_id());
  if (shared) floor_.reset();
  for (std::size_t j = 0; j < plan_.size(); ++j)
    if (plan_.run(j).reference_id == run.id || (shared && plan_.run(j).reference_kind == "shared")) {
      columns_[j].reset();
      affected.push_back(j);
    }
  return affected;
}

}  // namespace ricochet
