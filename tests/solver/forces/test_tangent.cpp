// Verification of the linearisation (solver/tangent, material tangents in solver/material):
// A = dP/dF against central differences of first_piola and its major symmetry; the assembled
// K_T and C against finite-difference Jacobians of internal_forces for every element
// formulation and material; linearity in (m_scale, k_scale, c_scale); symmetry; f_int and the
// force totals identical to internal_forces; the sparsity pattern and slots; and no heap
// allocation inside assemble_system.
//
// The allocation counter is the one of test_no_allocation.cpp: every replaceable global
// operator new / delete and the C allocation functions (Eigen allocates with std::malloc)
// count into one atomic, forwarding to glibc's __libc_* entry points.
#include <gtest/gtest.h>

#include <Eigen/SparseCore>
#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "solver/forces/internal_forces.hpp"
#include "solver/forces/tangent.hpp"
#include "tests/support/deformations.hpp"
#include "tests/support/finite_difference.hpp"
#include "tests/support/matrix_checks.hpp"
#include "tests/support/verification_meshes.hpp"

#include "tests/support/alloc_counter.hpp"

namespace ricochet {
namespace {

using verification::all_element_kinds;
using verification::element_name;
using verification::ElementKind;
using verification::grid_mesh;
using verification::single_body_model;

constexpr double kYoung = 200e9;     // [Pa]
constexpr double kPoisson = 0.3;     // [-]
constexpr double kDensity = 7800.0;  // [kg/m^3]
constexpr double kThickness = 0.01;  // [m]

struct MaterialCase {
  std::string name;
  Material material;
  PlaneMode plane;
};

std::vector<MaterialCase> material_cases(double poisson = kPoisson) {
  std::vector<MaterialCase> c;
  for (PlaneMode p : {PlaneMode::stress, PlaneMode::strain}) {
    const std::string suffix = p == PlaneMode::stress ? ", plane stress" : ", plane strain";
    c.push_back({"SVK" + suffix, StVenantKirchhoff::make(kYoung, poisson, kDensity, p), p});
    c.push_back({"neo-Hookean" + suffix, NeoHookean::make(kYoung, poisson, kDensity, p), p});
  }
  return c;
}

using test_support::random_deformations;  // as in test_materials
using test_support::rotation;

using test_support::max_abs;

Eigen::Matrix4d fd_tangent(const Material& m, const Mat2& F, double h) {
  return test_support::fd_tangent<2>(
      [&](const Mat2& g) { return std::visit([&](const auto& x) { return Mat2(x.first_piola(g)); }, m); }, F, h);
}

TEST(MaterialTangent, MatchesFiniteDifferenceOfFirstPiola) {
  // Central differences with step 1e-6 on F ~ 1: truncation ~ h^2 ~ 1e-12 relative; round-off
  // ~ eps |P| / (h |A|) ~ 1e-16 * 0.3 / 1e-6 ~ 3e-11 (the plane-stress Newton in ln C33 is
  // converged to ~1e-15 relative, which adds ~1e-9 at most). 1e-6 catches any missing term
  // (e.g. ds/dF in plane stress contributes O(lambda/(lambda + 2 mu)) ~ 40 %).
  const double h = 1e-6;
  const std::vector<Mat2> fs = random_deformations(40, 7);
  for (double poisson : {0.3, 0.45})
    for (const MaterialCase& mc : material_cases(poisson)) {
      double worst = 0.0, worst_sym = 0.0, worst_p = 0.0;
      for (const Mat2& F : fs) {
        const Eigen::Matrix4d a = material_tangent(mc.material, F);
        const Eigen::Matrix4d fd = fd_tangent(mc.material, F, h);
        const double err = max_abs(a - fd) / max_abs(fd);
        const double sym = max_abs(a - a.transpose()) / max_abs(a);
        worst = std::max(worst, err);
        worst_sym = std::max(worst_sym, sym);
        EXPECT_LT(err, 1e-6) << mc.name << " nu " << poisson << "\nF =\n" << F;
        EXPECT_LT(sym, 1e-14) << mc.name << " nu " << poisson;
        // The member functions agree with the variant dispatch, and the fused P is first_piola,
        // up to round-off (the compiler may contract a*b + c into FMAs differently in each
        // inlined copy, so not bitwise).
        std::visit(
            [&](const auto& x) {
              Mat2 p;
              Eigen::Matrix4d a2;
              x.first_piola_and_tangent(F, p, a2);
              const double as = max_abs(a);
              EXPECT_LE(max_abs(a2 - x.tangent(F)), 1e-14 * as);
              EXPECT_LE(max_abs(a2 - a), 1e-14 * as);
              const Mat2 pr = x.first_piola(F);
              const double dp = max_abs(p - pr) / max_abs(pr);
              EXPECT_LE(dp, 1e-14);
              worst_p = std::max(worst_p, dp);
            },
            mc.material);
      }
      std::printf("[tangent] dP/dF vs FD  %-28s nu %.2f  max rel. error %.2e, asymmetry %.1e, "
                  "fused P vs first_piola %.1e\n",
                  mc.name.c_str(), poisson, worst, worst_sym, worst_p);
    }
}

TEST(MaterialTangent, SmallStrainLimitIsHooke) {
  // At F = I the tangent is the linear elastic modulus: A(iJ,kL) = lambda d_iJ d_kL +
  // mu (d_ik d_JL + d_iL d_kJ), with the plane-reduced lambda in plane stress for both laws.
  for (const MaterialCase& mc : material_cases()) {
    const Lame l = lame_from_young_poisson(kYoung, kPoisson);
    const double lam = mc.plane == PlaneMode::stress
                           ? 2.0 * l.lambda * l.shear_modulus / (l.lambda + 2.0 * l.shear_modulus)
                           : l.lambda;
    const double mu = l.shear_modulus;
    Eigen::Matrix4d hooke;
    for (int i = 0; i < 2; ++i)
      for (int J = 0; J < 2; ++J)
        for (int k = 0; k < 2; ++k)
          for (int L = 0; L < 2; ++L)
            hooke(2 * i + J, 2 * k + L) = lam * (i == J) * (k == L) +
                                          mu * ((i == k) * (J == L) + (i == L) * (k == J));
    const Eigen::Matrix4d a = material_tangent(mc.material, Mat2::Identity());
    EXPECT_LT(max_abs(a - hooke), 1e-12 * kYoung) << mc.name;
  }
}

// Mesh of 1 m x 0.8 m, 4 x 3 cells, interior nodes moved by up to 20 % of a cell.
Mesh distorted_mesh(ElementKind kind) { return grid_mesh(1.0, 0.8, 4, 3, 0.2, kind); }

Eigen::VectorXd random_field(int size, double amplitude, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> amp(-amplitude, amplitude);
  Eigen::VectorXd a(size);
  for (int d = 0; d < size; ++d) a[d] = amp(gen);
  return a;
}

Eigen::VectorXd forces(const Model<2>& model, const Eigen::VectorXd& u, const Eigen::VectorXd& v) {
  Eigen::VectorXd f(model.num_dofs());
  internal_forces(model, u.data(), v.data(), f.data(), false);
  return f;
}

// Central-difference Jacobian of internal_forces with respect to u (wrt_v = false) or v.
Eigen::MatrixXd fd_jacobian(const Model<2>& model, const Eigen::VectorXd& u,
                            const Eigen::VectorXd& v, bool wrt_v, double h) {
  if (wrt_v) return test_support::fd_jacobian([&](const Eigen::VectorXd& w) { return forces(model, u, w); }, v, h);
  return test_support::fd_jacobian([&](const Eigen::VectorXd& w) { return forces(model, w, v); }, u, h);
}

Eigen::MatrixXd assembled(const Model<2>& model, SystemMatrix& s, const Eigen::VectorXd& u,
                          const Eigen::VectorXd& v, double ms, double ks, double cs) {
  Eigen::VectorXd f(model.num_dofs());
  assemble_system(model, u.data(), v.data(), ms, ks, cs, s, f.data(), false);
  return Eigen::MatrixXd(s.matrix);
}

double rel_frobenius(const Eigen::MatrixXd& a, const Eigen::MatrixXd& ref) {
  return (a - ref).norm() / ref.norm();
}

TEST(Tangent, StiffnessAndDampingMatchFiniteDifferenceJacobians) {
  // K_T against central differences of f_int(u) with step 1e-7 m around a random displacement
  // of up to 4 % of the mesh size (strains ~10 %; as in test_elements); truncation
  // ~ (1e-7 / 0.04)^2 ~ 1e-11, round-off ~ eps |f| / (h |K|) ~ 1e-10 relative. C against
  // differences in v with step 1 m/s (no truncation error: f_int is linear in v), whose
  // round-off eps |f| / (h |C|) ~ 1e-16 * 5e7 / 1e2 ~ 1e-10 relative is set by the elastic
  // forces; C = 0 exactly for the other forms.
  const double h = 1e-7;
  for (const MaterialCase& mc : material_cases())
    for (ElementKind kind : all_element_kinds()) {
      const Model<2> model = single_body_model(distorted_mesh(kind), mc.material, mc.plane, kind,
                                            kThickness);
      const int n = model.num_dofs();
      const Eigen::VectorXd u = random_field(n, 0.04, 42);
      const Eigen::VectorXd v = random_field(n, 3.0, 43);
      SystemMatrix s = make_system_matrix(model);
      const Eigen::MatrixXd k = assembled(model, s, u, v, 0.0, 1.0, 0.0);
      const Eigen::MatrixXd c = assembled(model, s, u, v, 0.0, 0.0, 1.0);
      const Eigen::MatrixXd jk = fd_jacobian(model, u, v, false, h);
      const Eigen::MatrixXd jc = fd_jacobian(model, u, v, true, 1.0);
      const double ek = rel_frobenius(k, jk);
      EXPECT_LT(ek, 1e-6) << element_name(kind) << ", " << mc.name;
      if (kind == ElementKind::q4_viscous) {
        ASSERT_GT(jc.norm(), 0.0);
        const double ec = rel_frobenius(c, jc);
        EXPECT_LT(ec, 1e-8) << element_name(kind) << ", " << mc.name;
        std::printf("[tangent] K vs FD %-20s %-26s rel. error %.2e; C vs FD %.2e\n",
                    element_name(kind), mc.name.c_str(), ek, ec);
      } else {
        EXPECT_EQ(c.norm(), 0.0) << element_name(kind) << ", " << mc.name;
        EXPECT_EQ(jc.norm(), 0.0) << element_name(kind) << ", " << mc.name;
        std::printf("[tangent] K vs FD %-20s %-26s rel. error %.2e; C = 0\n", element_name(kind),
                    mc.name.c_str(), ek);
      }
    }
}

// Two bodies: a Q4 one-point stiffness-HG body and a body whose mesh mixes quads and triangles
// (a Q4 2x2 block and a T3 block sharing nodes), so the matrix has three blocks of different
// formulations and materials.
Model<2> mixed_model() {
  BodyInput<2> a;
  a.name = "hourglass";
  a.mesh = grid_mesh(1.0, 0.8, 3, 2, 0.2, false);
  a.material = NeoHookean::make(kYoung, kPoisson, kDensity, PlaneMode::stress);
  a.quad_element = QuadElement::one_point_hourglass;
  a.hourglass.form = HourglassForm::stiffness;
  a.thickness = kThickness;
  BodyInput<2> b;
  b.name = "mixed";
  Mesh quads = grid_mesh(1.0, 0.8, 3, 2, 0.2, false);
  const Mesh tris = grid_mesh(1.0, 0.8, 3, 2, 0.2, true);
  quads.nodes.row(0).array() += 2.0;
  b.mesh = quads;
  b.mesh.quads.assign(quads.quads.begin(), quads.quads.begin() + 3);  // bottom row: quads
  b.mesh.tris.assign(tris.tris.begin() + 6, tris.tris.end());          // top row: triangles
  b.material = StVenantKirchhoff::make(kYoung, kPoisson, kDensity, PlaneMode::stress);
  b.quad_element = QuadElement::full_2x2;
  b.thickness = 2 * kThickness;
  return build_model({a, b}, PlaneMode::stress, Vec2::Zero());
}

TEST(Tangent, MixedBlocksMatchFiniteDifferenceJacobian) {
  const Model<2> model = mixed_model();
  ASSERT_EQ(model.q4_full.size(), 1u);
  ASSERT_EQ(model.q4_hourglass.size(), 1u);
  ASSERT_EQ(model.t3.size(), 1u);
  const int n = model.num_dofs();
  const Eigen::VectorXd u = random_field(n, 0.04, 5);
  const Eigen::VectorXd v = random_field(n, 3.0, 6);
  SystemMatrix s = make_system_matrix(model);
  const double ek = rel_frobenius(assembled(model, s, u, v, 0.0, 1.0, 0.0),
                                  fd_jacobian(model, u, v, false, 1e-7));
  EXPECT_LT(ek, 1e-6);
  std::printf("[tangent] K vs FD, two bodies / three blocks: rel. error %.2e\n", ek);
}

TEST(Tangent, ScalesCombineLinearlyAndMatrixIsSymmetric) {
  for (const MaterialCase& mc : material_cases())
    for (ElementKind kind : all_element_kinds()) {
      const Model<2> model = single_body_model(distorted_mesh(kind), mc.material, mc.plane, kind,
                                            kThickness);
      const int n = model.num_dofs();
      const Eigen::VectorXd u = random_field(n, 0.04, 11);
      const Eigen::VectorXd v = random_field(n, 3.0, 12);
      SystemMatrix s = make_system_matrix(model);
      const Eigen::MatrixXd m = assembled(model, s, u, v, 1.0, 0.0, 0.0);
      const Eigen::MatrixXd k = assembled(model, s, u, v, 0.0, 1.0, 0.0);
      const Eigen::MatrixXd c = assembled(model, s, u, v, 0.0, 0.0, 1.0);
      const Eigen::MatrixXd a = assembled(model, s, u, v, 2.0, 3.0, 5.0);
      // M is the lumped mass on the diagonal.
      EXPECT_EQ((m - Eigen::MatrixXd(model.mass.asDiagonal())).norm(), 0.0);
      const Eigen::MatrixXd combo = 2.0 * m + 3.0 * k + 5.0 * c;
      EXPECT_LT(rel_frobenius(a, combo), 1e-15) << element_name(kind) << ", " << mc.name;
      // Symmetric up to round-off in the element sums.
      EXPECT_LT((a - a.transpose()).norm(), 1e-14 * a.norm()) << element_name(kind);
      // The diagonal copy.
      EXPECT_EQ((s.diagonal - a.diagonal()).norm(), 0.0) << element_name(kind);
    }
}

TEST(Tangent, ForcesAndTotalsEqualInternalForces) {
  // Same expressions, except that assemble_system forms F = I + ue^T dN/dX column by column
  // (2-wide FMAs that stay in registers) where internal_forces uses Eigen's dot products, so F
  // and hence f_int may differ in the last bits: 1e-14 of the largest force.
  for (const MaterialCase& mc : material_cases())
    for (ElementKind kind : all_element_kinds())
      for (bool with_energy : {false, true}) {
        const Model<2> model = single_body_model(distorted_mesh(kind), mc.material, mc.plane, kind,
                                              kThickness);
        const int n = model.num_dofs();
        const Eigen::VectorXd u = random_field(n, 0.04, 21);
        const Eigen::VectorXd v = random_field(n, 3.0, 22);
        SystemMatrix s = make_system_matrix(model);
        Eigen::VectorXd f_ref(n), f(n);
        f.setConstant(1e300);  // overwritten, not accumulated
        const ForceTotals tr =
            internal_forces(model, u.data(), v.data(), f_ref.data(), with_energy);
        const ForceTotals t =
            assemble_system(model, u.data(), v.data(), 1.0, 0.5, 0.25, s, f.data(), with_energy);
        const double scale = f_ref.lpNorm<Eigen::Infinity>();
        EXPECT_LE((f - f_ref).lpNorm<Eigen::Infinity>(), 1e-14 * scale) << element_name(kind);
        const auto close = [](double a, double b) {
          return std::abs(a - b) <= 1e-14 * std::max(std::abs(a), std::abs(b));
        };
        EXPECT_TRUE(close(t.strain_energy, tr.strain_energy)) << element_name(kind);
        EXPECT_TRUE(close(t.hourglass_energy, tr.hourglass_energy)) << element_name(kind);
        EXPECT_TRUE(close(t.hourglass_power, tr.hourglass_power)) << element_name(kind);
        EXPECT_TRUE(close(t.min_jacobian, tr.min_jacobian)) << element_name(kind);
        if (with_energy) {
          EXPECT_GT(t.strain_energy, 0.0);
        } else {
          EXPECT_EQ(t.strain_energy, 0.0);
        }
        if (with_energy)
          std::printf("[tangent] f_int vs internal_forces %-20s %-26s max diff / max |f| %.1e\n",
                      element_name(kind), mc.name.c_str(),
                      (f - f_ref).lpNorm<Eigen::Infinity>() / scale);
      }
}

using Coupling = std::pair<int, int>;

template <class Block>
void expected_couplings(const Block& b, std::set<Coupling>& out) {
  for (const auto& c : b.conn)
    for (int p : c)
      for (int q : c)
        for (int i = 0; i < 2; ++i)
          for (int k = 0; k < 2; ++k) out.insert({2 * p + i, 2 * q + k});
}

// Every slot of every element names the entry (row, col) of its element DOFs.
template <int N, class Block>
void check_slots(const Block& b, const SystemMatrix& s, std::size_t& offset) {
  const int* outer = s.matrix.outerIndexPtr();
  const int* inner = s.matrix.innerIndexPtr();
  for (const auto& c : b.conn)
    for (int a = 0; a < 2 * N; ++a)
      for (int bb = 0; bb < 2 * N; ++bb) {
        const int row = 2 * c[a / 2] + a % 2, col = 2 * c[bb / 2] + bb % 2;
        const int slot = s.slots[offset++];
        ASSERT_GE(slot, outer[row]);
        ASSERT_LT(slot, outer[row + 1]);
        ASSERT_EQ(inner[slot], col);
      }
}

TEST(Tangent, PatternHasExactlyTheElementCouplings) {
  std::vector<Model<2>> models;
  for (ElementKind kind : all_element_kinds())
    models.push_back(single_body_model(distorted_mesh(kind), material_cases()[0].material,
                                       PlaneMode::stress, kind, kThickness));
  models.push_back(mixed_model());
  for (const Model<2>& model : models) {
    const SystemMatrix s = make_system_matrix(model);
    std::set<Coupling> expected;
    for (const auto& b : model.q4_full) expected_couplings(b, expected);
    for (const auto& b : model.q4_hourglass) expected_couplings(b, expected);
    for (const auto& b : model.t3) expected_couplings(b, expected);
    std::set<Coupling> actual;
    for (int r = 0; r < s.matrix.outerSize(); ++r)
      for (Eigen::SparseMatrix<double, Eigen::RowMajor, int>::InnerIterator it(s.matrix, r); it;
           ++it)
        actual.insert({static_cast<int>(it.row()), static_cast<int>(it.col())});
    EXPECT_TRUE(s.matrix.isCompressed());
    EXPECT_EQ(static_cast<std::size_t>(s.matrix.nonZeros()), actual.size());  // no duplicates
    EXPECT_TRUE(actual == expected) << "pattern differs: " << actual.size() << " vs "
                                    << expected.size();
    std::size_t offset = 0, total = 0;
    // The slots in the order every pass visits the blocks (kBlockKinds).
    for (const auto& b : model.q4_hourglass) check_slots<4>(b, s, offset);
    for (const auto& b : model.q4_full) check_slots<4>(b, s, offset);
    for (const auto& b : model.t3) check_slots<3>(b, s, offset);
    for (const auto& b : model.q4_full) total += 64 * b.conn.size();
    for (const auto& b : model.q4_hourglass) total += 64 * b.conn.size();
    for (const auto& b : model.t3) total += 36 * b.conn.size();
    EXPECT_EQ(s.slots.size(), total);
    EXPECT_EQ(offset, total);
    for (int d = 0; d < model.num_dofs(); ++d) {
      ASSERT_EQ(s.matrix.innerIndexPtr()[s.diagonal_slots[d]], d);
      ASSERT_GE(s.diagonal_slots[d], s.matrix.outerIndexPtr()[d]);
      ASSERT_LT(s.diagonal_slots[d], s.matrix.outerIndexPtr()[d + 1]);
    }
  }
}

TEST(Tangent, AssemblyDoesNotAllocate) {
  // The counter works (or a zero below would prove nothing).
  long before = g_allocations.load();
  Eigen::VectorXd x = Eigen::VectorXd::Ones(100);
  Eigen::VectorXd y = x + x;
  escape(y.data());
  EXPECT_GE(g_allocations.load() - before, 2) << "Eigen dynamic storage";
  before = g_allocations.load();
  int* p = new int(3);
  escape(p);
  delete p;
  EXPECT_GE(g_allocations.load() - before, 1) << "operator new";

  std::vector<Model<2>> models;
  for (const MaterialCase& mc : material_cases())
    for (ElementKind kind : all_element_kinds())
      models.push_back(single_body_model(distorted_mesh(kind), mc.material, mc.plane, kind,
                                         kThickness));
  models.push_back(mixed_model());
  for (const Model<2>& model : models) {
    const int n = model.num_dofs();
    const Eigen::VectorXd u = random_field(n, 0.04, 31);
    const Eigen::VectorXd v = random_field(n, 3.0, 32);
    Eigen::VectorXd f(n);
    SystemMatrix s = make_system_matrix(model);
    double sink = 0.0;
    const long start = g_allocations.load();
    for (int it = 0; it < 5; ++it) {
      const ForceTotals t = assemble_system(model, u.data(), v.data(), 1.0, 1e-6, 1e-3, s,
                                            f.data(), it % 2 == 0);
      sink += t.strain_energy + t.min_jacobian + s.diagonal[0];
    }
    EXPECT_EQ(g_allocations.load() - start, 0);
    EXPECT_TRUE(std::isfinite(sink));
  }
}

}  // namespace
}  // namespace ricochet
