// The implicit scheme's iteration matrix for a 3D model (tangent.hpp, tangent3.cpp):
// A = m_scale M + k_scale K_T + c_scale C with K_T = d f_int / du and C = d f_int / dv of the 3D
// force pass, for the four laws and every element formulation, against central-difference
// Jacobians of internal_forces(const Model<3>&, ...); the mass term, symmetry and the pattern.
#include <gtest/gtest.h>

#include <cstdio>

#include "tests/support/finite_difference.hpp"
#include "solver/forces/tangent.hpp"
#include "tests/support/meshes3.hpp"

namespace ricochet {
namespace {

using test3::Kind;

Eigen::VectorXd forces(const Model<3>& model, const Eigen::VectorXd& u, const Eigen::VectorXd& v) {
  Eigen::VectorXd f(model.num_dofs());
  internal_forces(model, u.data(), v.data(), f.data(), false);
  return f;
}

// Central-difference Jacobian of the 3D force pass with respect to u (wrt_v = false) or v.
Eigen::MatrixXd fd_jacobian(const Model<3>& model, const Eigen::VectorXd& u, const Eigen::VectorXd& v, bool wrt_v,
                            double h) {
  if (wrt_v) return test_support::fd_jacobian([&](const Eigen::VectorXd& w) { return forces(model, u, w); }, v, h);
  return test_support::fd_jacobian([&](const Eigen::VectorXd& w) { return forces(model, w, v); }, u, h);
}

Eigen::MatrixXd assembled(const Model<3>& model, SystemMatrix& s, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                          double ms, double ks, double cs) {
  Eigen::VectorXd f(model.num_dofs());
  assemble_system(model, u.data(), v.data(), ms, ks, cs, s, f.data(), false);
  return Eigen::MatrixXd(s.matrix);
}

Model<3> box_model(Kind kind, const Material3& m) {
  return build_model({test3::body_of(kind, test3::distorted_box(2, 2, 1, test3::is_tet(kind), 0.1), m)},
                      Vec3::Zero());
}

// K_T against central differences in u with step 1e-7 m around a smooth displacement of
// gradient ~5 % (truncation ~ (1e-7 / 0.05)^2 ~ 1e-11 relative, round-off ~ eps |f| / (h |K|)
// ~ 1e-9); C against differences in v with step 1 m/s (f is linear in v: no truncation), C = 0
// where no force depends on v.
TEST(Tangent3, StiffnessAndDampingMatchFiniteDifferenceJacobians) {
  for (const test3::Law& law : test3::all_laws())
    for (Kind kind : test3::kAllKinds) {
      SCOPED_TRACE(law.name + ", " + test3::kind_name(kind));
      const Model<3> model = box_model(kind, law.m);
      const Eigen::VectorXd u = test3::smooth_field(model, 0.05) + test3::random_field(model.num_dofs(), 0.01, 3);
      const Eigen::VectorXd v = test3::random_field(model.num_dofs(), 3.0, 4);
      SystemMatrix s = make_system_matrix(model);
      const Eigen::MatrixXd k = assembled(model, s, u, v, 0.0, 1.0, 0.0);
      const Eigen::MatrixXd c = assembled(model, s, u, v, 0.0, 0.0, 1.0);
      const Eigen::MatrixXd jk = fd_jacobian(model, u, v, false, 1e-7);
      const Eigen::MatrixXd jc = fd_jacobian(model, u, v, true, 1.0);
      ASSERT_GT(jk.norm(), 0.0);
      const double ek = (k - jk).norm() / jk.norm();
      EXPECT_LT(ek, 1e-6);
      if (kind == Kind::hex8_viscous) {
        ASSERT_GT(jc.norm(), 0.0);
        const double ec = (c - jc).norm() / jc.norm();
        EXPECT_LT(ec, 1e-8);
        std::printf("[tangent3] %-18s %-18s K vs FD %.2e, C vs FD %.2e\n", law.name.c_str(), test3::kind_name(kind),
                    ek, ec);
      } else {
        EXPECT_EQ(c.norm(), 0.0);
        EXPECT_EQ(jc.norm(), 0.0);
        std::printf("[tangent3] %-18s %-18s K vs FD %.2e, C = 0\n", law.name.c_str(), test3::kind_name(kind), ek);
      }
      // Hyperelastic: A = dP/dF has major symmetry, so K_T is symmetric (CHOLMOD needs it).
      EXPECT_LT((k - k.transpose()).norm(), 1e-12 * k.norm());
    }
}

// m_scale M is the lumped mass on the diagonal and nothing else; the three scales add linearly.
TEST(Tangent3, ScalesCombineLinearly) {
  const Model<3> model = box_model(Kind::hex8_viscous, test3::all_laws()[1].m);
  const Eigen::VectorXd u = test3::smooth_field(model, 0.05), v = test3::random_field(model.num_dofs(), 2.0, 9);
  SystemMatrix s = make_system_matrix(model);
  const Eigen::MatrixXd m = assembled(model, s, u, v, 1.0, 0.0, 0.0);
  EXPECT_EQ((m - Eigen::MatrixXd(model.mass.asDiagonal())).norm(), 0.0);
  const Eigen::MatrixXd k = assembled(model, s, u, v, 0.0, 1.0, 0.0), c = assembled(model, s, u, v, 0.0, 0.0, 1.0);
  const Eigen::MatrixXd a = assembled(model, s, u, v, 2.0, 0.5, 3.0);
  EXPECT_LT((a - (2.0 * m + 0.5 * k + 3.0 * c)).norm(), 1e-14 * a.norm());
  for (int d = 0; d < model.num_dofs(); ++d) EXPECT_EQ(s.diagonal[d], a(d, d));
}

// The pattern holds exactly the couplings of nodes that share a cell (and the diagonal), in
// 3 x 3 blocks; two bodies, one of hexahedra and one of tetrahedra, are not coupled.
TEST(Tangent3, PatternHasExactlyTheCellCouplings) {
  BodyInput<3> a = test3::body_of(Kind::hex8, test3::distorted_box(2, 1, 1, false, 0.1), test3::all_laws()[0].m, "a");
  BodyInput<3> b = test3::body_of(Kind::tet4, test3::distorted_box(1, 1, 1, true, 0.1), test3::all_laws()[0].m, "b");
  b.mesh.nodes.row(0).array() += 3.0;
  const Model<3> model = build_model({a, b}, Vec3::Zero());
  const SystemMatrix s = make_system_matrix(model);
  const int n = model.num_nodes();
  Eigen::MatrixXi share = Eigen::MatrixXi::Identity(n, n);
  for_each_cell_block(model, [&](const auto& blk) {
    for (const auto& cell : blk.conn)
      for (int p : cell)
        for (int q : cell) share(p, q) = 1;
  });
  Eigen::MatrixXi pattern = Eigen::MatrixXi::Zero(3 * n, 3 * n);
  for (int r = 0; r < 3 * n; ++r)
    for (Eigen::SparseMatrix<double, Eigen::RowMajor, int>::InnerIterator it(s.matrix, r); it; ++it)
      pattern(r, it.col()) = 1;
  for (int r = 0; r < 3 * n; ++r)
    for (int c = 0; c < 3 * n; ++c) EXPECT_EQ(pattern(r, c), share(r / 3, c / 3)) << r << ", " << c;
  EXPECT_EQ(share.block(0, a.mesh.num_nodes(), a.mesh.num_nodes(), b.mesh.num_nodes()).sum(), 0);
}

}  // namespace
}  // namespace ricochet
