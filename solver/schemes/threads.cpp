#include "solver/schemes/threads.hpp"

#include <omp.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace ricochet {

int resolve_threads(int requested) {
  if (requested < 0)
    throw std::invalid_argument("threads: expected 0 (all cores) or a count >= 1; got " + std::to_string(requested));
  const int n = requested == 0 ? omp_get_num_procs() : requested;
  return std::clamp(n, 1, kMaxThreads);
}

ThreadScope::ThreadScope(int requested) : threads_(resolve_threads(requested)), previous_(omp_get_max_threads()) {
  omp_set_num_threads(threads_);
}

ThreadScope::~ThreadScope() { omp_set_num_threads(previous_); }

}  // namespace ricochet
