#include "harness/sweeps/sweep_plan.hpp"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "harness/external/external_run.hpp"
#include "harness/input/case_spec.hpp"
#include "harness/input/input_error.hpp"
#include "harness/sweeps/run_identity.hpp"
#include "harness/sweeps/sweep.hpp"

namespace ricochet {
namespace fs = std::filesystem;

std::uint64_t fnv1a(std::string_view s) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

std::string fnv1a_hex(std::string_view s) {
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(fnv1a(s)));
  return buf;
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

double json_number(const Json& summary, std::string_view key, double fallback) {
  const auto v = summary.find(key);
  return v != summary.end() && v->is_number() ? v->get<double>() : fallback;
}

std::string json_text(const Json& summary, std::string_view key) {
  const auto v = summary.find(key);
  if (v == summary.end()) return {};
  if (v->is_string()) return v->get<std::string>();
  return v->is_number() ? compact_json(*v) : std::string();
}

namespace {

std::string shown(const Json& v) {
  const std::string t = compact_json(v);
  return t.size() > 40 ? t.substr(0, 40) + "..." : t;
}

}  // namespace

std::string summary_problem(const Json& s) {
  if (!s.is_object()) return "not a JSON object";
  const auto at = [&](const char* key) { return s.contains(key) ? s.at(key) : Json(); };
  const Json status = at("status");
  if (!status.is_string() || (status != "ok" && status != "diverged"))
    return "status: expected \"ok\" or \"diverged\", got " + (s.contains("status") ? shown(status) : "nothing");
  const Json d = at("diverged");
  if (status == "diverged" && !(d.is_object() && d.contains("reason") && d.at("reason").is_string()))
    return "diverged: expected an object with a string \"reason\" (status \"diverged\"), got " + shown(d);
  if (status == "ok" && !d.is_null()) return "diverged: expected null (status \"ok\"), got " + shown(d);
  for (const char* key : {"wall_seconds", "cpu_seconds"}) {
    const Json v = at(key);
    if (!v.is_number() || !std::isfinite(v.get<double>()) || v.get<double>() < 0.0)
      return std::string(key) + ": expected a number >= 0, got " + shown(v);
  }
  for (const char* key : {"steps", "elements"}) {
    const Json v = at(key);
    if (!v.is_number_integer() || v.get<long long>() < 0)
      return std::string(key) + ": expected an integer >= 0, got " + shown(v);
  }
  const Json dt = at("dt");
  if (!dt.is_number() || !std::isfinite(dt.get<double>()) || dt.get<double>() <= 0.0)
    return "dt: expected a number > 0, got " + shown(dt);
  return {};
}

std::string stability_problem(const Json& s) {
  if (!s.is_object()) return "not a JSON object";
  const auto at = [&](const char* key) { return s.contains(key) ? s.at(key) : Json(); };
  const Json outcome = at("outcome");
  if (!outcome.is_string() || (outcome != "bracketed" && outcome != "no_unstable_up_to_cap" &&
                               outcome != "no_stable_down_to_floor" && outcome != "run_limit"))
    return "outcome: expected \"bracketed\", \"no_unstable_up_to_cap\", \"no_stable_down_to_floor\" or "
           "\"run_limit\", got " + (s.contains("outcome") ? shown(outcome) : "nothing");
  if (!at("converged").is_boolean()) return "converged: expected true or false, got " + shown(at("converged"));
  const Json e = at("estimate");
  if (!e.is_number() || !std::isfinite(e.get<double>()) || e.get<double>() <= 0.0)
    return "estimate: expected a number > 0, got " + shown(e);
  for (const char* key : {"largest_stable_dt", "smallest_unstable_dt"}) {
    const Json v = at(key);
    if (!v.is_null() && (!v.is_number() || !std::isfinite(v.get<double>()) || v.get<double>() <= 0.0))
      return std::string(key) + ": expected null or a number > 0, got " + shown(v);
  }
  if (!at("runs").is_number_integer() || at("runs").get<long long>() < 0)
    return "runs: expected an integer >= 0, got " + shown(at("runs"));
  if (!at("trials").is_array()) return "trials: expected an array, got " + shown(at("trials"));
  return {};
}

void set_stability_finished(RunRecord& record, Json report) {
  record.status = "ok";
  record.reason.clear();
  record.summary = std::move(report);
  record.wall.clear();
  record.cpu.clear();
}

void set_finished(RunRecord& record, Json summary) {
  record.status = json_text(summary, "status");
  if (record.status != "ok" && record.status != "diverged") record.status = "diverged";
  record.reason.clear();
  if (const auto d = summary.find("diverged"); d != summary.end() && d->is_object())
    record.reason = json_text(*d, "reason");
  record.summary = std::move(summary);
}

SweepPlan::SweepPlan(const SweepSpec& spec, const std::vector<SweepRun>& runs, const SweepOptions& options)
    : spec_(spec), runs_(runs), options_(options) {
  for (std::size_t i = 0; i < runs_.size(); ++i) index_[runs_[i].id] = i;
  for (const SweepRun& r : runs_)
    if (!base_hash_.count(r.base)) base_hash_[r.base] = fnv1a_hex(read_text(r.base));
  build_id_ = program_build_id(options_.executable);
  // The mesh files of each run's resolved case (its overrides may pick or replace them), each
  // file hashed once. A case that cannot be read (check_runs reports it) reads no mesh here.
  std::map<fs::path, Json> hashes;
  mesh_hashes_.resize(runs_.size(), Json::object());
  adapter_hashes_.resize(runs_.size(), Json());
  for (std::size_t i = 0; i < runs_.size(); ++i) {
    std::vector<fs::path> files;
    try {
      const CaseSpec spec = read_case(runs_[i].base.string(), runs_[i].set_args());
      files = mesh_files(spec);
      // An external scheme's run is also what its adapter is: an edited adapter reruns it.
      if (spec.scheme == Scheme::external) {
        adapter_hashes_[i] = Json::object();
        for (const std::string& arg : adapter_command(spec)) {
          std::error_code ec;
          if (!fs::is_regular_file(arg, ec)) continue;
          auto it = hashes.find(arg);
          if (it == hashes.end()) {
            const std::string h = file_fnv1a(arg);
            it = hashes.emplace(arg, h.empty() ? Json() : Json(h)).first;
          }
          adapter_hashes_[i][arg] = it->second;
        }
      }
    } catch (const InputError&) {
    }
    for (const fs::path& f : files) {
      auto it = hashes.find(f);
      if (it == hashes.end()) {
        const std::string h = file_fnv1a(f);
        it = hashes.emplace(f, h.empty() ? Json() : Json(h)).first;
      }
      mesh_hashes_[i][f.string()] = it->second;
    }
  }
}

fs::path SweepPlan::folder(std::size_t i) const { return options_.out_dir / runs_[i].folder(); }

int SweepPlan::repeats(std::size_t i) const {
  // A search's trials are its repeats of a kind; timing it K times would only cost K searches.
  return runs_[i].is_reference || runs_[i].stability ? 1 : options_.repeat;
}

fs::path SweepPlan::repeat_dir(std::size_t i, int k) const {
  return repeats(i) == 1 ? folder(i) : folder(i) / ("repeat-" + std::to_string(k));
}

std::string SweepPlan::request(std::size_t i) const {
  const SweepRun& run = runs_[i];
  Json j = Json::object();
  j["run_id"] = run.id;
  j["base"] = run.base.string();
  j["base_fnv1a"] = base_hash_.at(run.base);
  Json o = Json::array();
  for (const SweepValue& v : run.overrides)
    if (v.key != "threads") o.push_back(v.set_arg());
  j["overrides"] = o;
  j["repeats"] = repeats(i);
  j["meshes_fnv1a"] = mesh_hashes_[i];
  j["program_build"] = build_id_;
  if (!adapter_hashes_[i].is_null()) j["adapter_fnv1a"] = adapter_hashes_[i];
  if (run.stability) {
    j["kind"] = "stability";
    Json opt = Json::array();
    for (const SweepStabilityOption& o : run.stability_options) opt.push_back(o.flag + "=" + o.text);
    j["stability_options"] = opt;
  }
  return dump_json(j);
}

std::optional<int> SweepPlan::threads(std::size_t i) const {
  if (options_.threads) return options_.threads;
  for (const SweepValue& v : runs_[i].overrides)
    if (v.key == "threads") return std::nullopt;
  return 1;
}

std::size_t SweepPlan::scope_size() const {
  std::size_t n = 0;
  for (std::size_t i = 0; i < runs_.size(); ++i) n += in_scope(i);
  return n;
}

std::vector<std::size_t> SweepPlan::queue(const std::vector<RunRecord>& records) const {
  std::vector<std::size_t> queue;
  for (int pass = 0; pass < 2; ++pass)
    for (std::size_t i = 0; i < runs_.size(); ++i)
      if (in_scope(i) && records[i].state == RunRecord::State::pending && runs_[i].is_reference == (pass == 0))
        queue.push_back(i);
  return queue;
}

bool SweepPlan::startable(std::size_t i, const std::vector<RunRecord>& records) const {
  const std::string& ref = runs_[i].reference_id;
  if (runs_[i].is_reference || ref.empty()) return true;
  const std::size_t r = index_.at(ref);
  return !in_scope(r) || records[r].state == RunRecord::State::done;
}

std::string SweepPlan::definition() const {
  std::string all;
  for (std::size_t i = 0; i < runs_.size(); ++i) all += request(i);
  return fnv1a_hex(all);
}

bool SweepPlan::load_finished(std::size_t i, RunRecord& record, std::string& note) const {
  note.clear();
  const fs::path f = folder(i);
  if (read_text(f / "overrides.json") != request(i)) return false;
  if (runs_[i].stability) {
    const fs::path p = f / "stability.json";
    if (!fs::is_regular_file(p)) return false;
    try {
      Json s = read_json_file(p);
      if (const std::string problem = stability_problem(s); !problem.empty()) {
        note = p.string() + ": " + problem;
        return false;
      }
      set_stability_finished(record, std::move(s));
      return true;
    } catch (const JsonParseError& e) {
      note = p.string() + ": " + e.what();
      return false;
    }
  }
  if (!fs::is_regular_file(f / "summary.json")) return false;
  std::vector<double> wall, cpu;
  std::vector<fs::path> files;
  for (int k = 1; k <= repeats(i); ++k) files.push_back(repeat_dir(i, k) / "summary.json");
  if (repeats(i) > 1) files.push_back(f / "summary.json");
  Json last;
  for (const fs::path& p : files) {
    try {
      Json s = read_json_file(p);
      if (const std::string problem = summary_problem(s); !problem.empty()) {
        note = p.string() + ": " + problem;
        return false;
      }
      if (p.parent_path() != f || repeats(i) == 1) {
        wall.push_back(s.at("wall_seconds").get<double>());
        cpu.push_back(s.at("cpu_seconds").get<double>());
      }
      last = std::move(s);
    } catch (const JsonParseError& e) {
      note = p.string() + ": " + e.what();
      return false;
    }
  }
  set_finished(record, std::move(last));
  record.wall = std::move(wall);
  record.cpu = std::move(cpu);
  return true;
}

void check_runs(const SweepSpec& spec, const std::vector<SweepRun>& runs) {
  std::map<std::string, const SweepGroup*> groups;
  for (const SweepGroup& g : spec.groups) groups[g.name] = &g;
  for (const SweepRun& r : runs) {
    CaseSpec c;
    try {
      c = read_case(r.base.string(), r.set_args());
    } catch (const InputError& e) {
      // Point at the sweep-file value that the case rejects, when the message names it.
      const std::string msg = e.what();
      std::string where = spec.file;
      if (const auto at = msg.find(": --set "); at != std::string::npos) {
        const std::size_t from = at + 8;
        const std::string key = msg.substr(from, msg.find(':', from) - from);
        for (const SweepValue& v : r.overrides)
          if (v.key == key) where = v.where;
      }
      throw InputError(where + ": run " + r.id + ": " + msg);
    }
    if (!r.error_probe.empty()) {
      std::string names;
      bool found = false;
      for (const ProbeSpec& p : c.probes) {
        names += (names.empty() ? "" : ", ") + p.name;
        found = found || p.name == r.error_probe;
      }
      if (!found) {
        const SweepGroup* g = groups.count(r.group) ? groups.at(r.group) : nullptr;
        const bool shared = r.reference_kind == "shared" || (spec.reference.present && r.id == spec.reference.id());
        const std::string where = shared ? spec.reference.where : g ? g->where : spec.file;
        throw InputError(where + ".error_probe: the case of run " + r.id + " has no probe \"" + r.error_probe +
                         "\"; its probes: " + (names.empty() ? "none" : names));
      }
    }
  }
}

}  // namespace ricochet
