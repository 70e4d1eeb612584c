// Sparse Cholesky factorization of the implicit scheme's iteration matrix by SuiteSparse CHOLMOD
// (Debian's libsuitesparse-dev), called through its C interface:
//  - analyze() once per run: fill-reducing ordering (AMD), elimination tree, supernodes and
//    the pattern of L; it also runs a factorization, the solves and a second factorization on a
//    positive definite matrix of the same pattern, so that every block CHOLMOD's numeric phase
//    asks for has been allocated once (see below);
//  - factorize() per refactorization: P A P^T = L L^T (supernodal) or L D L^T (simplicial) into
//    the analysed structure;
//  - solve() per right-hand side: two triangular solves with reused CHOLMOD work vectors.
//
// The matrix is the scheme's full symmetric row-major SparseMatrix (both triangles stored),
// passed to CHOLMOD without a copy: its row-major arrays read as column-major are the same
// (symmetric) matrix, and CHOLMOD with stype = -1 reads only the lower triangle.
//
// Allocation: CHOLMOD allocates temporaries inside cholmod_factorize (the permuted transpose
// of A, the supernodal update matrix) and frees them before it returns. All its allocations go
// through the SuiteSparse_config function pointers, which this file points, once per process,
// at a recycling allocator: a freed block is kept in a list for its exact size and handed back
// on the next request of that size. The numeric phase of a fixed pattern asks for the same
// sizes every time, so after analyze()'s warm-up factorize() and solve() take no memory from the
// heap (tests/solver/linear/test_cholmod_factor.cpp and ImplicitStepsDoNotAllocate count it;
// the supernodal method once CHOLMOD's OpenMP regions run serially, cholmod_factor.cpp). The kept
// blocks (a few times the size of L) are returned to the heap only at process exit.
//
// Why not Eigen's CholmodSupport: its factorize() takes a column-major SparseMatrix (our
// row-major matrix would be copied per factorization) and its solve() allocates a new
// cholmod_dense per call.
#pragma once

#include <Eigen/SparseCore>

#include "solver/linear/single_factor.hpp"

struct cholmod_common_struct;
struct cholmod_factor_struct;
struct cholmod_dense_struct;

namespace ricochet {

class CholmodFactor {
 public:
  using RowMajor = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;
  // Measured on the oblique plate's matrices (docs/implicit.md, "The factorization method"):
  // with Debian's reference BLAS the supernodal method gains nothing (its solve is up to 2.4x
  // slower); with OpenBLAS its factorization is 4-6x faster on M2x4 and the 3D M2x2, its solve
  // as fast there but slower on M2, whose factor is small. The implicit scheme uses automatic.
  enum class Method {
    supernodal,  // L L^T with dense supernode blocks (BLAS)
    simplicial,  // L D L^T column by column, no BLAS
    automatic,   // supernodal with an optimized BLAS (optimized_blas()) where CHOLMOD's analysis
                 // counts at least kSupernodalFlopsPerEntry flops per entry of L; else simplicial
  };
  // 72 on M2 (simplicial measured faster), 116 on M2x2, 210 on M2x4 (supernodal faster).
  static constexpr double kSupernodalFlopsPerEntry = 100.0;
  // OpenBLAS is the process's BLAS (Debian's libopenblas0-serial, which ci/setup installs);
  // its own threads, if it has any, are then set to one.
  static bool optimized_blas();

  // The fill-reducing ordering of analyze() (docs/implicit.md, "The linear solver"):
  enum class Ordering {
    amd,     // approximate minimum degree: cheapest analysis, most fill on large 2D/3D meshes
    metis,   // METIS nested dissection (METIS_NodeND): least fill on meshes of some thousands of nodes up
    nesdis,  // CHOLMOD's own nested dissection (METIS edge separators, constrained minimum degree)
  };

  CholmodFactor();
  ~CholmodFactor();
  CholmodFactor(const CholmodFactor&) = delete;
  CholmodFactor& operator=(const CholmodFactor&) = delete;

  // Symbolic analysis of the pattern of `a` (square, symmetric, both triangles stored,
  // compressed; the pattern must not change afterwards, its values are read by factorize).
  // Allocates. Replaces any previous analysis.
  void analyze(const RowMajor& a, Method method = Method::simplicial, Ordering ordering = Ordering::amd);

  // Numeric factorization of the matrix with a's pattern and the values a_values[0 .. nnz)
  // (same layout as a.valuePtr()). Returns false if it is not positive definite (a pivot not
  // positive; CHOLMOD stops there) or not finite; solve() must not be called after a false.
  bool factorize(const double* a_values);

  // x = A^-1 b with the last successful factorization (size n). x and b may be the same vector.
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);
  // X = A^-1 B for ncol right-hand sides at once (column-major n x ncol arrays, 1 <= ncol <=
  // kMaxBlock; CHOLMOD solves up to four columns in one sweep over L). Allocates nothing (every
  // width is warmed up by analyze()).
  static constexpr int kMaxBlock = 4;
  void solve_block(const double* b, double* x, int ncol);

  // Solves with a single-precision copy of L (single_factor.hpp) instead of CHOLMOD's double
  // one: on, the copy is made now and after every factorize(); off, CHOLMOD solves. The
  // factorization itself is always double. Allocates when turned on.
  void use_single(bool on);
  bool single() const { return use_single_; }
  // The storage a solve reads [bytes]: L's values and row indices, of the single-precision copy
  // when it is used, else of CHOLMOD's factor (supernodal: its blocks and one row list per
  // supernode; simplicial: a row index per entry).
  double solve_bytes() const;

  int size() const { return n_; }
  bool analyzed() const { return factor_ != nullptr; }
  double factor_nonzeros() const;  // entries of L (supernodal: including the zeros of its blocks)
  double factor_flops() const;     // floating-point operations of one factorization (CHOLMOD's count)
  bool supernodal() const;         // the analysed factor is supernodal (Method::automatic's choice)

 private:
  void release();

  cholmod_common_struct* common_ = nullptr;
  cholmod_factor_struct* factor_ = nullptr;
  cholmod_dense_struct* x_ = nullptr;  // solve2's solution and workspaces, reused
  cholmod_dense_struct* y_ = nullptr;
  cholmod_dense_struct* e_ = nullptr;
  cholmod_dense_struct* xb_ = nullptr;  // the same for solve_block
  cholmod_dense_struct* yb_ = nullptr;
  cholmod_dense_struct* eb_ = nullptr;
  SingleFactor single_;
  bool use_single_ = false;
  int n_ = 0;
  long nnz_ = 0;
  const int* outer_ = nullptr;  // the analysed matrix's arrays (read by factorize)
  const int* inner_ = nullptr;
};

}  // namespace ricochet
