#include "harness/sweeps/sweep_shard.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "harness/input/input_error.hpp"
#include "harness/outputs/atomic_file.hpp"
#include "harness/outputs/run_outputs.hpp"
#include "harness/sweeps/sweep_exec.hpp"

namespace ricochet {
namespace {

namespace fs = std::filesystem;

double unix_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

// The integer of `text` (digits only), or -1.
long whole_number(const std::string& text) {
  if (text.empty() || text.size() > 9 || text.find_first_not_of("0123456789") != std::string::npos) return -1;
  return std::strtol(text.c_str(), nullptr, 10);
}

// A shard's manifest, DIR/shards/K-of-N/shard.json, as far as the merge uses it.
struct Manifest {
  SweepShard shard;
  std::string definition;
  std::string host, program, started_at;
  Json finished_at, threads;
  double start = 0.0;
  std::optional<double> end;
  int jobs = 1;
  Json counts;
  bool running = false;  // its shard.lock is held now
};

// Whether another process holds `file`'s flock; false if the file is not there.
bool lock_held(const fs::path& file) {
  const int fd = ::open(file.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) return false;
  const bool held = flock(fd, LOCK_EX | LOCK_NB) != 0;
  ::close(fd);
  return held;
}

// Every readable manifest under DIR/shards/, by shard name; an unreadable one gets a note.
std::map<std::string, Manifest> read_manifests(const fs::path& out_dir, std::ostream& log, const std::string& who) {
  std::map<std::string, Manifest> found;
  std::error_code ec;
  if (!fs::is_directory(out_dir / "shards", ec)) return found;
  for (const auto& e : fs::directory_iterator(out_dir / "shards", ec)) {
    const fs::path file = e.path() / "shard.json";
    if (!fs::is_regular_file(file, ec)) continue;
    try {
      const Json j = read_json_file(file);
      Manifest m;
      const auto number = [&](const char* key) {
        if (!j.is_object() || !j.contains(key) || !j.at(key).is_number_integer())
          throw JsonParseError(std::string(key) + ": expected an integer");
        return j.at(key).get<long long>();
      };
      const auto text = [&](const char* key) {
        return j.is_object() && j.contains(key) && j.at(key).is_string() ? j.at(key).get<std::string>() : std::string();
      };
      const long long k = number("shard"), n = number("shards");
      if (k < 1 || k > n || n > kMaxShards) throw JsonParseError("shard, shards: not 1 <= K <= N");
      m.shard = {static_cast<int>(k), static_cast<int>(n)};
      if (e.path().filename() != m.shard.name()) throw JsonParseError("shard, shards: not those of its folder's name");
      m.definition = text("definition");
      m.host = text("host");
      m.program = text("program");
      m.started_at = text("started_at");
      m.finished_at = j.value("finished_at", Json());
      m.threads = j.value("threads", Json());
      m.counts = j.value("counts", Json());
      if (j.contains("jobs") && j.at("jobs").is_number_integer()) m.jobs = std::max(1, j.at("jobs").get<int>());
      if (j.contains("started_unix") && j.at("started_unix").is_number()) m.start = j.at("started_unix").get<double>();
      if (j.contains("finished_unix") && j.at("finished_unix").is_number()) m.end = j.at("finished_unix").get<double>();
      m.running = lock_held(e.path() / "shard.lock");
      found[m.shard.name()] = std::move(m);
    } catch (const std::exception& err) {
      log << who << ": " << file.string() << ": not a shard manifest (" << err.what() << "); left out" << std::endl;
    }
  }
  return found;
}

// The most runs at the same time on one host, from the manifests' times and --jobs: shards on one
// host that overlap in time share its cores, as --jobs runs do. A shard that did not finish
// counts until `now`.
int concurrent_jobs(const std::vector<const Manifest*>& ms, double now) {
  std::map<std::string, std::vector<std::pair<double, int>>> events;  // host -> (time, +jobs / -jobs)
  for (const Manifest* m : ms) {
    events[m->host].push_back({m->start, m->jobs});
    events[m->host].push_back({m->end.value_or(now), -m->jobs});
  }
  int most = 1;
  for (auto& [host, ev] : events) {
    // Ends before starts at the same time: a shard started as another ended did not overlap it.
    std::sort(ev.begin(), ev.end());
    int now_running = 0;
    for (const auto& [t, d] : ev) {
      now_running += d;
      most = std::max(most, now_running);
    }
  }
  return most;
}

// Locks FOLDER/run.lock without waiting and without creating it. Returns its descriptor (close it
// after reading), -1 if there is no run.lock, or -2 if another process holds it (`holder`: the
// pid written in it).
int try_run_lock(const fs::path& folder, std::string& holder) {
  const fs::path p = folder / "run.lock";
  const int fd = ::open(p.c_str(), O_RDWR | O_CLOEXEC);
  if (fd < 0) return -1;
  if (flock(fd, LOCK_EX | LOCK_NB) == 0) return fd;
  ::close(fd);
  holder = read_text(p);
  while (!holder.empty() && (holder.back() == '\n' || holder.back() == ' ')) holder.pop_back();
  if (holder.find_first_not_of("0123456789") != std::string::npos) holder.clear();
  return -2;
}

// Why a run folder's overrides.json (`found`) is not this sweep's request (`expected`, SweepPlan::
// request), in words: which part of the run's identity differs.
std::string difference(const std::string& found, const std::string& expected, const fs::path& folder) {
  Json f, e = parse_json(expected);
  try {
    f = parse_json(found);
  } catch (const JsonParseError& err) {
    return (folder / "overrides.json").string() + " is not a run's request (" + err.what() + ")";
  }
  if (!f.is_object()) return (folder / "overrides.json").string() + " is not a run's request (not a JSON object)";
  const auto at = [](const Json& j, const std::string& key) { return j.contains(key) ? j.at(key) : Json(); };
  std::vector<std::string> keys;
  for (const auto& [k, v] : e.items()) keys.push_back(k);
  for (const auto& [k, v] : f.items())
    if (!e.contains(k)) keys.push_back(k);
  for (const std::string& k : keys) {
    const Json a = at(f, k), b = at(e, k);
    if (a == b) continue;
    if (k == "base_fnv1a") return "its base case " + compact_json(at(e, "base")) + " has changed since it ran";
    if (k == "meshes_fnv1a") return "a mesh file of its case has changed since it ran (" + compact_json(a) + " then, " + compact_json(b) + " now)";
    if (k == "adapter_fnv1a")
      return "its external scheme's adapter has changed since it ran (" + compact_json(a) + " then, " + compact_json(b) + " now)";
    if (k == "program_build")
      return "another build of the program ran it (" + compact_json(a) + "; this one is " + compact_json(b) + ")";
    if (k == "repeats")
      return "it ran with --repeat " + compact_json(a) + ", this merge has --repeat " + compact_json(b) +
             " (give --merge the shards' --repeat)";
    if (k == "overrides") return "it ran with the overrides " + compact_json(a) + ", this sweep's are " + compact_json(b);
    if (k == "base") return "it ran on the base case " + compact_json(a) + ", this sweep's is " + compact_json(b);
    return k + " " + compact_json(a) + " in its overrides.json, " + compact_json(b) + " in this sweep";
  }
  return "its overrides.json differs from this sweep's request";
}

// What a merge found in one run folder.
struct Found {
  bool done = false;
  MissingRun missing;  // when not done
};

Found read_run(const SweepPlan& plan, std::size_t i, RunRecord& rec) {
  Found r;
  MissingRun& m = r.missing;
  m.index = i;
  m.id = plan.run(i).id;
  const fs::path f = plan.folder(i);
  std::error_code ec;
  if (!fs::is_directory(f, ec)) {
    m.why = "not run (no folder " + f.string() + ")";
    return r;
  }
  std::string holder;
  const int fd = try_run_lock(f, holder);
  if (fd == -2) {
    m.why = "being written by " + (holder.empty() ? std::string("another process") : "process " + holder) +
            " (it holds run.lock; on this host or another)";
    return r;
  }
  struct Close {
    int fd;
    ~Close() {
      if (fd >= 0) ::close(fd);
    }
  } closer{fd};
  if (!fs::is_regular_file(f / "overrides.json", ec)) {
    m.why = "not run (no overrides.json)";
    return r;
  }
  const std::string found = read_text(f / "overrides.json"), expected = plan.request(i);
  if (found != expected) {
    m.foreign = true;
    m.why = "from another sweep definition, not merged: " + difference(found, expected, f);
    return r;
  }
  std::string note;
  if (plan.load_finished(i, rec, note)) {
    rec.state = RunRecord::State::done;
    rec.resumed = true;
    r.done = true;
    return r;
  }
  if (const std::optional<std::string> reason = read_failure(f, m.id)) {
    rec.status = "failed";
    rec.reason = *reason;
    rec.state = RunRecord::State::done;
    rec.resumed = true;
    r.done = true;
    return r;
  }
  m.why = note.empty() ? std::string("interrupted (no ") + (plan.run(i).stability ? "stability.json" : "summary.json") +
                             " and no failure.json)"
                       : "not finished: " + note;
  return r;
}

}  // namespace

SweepShard parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  const long k = slash == std::string::npos ? -1 : whole_number(text.substr(0, slash));
  const long n = slash == std::string::npos ? -1 : whole_number(text.substr(slash + 1));
  std::string why;
  if (k < 0 || n < 0) why = "expected K/N, two integers, e.g. 2/8";
  else if (n < 1 || n > kMaxShards) why = "N must be in 1 ... " + std::to_string(kMaxShards);
  else if (k < 1 || k > n) why = "K must be in 1 ... N (shards count from 1)";
  if (!why.empty()) throw InputError("ricochet sweep: --shard: " + why + "; got '" + text + "'");
  return {static_cast<int>(k), static_cast<int>(n)};
}

std::vector<int> shard_assignment(const std::vector<SweepRun>& runs, int n) {
  std::vector<std::size_t> order(runs.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::vector<std::uint64_t> hash(runs.size());
  for (std::size_t i = 0; i < runs.size(); ++i) hash[i] = fnv1a(runs[i].id);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return hash[a] < hash[b]; });
  std::vector<int> shard(runs.size());
  for (std::size_t j = 0; j < order.size(); ++j) shard[order[j]] = static_cast<int>(j % static_cast<std::size_t>(n)) + 1;
  return shard;
}

std::vector<bool> shard_scope(const std::vector<SweepRun>& runs, const SweepShard& s) {
  const std::vector<int> shard = shard_assignment(runs, s.n);
  std::vector<bool> in(runs.size());
  for (std::size_t i = 0; i < runs.size(); ++i) in[i] = shard[i] == s.k;
  return in;
}

fs::path shard_folder(const fs::path& out_dir, const SweepShard& s) { return out_dir / "shards" / s.name(); }

int try_lock_file(const fs::path& file, bool exclusive) {
  const int fd = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("cannot write '" + file.string() + "': " + std::generic_category().message(errno));
  if (flock(fd, (exclusive ? LOCK_EX : LOCK_SH) | LOCK_NB) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

MergeOutcome merge_sweep(const SweepSpec& spec, const std::vector<SweepRun>& runs, const SweepOptions& options) {
  const std::string p = "ricochet sweep: ";
  if (options.out_dir.empty()) throw InputError(p + "no output folder");
  if (options.shard)
    throw InputError(p + "--shard and --merge exclude each other: run each shard with --shard K/N, then merge once with --merge");
  for (const auto& [given, flag] : {std::pair{options.jobs != 1, "--jobs"}, std::pair{options.threads.has_value(), "--threads"},
                                    std::pair{options.force, "--force"}})
    if (given) throw InputError(p + "--merge runs nothing: " + flag + " is for the shards (--shard K/N), not for the merge");
  if (options.repeat < 1) throw InputError(p + "--repeat: expected an integer >= 1");
  check_runs(spec, runs);
  const fs::path& out = options.out_dir;
  if (const std::string problem = output_folder_problem(out); !problem.empty())
    throw InputError(p + "--out " + out.string() + ": " + problem);
  std::error_code ec;
  if (!fs::is_directory(out, ec))
    throw InputError(p + "--merge: --out " + out.string() +
                     ": no such folder: nothing to merge (run the shards into it first: --shard K/N)");
  std::ostream& log = options.log ? *options.log : std::cerr;
  const std::string who = "sweep " + spec.name;
  const std::string started_at = utc_now();

  // Beside shards and another merge's readers, never beside a sweep without --shard or another merge.
  struct Locks {
    int fd[2] = {-1, -1};
    ~Locks() {
      for (int f : fd)
        if (f >= 0) ::close(f);
    }
  } locks;
  locks.fd[0] = try_lock_file(out / "sweep.lock", false);
  if (locks.fd[0] < 0)
    throw std::runtime_error(out.string() + ": a sweep without --shard is running in this folder; merge once it has ended");
  locks.fd[1] = try_lock_file(out / "merge.lock", true);
  if (locks.fd[1] < 0) throw std::runtime_error(out.string() + ": another merge is running in this folder");

  SweepPlan plan(spec, runs, options);
  std::vector<RunRecord> records(runs.size());
  const std::string definition = plan.definition();

  // The shards of this definition; their N names the shard of each missing run (the latest
  // started, if they differ).
  const std::map<std::string, Manifest> manifests = read_manifests(out, log, who);
  std::vector<const Manifest*> ours;
  const Manifest* latest = nullptr;
  for (const auto& [name, m] : manifests) {
    if (m.definition != definition) {
      if (!options.quiet)
        log << who << ": shards/" << name << "/shard.json: its last run was of another sweep definition (definition "
            << m.definition << ", this sweep's " << definition << ")" << std::endl;
      continue;
    }
    ours.push_back(&m);
    if (!latest || m.start > latest->start) latest = &m;
  }
  const int n_shards = latest ? latest->shard.n : 0;
  const std::vector<int> assignment = n_shards ? shard_assignment(runs, n_shards) : std::vector<int>();

  MergeOutcome outcome;
  outcome.total = runs.size();
  for (std::size_t i = 0; i < runs.size(); ++i) {
    Found f = read_run(plan, i, records[i]);
    if (f.done) continue;
    if (n_shards) {
      f.missing.shard = assignment[i];
      f.missing.shards = n_shards;
    }
    outcome.missing.push_back(std::move(f.missing));
  }
  for (const RunRecord& r : records) {
    if (r.state != RunRecord::State::done) continue;
    if (r.status == "ok") ++outcome.ok;
    else if (r.status == "diverged") ++outcome.diverged;
    else ++outcome.failed;
  }
  const std::size_t merged = outcome.ok + outcome.diverged + outcome.failed;

  SweepTable table(plan, records);
  table.write(out / "summary.csv");

  // sweep.json: as a sweep's, with what the shards' manifests tell about how the runs ran.
  SweepJsonHead h;
  h.out = out;
  h.program = fs::read_symlink("/proc/self/exe", ec);
  if (!ours.empty() && std::all_of(ours.begin(), ours.end(), [&](const Manifest* m) { return m->program == ours[0]->program; }))
    h.program = ours[0]->program;
  h.jobs = concurrent_jobs(ours, unix_now());
  h.threads = !ours.empty() && std::all_of(ours.begin(), ours.end(), [&](const Manifest* m) { return m->threads == ours[0]->threads; })
                  ? ours[0]->threads
                  : Json();
  h.repeat = options.repeat;
  h.started_at = started_at;
  for (const Manifest* m : ours)
    if (!m->started_at.empty() && m->started_at < h.started_at) h.started_at = m->started_at;
  h.finished_at = outcome.complete() ? Json(utc_now()) : Json();
  h.resumed = merged;
  Json counts = Json::object();
  counts["executed"] = 0;
  counts["ok"] = outcome.ok;
  counts["diverged"] = outcome.diverged;
  counts["failed"] = outcome.failed;
  h.counts = counts;
  Json j = sweep_json(plan, records, table, h);
  Json mj = Json::object();
  mj["definition"] = definition;
  mj["merged_at"] = utc_now();
  mj["complete"] = outcome.complete();
  Json shards = Json::array();
  for (const auto& [name, m] : manifests) {
    Json s = Json::object();
    s["folder"] = "shards/" + name;
    s["shard"] = m.shard.k;
    s["shards"] = m.shard.n;
    s["definition_matches"] = m.definition == definition;
    s["host"] = m.host;
    s["jobs"] = m.jobs;
    s["started_at"] = m.started_at;
    s["finished_at"] = m.finished_at;
    s["running"] = m.running;
    s["counts"] = m.counts;
    shards.push_back(s);
  }
  mj["shards"] = shards;
  Json missing = Json::array(), failed = Json::array();
  for (const MissingRun& m : outcome.missing) {
    Json e = Json::object();
    e["id"] = m.id;
    e["shard"] = m.shard ? Json(m.shard) : Json();
    e["shards"] = m.shards ? Json(m.shards) : Json();
    e["foreign"] = m.foreign;
    e["why"] = m.why;
    missing.push_back(e);
  }
  for (std::size_t i = 0; i < runs.size(); ++i)
    if (records[i].state == RunRecord::State::done && records[i].status == "failed") {
      Json e = Json::object();
      e["id"] = runs[i].id;
      e["reason"] = records[i].reason;
      failed.push_back(e);
    }
  mj["missing"] = missing;
  mj["failed"] = failed;
  j["merge"] = mj;
  write_file_atomic(out / "sweep.json", dump_json(j));

  // What is missing or failed, even with --quiet: it is the merge's answer.
  if (!options.quiet) {
    log << who << ": merged " << merged << " of " << runs.size() << " runs (" << outcome.ok << " ok, " << outcome.diverged
        << " diverged, " << outcome.failed << " failed)";
    if (!outcome.complete()) log << ", " << outcome.missing.size() << " missing";
    log << " -> " << (out / "summary.csv").string() << std::endl;
  }
  constexpr std::size_t kListed = 20;
  std::size_t listed = 0;
  for (const Json& e : failed)
    if (listed++ < kListed)
      log << who << ": failed: " << e.at("id").get<std::string>() << ": " << e.at("reason").get<std::string>() << std::endl;
  if (failed.size() > kListed) log << who << ": ... and " << failed.size() - kListed << " more failed (sweep.json: merge.failed)" << std::endl;
  listed = 0;
  for (const MissingRun& m : outcome.missing)
    if (listed++ < kListed)
      log << who << ": missing: " << m.id
          << (m.shard ? " (shard " + std::to_string(m.shard) + " of " + std::to_string(m.shards) + ")" : std::string()) << ": "
          << m.why << std::endl;
  if (outcome.missing.size() > kListed)
    log << who << ": ... and " << outcome.missing.size() - kListed << " more missing (sweep.json: merge.missing)" << std::endl;
  if (outcome.complete()) return outcome;

  // Per shard, what became of it and the command that completes it.
  if (n_shards) {
    std::map<int, std::size_t> per_shard;
    for (const MissingRun& m : outcome.missing) ++per_shard[m.shard];
    std::size_t shards_listed = 0;
    for (const auto& [k, count] : per_shard) {
      if (shards_listed++ == kListed) {
        log << who << ": ... and " << per_shard.size() - kListed << " more shards with runs missing (sweep.json: merge.missing)"
            << std::endl;
        break;
      }
      const SweepShard s{k, n_shards};
      const auto it = manifests.find(s.name());
      std::string state;
      if (it == manifests.end()) state = "it has not run (no shards/" + s.name() + "/shard.json)";
      else if (it->second.definition != definition) state = "its last run was of another sweep definition";
      else if (it->second.running) state = "it is running (host " + it->second.host + ", since " + it->second.started_at + ")";
      else if (it->second.finished_at.is_null())
        state = "it did not finish (started " + it->second.started_at + " on host " + it->second.host + ")";
      else state = "its last run finished at " + it->second.finished_at.get<std::string>();
      log << who << ": " << s.text() << ": " << count << " run(s) missing; " << state;
      if (it == manifests.end() || !it->second.running)
        log << "; run it: ricochet sweep " << spec.file << " --out " << out.string() << " --shard " << k << "/" << n_shards
            << (options.repeat > 1 ? " --repeat " + std::to_string(options.repeat) : std::string());
      log << std::endl;
    }
  }
  log << who << ": incomplete: " << outcome.missing.size() << " of " << runs.size()
      << " runs missing; merge again once they have run (exit " << kExitIncomplete << ")" << std::endl;
  return outcome;
}

}  // namespace ricochet
