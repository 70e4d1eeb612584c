#include "harness/sweeps/sweep_exec.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <system_error>
#include <thread>
#include <utility>

#include "harness/outputs/atomic_file.hpp"
#include "harness/sweeps/sweep.hpp"

extern char** environ;

namespace ricochet {
namespace {

namespace fs = std::filesystem;
using Clock = SweepExecution::Clock;

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

extern "C" void forward_signal(int sig);

// While it lives, SIGINT, SIGTERM and SIGHUP are passed on to the children set() names before
// this process ends by the same signal, so that no orphaned run keeps writing into the sweep's
// folder. (A signal the process ignored stays ignored.) The handler finds it through the one
// static pointer; there is one at a time.
class SignalForwarding {
 public:
  SignalForwarding() {
    active_.store(this);
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
    active_.store(nullptr);
  }
  SignalForwarding(const SignalForwarding&) = delete;
  SignalForwarding& operator=(const SignalForwarding&) = delete;

  // The children to pass signals on to.
  void set(const std::vector<pid_t>& pids) {
    count_ = 0;
    const std::size_t n = std::min<std::size_t>(pids.size(), kMaxSweepJobs);
    for (std::size_t i = 0; i < n; ++i) children_[i] = pids[i];
    count_ = static_cast<std::sig_atomic_t>(n);
  }

  // The signal handler's work: async-signal-safe calls only.
  static void forward(int sig) {
    if (const SignalForwarding* f = active_.load())
      for (std::sig_atomic_t i = 0; i < f->count_; ++i)
        if (f->children_[i] > 0) kill(f->children_[i], sig);
    signal(sig, SIG_DFL);
    raise(sig);
  }

 private:
  static constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP};
  static inline std::atomic<SignalForwarding*> active_{nullptr};
  static_assert(std::atomic<SignalForwarding*>::is_always_lock_free);
  pid_t children_[kMaxSweepJobs] = {};
  volatile std::sig_atomic_t count_ = 0;
  struct sigaction old_[std::size(kSignals)] {};
};

extern "C" void forward_signal(int sig) { SignalForwarding::forward(sig); }

struct Exit {
  bool signaled = false;
  int code = 0;  // exit status or signal number
};

Exit decode(int status) {
  if (WIFSIGNALED(status)) return {true, WTERMSIG(status)};
  return {false, WIFEXITED(status) ? WEXITSTATUS(status) : -1};
}

pid_t spawn_run(const fs::path& exe, const SweepRun& run, std::optional<int> threads, const fs::path& out) {
  std::vector<std::string> args = {exe.string(), "run", run.base.string()};
  for (const auto& a : run.set_args()) {
    args.push_back("--set");
    args.push_back(a);
  }
  if (threads) args.insert(args.end(), {"--threads", std::to_string(*threads)});
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

// Waits for one of the children; returns its index in `pids` and its wait status.
std::pair<std::size_t, int> wait_one(const std::vector<pid_t>& pids) {
  for (;;) {
    for (std::size_t a = 0; a < pids.size(); ++a) {
      int status = 0;
      const pid_t r = waitpid(pids[a], &status, pids.size() == 1 ? 0 : WNOHANG);
      if (r == pids[a]) return {a, status};
      if (r < 0 && errno != EINTR) throw std::runtime_error("waitpid: " + std::generic_category().message(errno));
    }
    if (pids.size() > 1) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

std::string first_line(const fs::path& p) {
  std::ifstream in(p);
  for (std::string line; std::getline(in, line);) {
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    if (!line.empty()) return line.size() > 300 ? line.substr(0, 300) + "..." : line;
  }
  return {};
}

// The summary of a finished child, or nothing (and the record marked failed, with the reason).
std::optional<Json> outcome(const Exit& e, const fs::path& dir, RunRecord& rec) {
  const std::string line = first_line(dir / "stderr.txt");
  if (e.signaled) {
    rec.status = "failed";
    rec.reason = "killed by signal " + std::to_string(e.code) + " (" + strsignal(e.code) + ")";
    if (!line.empty()) rec.reason += ": " + line;
    return std::nullopt;
  }
  if (e.code == 0 || e.code == 3) {
    std::string problem;
    try {
      Json s = read_json_file(dir / "summary.json");
      problem = summary_problem(s);
      if (problem.empty()) return s;
    } catch (const JsonParseError& err) {
      problem = err.what();
    }
    rec.status = "failed";
    rec.reason = "exit " + std::to_string(e.code) + " without a valid summary.json: " + problem;
    return std::nullopt;
  }
  rec.status = "failed";
  rec.reason = "exit " + std::to_string(e.code) + (line.empty() ? std::string() : ": " + line);
  return std::nullopt;
}

void link_or_copy(const fs::path& from, const fs::path& to) {
  std::error_code ec;
  fs::copy(from, to, fs::copy_options::recursive | fs::copy_options::overwrite_existing |
                         fs::copy_options::create_hard_links, ec);
  if (ec) fs::copy(from, to, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
}

std::string duration_text(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, s < 10.0 ? "%.1f s" : "%.0f s", s);
  return buf;
}

}  // namespace

struct SweepExecution::Task {
  std::size_t run;
  int k = 1;  // current repeat, from 1
  pid_t pid = -1;
  Clock::time_point started;
  double wall = 0.0;  // process wall time over the repeats so far [s]
  std::vector<double> walls, cpus;
};

SweepExecution::SweepExecution(const SweepPlan& plan, std::vector<RunRecord>& records, const SweepOptions& options,
                               fs::path program, Clock::time_point start, std::size_t done)
    : plan_(plan),
      records_(records),
      options_(options),
      program_(std::move(program)),
      log_(options.log ? options.log : &std::cerr),
      start_(start),
      done_(done) {}

void SweepExecution::start(Task& t) {
  const fs::path dir = plan_.repeat_dir(t.run, t.k);
  fs::create_directories(dir);
  t.started = Clock::now();
  t.pid = spawn_run(program_, plan_.run(t.run), plan_.threads(t.run), dir);
}

void SweepExecution::begin(std::size_t i, std::vector<Task>& active) {
  const fs::path f = plan_.folder(i);
  fs::remove_all(f);
  fs::create_directories(f);
  write_file_atomic(f / "overrides.json", plan_.request(i));
  records_[i].state = RunRecord::State::active;
  Task t;
  t.run = i;
  start(t);
  active.push_back(std::move(t));
}

void SweepExecution::run(std::vector<std::size_t> queue, const std::function<void(std::size_t)>& on_done) {
  SignalForwarding forwarding;
  std::vector<Task> active;
  auto pids = [&] {
    std::vector<pid_t> p;
    for (const Task& t : active) p.push_back(t.pid);
    return p;
  };
  while (!queue.empty() || !active.empty()) {
    while (static_cast<int>(active.size()) < options_.jobs) {
      const auto it = std::find_if(queue.begin(), queue.end(), [&](std::size_t i) { return plan_.startable(i, records_); });
      if (it == queue.end()) break;
      const std::size_t i = *it;
      queue.erase(it);
      begin(i, active);
    }
    if (active.empty()) break;  // cannot happen: a reference never waits for anything
    const std::vector<pid_t> children = pids();
    forwarding.set(children);
    const auto [a, status] = wait_one(children);
    Task& t = active[a];
    t.wall += seconds(Clock::now() - t.started);
    finish(t, status);
    if (records_[t.run].state != RunRecord::State::done) continue;  // its next repeat runs
    on_done(t.run);
    progress(t);
    active.erase(active.begin() + static_cast<std::ptrdiff_t>(a));
    forwarding.set(pids());
  }
}

// Either starts the task's next repeat or marks its run done.
void SweepExecution::finish(Task& t, int wait_status) {
  const fs::path dir = plan_.repeat_dir(t.run, t.k);
  RunRecord& rec = records_[t.run];
  if (const std::optional<Json> s = outcome(decode(wait_status), dir, rec)) {
    t.walls.push_back(json_number(*s, "wall_seconds", std::nan("")));
    t.cpus.push_back(json_number(*s, "cpu_seconds", std::nan("")));
    if (t.k < plan_.repeats(t.run)) {
      ++t.k;
      start(t);
      return;
    }
    if (plan_.repeats(t.run) > 1) {  // the last repeat's outputs, in the run's folder
      const fs::path f = plan_.folder(t.run);
      if (fs::exists(dir / "history.csv")) link_or_copy(dir / "history.csv", f / "history.csv");
      if (fs::exists(dir / "fields")) link_or_copy(dir / "fields", f / "fields");
      write_file_atomic(f / "summary.json", read_text(dir / "summary.json"));
    }
    set_finished(rec, *s);
    rec.wall = t.walls;
    rec.cpu = t.cpus;
  }
  rec.state = RunRecord::State::done;
  ++done_;
  session_wall_ += t.wall;
  ++session_runs_;
}

void SweepExecution::progress(const Task& t) {
  if (options_.quiet) return;
  const RunRecord& rec = records_[t.run];
  const double elapsed = seconds(Clock::now() - start_);
  const std::size_t left_runs = plan_.size() - done_;
  const double left = session_wall_ / static_cast<double>(session_runs_) * static_cast<double>(left_runs) / options_.jobs;
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.2f s", t.wall);
  *log_ << "[" << done_ << "/" << plan_.size() << "] " << plan_.run(t.run).id << " " << rec.status << " wall " << buf
        << " | elapsed " << duration_text(elapsed) << ", left ~" << duration_text(left);
  if (!rec.reason.empty()) *log_ << " | " << rec.reason;
  *log_ << std::endl;
}

}  // namespace ricochet
