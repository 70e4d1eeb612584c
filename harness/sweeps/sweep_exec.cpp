#include "harness/sweeps/sweep_exec.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <time.h>
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
#include <sstream>
#include <stdexcept>
#include <system_error>
#include <thread>
#include <utility>

#include "harness/outputs/atomic_file.hpp"
#include "harness/outputs/run_outputs.hpp"
#include "harness/sweeps/sweep.hpp"

namespace ricochet {
namespace {

namespace fs = std::filesystem;
using Clock = SweepExecution::Clock;

double seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

extern "C" void forward_signal(int sig);

// While it lives, SIGINT, SIGTERM and SIGHUP are passed on to the process groups of the runs
// set() names; the sweep then waits up to kGrace for them to end, kills what is left (SIGKILL to
// the groups) and ends by the same signal, so that no run keeps writing into the sweep's folder
// after the sweep has ended. (A signal the process ignored stays ignored.) The handler finds it
// through the one static pointer; there is one at a time.
class SignalForwarding {
 public:
  SignalForwarding() {
    active_.store(this);
    struct sigaction now {};
    now.sa_handler = forward_signal;
    sigemptyset(&now.sa_mask);
    for (int sig : kSignals) sigaddset(&now.sa_mask, sig);  // one handler at a time
    for (std::size_t i = 0; i < std::size(kSignals); ++i) {
      sigaction(kSignals[i], nullptr, &old_[i]);
      if (old_[i].sa_handler == SIG_IGN) continue;
      sigaction(kSignals[i], &now, nullptr);
    }
  }
  ~SignalForwarding() {
    for (std::size_t i = 0; i < std::size(kSignals); ++i) sigaction(kSignals[i], &old_[i], nullptr);
    active_.store(nullptr);
  }
  SignalForwarding(const SignalForwarding&) = delete;
  SignalForwarding& operator=(const SignalForwarding&) = delete;

  // The runs to pass signals on to: each pid is its process group's id.
  void set(const std::vector<pid_t>& pids) {
    count_ = 0;
    const std::size_t n = std::min<std::size_t>(pids.size(), kMaxSweepJobs);
    for (std::size_t i = 0; i < n; ++i) children_[i] = pids[i];
    count_ = static_cast<std::sig_atomic_t>(n);
  }

  // The signal handler's work: async-signal-safe calls only.
  static void forward(int sig) {
    if (SignalForwarding* f = active_.load()) {
      const std::sig_atomic_t n = f->count_;
      for (std::sig_atomic_t i = 0; i < n; ++i)
        if (f->children_[i] > 0) kill(-f->children_[i], sig);
      const struct timespec step = {0, 10 * 1000 * 1000};
      for (int tick = 0; tick < kGraceTicks; ++tick) {
        bool alive = false;
        for (std::sig_atomic_t i = 0; i < n; ++i)
          if (f->children_[i] > 0) {
            if (waitpid(f->children_[i], nullptr, WNOHANG) == 0) alive = true;
            else f->children_[i] = -f->children_[i];  // ended (reaped here or before)
          }
        if (!alive) break;
        nanosleep(&step, nullptr);
      }
      for (std::sig_atomic_t i = 0; i < n; ++i)
        if (f->children_[i] > 0) kill(-f->children_[i], SIGKILL);
    }
    signal(sig, SIG_DFL);
    raise(sig);  // delivered when the handler returns (the signal is blocked until then)
  }

 private:
  static constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP};
  static constexpr int kGraceTicks = 500;  // x 10 ms: kGrace = 5 s
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

// Starts `ricochet run` for one repeat of a run (`ricochet stability ... [search options]` for a
// stability search), in its own process group, with stdin and
// stdout on /dev/null, stderr into OUT/stderr.txt, and the run folder's lock (`lock_fd`, which
// the child keeps open through exec: the lock is held as long as the run lives). The child is
// killed (SIGKILL) when the thread that forks it ends (PR_SET_PDEATHSIG), so a sweep killed by
// any signal, SIGKILL included, takes its runs with it; SweepExecution::run() forks from its own
// thread, which outlives every child it starts. Throws std::runtime_error if the child cannot be
// started (the error comes back through a close-on-exec pipe).
pid_t spawn_run(const fs::path& exe, const SweepRun& run, std::optional<int> threads, const fs::path& out, int lock_fd) {
  std::vector<std::string> args = {exe.string(), run.stability ? "stability" : "run", run.base.string()};
  for (const auto& a : run.set_args()) {
    args.push_back("--set");
    args.push_back(a);
  }
  if (threads) args.insert(args.end(), {"--threads", std::to_string(*threads)});
  args.insert(args.end(), {"--out", out.string(), "--quiet"});
  for (const SweepStabilityOption& o : run.stability_options) args.insert(args.end(), {o.flag, o.text});
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const std::string err = (out / "stderr.txt").string();
  const pid_t parent = getpid();

  int report[2];
  if (pipe2(report, O_CLOEXEC) != 0) throw std::runtime_error("pipe: " + std::generic_category().message(errno));
  // No signal handler may run in the child before exec (it would act on the sweep's runs).
  sigset_t all, old;
  sigfillset(&all);
  pthread_sigmask(SIG_SETMASK, &all, &old);
  const pid_t pid = fork();
  if (pid == 0) {
    // The child: async-signal-safe calls only, until exec.
    int failure[2] = {0, 0};  // {what failed: 1 stderr.txt, 2 exec, 3 set-up; errno}
    setpgid(0, 0);
    if (prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || getppid() != parent) _exit(127);  // the sweep already ended
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
      struct sigaction a {};
      sigaction(sig, nullptr, &a);
      if (a.sa_handler != SIG_IGN) {
        a.sa_handler = SIG_DFL;
        sigaction(sig, &a, nullptr);
      }
    }
    const int in = open("/dev/null", O_RDWR);
    const int e = open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (e < 0) failure[0] = 1;
    else if (in < 0 || dup2(in, 0) < 0 || dup2(in, 1) < 0 || dup2(e, 2) < 0 || fcntl(lock_fd, F_SETFD, 0) != 0)
      failure[0] = 3;
    if (failure[0] == 0) {
      pthread_sigmask(SIG_SETMASK, &old, nullptr);
      execv(exe.c_str(), argv.data());
      failure[0] = 2;
    }
    failure[1] = errno;
    if (write(report[1], failure, sizeof failure) < 0) _exit(127);
    _exit(127);
  }
  const int fork_errno = errno;
  pthread_sigmask(SIG_SETMASK, &old, nullptr);
  close(report[1]);
  if (pid < 0) {
    close(report[0]);
    throw std::runtime_error("cannot start '" + exe.string() + "': fork: " + std::generic_category().message(fork_errno));
  }
  setpgid(pid, pid);  // as the child does, so that a signal forwarded at once finds the group
  int failure[2] = {0, 0};
  ssize_t got = 0;
  do got = read(report[0], failure, sizeof failure);
  while (got < 0 && errno == EINTR);
  close(report[0]);
  if (got <= 0) return pid;  // exec succeeded (the pipe closed on exec)
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  const std::string why = std::generic_category().message(failure[1]);
  if (failure[0] == 1) throw std::runtime_error("cannot write '" + err + "': " + why);
  throw std::runtime_error("cannot start '" + exe.string() + "': " + why);
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
// A stability search's "summary" is its stability.json: `ricochet stability` exits 0 (bracket
// found), 4 (no bracket) or 5 (no unstable dt up to the cap) after a finished search, whose
// report it writes last.
std::optional<Json> outcome(const Exit& e, const fs::path& dir, RunRecord& rec, bool stability) {
  const std::string line = first_line(dir / "stderr.txt");
  if (e.signaled) {
    rec.status = "failed";
    rec.reason = "killed by signal " + std::to_string(e.code) + " (" + strsignal(e.code) + ")";
    if (!line.empty()) rec.reason += ": " + line;
    return std::nullopt;
  }
  // A finished child: a run exits 0 (ok) or 3 (diverged), a search 0, 4 or 5; its report must
  // then be there and valid.
  const bool finished = stability ? (e.code == 0 || e.code == 4 || e.code == 5) : (e.code == 0 || e.code == 3);
  if (finished) {
    const char* report = stability ? "stability.json" : "summary.json";
    std::string problem;
    try {
      Json s = read_json_file(dir / report);
      problem = stability ? stability_problem(s) : summary_problem(s);
      if (problem.empty()) return s;
    } catch (const JsonParseError& err) {
      problem = err.what();
    }
    rec.status = "failed";
    rec.reason = "exit " + std::to_string(e.code) + " without a valid " + report + ": " + problem;
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

// The pid of the process that holds an flock on the file open as `fd`, from /proc/locks; empty
// if not found.
std::string lock_holder(int fd) {
  struct stat st {};
  if (fstat(fd, &st) != 0) return {};
  char id[64];
  std::snprintf(id, sizeof id, "%02x:%02x:%llu", major(st.st_dev), minor(st.st_dev),
                static_cast<unsigned long long>(st.st_ino));
  std::ifstream locks("/proc/locks");
  for (std::string line; std::getline(locks, line);) {
    std::istringstream in(line);
    std::vector<std::string> f;
    for (std::string w; in >> w;) f.push_back(w);
    // "1: FLOCK  ADVISORY  WRITE 1234 08:01:5678 0 EOF" (a waiter's line has "->" after "1:")
    if (f.size() < 6 || f[1] != "FLOCK") continue;
    if (f[5] == id) return f[4];
  }
  return {};
}

std::string duration_text(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, s < 10.0 ? "%.1f s" : "%.0f s", s);
  return buf;
}

}  // namespace

RunFolderLock::RunFolderLock(const fs::path& folder, double wait, std::ostream& log, const std::string& who)
    : folder_(folder) {
  std::error_code ec;
  fs::create_directories(folder, ec);
  const fs::path p = folder / "run.lock";
  fd_ = ::open(p.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) throw std::runtime_error("cannot write '" + p.string() + "': " + std::generic_category().message(errno));
  if (flock(fd_, LOCK_EX | LOCK_NB) == 0) return;
  auto holder = [&] {
    std::string pid = lock_holder(fd_);
    if (pid.empty()) {  // not in /proc/locks (another pid namespace): the last run started in it
      pid = read_text(p);
      while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
    }
    return pid.empty() || pid.find_first_not_of("0123456789") != std::string::npos ? std::string("another process")
                                                                                   : "process " + pid;
  };
  log << who << ": " << folder.string() << ": still being written by " << holder()
      << " (it holds run.lock); waiting up to " << duration_text(wait) << " for it to end" << std::endl;
  const auto until = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(wait));
  while (Clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (flock(fd_, LOCK_EX | LOCK_NB) == 0) return;
  }
  const std::string who_holds = holder();
  ::close(fd_);
  fd_ = -1;
  throw std::runtime_error(folder.string() + ": still being written by " + who_holds + " after " + duration_text(wait) +
                           " (it holds run.lock: a run of an earlier sweep that did not end); stop it, then resume the sweep");
}

RunFolderLock::RunFolderLock(RunFolderLock&& o) noexcept : folder_(std::move(o.folder_)), fd_(o.fd_) { o.fd_ = -1; }

RunFolderLock& RunFolderLock::operator=(RunFolderLock&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) ::close(fd_);
    folder_ = std::move(o.folder_);
    fd_ = o.fd_;
    o.fd_ = -1;
  }
  return *this;
}

RunFolderLock::~RunFolderLock() {
  if (fd_ >= 0) ::close(fd_);
}

void RunFolderLock::record(long pid) {
  const std::string text = std::to_string(pid) + "\n";
  if (ftruncate(fd_, 0) != 0 || pwrite(fd_, text.data(), text.size(), 0) != static_cast<ssize_t>(text.size())) {
    // Only the messages of a later sweep that finds the folder locked use it.
  }
}

void RunFolderLock::clear_folder() const {
  for (const auto& e : fs::directory_iterator(folder_))
    if (e.path().filename() != "run.lock") fs::remove_all(e.path());
}

void write_failure(const fs::path& folder, const std::string& run_id, const std::string& reason) {
  Json j = Json::object();
  j["run_id"] = run_id;
  j["status"] = "failed";
  j["reason"] = reason;
  j["written_at"] = utc_now();
  write_file_atomic(folder / "failure.json", dump_json(j));
}

std::optional<std::string> read_failure(const fs::path& folder, const std::string& run_id) {
  const fs::path p = folder / "failure.json";
  if (!fs::is_regular_file(p)) return std::nullopt;
  try {
    const Json j = read_json_file(p);
    if (!j.is_object() || !j.contains("run_id") || j.at("run_id") != run_id || !j.contains("status") ||
        j.at("status") != "failed" || !j.contains("reason") || !j.at("reason").is_string())
      return std::nullopt;
    return j.at("reason").get<std::string>();
  } catch (const JsonParseError&) {
    return std::nullopt;
  }
}

struct SweepExecution::Task {
  std::size_t run;
  std::optional<RunFolderLock> lock;  // held from the run's start until it is done
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
      total_(plan.scope_size()),
      done_(done) {}

void SweepExecution::start(Task& t) {
  const fs::path dir = plan_.repeat_dir(t.run, t.k);
  fs::create_directories(dir);
  t.started = Clock::now();
  t.pid = spawn_run(program_, plan_.run(t.run), plan_.threads(t.run), dir, t.lock->fd());
  t.lock->record(t.pid);
}

void SweepExecution::begin(std::size_t i, std::vector<Task>& active) {
  Task t;
  t.run = i;
  t.lock.emplace(plan_.folder(i), options_.writer_wait, *log_, "sweep " + plan_.spec().name);
  t.lock->clear_folder();
  write_file_atomic(plan_.folder(i) / "overrides.json", plan_.request(i));
  records_[i].state = RunRecord::State::active;
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
  try {
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
  } catch (...) {
    // Nothing of this sweep may go on writing after it stopped with an error.
    forwarding.set({});
    for (const Task& t : active)
      if (t.pid > 0) kill(-t.pid, SIGKILL);
    for (const Task& t : active)
      if (t.pid > 0)
        while (waitpid(t.pid, nullptr, 0) < 0 && errno == EINTR) {
        }
    throw;
  }
}

// Either starts the task's next repeat or marks its run done.
void SweepExecution::finish(Task& t, int wait_status) {
  const fs::path dir = plan_.repeat_dir(t.run, t.k);
  RunRecord& rec = records_[t.run];
  const bool stability = plan_.run(t.run).stability;
  const std::optional<Json> s = outcome(decode(wait_status), dir, rec, stability);
  if (s && stability) {
    set_stability_finished(rec, *s);
  } else if (s) {
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
  if (rec.status == "failed") write_failure(plan_.folder(t.run), plan_.run(t.run).id, rec.reason);
  rec.state = RunRecord::State::done;
  ++done_;
  session_wall_ += t.wall;
  ++session_runs_;
}

void SweepExecution::progress(const Task& t) {
  if (options_.quiet) return;
  const RunRecord& rec = records_[t.run];
  const double elapsed = seconds(Clock::now() - start_);
  const std::size_t left_runs = total_ - done_;
  const double left = session_wall_ / static_cast<double>(session_runs_) * static_cast<double>(left_runs) / options_.jobs;
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.2f s", t.wall);
  *log_ << "[" << done_ << "/" << total_ << "] " << plan_.run(t.run).id << " " << rec.status << " wall " << buf
        << " | elapsed " << duration_text(elapsed) << ", left ~" << duration_text(left);
  if (!rec.reason.empty()) *log_ << " | " << rec.reason;
  *log_ << std::endl;
}

}  // namespace ricochet
