#include "harness/external/external_run.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <set>
#include <thread>

#include "harness/input/input_error.hpp"
#include "harness/external/external_case.hpp"
#include "harness/outputs/atomic_file.hpp"
#include "harness/outputs/csv_writer.hpp"
#include "harness/outputs/run_outputs.hpp"
#include "harness/studies/study_placeholders.hpp"
#include "solver/schemes/threads.hpp"

namespace ricochet {
namespace {

namespace fs = std::filesystem;

// ---- the adapter's command ----

// A command argument with its placeholders resolved ({{ is a literal {).
std::string resolve_placeholders(const std::string& arg, const fs::path& case_dir) {
  std::string out;
  for (std::size_t i = 0; i < arg.size();) {
    if (arg.compare(i, 2, "{{") == 0) {
      out += '{';
      i += 2;
    } else if (arg.compare(i, 8, "{python}") == 0) {
      out += report_python();
      i += 8;
    } else if (arg.compare(i, 10, "{adapters}") == 0) {
      out += shipped_adapters_dir().string();
      i += 10;
    } else if (arg.compare(i, 10, "{case_dir}") == 0) {
      out += case_dir.string();
      i += 10;
    } else {
      out += arg[i++];
    }
  }
  return out;
}

// ---- running it ----

volatile std::sig_atomic_t g_stop_signal = 0;
extern "C" void note_stop_signal(int sig) { g_stop_signal = sig; }

// SIGTERM, SIGINT and SIGHUP noted, not acted on, while the adapter runs: ricochet then stops
// the adapter's whole process group before it ends itself by the same signal.
class StopSignals {
 public:
  StopSignals() {
    struct sigaction sa {};
    sa.sa_handler = note_stop_signal;
    sigemptyset(&sa.sa_mask);
    for (int k = 0; k < 3; ++k) sigaction(kSignals[k], &sa, &old_[k]);
  }
  ~StopSignals() { restore(); }
  void restore() {
    if (restored_) return;
    restored_ = true;
    for (int k = 0; k < 3; ++k) sigaction(kSignals[k], &old_[k], nullptr);
  }

 private:
  static constexpr int kSignals[3] = {SIGTERM, SIGINT, SIGHUP};
  struct sigaction old_[3];
  bool restored_ = false;
};

double seconds_of(const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); }

// The last non-empty line of a text file (at most its last 4 kB), for progress and reasons.
std::string last_line(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return {};
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  const std::streamoff from = std::max<std::streamoff>(0, size - 4096);
  in.seekg(from);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' ')) text.pop_back();
  const auto nl = text.find_last_of("\r\n");
  std::string line = nl == std::string::npos ? text : text.substr(nl + 1);
  return line.size() > 300 ? line.substr(0, 300) + "..." : line;
}

[[noreturn]] void fail(const std::string& why) { throw std::runtime_error(why); }

std::string fmt_seconds(double t) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", t);
  return buf;
}

// Runs argv in `work` (its own process group; stdin /dev/null, stdout and stderr to files),
// stopping it after `timeout` seconds; returns what it did. Throws std::runtime_error with the
// reason when it cannot be started, is killed or times out.
AdapterProcess run_adapter(std::vector<std::string> argv, const fs::path& work, double timeout, int threads,
                           const std::string& label, bool quiet) {
  AdapterProcess p;
  p.argv = argv;
  const fs::path out_file = work / "stdout.txt", err_file = work / "stderr.txt";
  std::vector<char*> args;
  for (auto& a : argv) args.push_back(a.data());
  args.push_back(nullptr);
  const std::string threads_text = std::to_string(threads);

  int report[2];
  if (pipe2(report, O_CLOEXEC) != 0) fail(std::string("cannot start the adapter: pipe: ") + std::strerror(errno));
  StopSignals stop_signals;
  const auto start = std::chrono::steady_clock::now();
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = fork();
  if (pid == 0) {
    setpgid(0, 0);
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    int stage = 0;
    const int in = open("/dev/null", O_RDONLY);
    const int out = open(out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err = open(err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (in < 0 || out < 0 || err < 0 || dup2(in, 0) < 0 || dup2(out, 1) < 0 || dup2(err, 2) < 0) stage = 1;
    if (stage == 0 && chdir(work.c_str()) != 0) stage = 2;
    if (stage == 0) {
      setenv("RICOCHET_THREADS", threads_text.c_str(), 1);
      setenv("OMP_NUM_THREADS", threads_text.c_str(), 1);
      signal(SIGTERM, SIG_DFL);
      signal(SIGINT, SIG_DFL);
      signal(SIGHUP, SIG_DFL);
      execvp(args[0], args.data());
      stage = 3;
    }
    const int failure[2] = {stage, errno};
    if (write(report[1], failure, sizeof failure) < 0) _exit(127);
    _exit(127);
  }
  const int fork_errno = errno;
  close(report[1]);
  if (pid < 0) {
    close(report[0]);
    fail(std::string("cannot start the adapter: fork: ") + std::strerror(fork_errno));
  }
  setpgid(pid, pid);
  int failure[2] = {0, 0};
  ssize_t got;
  do got = read(report[0], failure, sizeof failure);
  while (got < 0 && errno == EINTR);
  close(report[0]);

  int status = 0;
  rusage ru{};
  bool timed_out = false;
  int stopped_by = 0;
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  auto stop_group = [&] {
    kill(-pid, SIGTERM);
    for (int k = 0; k < 100; ++k) {  // 5 s, then SIGKILL
      if (wait4(pid, &status, WNOHANG, &ru) == pid) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    kill(-pid, SIGKILL);
    while (wait4(pid, &status, 0, &ru) < 0 && errno == EINTR) {
    }
  };
  const bool tty = isatty(STDERR_FILENO);
  double next_progress = tty ? 2.0 : 10.0;
  for (;;) {
    const pid_t w = wait4(pid, &status, WNOHANG, &ru);
    if (w == pid) break;
    if (w < 0 && errno != EINTR) fail(std::string("waiting for the adapter: ") + std::strerror(errno));
    if (g_stop_signal) {
      stopped_by = g_stop_signal;
      stop_group();
      break;
    }
    if (elapsed() > timeout) {
      timed_out = true;
      stop_group();
      break;
    }
    if (!quiet && elapsed() >= next_progress) {
      next_progress += tty ? 1.0 : 10.0;
      std::fprintf(stderr, "%sexternal %s: %.0f s: %s%s", tty ? "\r\033[K" : "", label.c_str(), elapsed(),
                   last_line(out_file).c_str(), tty ? "" : "\n");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (!quiet && tty && next_progress > 2.0) std::fprintf(stderr, "\n");
  p.wall_seconds = elapsed();
  p.cpu_seconds = seconds_of(ru.ru_utime) + seconds_of(ru.ru_stime);
  p.peak_memory_bytes = ru.ru_maxrss * 1024L;
  if (stopped_by) {
    g_stop_signal = 0;
    stop_signals.restore();
    signal(stopped_by, SIG_DFL);
    raise(stopped_by);
    fail(std::string("stopped by signal ") + strsignal(stopped_by));
  }
  if (failure[0] != 0) {
    const char* what = failure[0] == 1 ? "cannot open its output files" : failure[0] == 2 ? "cannot enter its folder" : "cannot run";
    fail(std::string("adapter: ") + what + " '" + argv[0] + "': " + std::strerror(failure[1]));
  }
  if (timed_out) fail("timed out after " + fmt_seconds(timeout) + " s (external.timeout); its last output: " + last_line(out_file));
  // The last line of its stderr: where a Python traceback or a solver's final error is.
  if (WIFSIGNALED(status)) {
    const std::string line = last_line(err_file);
    fail("adapter killed by signal " + std::to_string(WTERMSIG(status)) + " (" + strsignal(WTERMSIG(status)) + ")" +
         (line.empty() ? "" : ": " + line));
  }
  p.exit_status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (p.exit_status != 0) {
    const std::string line = last_line(err_file);
    fail("adapter exit " + std::to_string(p.exit_status) + (line.empty() ? " (nothing on its stderr)" : ": " + line));
  }
  return p;
}

// ---- reading its results ----

bool finite_number(const Json& v) { return v.is_number() && std::isfinite(v.get<double>()); }

std::string shown(const Json& v) {
  std::string s = v.dump();
  return s.size() > 60 ? s.substr(0, 60) + "..." : s;
}

// The history columns an adapter may fill, in the order ricochet writes them, energy_error
// (ricochet's to compute) included.
std::vector<std::string> known_columns(const PreparedCase& pc) {
  const int d = pc.dimension();
  std::vector<std::string> c = {"time", "kinetic_energy", "strain_energy", "hourglass_energy", "external_work",
                                "friction_dissipation", "total_energy", "energy_error", "momentum_x", "momentum_y"};
  if (d == 3) c.push_back("momentum_z");
  c.insert(c.end(), {"von_mises_max", "penetration_max", "contact_nodes", "normal_force", "tangential_force",
                     "contact_work", "contact_energy"});
  if (d == 2)
    c.push_back("angular_momentum");
  else
    c.insert(c.end(), {"angular_momentum_x", "angular_momentum_y", "angular_momentum_z"});
  const char* axes = d == 2 ? "xy" : "xyz";
  for (const ProbeInfo& p : pc.probes) {
    for (const char* a = axes; *a; ++a) c.push_back(p.name + "_u" + *a);
    for (const char* a = axes; *a; ++a) c.push_back(p.name + "_v" + *a);
  }
  return c;
}

constexpr const char* kSummaryKeys[] = {"von_mises_max", "von_mises_max_time", "von_mises_interior_max",
                                         "von_mises_interior_max_time", "penetration_max", "contact_impulse_normal",
                                         "contact_impulse_tangential", "contact_start_time", "contact_end_time",
                                         "contact_duration", "friction_dissipation", "contact_work"};

struct Result {
  std::string status, reason, code, code_version;
  long steps = 0;
  double dt = 0.0;
  std::optional<double> time_reached, solver_cpu;
  Json summary = Json::object();
  Json translation = Json::object();
};

Result read_result(const fs::path& file) {
  std::error_code ec;
  if (!fs::exists(file, ec)) fail(file.string() + ": missing (the adapter exited 0 without writing it)");
  Json j;
  try {
    j = read_json_file(file);
  } catch (const JsonParseError& e) {
    fail(e.what());
  }
  const std::string f = file.string();
  if (!j.is_object()) fail(f + ": expected a JSON object");
  auto at = [&](const char* k) { return j.contains(k) ? j.at(k) : Json(); };
  if (at("format") != "ricochet-external-result")
    fail(f + ": format: expected \"ricochet-external-result\", got " + shown(at("format")));
  if (at("version") != 1) fail(f + ": version: expected 1, got " + shown(at("version")));
  static const std::set<std::string> allowed = {"format", "version", "status", "reason", "steps", "dt", "time_reached",
                                                "code", "code_version", "solver_cpu_seconds", "summary", "translation"};
  for (const auto& [k, v] : j.items())
    if (!allowed.count(k)) fail(f + ": unknown key \"" + k + "\"");
  Result r;
  const Json st = at("status");
  if (st != "ok" && st != "diverged") fail(f + ": status: expected \"ok\" or \"diverged\", got " + shown(st));
  r.status = st.get<std::string>();
  if (r.status == "diverged") {
    if (!at("reason").is_string() || at("reason").get<std::string>().empty())
      fail(f + ": reason: a non-empty string is required with status \"diverged\", got " + shown(at("reason")));
  }
  if (at("reason").is_string()) r.reason = at("reason").get<std::string>();
  else if (!at("reason").is_null()) fail(f + ": reason: expected a string, got " + shown(at("reason")));
  const Json steps = at("steps");
  if (!steps.is_number_integer() || steps.get<long long>() < 0) fail(f + ": steps: expected an integer >= 0, got " + shown(steps));
  r.steps = steps.get<long>();
  const Json dt = at("dt");
  if (!finite_number(dt) || dt.get<double>() <= 0.0) fail(f + ": dt: expected a number > 0, got " + shown(dt));
  r.dt = dt.get<double>();
  auto optional_number = [&](const char* k) -> std::optional<double> {
    const Json v = at(k);
    if (v.is_null()) return std::nullopt;
    if (!finite_number(v) || v.get<double>() < 0.0) fail(f + ": " + k + ": expected a number >= 0, got " + shown(v));
    return v.get<double>();
  };
  r.time_reached = optional_number("time_reached");
  r.solver_cpu = optional_number("solver_cpu_seconds");
  for (const char* k : {"code", "code_version"}) {
    const Json v = at(k);
    if (!v.is_null() && !v.is_string()) fail(f + ": " + k + ": expected a string, got " + shown(v));
  }
  r.code = at("code").is_string() ? at("code").get<std::string>() : "";
  r.code_version = at("code_version").is_string() ? at("code_version").get<std::string>() : "";
  if (const Json s = at("summary"); !s.is_null()) {
    if (!s.is_object()) fail(f + ": summary: expected an object, got " + shown(s));
    for (const auto& [k, v] : s.items()) {
      if (std::none_of(std::begin(kSummaryKeys), std::end(kSummaryKeys), [&](const char* a) { return k == a; })) {
        std::string list;
        for (const char* a : kSummaryKeys) list += (list.empty() ? "" : ", ") + std::string(a);
        fail(f + ": summary." + k + ": not a key an adapter gives; allowed: " + list);
      }
      if (!finite_number(v)) fail(f + ": summary." + k + ": expected a finite number, got " + shown(v));
      r.summary[k] = v;
    }
  }
  if (const Json t = at("translation"); !t.is_null()) {
    if (!t.is_object()) fail(f + ": translation: expected an object, got " + shown(t));
    for (const auto& [k, v] : t.items()) {
      if (k != "translated" && k != "not_translated" && k != "notes")
        fail(f + ": translation." + k + ": unknown key; allowed: translated, not_translated, notes");
      if (!v.is_array() || !std::all_of(v.begin(), v.end(), [](const Json& e) { return e.is_string(); }))
        fail(f + ": translation." + k + ": expected an array of strings");
    }
    r.translation = t;
  }
  return r;
}

// The adapter's history.csv checked, as columns by name.
struct AdapterHistory {
  std::vector<std::string> columns;                // in the file's order
  std::vector<std::vector<double>> values;         // per column, per row
  std::size_t rows = 0;
  const std::vector<double>* find(const std::string& c) const {
    for (std::size_t k = 0; k < columns.size(); ++k)
      if (columns[k] == c) return &values[k];
    return nullptr;
  }
};

AdapterHistory read_history(const fs::path& file, const PreparedCase& pc) {
  std::error_code ec;
  if (!fs::exists(file, ec)) fail(file.string() + ": missing (the adapter exited 0 without writing it)");
  CsvTable t;
  try {
    t = read_csv(file);
  } catch (const InputError& e) {
    fail(e.what());
  }
  const std::string f = file.string();
  const std::vector<std::string> known = known_columns(pc);
  if (t.columns.empty() || t.columns.front() != "time") fail(f + ": the first column must be \"time\"");
  std::set<std::string> seen;
  for (const std::string& c : t.columns) {
    if (!seen.insert(c).second) fail(f + ": column \"" + c + "\" appears twice");
    if (c == "energy_error") fail(f + ": energy_error is computed by ricochet from the energy columns; leave it out");
    if (std::find(known.begin(), known.end(), c) == known.end())
      fail(f + ": unknown column \"" + c + "\" (ricochet's history columns and the case's probes' <probe>_u*, _v*: docs/peers.md)");
  }
  if (t.rows.empty()) fail(f + ": no rows (at least the sample at t = 0)");
  AdapterHistory h;
  h.columns = t.columns;
  h.rows = t.rows.size();
  h.values.assign(t.columns.size(), std::vector<double>(h.rows));
  for (std::size_t r = 0; r < h.rows; ++r)
    for (std::size_t c = 0; c < t.columns.size(); ++c) {
      const std::optional<double> v = parse_csv_number(t.rows[r][c]);
      if (!v || !std::isfinite(*v))
        fail(f + ":" + std::to_string(t.lines[r]) + ": " + t.columns[c] + ": expected a finite number, got \"" + t.rows[r][c] + "\"");
      h.values[c][r] = *v;
    }
  const std::vector<double>& time = h.values[0];
  if (std::abs(time[0]) > 1e-12) fail(f + ":" + std::to_string(t.lines[0]) + ": time: the first sample must be at t = 0, got " + fmt_seconds(time[0]));
  for (std::size_t r = 1; r < h.rows; ++r)
    if (!(time[r] > time[r - 1]))
      fail(f + ":" + std::to_string(t.lines[r]) + ": time: must increase strictly; " + fmt_seconds(time[r]) + " after " + fmt_seconds(time[r - 1]));
  return h;
}

double largest(const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); }

}  // namespace

std::vector<std::string> adapter_command(const CaseSpec& spec) {
  const ExternalSpec& e = spec.external;
  const fs::path case_dir = fs::absolute(fs::path(spec.file)).parent_path().lexically_normal();
  std::vector<std::string> argv;
  if (!e.adapter.empty()) {
    argv = {report_python(), (shipped_adapters_dir() / (e.adapter + ".py")).string()};
  } else {
    for (const std::string& a : e.command) argv.push_back(resolve_placeholders(a, case_dir));
    // A program given by a relative path is taken from the case file's folder.
    if (argv[0].find('/') != std::string::npos && fs::path(argv[0]).is_relative())
      argv[0] = (case_dir / argv[0]).lexically_normal().string();
  }
  return argv;
}

ExternalResult import_external_result(const PreparedCase& pc, const Json& case_json, const fs::path& work,
                                      const AdapterProcess& process) {
  const CaseSpec& c = pc.spec;
  const Result res = read_result(work / "result.json");
  const AdapterHistory h = read_history(work / "history.csv", pc);
  const double end = c.end_time, dt = case_json.at("time").at("dt").get<double>();
  const double t_last = h.values[0].back();
  if (res.status == "ok" && std::abs(t_last - end) > 0.5 * dt)
    fail((work / "history.csv").string() + ": status \"ok\" but the last sample is at t = " + fmt_seconds(t_last) +
         " s, not time.end = " + fmt_seconds(end) + " s");

  // The energy balance, ricochet's definition (docs/outputs.md, Energy definitions).
  const std::size_t n = h.rows;
  const std::vector<double>* total = h.find("total_energy");
  std::vector<double> error;
  double initial_energy = 0.0;
  if (total) {
    auto col = [&](const char* name) {
      const std::vector<double>* v = h.find(name);
      return v ? *v : std::vector<double>(n, 0.0);
    };
    const std::vector<double> pen = col("contact_energy"), diss = col("friction_dissipation"), work_ext = col("external_work");
    initial_energy = (*total)[0] + pen[0];
    double w_max = 0.0;
    error.resize(n);
    for (std::size_t r = 0; r < n; ++r) {
      w_max = std::max(w_max, std::abs(work_ext[r]));
      const double ref = std::max(initial_energy, w_max);
      error[r] = ref > 0.0 ? std::abs((*total)[r] + pen[r] + diss[r] - initial_energy - work_ext[r]) / ref : 0.0;
    }
  }

  ExternalResult out;
  for (const std::string& name : known_columns(pc)) {
    if (name == "energy_error" ? error.empty() : h.find(name) == nullptr) continue;
    out.columns.push_back(name);
  }
  std::vector<const std::vector<double>*> sources;
  for (const std::string& name : out.columns) sources.push_back(name == "energy_error" ? &error : h.find(name));
  out.rows.reserve(n * out.columns.size());
  for (std::size_t r = 0; r < n; ++r)
    for (const std::vector<double>* v : sources) out.rows.push_back((*v)[r]);

  // summary.json: what ricochet's own runs have, where the adapter's files give it.
  Json j = case_identity(pc);
  j["scheme"] = c.external.name;
  Json ext = Json::object();
  ext["adapter"] = c.external.adapter.empty() ? Json() : Json(c.external.adapter);
  ext["command"] = process.argv;
  ext["code"] = res.code.empty() ? Json() : Json(res.code);
  ext["code_version"] = res.code_version.empty() ? Json() : Json(res.code_version);
  ext["solver_cpu_seconds"] = res.solver_cpu ? Json(*res.solver_cpu) : Json();
  ext["timeout"] = c.external.timeout;
  ext["exit_status"] = process.exit_status;
  ext["folder"] = "external";
  ext["options"] = case_json.at("options");
  ext["translation"] = res.translation;
  j["external"] = ext;
  add_case_shape(j, pc);
  add_model_size(j, pc);
  j["dt"] = res.dt;
  j["dt_mode"] = pc.dt_auto() ? "auto" : "fixed";
  j["dt_safety"] = pc.dt_auto() ? Json(c.dt_safety) : Json();
  j["critical_dt"] = case_json.at("time").at("critical_dt");
  j["end_time"] = end;
  const double reached = res.time_reached.value_or(t_last);
  j["time_reached"] = reached;
  j["steps"] = res.steps;
  j["planned_steps"] = case_json.at("time").at("steps");
  j["status"] = res.status;
  if (res.status == "diverged") {
    Json d = Json::object();
    d["reason"] = res.reason;
    d["step"] = res.steps;
    d["time"] = reached;
    j["diverged"] = d;
  } else {
    j["diverged"] = nullptr;
  }
  j["relaxation"] = nullptr;
  j["threads"] = case_json.at("threads");
  j["wall_seconds"] = process.wall_seconds;
  j["cpu_seconds"] = process.cpu_seconds;
  j["peak_memory_bytes"] = process.peak_memory_bytes;
  const long elements = j["elements"].get<long>();
  j["element_steps_per_second"] =
      process.wall_seconds > 0.0 ? static_cast<double>(elements) * static_cast<double>(res.steps) / process.wall_seconds : 0.0;
  if (!error.empty()) {
    j["initial_energy"] = initial_energy;
    j["energy_error_max"] = largest(error);
  }
  auto from_summary_or_column = [&](const char* key, const char* column) {
    if (res.summary.contains(key))
      j[key] = res.summary.at(key);
    else if (const std::vector<double>* v = h.find(column))
      j[key] = largest(*v);
  };
  from_summary_or_column("penetration_max", "penetration_max");
  j["stress_measure"] = case_json.at("output").at("stress_measure");
  from_summary_or_column("von_mises_max", "von_mises_max");
  for (const char* k : kSummaryKeys)
    if (!j.contains(k) && res.summary.contains(k)) j[k] = res.summary.at(k);
  double total_mass = 0.0;
  with_model(pc, [&](const auto& m) {
    for (int i = 0; i < m.num_nodes(); ++i) total_mass += m.mass(m.kDim * i);
  });
  j["total_mass"] = total_mass;
  const char* axes[] = {"x", "y", "z"};
  for (int k = 0; k < c.dimension; ++k) {
    const std::string col = std::string("momentum_") + axes[k];
    if (const std::vector<double>* v = h.find(col); v && total_mass > 0.0)
      j[std::string("rebound_velocity_") + axes[k]] = v->back() / total_mass;
  }
  if (const std::vector<double>* v = h.find("normal_force")) j["contact_force_max"] = std::max(0.0, largest(*v));
  Json fin = Json::object();
  for (std::size_t k = 0; k < out.columns.size(); ++k) {
    const std::string& name = out.columns[k];
    // The probes' velocities stay in the history, as in ricochet's own summaries.
    const bool probe_velocity = std::any_of(pc.probes.begin(), pc.probes.end(), [&](const ProbeInfo& p) {
      return name.size() == p.name.size() + 3 && name.compare(0, p.name.size() + 2, p.name + "_v") == 0;
    });
    if (probe_velocity || name == "von_mises_max" || name == "penetration_max" || name == "contact_nodes" || name == "normal_force" ||
        name == "tangential_force")
      continue;
    fin[name] = out.rows[(n - 1) * out.columns.size() + k];
  }
  j["final"] = fin;
  j["probes"] = probes_json(pc);
  j["history_rows"] = static_cast<long>(n);
  j["field_files"] = 0;
  j["build"] = build_info();
  j["written_at"] = utc_now();
  out.summary = j;
  return out;
}

int run_external(const PreparedCase& pc, const fs::path& out_dir, bool quiet) {
  const CaseSpec& c = pc.spec;
  const std::string label = c.external.name;
  const fs::path work = out_dir / "external";
  std::error_code ec;
  fs::create_directories(work, ec);
  if (ec) throw InputError("ricochet run: cannot create '" + work.string() + "': " + ec.message());
  // What an earlier run left must not be read as this run's, nor stand as its result.
  for (const fs::path& stale : {out_dir / "summary.json", out_dir / "history.csv", work / "result.json", work / "history.csv"})
    fs::remove(stale, ec);

  const Json case_json = external_case_json(pc);
  const fs::path case_file = fs::absolute(work / "case.json");
  write_file_atomic(case_file, dump_json(case_json));

  std::vector<std::string> argv = adapter_command(c);
  argv.push_back(case_file.string());
  argv.push_back(fs::absolute(work).string());
  try {
    const AdapterProcess process =
        run_adapter(argv, fs::absolute(work), c.external.timeout, case_json.at("threads").get<int>(), label, quiet);
    const ExternalResult r = import_external_result(pc, case_json, work, process);
    write_file_atomic(out_dir / "history.csv", format_csv(r.columns, r.rows));
    write_file_atomic(out_dir / "summary.json", dump_json(r.summary));
    if (!quiet) {
      const Json& s = r.summary;
      std::printf("%s: %s (external, %s), %ld steps, cpu %.3g s, wall %.3g s -> %s\n", c.name.c_str(), label.c_str(),
                  s.at("status").get<std::string>().c_str(), s.at("steps").get<long>(), process.cpu_seconds,
                  process.wall_seconds, out_dir.string().c_str());
    }
    return r.summary.at("status") == "ok" ? 0 : 3;
  } catch (const std::runtime_error& e) {
    throw ExternalRunFailure("external scheme '" + label + "': " + e.what());
  }
}

}  // namespace ricochet
