// The implicit scheme's direct solver (solver/linear/cholmod_factor.hpp, CHOLMOD): solutions of
// iteration matrices against a dense factorization with both methods, the fill against the
// dense triangle, the indefinite-matrix report and a clean refactorization after it, the
// single-precision copy of L (single_factor.hpp), and no allocation by factorize() and solve()
// after analyze().
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "solver/forces/tangent.hpp"
#include "solver/linear/cholmod_factor.hpp"
#include "tests/support/verification_meshes.hpp"
// Last: it declares the C allocation functions that Eigen's headers declare differently.
#include "tests/support/alloc_counter.hpp"

namespace ricochet {
namespace {

using RowMajor = CholmodFactor::RowMajor;
using Method = CholmodFactor::Method;
using verification::ElementKind;

// The implicit scheme's iteration matrix M + s K_T of a distorted, pre-deformed mesh: the
// pattern and the values the factorization meets in a run. s = 0 gives the (diagonal) mass.
RowMajor iteration_matrix(ElementKind kind, double k_scale, int nx = 9, int ny = 4) {
  const Mesh mesh = verification::grid_mesh(2.0, 0.8, nx, ny, 0.2, kind);
  const Model<2> model = verification::single_body_model(
      mesh, StVenantKirchhoff::make(2.0e11, 0.3, 7800.0, PlaneMode::strain), PlaneMode::strain, kind);
  SystemMatrix s = make_system_matrix(model);
  Eigen::VectorXd u(model.num_dofs()), v = Eigen::VectorXd::Zero(model.num_dofs()), f(model.num_dofs());
  for (int i = 0; i < model.num_dofs(); ++i) u[i] = 1e-3 * std::sin(0.7 * i + 0.2);
  assemble_system(model, u.data(), v.data(), 1.0, k_scale, 0.0, s, f.data(), false);
  return s.matrix;
}

Eigen::VectorXd rhs(int n) {
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) b[i] = std::cos(1.3 * i) + 0.1 * i;
  return b;
}

const char* method_name(Method m) { return m == Method::supernodal ? "supernodal" : "simplicial"; }

void expect_solves(const RowMajor& a, Method method, const char* what) {
  SCOPED_TRACE(std::string(what) + ", " + method_name(method));
  CholmodFactor f;
  f.analyze(a, method);
  ASSERT_TRUE(f.factorize(a.valuePtr()));
  const Eigen::VectorXd b = rhs(static_cast<int>(a.rows()));
  Eigen::VectorXd x;
  f.solve(b, x);
  const Eigen::MatrixXd dense = Eigen::MatrixXd(a);
  const Eigen::VectorXd ref = dense.ldlt().solve(b);
  // Backward error at round-off, and the same solution as the dense factorization.
  EXPECT_LE((dense * x - b).norm(), 1e-13 * b.norm() * dense.norm());
  EXPECT_LE((x - ref).norm(), 1e-10 * ref.norm());
  // In place: x and b the same vector.
  Eigen::VectorXd y = b;
  f.solve(y, y);
  EXPECT_EQ((y - x).norm(), 0.0);
}

TEST(CholmodFactor, SolvesIterationMatrices) {
  for (Method m : {Method::supernodal, Method::simplicial}) {
    expect_solves(iteration_matrix(ElementKind::q4_full, 1e-8), m, "q4 2x2, stiffness-dominated");
    expect_solves(iteration_matrix(ElementKind::t3, 1e-8), m, "t3, stiffness-dominated");
    expect_solves(iteration_matrix(ElementKind::q4_viscous, 1e-12), m, "q4 one-point, mass-dominated");
    expect_solves(iteration_matrix(ElementKind::q4_full, 0.0), m, "mass only (diagonal)");
    expect_solves(iteration_matrix(ElementKind::q4_full, 1e-8, 40, 12), m, "q4 2x2, 40 x 12 cells");
  }
}

// The single-precision copy of L (single_factor.hpp): its solution is the double factor's to
// float round-off times the conditioning (the matrices here have condition numbers up to about
// 1e4), the block solve gives each column's single solve, and turning it off gives CHOLMOD's
// double solution again, bit for bit. After a refactorization the copy follows the new factor.
void expect_single_solves(const RowMajor& a, Method method, const char* what) {
  SCOPED_TRACE(std::string(what) + ", " + method_name(method));
  CholmodFactor f;
  f.analyze(a, method);
  ASSERT_TRUE(f.factorize(a.valuePtr()));
  const int n = static_cast<int>(a.rows());
  const Eigen::VectorXd b = rhs(n);
  Eigen::VectorXd exact, x;
  f.solve(b, exact);
  f.use_single(true);
  ASSERT_TRUE(f.single());
  f.solve(b, x);
  const double difference = (x - exact).norm() / exact.norm();
  EXPECT_LE(difference, 1e-4);
  EXPECT_GT(difference, 0.0);  // the copy is used, and is not exact
  // Four right-hand sides in one sweep: each column as its own solve.
  Eigen::MatrixXd bb(n, 4), xb(n, 4);
  for (int c = 0; c < 4; ++c) bb.col(c) = b * (c + 1.0) + Eigen::VectorXd::LinSpaced(n, 0.0, c);
  for (int ncol = 1; ncol <= 4; ++ncol) {
    f.solve_block(bb.data(), xb.data(), ncol);
    for (int c = 0; c < ncol; ++c) {
      Eigen::VectorXd one;
      f.solve(bb.col(c), one);
      EXPECT_LE((xb.col(c) - one).norm(), 1e-14 * one.norm()) << ncol << " columns, column " << c;
    }
  }
  // A refactorization with other values: the copy is of the new factor.
  std::vector<double> twice(a.valuePtr(), a.valuePtr() + a.nonZeros());
  for (double& v : twice) v *= 2.0;
  ASSERT_TRUE(f.factorize(twice.data()));
  f.solve(b, x);
  EXPECT_LE((2.0 * x - exact).norm(), 1e-4 * exact.norm());
  ASSERT_TRUE(f.factorize(a.valuePtr()));
  f.use_single(false);
  f.solve(b, x);
  EXPECT_EQ((x - exact).norm(), 0.0);
}

TEST(CholmodFactor, SinglePrecisionCopySolves) {
  for (Method m : {Method::supernodal, Method::simplicial}) {
    expect_single_solves(iteration_matrix(ElementKind::q4_full, 1e-8), m, "q4 2x2, stiffness-dominated");
    expect_single_solves(iteration_matrix(ElementKind::t3, 1e-8), m, "t3, stiffness-dominated");
    expect_single_solves(iteration_matrix(ElementKind::q4_full, 1e-8, 40, 12), m, "q4 2x2, 40 x 12 cells");
  }
}

TEST(CholmodFactor, FillIsReducedByTheOrdering) {
  // A long strip numbered along its length has a wide band; AMD keeps L far below the dense
  // lower triangle.
  const RowMajor a = iteration_matrix(ElementKind::q4_full, 1e-8, 40, 3);
  CholmodFactor f;
  f.analyze(a, Method::simplicial);
  const double n = static_cast<double>(a.rows());
  EXPECT_LT(f.factor_nonzeros(), n * (n + 1) / 2 / 10);
  EXPECT_GE(f.factor_nonzeros(), static_cast<double>(a.nonZeros() + a.rows()) / 2);  // A's lower pattern
}

TEST(CholmodFactor, ReportsIndefiniteAndRecovers) {
  for (Method m : {Method::supernodal, Method::simplicial}) {
    SCOPED_TRACE(method_name(m));
    const RowMajor a = iteration_matrix(ElementKind::q4_full, 1e-8);
    const int n = static_cast<int>(a.rows());
    std::vector<double> values(a.valuePtr(), a.valuePtr() + a.nonZeros());
    std::vector<int> diagonal(n);
    for (int r = 0; r < n; ++r)
      for (int q = a.outerIndexPtr()[r]; q < a.outerIndexPtr()[r + 1]; ++q)
        if (a.innerIndexPtr()[q] == r) diagonal[r] = q;
    CholmodFactor f;
    f.analyze(a, m);
    // Subtracting 2 x the largest diagonal entry from one diagonal entry makes A indefinite.
    double largest = 0.0;
    for (int i = 0; i < n; ++i) largest = std::max(largest, values[diagonal[i]]);
    std::vector<double> bad = values;
    bad[diagonal[n / 2]] -= 2.0 * largest;
    EXPECT_FALSE(f.factorize(bad.data()));
    std::vector<double> zero(values.size(), 0.0);
    EXPECT_FALSE(f.factorize(zero.data()));
    std::vector<double> nan = values;
    nan[diagonal[0]] = std::nan("");
    EXPECT_FALSE(f.factorize(nan.data()));
    // The next factorization starts clean: the same solution as a fresh object.
    ASSERT_TRUE(f.factorize(values.data()));
    CholmodFactor fresh;
    fresh.analyze(a, m);
    ASSERT_TRUE(fresh.factorize(values.data()));
    const Eigen::VectorXd b = rhs(n);
    Eigen::VectorXd x, y;
    f.solve(b, x);
    fresh.solve(b, y);
    EXPECT_EQ((x - y).norm(), 0.0);
  }
}

// CHOLMOD allocates temporaries in every numeric factorization; after analyze() they come from
// the recycling allocator (cholmod_factor.hpp), not the heap. Also after a failed
// factorization, and with two factors alive at once. Both methods: the supernodal one made
// 1852 heap allocations over these three rounds while CHOLMOD's OpenMP regions ran threaded
// (libgomp's team), none since they run serially.
TEST(CholmodFactor, FactorizeAndSolveDoNotAllocate) {
  const RowMajor a = iteration_matrix(ElementKind::q4_full, 1e-8, 30, 10);
  const RowMajor a2 = iteration_matrix(ElementKind::t3, 1e-8, 12, 5);
  for (Method m : {Method::simplicial, Method::supernodal}) {
    SCOPED_TRACE(method_name(m));
    CholmodFactor f, g;
    f.analyze(a, m);
    g.analyze(a2, m);
    g.use_single(true);  // its copy is made again by every factorization
    const Eigen::VectorXd b = rhs(static_cast<int>(a.rows())), b2 = rhs(static_cast<int>(a2.rows()));
    Eigen::VectorXd x(a.rows()), x2(a2.rows());
    std::vector<double> zero(static_cast<std::size_t>(a.nonZeros()), 0.0);
    const long before = g_allocations.load();
    for (int n = 0; n < 3; ++n) {
      EXPECT_FALSE(f.factorize(zero.data()));
      ASSERT_TRUE(f.factorize(a.valuePtr()));
      f.solve(b, x);
      ASSERT_TRUE(g.factorize(a2.valuePtr()));
      g.solve(b2, x2);
    }
    EXPECT_EQ(g_allocations.load() - before, 0);
    EXPECT_TRUE(x.allFinite());
    EXPECT_GT(x.norm(), 0.0);
    EXPECT_GT(x2.norm(), 0.0);
  }
}

TEST(CholmodFactor, AutomaticMethodIsSupernodalOnlyForLargeFactorsWithAnOptimizedBlas) {
  // Method::automatic: CHOLMOD's analysis decides with supernodal_switch =
  // kSupernodalFlopsPerEntry, and only where OpenBLAS is the process's BLAS (ci/setup installs
  // it); with the reference BLAS the supernodal method gained nothing (docs/implicit.md).
  std::printf("[cholmod] optimized BLAS (OpenBLAS): %s\n", CholmodFactor::optimized_blas() ? "yes" : "no");
  const RowMajor small = iteration_matrix(ElementKind::q4_full, 1e-8, 12, 4);
  const RowMajor large = iteration_matrix(ElementKind::q4_full, 1e-8, 240, 60);
  for (const RowMajor* a : {&small, &large}) {
    CholmodFactor probe;
    probe.analyze(*a, Method::simplicial);
    const double per_entry = probe.factor_flops() / probe.factor_nonzeros();
    CholmodFactor f;
    f.analyze(*a, Method::automatic);
    SCOPED_TRACE("flops per entry of L: " + std::to_string(per_entry));
    EXPECT_EQ(f.supernodal(), CholmodFactor::optimized_blas() && per_entry >= CholmodFactor::kSupernodalFlopsPerEntry);
    ASSERT_TRUE(f.factorize(a->valuePtr()));
    const Eigen::VectorXd b = rhs(static_cast<int>(a->rows()));
    Eigen::VectorXd x;
    f.solve(b, x);
    EXPECT_LE((*a * x - b).norm(), 1e-13 * a->norm() * x.norm());  // backward error at round-off
  }
  CholmodFactor s, t;
  s.analyze(small, Method::supernodal);
  t.analyze(small, Method::simplicial);
  EXPECT_TRUE(s.supernodal());
  EXPECT_FALSE(t.supernodal());
}

}  // namespace
}  // namespace ricochet
