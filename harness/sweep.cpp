#include "harness/sweep.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iterator>
#include <limits>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <thread>
#include <unordered_map>
#include <unordered_set>

#include "harness/atomic_file.hpp"
#include "harness/case_spec.hpp"
#include "harness/csv_reader.hpp"
#include "harness/csv_writer.hpp"
#include "harness/gates.hpp"
#include "harness/input_error.hpp"
#include "harness/json_io.hpp"

extern char** environ;

namespace ricochet {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr const char* kUsage =
    "usage: ricochet sweep SWEEP.toml [--out DIR] [--jobs N] [--repeat K] [--check GATES.toml] [--force] [--quiet]\n"
    "  sweep     run every case of a sweep file; writes DIR/summary.csv, DIR/sweep.json, DIR/runs/\n"
    "  --out     output folder (default: results/<sweep name>)\n"
    "  --jobs    runs at the same time (default 1: one at a time, for clean timings)\n"
    "  --repeat  run each case K times; summary.csv gets the median and the spread of the timings\n"
    "  --check   then check the gates of GATES.toml on DIR/summary.csv (docs/gates.md); exit 4 if one fails\n"
    "  --force   rerun the runs that an earlier sweep finished\n"
    "  --quiet   no progress lines\n"
    "  --help    this text\n"
    "  exit status: 0 done (diverged and failed runs are results), 4 a gate failed, 2 bad input, 1 other error\n";

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

std::string number_text(double x) {
  std::string s;
  append_number(s, x);
  return s;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) return {};
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string fnv1a(const std::string& s) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
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

// ---- the run's request (overrides.json): what a finished run must match to be reused ----

std::string request_text(const SweepRun& run, int repeat, const std::string& base_hash) {
  Json j = Json::object();
  j["run_id"] = run.id;
  j["base"] = run.base.string();
  j["base_fnv1a"] = base_hash;
  Json o = Json::array();
  for (const auto& a : run.set_args()) o.push_back(a);
  j["overrides"] = o;
  j["repeats"] = repeat;
  return dump_json(j);
}

// ---- subprocesses ----

// While a sweep runs, SIGINT, SIGTERM and SIGHUP are passed on to the running children before
// the sweep itself ends by the same signal, so that no orphaned run keeps writing into the
// folder. (A signal the process ignored stays ignored.)
constexpr int kMaxJobs = 1024;
pid_t g_children[kMaxJobs];
volatile sig_atomic_t g_child_count = 0;

extern "C" void forward_signal(int sig) {
  for (sig_atomic_t i = 0; i < g_child_count; ++i)
    if (g_children[i] > 0) kill(g_children[i], sig);
  signal(sig, SIG_DFL);
  raise(sig);
}

class SignalForwarding {
 public:
  SignalForwarding() {
    for (std::size_t i = 0; i < std::size(kSignals); ++i) {
      struct sigaction now {};
      sigaction(kSignals[i], nullptr, &old_[i]);
      if (old_[i].sa_handler == SIG_IGN) continue;
      now.sa_handler = forward_signal;
      sigemptyset(&now.sa_mask);
      sigaction(kSignals[i], &now, nullptr);
    }
  }
  ~SignalForwarding() {
    for (std::size_t i = 0; i < std::size(kSignals); ++i) sigaction(kSignals[i], &old_[i], nullptr);
    g_child_count = 0;
  }
  SignalForwarding(const SignalForwarding&) = delete;
  SignalForwarding& operator=(const SignalForwarding&) = delete;

  // The children to pass signals on to.
  static void set(const std::vector<pid_t>& pids) {
    g_child_count = 0;
    const std::size_t n = std::min<std::size_t>(pids.size(), kMaxJobs);
    for (std::size_t i = 0; i < n; ++i) g_children[i] = pids[i];
    g_child_count = static_cast<sig_atomic_t>(n);
  }

 private:
  static constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP};
  struct sigaction old_[3] {};
};

struct Exit {
  bool signaled = false;
  int code = 0;  // exit status or signal number
};

pid_t spawn_run(const fs::path& exe, const SweepRun& run, const fs::path& out) {
  std::vector<std::string> args = {exe.string(), "run", run.base.string()};
  for (const auto& a : run.set_args()) {
    args.push_back("--set");
    args.push_back(a);
  }
  args.insert(args.end(), {"--out", out.string(), "--quiet"});
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);

  const std::string err = (out / "stderr.txt").string();
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, exe.c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0)
    throw std::runtime_error("cannot start '" + exe.string() + "': " + std::generic_category().message(rc));
  return pid;
}

Exit decode(int status) {
  if (WIFSIGNALED(status)) return {true, WTERMSIG(status)};
  return {false, WIFEXITED(status) ? WEXITSTATUS(status) : -1};
}

std::string first_line(const fs::path& p) {
  std::ifstream in(p);
  for (std::string line; std::getline(in, line);) {
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    if (!line.empty()) return line.size() > 300 ? line.substr(0, 300) + "..." : line;
  }
  return {};
}

// ---- per-run state ----

struct Record {
  enum class State { pending, active, done } state = State::pending;
  bool resumed = false;
  std::string status, reason;         // ok / diverged / failed
  std::optional<Json> summary;        // the run's summary.json (the last repeat's)
  std::vector<double> wall, cpu;      // per repeat, from the summaries [s]
  bool errors_done = false;
  std::vector<std::pair<std::string, std::string>> errors;  // error columns, cached
  std::optional<SummaryRow> row;                             // its summary.csv row, cached
};

double json_number(const Json& s, std::string_view key, double fallback = std::nan("")) {
  const auto v = s.find(key);
  return v != s.end() && v->is_number() ? v->get<double>() : fallback;
}

// A string member as it is, a number as summary.csv shows it; empty otherwise.
std::string json_text(const Json& s, std::string_view key) {
  const auto v = s.find(key);
  if (v == s.end()) return {};
  if (v->is_string()) return v->get<std::string>();
  return v->is_number() ? compact_json(*v) : std::string();
}

// Fills status/reason from a finished run's summary.json.
void set_finished(Record& rec, Json summary) {
  rec.status = json_text(summary, "status");
  if (rec.status != "ok" && rec.status != "diverged") rec.status = "diverged";
  rec.reason.clear();
  if (const auto d = summary.find("diverged"); d != summary.end() && d->is_object()) rec.reason = json_text(*d, "reason");
  rec.summary = std::move(summary);
}

// Outputs of repeat k of a run (k from 1).
fs::path repeat_dir(const fs::path& folder, int repeat, int k) {
  return repeat == 1 ? folder : folder / ("repeat-" + std::to_string(k));
}

// A run finished by an earlier invocation, if its folder matches the request.
bool load_finished(const fs::path& folder, const std::string& request, int repeat, Record& rec) {
  if (read_text(folder / "overrides.json") != request) return false;
  if (!fs::is_regular_file(folder / "summary.json")) return false;
  try {
    std::vector<double> wall, cpu;
    for (int k = 1; k <= repeat; ++k) {
      const Json s = read_json_file(repeat_dir(folder, repeat, k) / "summary.json");
      wall.push_back(json_number(s, "wall_seconds"));
      cpu.push_back(json_number(s, "cpu_seconds"));
    }
    set_finished(rec, read_json_file(folder / "summary.json"));
    rec.wall = std::move(wall);
    rec.cpu = std::move(cpu);
  } catch (const JsonParseError&) {
    return false;
  }
  return true;
}

void link_or_copy(const fs::path& from, const fs::path& to) {
  std::error_code ec;
  fs::copy(from, to, fs::copy_options::recursive | fs::copy_options::overwrite_existing |
                         fs::copy_options::create_hard_links, ec);
  if (ec) fs::copy(from, to, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
}

// ---- the sweep ----

class Sweep {
 public:
  Sweep(const SweepSpec& spec, const std::vector<SweepRun>& runs, const SweepOptions& opt)
      : spec_(spec), runs_(runs), opt_(opt), recs_(runs.size()) {
    for (std::size_t i = 0; i < runs_.size(); ++i) index_[runs_[i].id] = i;
    log_ = opt_.log ? opt_.log : &std::cerr;
    exe_ = opt_.executable.empty() ? fs::read_symlink("/proc/self/exe") : opt_.executable;
    // Each run's request holds the hash of its own base, so that editing one base case reruns
    // only the runs made from it.
    for (const SweepRun& r : runs_)
      if (!base_hash_.count(r.base)) base_hash_[r.base] = fnv1a(read_text(r.base));
    layout_ = make_layout();
  }

  SweepOutcome run() {
    const auto start = Clock::now();
    start_ = start;
    started_at_ = utc_now();
    fs::create_directories(opt_.out_dir);
    lock();

    for (std::size_t i = 0; i < runs_.size(); ++i) {
      Record& rec = recs_[i];
      if (!opt_.force && load_finished(folder(i), request(i), repeats(i), rec)) {
        rec.state = Record::State::done;
        rec.resumed = true;
        ++out_.resumed;
      }
    }
    out_.total = runs_.size();
    done_ = out_.resumed;
    write_sweep_json(false);
    write_summary();

    // Reference runs first, so that runs compared with them find them finished.
    std::vector<std::size_t> queue;
    for (int pass = 0; pass < 2; ++pass)
      for (std::size_t i = 0; i < runs_.size(); ++i)
        if (recs_[i].state == Record::State::pending && runs_[i].is_reference == (pass == 0)) queue.push_back(i);

    if (!opt_.quiet) {
      std::size_t refs = 0;
      for (const auto& r : runs_) refs += r.is_reference;
      *log_ << "sweep " << spec_.name << ": " << runs_.size() << " runs";
      if (refs) *log_ << " (" << refs << " reference)";
      *log_ << ", " << out_.resumed << " done before, " << queue.size() << " to run, "
            << (opt_.jobs == 1 ? std::string("one at a time") : std::to_string(opt_.jobs) + " in parallel");
      if (opt_.repeat > 1) *log_ << ", each " << opt_.repeat << " times (reference runs once)";
      *log_ << " -> " << opt_.out_dir.string() << std::endl;
    }

    execute(queue);

    for (const Record& r : recs_) {
      if (r.status == "ok") ++out_.ok;
      else if (r.status == "diverged") ++out_.diverged;
      else ++out_.failed;
    }
    write_summary();
    write_sweep_json(true);
    if (!opt_.quiet) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.1f", seconds(Clock::now() - start));
      *log_ << "sweep " << spec_.name << ": done in " << buf << " s: " << out_.ok << " ok, " << out_.diverged
            << " diverged, " << out_.failed << " failed -> " << (opt_.out_dir / "summary.csv").string() << std::endl;
    }
    if (lock_fd_ >= 0) close(lock_fd_);
    lock_fd_ = -1;
    return out_;
  }

  ~Sweep() {
    if (lock_fd_ >= 0) close(lock_fd_);
  }
  Sweep(const Sweep&) = delete;
  Sweep& operator=(const Sweep&) = delete;

 private:
  struct Task {
    std::size_t run;
    int k = 1;  // current repeat, from 1
    pid_t pid = -1;
    Clock::time_point started;
    double wall = 0.0;  // process wall time over the repeats so far [s]
    std::vector<double> walls, cpus;
  };

  fs::path folder(std::size_t i) const { return opt_.out_dir / runs_[i].folder(); }
  std::string request(std::size_t i) const {
    return request_text(runs_[i], repeats(i), base_hash_.at(runs_[i].base));
  }
  // --repeat K times each run; a reference run once: its errors are the point, its timing is
  // not compared with anything.
  int repeats(std::size_t i) const { return runs_[i].is_reference ? 1 : opt_.repeat; }

  void lock() {
    const fs::path p = opt_.out_dir / "sweep.lock";
    lock_fd_ = ::open(p.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (lock_fd_ < 0)
      throw std::runtime_error("cannot write '" + p.string() + "': " + std::generic_category().message(errno));
    if (flock(lock_fd_, LOCK_EX | LOCK_NB) != 0)
      throw std::runtime_error(opt_.out_dir.string() + ": another sweep is running in this folder");
  }

  // A run waits for its reference; a reference run (the shared reference's check run) does not:
  // its errors are computed again when the reference finishes.
  bool startable(std::size_t i) const {
    const std::string& ref = runs_[i].reference_id;
    return runs_[i].is_reference || ref.empty() || recs_[index_.at(ref)].state == Record::State::done;
  }

  void start(Task& t) {
    const fs::path dir = repeat_dir(folder(t.run), repeats(t.run), t.k);
    fs::create_directories(dir);
    t.started = Clock::now();
    t.pid = spawn_run(exe_, runs_[t.run], dir);
  }

  void begin(std::size_t i, std::vector<Task>& active) {
    const fs::path f = folder(i);
    fs::remove_all(f);
    fs::create_directories(f);
    write_file_atomic(f / "overrides.json", request(i));
    recs_[i].state = Record::State::active;
    Task t;
    t.run = i;
    start(t);
    active.push_back(std::move(t));
  }

  // Waits for one active child; returns its index in `active` and its wait status.
  std::pair<std::size_t, int> wait_one(const std::vector<Task>& active) {
    for (;;) {
      for (std::size_t a = 0; a < active.size(); ++a) {
        int status = 0;
        const pid_t r = waitpid(active[a].pid, &status, active.size() == 1 ? 0 : WNOHANG);
        if (r == active[a].pid) return {a, status};
        if (r < 0 && errno != EINTR)
          throw std::runtime_error("waitpid: " + std::generic_category().message(errno));
      }
      if (active.size() > 1) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }

  void execute(std::vector<std::size_t> queue) {
    const SignalForwarding forwarding;
    std::vector<Task> active;
    auto children = [&] {
      std::vector<pid_t> pids;
      for (const Task& t : active) pids.push_back(t.pid);
      SignalForwarding::set(pids);
    };
    while (!queue.empty() || !active.empty()) {
      while (static_cast<int>(active.size()) < opt_.jobs) {
        const auto it = std::find_if(queue.begin(), queue.end(), [&](std::size_t i) { return startable(i); });
        if (it == queue.end()) break;
        const std::size_t i = *it;
        queue.erase(it);
        begin(i, active);
      }
      if (active.empty()) break;  // cannot happen: a reference never waits for anything
      children();
      const auto [a, status] = wait_one(active);
      Task& t = active[a];
      t.wall += seconds(Clock::now() - t.started);
      const fs::path dir = repeat_dir(folder(t.run), repeats(t.run), t.k);
      Record& rec = recs_[t.run];
      if (const std::optional<Json> s = finished(decode(status), dir, rec)) {
        t.walls.push_back(json_number(*s, "wall_seconds"));
        t.cpus.push_back(json_number(*s, "cpu_seconds"));
        if (t.k < repeats(t.run)) {
          ++t.k;
          start(t);
          continue;
        }
        if (repeats(t.run) > 1) {
          const fs::path f = folder(t.run);
          if (fs::exists(dir / "history.csv")) link_or_copy(dir / "history.csv", f / "history.csv");
          if (fs::exists(dir / "fields")) link_or_copy(dir / "fields", f / "fields");
          write_file_atomic(f / "summary.json", read_text(dir / "summary.json"));
        }
        set_finished(rec, *s);
        rec.wall = t.walls;
        rec.cpu = t.cpus;
      }
      rec.state = Record::State::done;
      rec.row.reset();
      ++out_.executed;
      ++done_;
      session_wall_ += t.wall;
      ++session_runs_;
      // A rerun reference invalidates the errors of the runs compared with it; a rerun shared
      // reference or check run, the floor of every run compared with the shared reference.
      if (runs_[t.run].is_reference) {
        histories_.erase(t.run);
        const bool shared = spec_.reference.present && (runs_[t.run].id == spec_.reference.id() ||
                                                         runs_[t.run].id == spec_.reference.check_id());
        if (shared) floor_.reset();
        for (std::size_t j = 0; j < runs_.size(); ++j)
          if (runs_[j].reference_id == runs_[t.run].id || (shared && runs_[j].reference_kind == "shared")) {
            recs_[j].errors_done = false;
            recs_[j].row.reset();
          }
      }
      write_summary();
      progress(t);
      active.erase(active.begin() + static_cast<std::ptrdiff_t>(a));
      children();
    }
  }

  // The summary of a finished child, or nothing (and rec marked failed).
  std::optional<Json> finished(const Exit& e, const fs::path& dir, Record& rec) {
    const std::string line = first_line(dir / "stderr.txt");
    if (e.signaled) {
      rec.status = "failed";
      rec.reason = "killed by signal " + std::to_string(e.code) + " (" + strsignal(e.code) + ")";
      if (!line.empty()) rec.reason += ": " + line;
      return std::nullopt;
    }
    if (e.code == 0 || e.code == 3) {
      try {
        return read_json_file(dir / "summary.json");
      } catch (const JsonParseError& err) {
        rec.status = "failed";
        rec.reason = "exit " + std::to_string(e.code) + " without a readable summary.json: " + err.what();
        return std::nullopt;
      }
    }
    rec.status = "failed";
    rec.reason = "exit " + std::to_string(e.code) + (line.empty() ? std::string() : ": " + line);
    return std::nullopt;
  }

  static std::string duration_text(double s) {
    char buf[32];
    std::snprintf(buf, sizeof buf, s < 10.0 ? "%.1f s" : "%.0f s", s);
    return buf;
  }

  void progress(const Task& t) {
    if (opt_.quiet) return;
    const Record& rec = recs_[t.run];
    const double elapsed = seconds(Clock::now() - start_);
    const std::size_t left_runs = runs_.size() - done_;
    const double left = session_wall_ / static_cast<double>(session_runs_) * static_cast<double>(left_runs) / opt_.jobs;
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.2f s", t.wall);
    *log_ << "[" << done_ << "/" << runs_.size() << "] " << runs_[t.run].id << " " << rec.status << " wall " << buf
          << " | elapsed " << duration_text(elapsed) << ", left ~" << duration_text(left);
    if (!rec.reason.empty()) *log_ << " | " << rec.reason;
    *log_ << std::endl;
  }

  // ---- summary.csv ----

  SummaryLayout make_layout() const {
    SummaryLayout l;
    std::set<std::string> seen;
    for (int pass = 0; pass < 2; ++pass)
      for (const SweepRun& r : runs_)
        if (r.is_reference == (pass == 1))
          for (const SweepValue& v : r.overrides)
            if (seen.insert(v.key).second) l.swept.push_back(v.key);
    l.tail = {"repeats", "wall_seconds_min", "wall_seconds_max"};
    std::vector<std::string> probes;
    for (const SweepRun& r : runs_)
      if (!r.reference_id.empty() && std::find(probes.begin(), probes.end(), r.error_probe) == probes.end())
        probes.push_back(r.error_probe);
    if (probes.empty()) probes.push_back("P");
    for (const auto& p : probes) l.tail.push_back("error_probe_" + p);
    for (const auto& m : metric_names(probes.front()))
      if (m.rfind("probe_", 0) != 0) l.tail.push_back("error_" + m);
    l.tail.insert(l.tail.end(), {"reference_run", "reference_kind", "reference_dt", "impulse_source"});
    if (!spec_.reference.check.empty())
      for (const auto& m : metric_names(spec_.reference.error_probe))
        if (has_floor(m)) l.tail.push_back("floor_" + m);
    return l;
  }

  const HistoryTable* reference_history(std::size_t ref) {
    auto it = histories_.find(ref);
    if (it != histories_.end()) return &it->second;
    try {
      return &histories_.emplace(ref, read_history_csv(folder(ref) / "history.csv")).first->second;
    } catch (const std::exception&) {
      return nullptr;
    }
  }

  // A finished run's outputs; `history` holds its history.csv if it could be read.
  RunOutputs outputs(std::size_t i, std::optional<HistoryTable>& history) {
    RunOutputs o;
    const Record& rec = recs_[i];
    if (rec.state != Record::State::done || !rec.summary) return o;
    o.summary = &*rec.summary;
    if (runs_[i].is_reference) {
      o.history = reference_history(i);
    } else {
      try {
        history = read_history_csv(folder(i) / "history.csv");
        o.history = &*history;
      } catch (const std::exception&) {
        // No history: the history metrics stay empty.
      }
    }
    return o;
  }

  // The shared reference's uncertainty: its check run's errors against it (cached), or nothing
  // while either has not finished.
  const std::optional<ReferenceMetrics>& floor() {
    if (floor_ || spec_.reference.check.empty()) return floor_;
    const std::size_t ref = index_.at(spec_.reference.id()), check = index_.at(spec_.reference.check_id());
    std::optional<HistoryTable> h1, h2;  // unused: both are reference runs, whose histories are cached
    const RunOutputs a = outputs(check, h1), b = outputs(ref, h2);
    if (a.summary && b.summary) floor_ = compare_with_reference(a, b, spec_.reference.error_probe);
    return floor_;
  }

  void compute_errors(std::size_t i) {
    Record& rec = recs_[i];
    const SweepRun& run = runs_[i];
    rec.errors.clear();
    rec.errors_done = true;
    if (run.reference_id.empty()) return;
    const std::size_t ref = index_.at(run.reference_id);
    const Record& rr = recs_[ref];
    rec.errors.push_back({"reference_run", run.reference_id});
    rec.errors.push_back({"reference_kind", run.reference_kind});
    if (rr.state == Record::State::done && rr.summary) rec.errors.push_back({"reference_dt", json_text(*rr.summary, "dt")});
    if (!rec.summary) return;
    std::optional<HistoryTable> own, theirs;
    const RunOutputs a = outputs(i, own), b = outputs(ref, theirs);
    const ReferenceMetrics m = compare_with_reference(a, b, run.error_probe);
    for (const auto& [name, value] : metric_values(m, run.error_probe))
      if (value) rec.errors.push_back({"error_" + name, number_text(*value)});
    if (!m.impulse_source.empty()) rec.errors.push_back({"impulse_source", m.impulse_source});
    if (run.reference_kind == "shared")
      if (const auto& f = floor())
        for (const auto& [name, value] : metric_values(*f, spec_.reference.error_probe))
          if (value && has_floor(name)) rec.errors.push_back({"floor_" + name, number_text(*value)});
  }

  const SummaryRow& row(std::size_t i) {
    const SweepRun& run = runs_[i];
    Record& rec = recs_[i];
    if (rec.row) return *rec.row;
    SummaryRow r;
    r.run_id = run.id;
    r.group = run.group;
    r.kind = run.is_reference ? "reference" : "run";
    r.status = rec.status;
    r.reason = rec.reason;
    for (const SweepValue& v : run.overrides) r.swept.push_back({v.key, v.display});
    if (rec.summary) {
      r.summary = flatten_summary(*rec.summary);
      const std::size_t k = rec.wall.size();
      if (k > 0) {
        const double wall = median(rec.wall), cpu = median(rec.cpu);
        if (k > 1) {
          const double cells = json_number(*rec.summary, "elements"), steps = json_number(*rec.summary, "steps");
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
    if (!rec.errors_done) compute_errors(i);
    r.extra.insert(r.extra.end(), rec.errors.begin(), rec.errors.end());
    rec.row = std::move(r);
    return *rec.row;
  }

  void write_summary() {
    std::vector<SummaryRow> rows;
    for (std::size_t i = 0; i < runs_.size(); ++i)
      if (recs_[i].state == Record::State::done) rows.push_back(row(i));
    write_summary_csv(opt_.out_dir / "summary.csv", rows, layout_);
  }

  // sweep.json's `reference`: the shared reference, its check run and its floor; null without one.
  Json shared_reference_json() {
    const SweepReference& sr = spec_.reference;
    if (!sr.present) return Json();
    auto run_json = [&](const std::string& id) {
      const std::size_t i = index_.at(id);
      Json e = Json::object();
      e["id"] = id;
      e["base"] = runs_[i].base.string();
      Json o = Json::array();
      for (const auto& a : runs_[i].set_args()) o.push_back(a);
      e["overrides"] = o;
      e["status"] = recs_[i].state == Record::State::done ? Json(recs_[i].status) : Json();
      return e;
    };
    Json j = run_json(sr.id());
    j["name"] = sr.name;
    j["error_probe"] = sr.error_probe;
    if (sr.check.empty()) {
      j["check"] = nullptr;
      j["floor"] = nullptr;
      return j;
    }
    j["check"] = run_json(sr.check_id());
    const std::optional<ReferenceMetrics>& f = floor();
    if (!f) {
      j["floor"] = nullptr;
      return j;
    }
    Json fl = Json::object();
    for (const auto& [name, value] : metric_values(*f, sr.error_probe))
      if (has_floor(name)) fl[name] = value && std::isfinite(*value) ? Json(*value) : Json();
    fl["impulse_source"] = f->impulse_source.empty() ? Json() : Json(f->impulse_source);
    j["floor"] = fl;
    return j;
  }

  void write_sweep_json(bool finished) {
    Json j = Json::object();
    j["ricochet_version"] = RICOCHET_VERSION;
    j["sweep"] = spec_.name;
    j["description"] = spec_.description;
    j["sweep_file"] = spec_.file;
    j["base"] = spec_.base.empty() ? Json() : Json(spec_.base.string());  // null: every group has its own
    j["out"] = opt_.out_dir.string();
    j["program"] = exe_.string();
    j["jobs"] = opt_.jobs;
    j["repeat"] = opt_.repeat;
    j["force"] = opt_.force;
    j["started_at"] = started_at_;
    j["finished_at"] = finished ? Json(utc_now()) : Json();
    j["total_runs"] = runs_.size();
    j["resumed_runs"] = out_.resumed;
    if (finished) {
      Json c = Json::object();
      c["executed"] = out_.executed;
      c["ok"] = out_.ok;
      c["diverged"] = out_.diverged;
      c["failed"] = out_.failed;
      j["counts"] = c;
    } else {
      j["counts"] = nullptr;
    }
    Json list = Json::array();
    for (const SweepRun& r : runs_) {
      Json e = Json::object();
      e["id"] = r.id;
      e["group"] = r.group;
      e["kind"] = r.is_reference ? "reference" : "run";
      e["base"] = r.base.string();
      e["folder"] = r.folder().string();
      Json o = Json::array();
      for (const auto& a : r.set_args()) o.push_back(a);
      e["overrides"] = o;
      Json sw = Json::array();
      for (const auto& k : r.swept) sw.push_back(k);
      e["swept"] = sw;
      e["reference_run"] = r.reference_id.empty() ? Json() : Json(r.reference_id);
      e["reference_kind"] = r.reference_kind.empty() ? Json() : Json(r.reference_kind);
      list.push_back(e);
    }
    j["reference"] = shared_reference_json();
    j["runs"] = list;
    write_file_atomic(opt_.out_dir / "sweep.json", dump_json(j));
  }

  const SweepSpec& spec_;
  const std::vector<SweepRun>& runs_;
  const SweepOptions& opt_;
  std::vector<Record> recs_;
  std::map<std::string, std::size_t> index_;
  std::map<std::size_t, HistoryTable> histories_;  // reference histories, by run index
  std::optional<ReferenceMetrics> floor_;          // the shared reference's check against it
  std::ostream* log_ = nullptr;
  fs::path exe_;
  std::map<fs::path, std::string> base_hash_;  // FNV-1a of each base case's text
  SummaryLayout layout_;
  SweepOutcome out_;
  std::size_t done_ = 0, session_runs_ = 0;
  double session_wall_ = 0.0;
  Clock::time_point start_;
  std::string started_at_;
  int lock_fd_ = -1;
};

long parse_count(const std::string& flag, const std::string& v, long hi) {
  char* end = nullptr;
  errno = 0;
  const long x = std::strtol(v.c_str(), &end, 10);
  if (v.empty() || *end != '\0' || errno != 0 || x < 1 || x > hi)
    throw InputError("ricochet sweep: " + flag + ": expected an integer in [1, " + std::to_string(hi) + "]; got '" + v + "'");
  return x;
}

}  // namespace

const char* sweep_usage() { return kUsage; }

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

SweepOutcome run_sweep(const SweepSpec& spec, const std::vector<SweepRun>& runs, const SweepOptions& options) {
  if (options.out_dir.empty()) throw InputError("ricochet sweep: no output folder");
  if (options.jobs < 1 || options.jobs > kMaxJobs)
    throw InputError("ricochet sweep: --jobs: expected an integer in [1, " + std::to_string(kMaxJobs) + "]");
  if (options.repeat < 1) throw InputError("ricochet sweep: --repeat: expected an integer >= 1");
  check_runs(spec, runs);
  if (fs::exists(options.out_dir) && !fs::is_directory(options.out_dir))
    throw InputError("ricochet sweep: --out " + options.out_dir.string() + ": not a folder");
  Sweep s(spec, runs, options);
  return s.run();
}

int sweep_command(const std::vector<std::string>& args) {
  return command_status(std::cerr, [&]() -> int {
    std::string file, gates_file;
    SweepOptions opt;
    for (std::size_t i = 0; i < args.size(); ++i) {
      const std::string& a = args[i];
      auto value = [&](const std::string& flag) -> std::string {
        const auto eq = a.find('=');
        if (a.rfind(flag + "=", 0) == 0) return a.substr(eq + 1);
        if (i + 1 >= args.size()) throw InputError("ricochet sweep: " + flag + " needs a value");
        return args[++i];
      };
      auto is = [&](const std::string& flag) { return a == flag || a.rfind(flag + "=", 0) == 0; };
      if (is("--out")) opt.out_dir = value("--out");
      else if (is("--jobs")) opt.jobs = static_cast<int>(parse_count("--jobs", value("--jobs"), kMaxJobs));
      else if (a == "-j") opt.jobs = static_cast<int>(parse_count("--jobs", value("-j"), kMaxJobs));
      else if (is("--repeat")) opt.repeat = static_cast<int>(parse_count("--repeat", value("--repeat"), 1000));
      else if (is("--check")) gates_file = value("--check");
      else if (a == "--force") opt.force = true;
      else if (a == "--quiet" || a == "-q") opt.quiet = true;
      else if (a == "--help" || a == "-h") {
        std::fputs(kUsage, stdout);
        return 0;
      }
      else if (!a.empty() && a[0] == '-')
        throw InputError("ricochet sweep: unknown option '" + a + "'; allowed: --out, --jobs, --repeat, --check, --force, --quiet, --help");
      else if (file.empty()) file = a;
      else throw InputError("ricochet sweep: more than one sweep file ('" + file + "', '" + a + "')");
    }
    if (file.empty())
      throw InputError("ricochet sweep: missing SWEEP.toml; usage: ricochet sweep SWEEP.toml [--out DIR] "
                       "[--jobs N] [--repeat K] [--check GATES.toml] [--force] [--quiet]");
    const SweepSpec spec = read_sweep(file);
    if (opt.out_dir.empty()) opt.out_dir = fs::path("results") / spec.name;
    const std::vector<SweepRun> runs = expand(spec);
    // A bad gate file stops the sweep before any run.
    const std::optional<GateFile> gates = gates_file.empty() ? std::nullopt : std::optional(read_gates(gates_file));
    run_sweep(spec, runs, opt);
    if (!gates) return 0;
    const CsvTable table = read_csv(opt.out_dir / "summary.csv");
    return run_gates(table, *gates, opt.out_dir / "gates-junit.xml", std::cout);
  });
}

}  // namespace ricochet
