// The implicit scheme's sparse LDL^T (solver/linear/sparse_ldlt.hpp): solutions against a dense
// factorization, the fill against Eigen's SimplicialLDLT with the same AMD ordering, the
// indefinite-matrix report and a clean retry after it, and no allocation after analyze().
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <cmath>
#include <vector>

#include "solver/linear/sparse_ldlt.hpp"
#include "solver/elements/tangent.hpp"
#include "verification_meshes.hpp"
// Last: it declares the C allocation functions that Eigen's headers declare differently.
#include "alloc_counter.hpp"

namespace ricochet {
namespace {

using RowMajor = SparseLdlt::RowMajor;
using verification::ElementKind;

// The implicit scheme's iteration matrix M + s K_T of a distorted, pre-deformed mesh: the
// pattern and the values the factorization meets in a run. s = 0 gives the (diagonal) mass.
RowMajor iteration_matrix(ElementKind kind, double k_scale, int nx = 9, int ny = 4) {
  const Mesh mesh = verification::grid_mesh(2.0, 0.8, nx, ny, 0.2, kind);
  const Model model = verification::single_body_model(
      mesh, StVenantKirchhoff::make(2.0e11, 0.3, 7800.0, PlaneMode::strain), PlaneMode::strain, kind);
  SystemMatrix s = make_system_matrix(model);
  Eigen::VectorXd u(model.num_dofs()), v = Eigen::VectorXd::Zero(model.num_dofs()), f(model.num_dofs());
  for (int i = 0; i < model.num_dofs(); ++i) u[i] = 1e-3 * std::sin(0.7 * i + 0.2);
  assemble_system(model, u.data(), v.data(), 1.0, k_scale, 0.0, s, f.data(), false);
  return s.matrix;
}

// A structurally symmetric matrix with an irregular pattern (a ring with random chords) and
// a dominant diagonal: symmetric positive definite.
RowMajor irregular_spd(int n) {
  std::vector<Eigen::Triplet<double>> t;
  unsigned state = 12345u;
  auto next = [&] { return (state = state * 1103515245u + 12345u) % 65536u / 65536.0; };
  for (int i = 0; i < n; ++i) {
    const int j = (i + 1) % n, c = static_cast<int>(next() * n);
    for (int other : {j, c}) {
      if (other == i) continue;
      const double w = -0.5 - next();
      t.emplace_back(i, other, w);
      t.emplace_back(other, i, w);
    }
  }
  RowMajor a(n, n);
  a.setFromTriplets(t.begin(), t.end());
  Eigen::VectorXd row_sum = Eigen::VectorXd::Zero(n);
  for (int r = 0; r < n; ++r)
    for (RowMajor::InnerIterator it(a, r); it; ++it) row_sum[r] += std::abs(it.value());
  for (int i = 0; i < n; ++i) a.coeffRef(i, i) = row_sum[i] + 0.1 + next();
  a.makeCompressed();
  return a;
}

Eigen::VectorXd rhs(int n) {
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) b[i] = std::cos(1.3 * i) + 0.1 * i;
  return b;
}

void expect_solves(const RowMajor& a, const char* what) {
  SCOPED_TRACE(what);
  SparseLdlt ldlt;
  ldlt.analyze(a);
  ASSERT_TRUE(ldlt.factorize(a.valuePtr()));
  const Eigen::VectorXd b = rhs(static_cast<int>(a.rows()));
  Eigen::VectorXd x;
  ldlt.solve(b, x);
  const Eigen::MatrixXd dense = Eigen::MatrixXd(a);
  const Eigen::VectorXd ref = dense.ldlt().solve(b);
  EXPECT_LE((dense * x - b).norm(), 1e-13 * b.norm() * dense.norm());
  EXPECT_LE((x - ref).norm(), 1e-10 * ref.norm());
  // In place: x and b the same vector.
  Eigen::VectorXd y = b;
  ldlt.solve(y, y);
  EXPECT_EQ((y - x).norm(), 0.0);
  // The same ordering and the same up-looking algorithm as Eigen's SimplicialLDLT: the same
  // number of entries in L, and the same solution to round-off.
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> eigen(Eigen::SparseMatrix<double>(a.transpose()));
  ASSERT_EQ(eigen.info(), Eigen::Success);
  EXPECT_EQ(ldlt.factor_nonzeros(), eigen.matrixL().nestedExpression().nonZeros());
  EXPECT_LE((x - eigen.solve(b)).norm(), 1e-12 * ref.norm());
  EXPECT_GT(ldlt.min_pivot(), 0.0);
}

TEST(SparseLdlt, SolvesIterationMatrices) {
  expect_solves(iteration_matrix(ElementKind::q4_full, 1e-8), "q4 2x2, stiffness-dominated");
  expect_solves(iteration_matrix(ElementKind::t3, 1e-8), "t3, stiffness-dominated");
  expect_solves(iteration_matrix(ElementKind::q4_viscous, 1e-12), "q4 one-point, mass-dominated");
  expect_solves(iteration_matrix(ElementKind::q4_full, 0.0), "mass only (diagonal)");
  expect_solves(irregular_spd(300), "irregular pattern");
}

TEST(SparseLdlt, FillIsReducedByTheOrdering) {
  // A long strip numbered along its length has a wide band; AMD keeps L far below the dense
  // lower triangle.
  const RowMajor a = iteration_matrix(ElementKind::q4_full, 1e-8, 40, 3);
  SparseLdlt ldlt;
  ldlt.analyze(a);
  const long n = a.rows();
  EXPECT_LT(ldlt.factor_nonzeros(), n * (n - 1) / 2 / 10);
  EXPECT_GE(ldlt.factor_nonzeros(), (a.nonZeros() - n) / 2);  // L holds at least A's lower pattern
}

TEST(SparseLdlt, ReportsIndefiniteAndRecovers) {
  RowMajor a = iteration_matrix(ElementKind::q4_full, 1e-8);
  const int n = static_cast<int>(a.rows());
  std::vector<double> values(a.valuePtr(), a.valuePtr() + a.nonZeros());
  std::vector<int> diagonal(n);
  for (int r = 0; r < n; ++r)
    for (int q = a.outerIndexPtr()[r]; q < a.outerIndexPtr()[r + 1]; ++q)
      if (a.innerIndexPtr()[q] == r) diagonal[r] = q;
  SparseLdlt ldlt;
  ldlt.analyze(a);
  // Subtracting 2 x the largest diagonal entry from one diagonal entry makes A indefinite.
  double largest = 0.0;
  for (int i = 0; i < n; ++i) largest = std::max(largest, values[diagonal[i]]);
  std::vector<double> bad = values;
  bad[diagonal[n / 2]] -= 2.0 * largest;
  EXPECT_FALSE(ldlt.factorize(bad.data()));
  std::vector<double> zero(values.size(), 0.0);
  EXPECT_FALSE(ldlt.factorize(zero.data()));
  // The next factorization starts clean: same solution as a fresh object.
  ASSERT_TRUE(ldlt.factorize(values.data()));
  SparseLdlt fresh;
  fresh.analyze(a);
  ASSERT_TRUE(fresh.factorize(values.data()));
  const Eigen::VectorXd b = rhs(n);
  Eigen::VectorXd x, y;
  ldlt.solve(b, x);
  fresh.solve(b, y);
  EXPECT_EQ((x - y).norm(), 0.0);
}

TEST(SparseLdlt, FactorizeAndSolveDoNotAllocate) {
  const RowMajor a = iteration_matrix(ElementKind::q4_full, 1e-8, 30, 10);
  SparseLdlt ldlt;
  ldlt.analyze(a);
  const Eigen::VectorXd b = rhs(static_cast<int>(a.rows()));
  Eigen::VectorXd x(a.rows());
  const long before = g_allocations.load();
  for (int n = 0; n < 3; ++n) {
    ASSERT_TRUE(ldlt.factorize(a.valuePtr()));
    ldlt.solve(b, x);
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_TRUE(x.allFinite());
  EXPECT_GT(x.norm(), 0.0);
}

}  // namespace
}  // namespace ricochet
