#include "solver/linear/cholmod_factor.hpp"

#include <cholmod.h>
#include <dlfcn.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

namespace ricochet {
namespace {

// The recycling allocator behind CHOLMOD (see the header). Each block carries a header with its
// requested size; free() files it in the list for that size (buckets of intrusive lists, no
// bookkeeping memory of its own), malloc() takes from that list first. When every bucket holds
// blocks of other sizes, the least recently used bucket's blocks go back to the heap and the
// bucket takes the new size, so the sizes of the factorizations in use stay cached whatever
// else (analyses, other matrices) went through before. A mutex makes it safe for runs in
// several threads; its lock does not allocate.
struct alignas(std::max_align_t) BlockHeader {
  std::size_t size;
  BlockHeader* next;
};

struct Bucket {
  std::size_t size = 0;
  BlockHeader* head = nullptr;
  unsigned long used = 0;  // tick of the last malloc or free of this size
};

constexpr int kBuckets = 64;  // distinct block sizes kept; one factorization uses < 10
std::array<Bucket, kBuckets> g_buckets;
unsigned long g_tick = 0;
std::mutex g_mutex;

void* recycled_malloc(std::size_t size) {
  if (size == 0) size = 1;
  {
    std::lock_guard<std::mutex> lock(g_mutex);
    ++g_tick;
    for (Bucket& b : g_buckets)
      if (b.size == size) {
        b.used = g_tick;
        if (BlockHeader* h = b.head) {
          b.head = h->next;
          return h + 1;
        }
        break;
      }
  }
  auto* h = static_cast<BlockHeader*>(std::malloc(sizeof(BlockHeader) + size));
  if (!h) return nullptr;
  h->size = size;
  h->next = nullptr;
  return h + 1;
}

void recycled_free(void* p) {
  if (!p) return;
  BlockHeader* h = static_cast<BlockHeader*>(p) - 1;
  BlockHeader* evicted = nullptr;
  {
    std::lock_guard<std::mutex> lock(g_mutex);
    ++g_tick;
    Bucket* target = nullptr;
    Bucket* oldest = &g_buckets[0];
    for (Bucket& b : g_buckets) {
      if (b.size == h->size) {
        target = &b;
        break;
      }
      if (b.used < oldest->used) oldest = &b;
    }
    if (!target) {
      target = oldest;
      evicted = target->head;
      target->size = h->size;
      target->head = nullptr;
    }
    target->used = g_tick;
    h->next = target->head;
    target->head = h;
  }
  while (evicted) {  // outside the lock
    BlockHeader* next = evicted->next;
    std::free(evicted);
    evicted = next;
  }
}

void* recycled_calloc(std::size_t count, std::size_t size) {
  if (size != 0 && count > static_cast<std::size_t>(-1) / size) return nullptr;
  void* p = recycled_malloc(count * size);
  if (p) std::memset(p, 0, count * size);
  return p;
}

void* recycled_realloc(void* p, std::size_t size) {
  if (!p) return recycled_malloc(size);
  const BlockHeader* h = static_cast<BlockHeader*>(p) - 1;
  if (size <= h->size) return p;
  void* q = recycled_malloc(size);
  if (!q) return nullptr;
  std::memcpy(q, p, h->size);
  recycled_free(p);
  return q;
}

// Before the first cholmod_start of the process, so that every block CHOLMOD frees was
// allocated here.
void install_allocator() {
  static std::once_flag once;
  std::call_once(once, [] {
    SuiteSparse_config.malloc_func = recycled_malloc;
    SuiteSparse_config.calloc_func = recycled_calloc;
    SuiteSparse_config.realloc_func = recycled_realloc;
    SuiteSparse_config.free_func = recycled_free;
  });
}

// A (n x n, symmetric, lower triangle read) over the scheme's row-major arrays: row i of the
// row-major matrix is column i of its transpose, which is the matrix itself.
cholmod_sparse view(int n, const int* outer, const int* inner, const double* values) {
  cholmod_sparse a{};
  a.nrow = a.ncol = static_cast<std::size_t>(n);
  a.nzmax = static_cast<std::size_t>(outer[n]);
  a.p = const_cast<int*>(outer);
  a.i = const_cast<int*>(inner);
  a.x = const_cast<double*>(values);
  a.stype = -1;
  a.itype = CHOLMOD_INT;
  a.xtype = CHOLMOD_REAL;
  a.dtype = CHOLMOD_DOUBLE;
  a.sorted = 1;
  a.packed = 1;
  return a;
}

// CHOLMOD's supernodal numeric factorization (Debian's build, with OpenMP) opens parallel
// regions of a fixed 4 threads (`num_threads(CHOLMOD_OMP_NUM_THREADS) if (...)`) to clear and
// fill supernodes, whatever the run's thread count. On a shared 2-core machine their spinning
// made a factorization of the oblique plate's M2x2 3.8x slower. Made inactive
// (max-active-levels 0) they run on one thread, but libgomp still builds, and frees, a team for
// each region it meets (a 1.5 KB memalign in GOMP_parallel, 1878 per three rounds of the
// allocation test), and the implicit scheme must not allocate inside a step. So while a CHOLMOD
// call runs (SerialOpenMP in scope, outside any parallel region), the regions it opens run as a
// plain call of their body on this thread: GOMP_parallel below, which the program defines and
// so is the one libcholmod's calls bind to (an executable's definition comes first), runs
// fn(data) itself; every other region goes to libgomp's GOMP_parallel. A body outside a team
// sees omp_get_num_threads() = 1 and omp_get_thread_num() = 0, so a statically scheduled loop
// (CHOLMOD's are) runs all its iterations, as libgomp's one-thread team would.
thread_local bool t_inline_regions = false;

using GompParallel = void (*)(void (*)(void*), void*, unsigned, unsigned);
// libgomp's own entry point, resolved before main (dlsym may allocate on its first call).
const GompParallel g_libgomp_parallel = reinterpret_cast<GompParallel>(dlsym(RTLD_NEXT, "GOMP_parallel"));

class SerialOpenMP {
 public:
#ifdef _OPENMP
  SerialOpenMP() : levels_(omp_get_max_active_levels()), inline_(omp_get_level() == 0) {
    omp_set_max_active_levels(0);
    t_inline_regions = inline_;
  }
  ~SerialOpenMP() {
    t_inline_regions = false;
    omp_set_max_active_levels(levels_);
  }

 private:
  int levels_;
  bool inline_;
#endif
};

// Whether the BLAS in the process is OpenBLAS (Debian's libopenblas0-serial or -pthread behind
// libblas.so.3): its symbol is then visible. OpenBLAS's own threads, if any, are set to one.
bool find_optimized_blas() {
  using SetThreads = void (*)(int);
  if (auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"))) set(1);
  return dlsym(RTLD_DEFAULT, "openblas_get_config") != nullptr;
}

}  // namespace

CholmodFactor::CholmodFactor() {
  install_allocator();
  common_ = new cholmod_common;
  cholmod_start(common_);
  common_->print = 0;  // a non-positive-definite matrix is an expected outcome, not a message
  // One ordering, the one analyze() is given: deterministic (CHOLMOD's default would try
  // several and keep the one of least fill).
  common_->nmethods = 1;
  common_->postorder = 1;
}

CholmodFactor::~CholmodFactor() {
  release();
  cholmod_finish(common_);
  delete common_;
}

void CholmodFactor::use_single(bool on) {
  use_single_ = on && factor_ != nullptr;
  if (!use_single_) return;
  single_.reserve(factor_);
  single_.copy(factor_);
}

void CholmodFactor::release() {
  use_single_ = false;
  if (factor_) cholmod_free_factor(&factor_, common_);
  for (cholmod_dense** d : {&x_, &y_, &e_, &xb_, &yb_, &eb_})
    if (*d) cholmod_free_dense(d, common_);
}

void CholmodFactor::analyze(const RowMajor& a, Method method, Ordering ordering) {
  if (a.rows() != a.cols() || !a.isCompressed())
    throw std::invalid_argument("CholmodFactor::analyze: needs a square compressed matrix");
  release();
  n_ = static_cast<int>(a.rows());
  nnz_ = a.nonZeros();
  outer_ = a.outerIndexPtr();
  inner_ = a.innerIndexPtr();
  common_->method[0].ordering = ordering == Ordering::amd     ? CHOLMOD_AMD
                                : ordering == Ordering::metis ? CHOLMOD_METIS
                                                              : CHOLMOD_NESDIS;
  // automatic: CHOLMOD's own rule (supernodal when its analysis counts at least
  // supernodal_switch flops per entry of L), with an optimized BLAS only.
  common_->supernodal = method == Method::supernodal   ? CHOLMOD_SUPERNODAL
                        : method == Method::simplicial ? CHOLMOD_SIMPLICIAL
                        : optimized_blas()             ? CHOLMOD_AUTO
                                                       : CHOLMOD_SIMPLICIAL;
  common_->supernodal_switch = kSupernodalFlopsPerEntry;
  // Simplicial: keep L D L^T (no square roots); supernodal is L L^T by construction.
  common_->final_ll = 0;
  cholmod_sparse s = view(n_, outer_, inner_, a.valuePtr());
  {
    SerialOpenMP serial;
    factor_ = cholmod_analyze(&s, common_);
  }
  if (!factor_ || common_->status < CHOLMOD_OK)
    throw std::runtime_error("CHOLMOD analysis failed (status " + std::to_string(common_->status) + ")");
  // Warm-up on the identity with this pattern (positive definite whatever the pattern): the
  // numeric phase and the solve allocate their blocks here, once.
  std::vector<double> identity(static_cast<std::size_t>(nnz_), 0.0);
  for (int r = 0; r < n_; ++r)
    for (int q = outer_[r]; q < outer_[r + 1]; ++q)
      if (inner_[q] == r) identity[static_cast<std::size_t>(q)] = 1.0;
  if (!factorize(identity.data())) throw std::runtime_error("CHOLMOD warm-up factorization failed");
  Eigen::VectorXd b = Eigen::VectorXd::Ones(n_), x(n_);
  solve(b, x);
  // The block solves of the implicit contact problem (1 to kMaxBlock columns): each size once,
  // so that the recycling allocator holds the blocks of all of them.
  std::vector<double> bb(kMaxBlock * static_cast<std::size_t>(n_), 1.0), xb(bb.size());
  for (int ncol = kMaxBlock; ncol >= 1; --ncol) solve_block(bb.data(), xb.data(), ncol);
  // Once more: the solves kept the blocks the first factorization freed where their sizes
  // matched (the supernodal method's workspace header is a cholmod_dense, as are the solves'),
  // so the factorization's own are in the lists only after a second one.
  if (!factorize(identity.data())) throw std::runtime_error("CHOLMOD warm-up factorization failed");
}

bool CholmodFactor::factorize(const double* a_values) {
  cholmod_sparse s = view(n_, outer_, inner_, a_values);
  int ok;
  {
    SerialOpenMP serial;
    ok = cholmod_factorize(&s, factor_, common_);
  }
  // L L^T (supernodal) stops at the first pivot that is not positive (status CHOLMOD_NOT_POSDEF,
  // minor < n); a NaN pivot also fails that test. L D L^T (simplicial) stops only at a zero
  // pivot: it factorizes indefinite matrices, so D is checked here (D_jj is the first entry of
  // column j of the simplicial factor).
  if (!ok || common_->status != CHOLMOD_OK || factor_->minor != factor_->n) return false;
  if (!factor_->is_super && !factor_->is_ll) {
    const int* p = static_cast<const int*>(factor_->p);
    const double* x = static_cast<const double*>(factor_->x);
    for (int j = 0; j < n_; ++j)
      if (!(x[p[j]] > 0.0) || !std::isfinite(x[p[j]])) return false;
  }
  // OpenBLAS's dpotrf passes a NaN pivot (its test "not positive" is false for NaN), so the
  // supernodal blocks are checked here: O(nnz(L)) against the factorization's O(flops).
  if (factor_->is_super) {
    const double* x = static_cast<const double*>(factor_->x);
    for (std::size_t k = 0; k < factor_->xsize; ++k)
      if (!std::isfinite(x[k])) return false;
  }
  if (use_single_) single_.copy(factor_);
  return true;
}

void CholmodFactor::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  if (use_single_) {
    x.resize(n_);
    single_.solve(b.data(), x.data(), 1);
    return;
  }
  cholmod_dense rhs{};
  rhs.nrow = static_cast<std::size_t>(n_);
  rhs.ncol = 1;
  rhs.nzmax = static_cast<std::size_t>(n_);
  rhs.d = static_cast<std::size_t>(n_);
  rhs.x = const_cast<double*>(b.data());
  rhs.xtype = CHOLMOD_REAL;
  rhs.dtype = CHOLMOD_DOUBLE;
  SerialOpenMP serial;
  if (!cholmod_solve2(CHOLMOD_A, factor_, &rhs, nullptr, &x_, nullptr, &y_, &e_, common_))
    throw std::runtime_error("CHOLMOD solve failed (status " + std::to_string(common_->status) + ")");
  x = Eigen::Map<const Eigen::VectorXd>(static_cast<const double*>(x_->x), n_);
}

void CholmodFactor::solve_block(const double* b, double* x, int ncol) {
  if (ncol < 1 || ncol > kMaxBlock) throw std::invalid_argument("CholmodFactor::solve_block: ncol out of range");
  if (use_single_) {
    single_.solve(b, x, ncol);
    return;
  }
  cholmod_dense rhs{};
  rhs.nrow = static_cast<std::size_t>(n_);
  rhs.ncol = static_cast<std::size_t>(ncol);
  rhs.nzmax = static_cast<std::size_t>(n_) * static_cast<std::size_t>(ncol);
  rhs.d = static_cast<std::size_t>(n_);
  rhs.x = const_cast<double*>(b);
  rhs.xtype = CHOLMOD_REAL;
  rhs.dtype = CHOLMOD_DOUBLE;
  SerialOpenMP serial;
  if (!cholmod_solve2(CHOLMOD_A, factor_, &rhs, nullptr, &xb_, nullptr, &yb_, &eb_, common_))
    throw std::runtime_error("CHOLMOD solve failed (status " + std::to_string(common_->status) + ")");
  std::memcpy(x, xb_->x, sizeof(double) * static_cast<std::size_t>(n_) * static_cast<std::size_t>(ncol));
}

double CholmodFactor::factor_nonzeros() const { return common_->lnz; }
double CholmodFactor::solve_bytes() const {
  if (use_single_) return single_.bytes();
  if (factor_ == nullptr) return 0.0;
  if (factor_->is_super)
    return static_cast<double>(factor_->xsize) * sizeof(double) + static_cast<double>(factor_->ssize) * sizeof(int);
  return static_cast<double>(factor_->nzmax) * (sizeof(double) + sizeof(int));
}
bool CholmodFactor::supernodal() const { return factor_ != nullptr && factor_->is_super; }

bool CholmodFactor::optimized_blas() {
  static const bool found = find_optimized_blas();
  return found;
}
double CholmodFactor::factor_flops() const { return common_->fl; }

}  // namespace ricochet

// See SerialOpenMP above. The signature is libgomp's (GOMP_4.0, gcc >= 4.9).
extern "C" void GOMP_parallel(void (*fn)(void*), void* data, unsigned num_threads, unsigned flags) {
  if (ricochet::t_inline_regions) {
    fn(data);
    return;
  }
  ricochet::g_libgomp_parallel(fn, data, num_threads, flags);
}
