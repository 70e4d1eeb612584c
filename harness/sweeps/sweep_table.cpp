#include "harness/sweeps/sweep_table.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "harness/outputs/atomic_file.hpp"
#include "harness/outputs/csv_writer.hpp"

namespace ricochet {
namespace {

namespace fs = std::filesystem;

std::string number_text(double x) {
  std::string s;
  append_number(s, x);
  return s;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  if (n == 0) return std::nan("");
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

void flatten_into(const Json& v, const std::string& name, std::vector<FlatField>& out) {
  if (v.is_object() && !v.empty()) {
    for (const auto& [k, m] : v.items()) flatten_into(m, name.empty() ? k : name + "." + k, out);
  } else if (v.is_null() || v.is_object()) {
    out.push_back({name, "", true});
  } else if (v.is_string()) {
    out.push_back({name, v.get<std::string>(), false});
  } else {
    out.push_back({name, compact_json(v), false});
  }
}

// The keys of a stability.json that a run's summary.json also has, with the same meaning: a
// search's row shares their columns with the runs (a gate's `where = { scheme = ... }` selects
// both); the rest of the report is in the search's own columns (stability_columns).
constexpr const char* kSharedStabilityKeys[] = {"ricochet_version", "case", "case_file", "overrides", "scheme",
                                                "mesh", "element", "nodes", "elements", "critical_dt",
                                                "penalty_critical_dt", "end_time"};

// The columns of a finished search, from its stability.json (stability_problem checked it).
std::vector<std::pair<std::string, std::string>> stability_columns(const Json& s) {
  // A missing bound is null, as stability_problem reads it.
  auto at = [&](const char* key) { return s.contains(key) ? s.at(key) : Json(); };
  auto text = [&](const char* key) { return at(key).is_null() ? std::string() : compact_json(at(key)); };
  std::vector<std::pair<std::string, std::string>> out;
  out.push_back({"stable_dt", text("largest_stable_dt")});
  out.push_back({"unstable_dt", text("smallest_unstable_dt")});
  out.push_back({"estimate_dt", text("estimate")});
  // lo / estimate, computed here rather than read: the report's key is optional to the table.
  const Json lo = at("largest_stable_dt");
  out.push_back({"stable_over_estimate", lo.is_null() ? std::string()
                                                      : number_text(lo.get<double>() / s.at("estimate").get<double>())});
  out.push_back({"outcome", s.at("outcome").get<std::string>()});
  out.push_back({"converged", s.at("converged").get<bool>() ? "true" : "false"});
  out.push_back({"trials", std::to_string(s.at("trials").size())});
  // What stopped the search from above: the reason of the smallest unstable trial (the
  // divergence, or the energy rule), empty when no trial was unstable.
  std::string reason;
  if (const Json hi = at("smallest_unstable_dt"); !hi.is_null())
    for (const Json& t : s.at("trials"))
      if (t.is_object() && t.contains("dt") && t.at("dt") == hi && t.contains("reason") && t.at("reason").is_string())
        reason = t.at("reason").get<std::string>();
  out.push_back({"unstable_reason", reason});
  return out;
}

}  // namespace

std::vector<FlatField> flatten_summary(const Json& summary) {
  std::vector<FlatField> out;
  if (!summary.is_object()) return out;
  for (const auto& [k, v] : summary.items()) {
    if (k == "status") continue;
    flatten_into(v, k, out);
  }
  return out;
}

std::string format_summary_csv(const std::vector<SummaryRow>& rows, const SummaryLayout& layout) {
  // Head and swept columns.
  std::vector<std::string> head = {"run_id", "group", "kind", "status", "reason"};
  std::vector<std::string> swept = layout.swept;
  for (const SummaryRow& r : rows)
    for (const auto& [k, v] : r.swept)
      if (std::find(swept.begin(), swept.end(), k) == swept.end()) swept.push_back(k);

  // Summary columns: union in first-seen order; a null is a placeholder that a later nested key
  // under the same name replaces, and new keys go next to their siblings.
  std::vector<std::string> cols;
  std::unordered_set<std::string> known, placeholders;
  auto has_child = [&](const std::string& name) {
    return std::any_of(cols.begin(), cols.end(), [&](const std::string& c) { return c.rfind(name + ".", 0) == 0; });
  };
  auto add = [&](const FlatField& f) {
    if (known.count(f.name)) return;
    if (f.null) {
      if (has_child(f.name)) return;
      cols.push_back(f.name);
      known.insert(f.name);
      placeholders.insert(f.name);
      return;
    }
    known.insert(f.name);
    for (auto pos = f.name.rfind('.'); pos != std::string::npos && pos > 0; pos = f.name.rfind('.', pos - 1)) {
      const std::string prefix = f.name.substr(0, pos);
      auto it = std::find(cols.begin(), cols.end(), prefix);
      if (it != cols.end() && placeholders.count(prefix)) {
        *it = f.name;
        placeholders.erase(prefix);
        known.erase(prefix);
        return;
      }
      std::ptrdiff_t last = -1;
      for (std::size_t c = 0; c < cols.size(); ++c)
        if (cols[c].rfind(prefix + ".", 0) == 0) last = static_cast<std::ptrdiff_t>(c);
      if (last >= 0) {
        cols.insert(cols.begin() + last + 1, f.name);
        return;
      }
    }
    cols.push_back(f.name);
  };
  for (const SummaryRow& r : rows)
    for (const FlatField& f : r.summary) add(f);

  std::set<std::string> taken(head.begin(), head.end());
  taken.insert(swept.begin(), swept.end());
  taken.insert(layout.tail.begin(), layout.tail.end());
  std::vector<std::string> header = head;
  header.insert(header.end(), swept.begin(), swept.end());
  for (const auto& c : cols) header.push_back(taken.count(c) ? "summary." + c : c);
  header.insert(header.end(), layout.tail.begin(), layout.tail.end());

  std::unordered_map<std::string, std::size_t> position;
  for (std::size_t c = 0; c < cols.size(); ++c) position.emplace(cols[c], c);

  std::string out;
  for (std::size_t c = 0; c < header.size(); ++c) out += (c ? "," : "") + csv_field(header[c]);
  out += '\n';
  for (const SummaryRow& r : rows) {
    std::vector<std::string> cells = {r.run_id, r.group, r.kind, r.status, r.reason};
    for (const auto& k : swept) {
      std::string v;
      for (const auto& [key, val] : r.swept)
        if (key == k) v = val;
      cells.push_back(v);
    }
    const std::size_t first = cells.size();
    cells.resize(first + cols.size());
    for (const FlatField& f : r.summary)
      if (const auto it = position.find(f.name); it != position.end()) cells[first + it->second] = f.value;
    for (const auto& t : layout.tail) {
      std::string v;
      for (const auto& [key, val] : r.extra)
        if (key == t) v = val;
      cells.push_back(v);
    }
    for (std::size_t c = 0; c < cells.size(); ++c) {
      if (c) out += ',';
      out += csv_field(cells[c]);
    }
    out += '\n';
  }
  return out;
}

void write_summary_csv(const fs::path& path, const std::vector<SummaryRow>& rows, const SummaryLayout& layout) {
  write_file_atomic(path, format_summary_csv(rows, layout));
}

SweepTable::SweepTable(const SweepPlan& plan, const std::vector<RunRecord>& records, bool measure_errors)
    : plan_(plan), records_(records), errors_(plan, records, measure_errors), rows_(plan.size()) {
  const std::vector<SweepRun>& runs = plan.runs();
  std::set<std::string> seen;
  for (int pass = 0; pass < 2; ++pass)
    for (const SweepRun& r : runs)
      if (r.is_reference == (pass == 1))
        for (const SweepValue& v : r.overrides)
          if (seen.insert(v.key).second) layout_.swept.push_back(v.key);
  std::vector<std::string>& tail = layout_.tail;
  tail = {"repeats", "wall_seconds_min", "wall_seconds_max"};
  std::vector<std::string> probes;
  for (const SweepRun& r : runs)
    if (!r.reference_id.empty() && std::find(probes.begin(), probes.end(), r.error_probe) == probes.end())
      probes.push_back(r.error_probe);
  if (probes.empty()) probes.push_back("P");
  for (const auto& p : probes) tail.push_back("error_probe_" + p);
  for (const auto& m : metric_names(probes.front()))
    if (m.rfind("probe_", 0) != 0) tail.push_back("error_" + m);
  tail.insert(tail.end(), {"reference_run", "reference_kind", "reference_dt", "impulse_source"});
  const SweepReference& sr = plan.spec().reference;
  if (!sr.check.empty())
    for (const auto& m : metric_names(sr.error_probe))
      if (has_floor(m)) tail.push_back("floor_" + m);
  // Only a sweep with stability groups has their columns: the table of any other sweep stays
  // as it was.
  if (std::any_of(runs.begin(), runs.end(), [](const SweepRun& r) { return r.stability; }))
    tail.insert(tail.end(), {"stable_dt", "unstable_dt", "estimate_dt", "stable_over_estimate", "outcome", "converged",
                             "trials", "unstable_reason"});
}

void SweepTable::run_done(std::size_t i) {
  rows_[i].reset();
  for (const std::size_t j : errors_.forget(i)) rows_[j].reset();
}

const SummaryRow& SweepTable::row(std::size_t i) {
  if (rows_[i]) return *rows_[i];
  const SweepRun& run = plan_.run(i);
  const RunRecord& rec = records_[i];
  SummaryRow r;
  r.run_id = run.id;
  r.group = run.group;
  r.kind = run.is_reference ? "reference" : run.stability ? "stability" : "run";
  r.status = rec.status;
  r.reason = rec.reason;
  for (const SweepValue& v : run.overrides) r.swept.push_back({v.key, v.display});
  if (run.stability) {
    if (rec.summary) {
      for (const char* key : kSharedStabilityKeys)
        if (const auto it = rec.summary->find(key); it != rec.summary->end()) {
          Json one = Json::object();
          one[key] = *it;
          for (FlatField& f : flatten_summary(one)) r.summary.push_back(std::move(f));
        }
      r.extra = stability_columns(*rec.summary);
    }
    rows_[i] = std::move(r);
    return *rows_[i];
  }
  if (rec.summary) {
    r.summary = flatten_summary(*rec.summary);
    const std::size_t k = rec.wall.size();
    if (k > 0) {
      // Repeated runs: the median timings, and the spread of the wall time.
      const double wall = median(rec.wall), cpu = median(rec.cpu);
      if (k > 1) {
        const double nan = std::nan("");
        const double cells = json_number(*rec.summary, "elements", nan), steps = json_number(*rec.summary, "steps", nan);
        for (FlatField& f : r.summary) {
          if (f.name == "wall_seconds") f = {f.name, number_text(wall), false};
          else if (f.name == "cpu_seconds") f = {f.name, number_text(cpu), false};
          else if (f.name == "element_steps_per_second" && wall > 0.0 && std::isfinite(cells * steps))
            f = {f.name, number_text(cells * steps / wall), false};
        }
      }
      r.extra.push_back({"repeats", std::to_string(k)});
      r.extra.push_back({"wall_seconds_min", number_text(*std::min_element(rec.wall.begin(), rec.wall.end()))});
      r.extra.push_back({"wall_seconds_max", number_text(*std::max_element(rec.wall.begin(), rec.wall.end()))});
    }
  }
  const SweepErrors::Columns& e = errors_.columns(i);
  r.extra.insert(r.extra.end(), e.begin(), e.end());
  rows_[i] = std::move(r);
  return *rows_[i];
}

void SweepTable::write(const fs::path& path) {
  std::vector<SummaryRow> rows;
  for (std::size_t i = 0; i < plan_.size(); ++i)
    if (records_[i].state == RunRecord::State::done) rows.push_back(row(i));
  write_summary_csv(path, rows, layout_);
}

}  // namespace ricochet
