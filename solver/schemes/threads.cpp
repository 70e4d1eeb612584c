#include "solver/schemes/threads.hpp"

#include <fcntl.h>
#include <omp.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace ricochet {
namespace {

// Reads the file at `path` into `buf` (NUL-terminated); the bytes read, or -1. No allocation.
long read_small_file(const char* path, char* buf, long size) {
  const int fd = ::open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return -1;
  const long n = ::read(fd, buf, static_cast<std::size_t>(size - 1));
  ::close(fd);
  if (n < 0) return -1;
  buf[n] = '\0';
  return n;
}

// The kernel's runnable tasks, all processes: the numerator of /proc/loadavg's fourth field
// ("0.52 0.58 0.59 3/812 12345": 3 runnable of 812). -1 when it cannot be read.
long runnable_tasks() {
  char buf[256];
  if (read_small_file("/proc/loadavg", buf, sizeof buf) <= 0) return -1;
  const char* p = buf;
  for (int field = 0; field < 3; ++field) {
    while (*p && *p != ' ') ++p;
    while (*p == ' ') ++p;
  }
  char* end = nullptr;
  const long n = std::strtol(p, &end, 10);
  return end != p && *end == '/' ? n : -1;
}

// Whether thread `tid` of this process is runnable (state R in /proc/self/task/TID/stat).
bool thread_runnable(int tid) {
  char path[64];
  std::snprintf(path, sizeof path, "/proc/self/task/%d/stat", tid);
  char buf[512];
  if (read_small_file(path, buf, sizeof buf) <= 0) return false;
  // "TID (comm) S ...": the state follows the last ')' (comm may hold spaces and parentheses).
  const char* close = nullptr;
  for (const char* p = buf; *p; ++p)
    if (*p == ')') close = p;
  return close && close[1] == ' ' && close[2] == 'R';
}

}  // namespace

int resolve_threads(int requested) {
  if (requested < 0)
    throw std::invalid_argument("threads: expected 0 (all cores) or a count >= 1; got " + std::to_string(requested));
  const int n = requested == 0 ? omp_get_num_procs() : requested;
  return std::clamp(n, 1, kMaxThreads);
}

int other_runnable_tasks(const std::vector<int>& own_tids) {
  const long all = runnable_tasks();
  if (all < 0) return -1;
  long own = 1;  // the calling thread, running while it reads
  for (std::size_t i = 1; i < own_tids.size(); ++i) own += thread_runnable(own_tids[i]);
  return static_cast<int>(std::max(0L, all - own));
}

ThreadScope::ThreadScope(int requested, bool adapt)
    : threads_(resolve_threads(requested)),
      previous_(omp_get_max_threads()),
      adapting_(adapt && threads_ > 1),
      now_(threads_),
      min_used_(threads_),
      cores_(omp_get_num_procs()) {
  omp_set_num_threads(threads_);
  if (!adapting_) return;
  // The team's thread ids, once: libgomp keeps its pool's threads in team order from one
  // parallel region to the next, so team member i is the same thread for the whole run.
  tids_.assign(static_cast<std::size_t>(threads_), 0);
#pragma omp parallel num_threads(threads_)
  tids_[static_cast<std::size_t>(omp_get_thread_num())] = static_cast<int>(::syscall(SYS_gettid));
  refit();
}

ThreadScope::~ThreadScope() { omp_set_num_threads(previous_); }

void ThreadScope::refit() {
  next_check_ = std::chrono::steady_clock::now() + kAdaptInterval;
  const int others = other_runnable_tasks(tids_);
  if (others < 0) {
    adapting_ = false;  // no load to read: the requested count stays
    return;
  }
  // Cores free of other work: the machine's online cores less the others' runnable tasks
  // (/proc/loadavg counts the whole machine, also where this process may use fewer cores).
  const long online = ::sysconf(_SC_NPROCESSORS_ONLN);
  const long free = std::min<long>(cores_, (online > 0 ? online : cores_) - others);
  const int fit = static_cast<int>(std::clamp<long>(free, 1, threads_));
  if (fit < now_ || (fit > now_ && ++free_streak_ >= 2)) {
    now_ = fit;
    omp_set_num_threads(now_);
  }
  if (fit <= now_) free_streak_ = 0;
  min_used_ = std::min(min_used_, now_);
}

}  // namespace ricochet
