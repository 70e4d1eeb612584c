// The implicit scheme's condensed contact problem (solver/contact/condensed_contact.hpp) on a
// small dense symmetric positive definite A, in 2D and 3D, with and without friction, with a
// stencil of several nodes: the reactions solve the contact law on the true W = c dt H A^-1 H^T
// (checked through the response: x = x_free + c H y with y = A^-1 dt H^T R computed here
// directly), and the node cache makes the solves it promises (none for a repeated call on the
// same factor, new ones after a direction turns or the factor changes).
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <random>

#include "solver/contact/condensed_contact.hpp"

namespace ricochet {
namespace {

template <int D>
struct Problem {
  using Vec = VecD<D>;
  using Local = typename Space<D>::Local;
  static constexpr int kNodes = 7;
  static constexpr int n = D * kNodes;

  Eigen::MatrixXd a;
  Eigen::LLT<Eigen::MatrixXd> llt;
  ContactSetT<D> cs;
  int solves = 0, block_solves = 0, block_columns = 0;

  explicit Problem(double mu) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::MatrixXd b(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) b(i, j) = u(rng);
    a = b * b.transpose() + n * Eigen::MatrixXd::Identity(n, n);
    llt.compute(a);
    // Three contacts: node 0 alone, node 2 against the "segment" of nodes 3 and 4 (or the "face"
    // 3, 4, 5 in 3D), node 6 alone.
    cs.candidates = {{0, 0, mu, -1}, {2, 0, mu, 0}, {6, 0, mu, -1}};
    cs.any_friction = mu > 0.0;
    cs.stencil.resize(3);
    cs.stencil[0].node[0] = 0;
    cs.stencil[1].count = D + 1;
    cs.stencil[1].node[0] = 2;
    for (int j = 1; j <= D; ++j) {
      cs.stencil[1].node[j] = 2 + j;
      cs.stencil[1].coef[j] = -1.0 / D - 0.1 * (j - 1);
    }
    cs.stencil[2].node[0] = 6;
    cs.normal.resize(3);
    for (auto& nv : cs.normal) {
      Vec v;
      for (int i = 0; i < D; ++i) v[i] = u(rng);
      v[1] += 2.0;  // mostly +y
      nv = v.normalized();
    }
    cs.reaction.assign(3, Local{});
    cs.active = {0, 1, 2};
  }

  // The master surface's nodes count among those a stencil can hold.
  void reserve(CondensedContact<D>& cc, int pool_columns) {
    typename Space<D>::Surface surface;
    surface.nodes = {3, 4, 5};
    cs.surfaces = {surface};
    cc.reserve(cs, n, pool_columns);
  }

  // Gaps that close (x_free_n < 0) and slips, as a step would set them.
  void set_locals(CondensedContact<D>& cc) {
    for (int k = 0; k < 3; ++k) {
      Local x{};
      x.n = -1e-3 * (k + 1);
      if constexpr (D == 2) {
        x.t = 2e-4 * (k - 1);
      } else {
        x.t = Eigen::Vector2d(2e-4 * (k - 1), -1e-4);
      }
      cc.set_local(k, x, 1.0);
    }
  }

  bool run(CondensedContact<D>& cc, long factor_id, double c, double dt) {
    auto solve = [&](const Eigen::VectorXd& rhs, Eigen::VectorXd& x) {
      ++solves;
      x = llt.solve(rhs);
      return true;
    };
    auto solve_block = [&](const double* rhs, double* x, int ncol) {
      ++block_solves;
      block_columns += ncol;
      Eigen::Map<const Eigen::MatrixXd> r(rhs, n, ncol);
      Eigen::Map<Eigen::MatrixXd>(x, n, ncol) = llt.solve(Eigen::MatrixXd(r));
      return true;
    };
    return cc.exact(cs, c, dt, 2000, 1e-13, solve, solve_block, factor_id);
  }

  // H^T R over the active contacts.
  Eigen::VectorXd impulse() const {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(n);
    for (int k : cs.active) {
      const Vec r = ContactFrame<D>(cs.normal[k]).global(cs.reaction[k]);
      for (int j = 0; j < cs.stencil[k].count; ++j)
        f.template segment<D>(D * cs.stencil[k].node[j]) += cs.stencil[k].coef[j] * r;
    }
    return f;
  }

  // Each contact's x = x_free + c H_k y is the fixed point of the bi-potential correction: the
  // reactions solve the contact law on the true W.
  void expect_contact_law(const CondensedContact<D>& cc, const Eigen::VectorXd& x_free_n, double c, double dt,
                          double mu) {
    const Eigen::VectorXd y = llt.solve(dt * impulse());
    EXPECT_LE((cc.response() - y).norm(), 1e-12 * y.norm());
    EXPECT_LE((cc.impulse() - impulse()).norm(), 1e-14 * impulse().norm());
    double scale = 0.0;
    for (int k : cs.active) scale = std::max(scale, local_norm(cs.reaction[k]));
    ASSERT_GT(scale, 0.0);
    for (int k : cs.active) {
      Vec sum = Vec::Zero();
      for (int j = 0; j < cs.stencil[k].count; ++j)
        sum += cs.stencil[k].coef[j] * y.template segment<D>(D * cs.stencil[k].node[j]);
      const Local hy = ContactFrame<D>(cs.normal[k]).local(sum);
      Local x = hy;
      x.n = x_free_n[k] + c * hy.n;
      if constexpr (D == 2) {
        x.t = 2e-4 * (k - 1) + c * hy.t;
      } else {
        x.t = Eigen::Vector2d(2e-4 * (k - 1), -1e-4) + c * hy.t;
      }
      const Local r = cs.reaction[k];
      const Local next = bipotential_correct(r, x, mu, 1.0 / (c * dt));
      EXPECT_LE(local_distance(next, r), 1e-9 * scale) << "contact " << k;
      EXPECT_GE(r.n, 0.0);
    }
  }
};

template <int D>
void check(double mu) {
  SCOPED_TRACE("D = " + std::to_string(D) + ", mu = " + std::to_string(mu));
  Problem<D> p(mu);
  CondensedContact<D> cc;
  p.reserve(cc, 64);
  p.set_locals(cc);
  const double c = 0.7, dt = 0.01;
  const Eigen::Vector3d x_free_n(-1e-3, -2e-3, -3e-3);
  ASSERT_TRUE(p.run(cc, 1, c, dt));
  EXPECT_TRUE(cc.converged());
  p.expect_contact_law(cc, x_free_n, c, dt, mu);
  const std::vector<typename Space<D>::Local> first = p.cs.reaction;
  // The stencils hold 2 + D nodes (0, 2, 3.., 6); without friction each needs its normal only,
  // with friction all D directions: that many columns, in blocks of at most four.
  const int nodes = 3 + D;
  const int columns = mu > 0.0 ? D * nodes : nodes;
  EXPECT_EQ(p.block_columns, columns);
  EXPECT_EQ(p.block_solves, (columns + 3) / 4);
  // Every column is in the pool: the response costs no solve.
  EXPECT_EQ(p.solves, 0);

  // The same factor again: no solve at all.
  p.block_solves = p.block_columns = p.solves = 0;
  ASSERT_TRUE(p.run(cc, 1, c, dt));
  EXPECT_EQ(p.block_columns + p.solves, 0);
  p.expect_contact_law(cc, x_free_n, c, dt, mu);

  // Contact 1's normal turns a little (1e-6 rad): its nodes complete their bases once (without
  // friction), then any direction is known.
  p.cs.normal[1] = (p.cs.normal[1] + 1e-6 * VecD<D>::UnitX()).normalized();
  p.block_solves = p.block_columns = p.solves = 0;
  ASSERT_TRUE(p.run(cc, 1, c, dt));
  EXPECT_EQ(p.block_columns, mu > 0.0 ? 0 : (D - 1) * (D + 1));
  p.expect_contact_law(cc, x_free_n, c, dt, mu);
  p.cs.normal[1] = (p.cs.normal[1] - 0.3 * VecD<D>::UnitX()).normalized();
  p.block_solves = p.block_columns = p.solves = 0;
  ASSERT_TRUE(p.run(cc, 1, c, dt));
  EXPECT_EQ(p.block_columns, 0);
  p.expect_contact_law(cc, x_free_n, c, dt, mu);

  // A new factor: everything anew.
  p.block_solves = p.block_columns = p.solves = 0;
  ASSERT_TRUE(p.run(cc, 2, c, dt));
  EXPECT_EQ(p.block_columns, columns);
  p.expect_contact_law(cc, x_free_n, c, dt, mu);

  // No fixed factor (CG): G is computed anew at every call.
  p.block_solves = p.block_columns = p.solves = 0;
  ASSERT_TRUE(p.run(cc, -1, c, dt));
  ASSERT_TRUE(p.run(cc, -1, c, dt));
  EXPECT_EQ(p.block_columns, 2 * columns);

  // A pool too small for the response: one solve instead, the same reactions.
  Problem<D> q(mu);
  CondensedContact<D> small;
  q.reserve(small, 1);
  q.set_locals(small);
  ASSERT_TRUE(q.run(small, 1, c, dt));
  EXPECT_EQ(q.solves, 1);
  q.expect_contact_law(small, x_free_n, c, dt, mu);
  for (int k = 0; k < 3; ++k) EXPECT_LE(local_distance(q.cs.reaction[k], first[k]), 1e-12 * local_norm(first[k]));
}

TEST(CondensedContact, TwoDimensionsFrictionless) { check<2>(0.0); }
TEST(CondensedContact, TwoDimensionsWithFriction) { check<2>(0.3); }
TEST(CondensedContact, ThreeDimensionsFrictionless) { check<3>(0.0); }
TEST(CondensedContact, ThreeDimensionsWithFriction) { check<3>(0.3); }

}  // namespace
}  // namespace ricochet
