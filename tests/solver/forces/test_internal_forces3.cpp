// Tests of the 3D force pass (solver/forces/internal_forces3.hpp, element_kernels3.hpp,
// material_lanes3.hpp, stress.hpp): the pass against element3d.hpp's kernels of one cell (the
// independent formulation), against the kernels' own arithmetic run one cell at a time (the
// lanes: bit for bit without floating-point contraction), rigid motions, the patch test, forces
// as the energy's gradient, the threaded pass for 1 and 2 threads, the stress tracking against the
// separate stress passes, the 3D von Mises against an independent formula, and that nothing
// allocates. Every measured error is printed ("[forces3] ...").
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <variant>
#include <vector>

#include <omp.h>

#include "solver/forces/element_kernels3.hpp"
#include "solver/forces/internal_forces.hpp"
#include "solver/materials/stress.hpp"
#include "solver/schemes/threads.hpp"
#include "tests/support/meshes3.hpp"

#include "tests/support/alloc_counter.hpp"

namespace ricochet {
namespace {

using namespace test3;

#ifdef RICOCHET_NO_FP_CONTRACT
// Built without contraction (ci/compare_results' configuration): the lanes do the one-cell
// arithmetic exactly.
constexpr double kLaneTol = 0.0, kLawTol = 0.0;
#else
// With contraction (the default build) the compiler may fuse a product into an addition in the
// vectorized code and not in the scalar one (or the reverse): one rounding apart per operation,
// a few ulps of the largest term. 1e-13 of the largest nodal force (forces cancel at shared
// nodes) and 1e-14 of the largest entry of P, as tests/solver/forces/test_element_lanes.cpp allows in 2D.
constexpr double kLaneTol = 1e-13, kLawTol = 1e-14;
#endif

Model<3> model_of(Kind kind, const Law& law, const Mesh3& mesh) { return build_model({body_of(kind, mesh, law.m)}, Vec3::Zero()); }

struct Reference {
  Eigen::VectorXd f;
  double strain_energy = 0.0, hourglass_energy = 0.0, hourglass_power = 0.0;
  double min_jacobian = 1e300;
};

// element3d.hpp's kernels cell by cell (the geometry of cell_geometry(), the kernels' own Eigen
// arithmetic), assembled in cell order.
Reference element3d_forces(const Model<3>& model, const double* u, const double* v) {
  Reference r;
  r.f = Eigen::VectorXd::Zero(model.num_dofs());
  auto add = [&](const auto& conn, const auto& fe, const ElementTotals3& t) {
    for (std::size_t a = 0; a < conn.size(); ++a)
      for (int k = 0; k < 3; ++k) r.f(3 * conn[a] + k) += fe(k, a);
    r.strain_energy += t.strain_energy;
    r.hourglass_energy += t.hourglass_energy;
    r.hourglass_power += t.hourglass_power;
    r.min_jacobian = std::min(r.min_jacobian, t.min_jacobian);
  };
  for (const Hex8OnePointBlock& b : model.hex8_hourglass)
    for (std::size_t e = 0; e < b.conn.size(); ++e) {
      Hex8Nodes fe;
      const ElementTotals3 t = hex8_one_point_forces(cell_geometry(model, b, e), b.material, gather3<8>(u, b.conn[e]),
                                                     gather3<8>(v, b.conn[e]), fe);
      add(b.conn[e], fe, t);
    }
  for (const Hex8Block& b : model.hex8_full)
    for (std::size_t e = 0; e < b.conn.size(); ++e) {
      Hex8Nodes fe;
      const ElementTotals3 t = hex8_forces(cell_geometry(model, b, e), b.material, gather3<8>(u, b.conn[e]), fe);
      add(b.conn[e], fe, t);
    }
  for (const Tet4Block& b : model.tet4)
    for (std::size_t e = 0; e < b.conn.size(); ++e) {
      Tet4Nodes fe;
      const ElementTotals3 t = tet4_forces(cell_geometry(model, b, e), b.material, gather3<4>(u, b.conn[e]), fe);
      add(b.conn[e], fe, t);
    }
  return r;
}

// The pass's arithmetic one cell at a time, written out here: the kernels' functions of
// element_kernels3.hpp with stride 1 on the cell's own arrays, the scalar laws of material3d.hpp
// (mat.first_piola) and Eigen's determinant, the sums in cell order.
Reference one_cell_forces(const Model<3>& model, const double* u, const double* v) {
  Reference r;
  r.f = Eigen::VectorXd::Zero(model.num_dofs());
  auto scatter = [&](const auto& conn, const double* fe) {
    const int n = static_cast<int>(conn.size());
    for (int a = 0; a < n; ++a)
      for (int k = 0; k < 3; ++k) r.f(3 * conn[a] + k) += fe[n * k + a];
  };
  auto law = [&](const auto& mat, const double* f, double* p, double* det) {
    const Mat3 F = row_major(f);
    const Mat3 P = mat.first_piola(F);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) p[3 * i + j] = P(i, j);
    *det = F.determinant();
    r.min_jacobian = std::min(r.min_jacobian, *det);
    return F;
  };
  for (const Hex8OnePointBlock& b : model.hex8_hourglass)
    std::visit(
        [&](const auto& mat) {
          const bool viscous = b.hourglass.form == HourglassForm::viscous;
          for (std::size_t e = 0; e < b.conn.size(); ++e) {
            const auto g = cell_lane_values(b, e);
            const auto ue = component_major<8>(gather3<8>(u, b.conn[e]));
            const auto ve = component_major<8>(gather3<8>(v, b.conn[e]));
            double h[9], f[9], p[9], det, fe[24];
            hex8wh::one_point_gradient(hex8wh::CellNodes<8>{ue.data()}, g.data(), h, f);
            const Mat3 F = law(mat, f, p, &det);
            const double work = viscous ? hex8wh::one_point_forces<true>(p, hex8wh::CellNodes<8>{ve.data()}, h, g.data(), fe)
                                        : hex8wh::one_point_forces<false>(p, hex8wh::CellNodes<8>{ue.data()}, h, g.data(), fe);
            scatter(b.conn[e], fe);
            (viscous ? r.hourglass_power : r.hourglass_energy) += viscous ? work : 0.5 * work;
            r.strain_energy += g[Hex8OnePointLanes::kVol] * mat.energy_density(F);
          }
        },
        b.material);
  for (const Hex8Block& b : model.hex8_full)
    std::visit(
        [&](const auto& mat) {
          for (std::size_t e = 0; e < b.conn.size(); ++e) {
            const auto g = cell_lane_values(b, e);
            const auto ue = component_major<8>(gather3<8>(u, b.conn[e]));
            double h[72], gq[72], fe[24];
            hex8wh::reference_gradients(hex8wh::CellNodes<8>{ue.data()}, h);
            for (int q = 0; q < 8; ++q) {
              double f[9], p[9], det;
              hex8wh::deformation_gradient(h + 9 * q, g.data() + Hex8Lanes::k(q, 0, 0), f);
              const Mat3 F = law(mat, f, p, &det);
              hex8wh::point_force_coefficients(p, g[Hex8Lanes::vol(q)], g.data() + Hex8Lanes::k(q, 0, 0), gq + 9 * q);
              r.strain_energy += g[Hex8Lanes::vol(q)] * mat.energy_density(F);
            }
            hex8wh::reference_forces(gq, fe);
            scatter(b.conn[e], fe);
          }
        },
        b.material);
  for (const Tet4Block& b : model.tet4)
    std::visit(
        [&](const auto& mat) {
          for (std::size_t e = 0; e < b.conn.size(); ++e) {
            const auto g = cell_lane_values(b, e);
            const auto ue = component_major<4>(gather3<4>(u, b.conn[e]));
            double f[9], p[9], det, fe[12];
            hex8wh::tet4_deformation_gradient(hex8wh::CellNodes<4>{ue.data()}, g.data(), f);
            const Mat3 F = law(mat, f, p, &det);
            hex8wh::tet4_forces(p, g.data(), fe);
            scatter(b.conn[e], fe);
            r.strain_energy += g[Tet4Lanes::kVol] * mat.energy_density(F);
          }
        },
        b.material);
  return r;
}

double rel(double a, double b) { return std::abs(a - b) / std::max(std::abs(b), 1e-300); }

// One cell as a model: the pass equals element3d.hpp's kernel of that cell to round-off.
// The hexahedra's kernels sum the same products in another order (element_kernels3.hpp), so the
// bound is round-off of the largest terms, not zero: 1e-13 of the largest nodal force and of the
// energies (each a few tens of ulps of terms of the same size; measured below).
TEST(InternalForces3, OneCellModelEqualsTheElementKernel) {
  double worst_f = 0.0, worst_e = 0.0, worst_hg = 0.0, worst_j = 0.0;
  for (const Kind kind : kAllKinds)
    for (const Law& law : all_laws())
      for (unsigned seed = 1; seed <= 10; ++seed) {
        SCOPED_TRACE(std::string(kind_name(kind)) + ", " + law.name + ", seed " + std::to_string(seed));
        Mesh3 cell = distorted_box(1, 1, 1, false, 0.15, seed);
        if (is_tet(kind)) {  // one of the six tetrahedra of a distorted cell, alone
          const Mesh3 six = distorted_box(1, 1, 1, true, 0.15, seed);
          cell = Mesh3{};
          cell.nodes.resize(3, 4);
          for (int a = 0; a < 4; ++a) cell.nodes.col(a) = six.nodes.col(six.tets[seed % 6][a]);
          cell.tets = {{0, 1, 2, 3}};
        }
        const Model<3> model = model_of(kind, law, cell);
        ASSERT_EQ(model.num_cells(), 1);
        const double size = std::cbrt(std::abs(is_tet(kind) ? signed_volume(cell, cell.tets[0]) : signed_volume(cell, cell.hexes[0])));
        const Eigen::VectorXd u = random_field(model.num_dofs(), 0.05 * size, seed);
        const Eigen::VectorXd v = random_field(model.num_dofs(), 2.0, seed + 100);
        const Reference ref = element3d_forces(model, u.data(), v.data());
        Eigen::VectorXd f(model.num_dofs());
        const ForceTotals t = internal_forces(model, u.data(), v.data(), f.data(), true);
        const double ef = max_abs(f - ref.f) / max_abs(ref.f);
        worst_f = std::max(worst_f, ef);
        EXPECT_LE(ef, 1e-13);
        worst_e = std::max(worst_e, rel(t.strain_energy, ref.strain_energy));
        EXPECT_LE(rel(t.strain_energy, ref.strain_energy), 1e-13);
        if (kind == Kind::hex8_viscous) {
          EXPECT_GT(ref.hourglass_power, 0.0);
          worst_hg = std::max(worst_hg, rel(t.hourglass_power, ref.hourglass_power));
          EXPECT_LE(rel(t.hourglass_power, ref.hourglass_power), 1e-13);
          EXPECT_EQ(t.hourglass_energy, 0.0);
        } else if (kind == Kind::hex8_stiffness) {
          EXPECT_GT(ref.hourglass_energy, 0.0);
          worst_hg = std::max(worst_hg, rel(t.hourglass_energy, ref.hourglass_energy));
          EXPECT_LE(rel(t.hourglass_energy, ref.hourglass_energy), 1e-13);
          EXPECT_EQ(t.hourglass_power, 0.0);
        } else {
          EXPECT_EQ(t.hourglass_energy, 0.0);
          EXPECT_EQ(t.hourglass_power, 0.0);
        }
        worst_j = std::max(worst_j, std::abs(t.min_jacobian - ref.min_jacobian));
        EXPECT_LE(std::abs(t.min_jacobian - ref.min_jacobian), 1e-14);  // det F ~ 1: a few ulps
        EXPECT_NE(ref.min_jacobian, 1.0);  // the field deforms the cell
      }
  std::printf("[forces3] one cell vs element3d: f %.2e of max |f|, strain energy %.2e, hourglass %.2e, det F %.2e\n",
              worst_f, worst_e, worst_hg, worst_j);
}

// A distorted box of cells: the assembled pass equals element3d.hpp's kernels assembled in the
// test, to the same round-off bound (relative to the largest nodal force: forces cancel at
// shared nodes).
TEST(InternalForces3, AssembledForcesEqualTheElementKernels) {
  double worst = 0.0;
  for (const Kind kind : kAllKinds)
    for (const Law& law : all_laws()) {
      SCOPED_TRACE(std::string(kind_name(kind)) + ", " + law.name);
      const Model<3> model = model_of(kind, law, distorted_box(3, 3, 2, is_tet(kind), 0.15, 21));
      const Eigen::VectorXd u = smooth_field(model, 0.05), v = smooth_field(model, 3.0);
      const Reference ref = element3d_forces(model, u.data(), v.data());
      Eigen::VectorXd f(model.num_dofs());
      const ForceTotals t = internal_forces(model, u.data(), v.data(), f.data(), true);
      const double ef = max_abs(f - ref.f) / max_abs(ref.f);
      worst = std::max(worst, ef);
      EXPECT_LE(ef, 1e-13);
      EXPECT_LE(rel(t.strain_energy, ref.strain_energy), 1e-13);
      EXPECT_LE(std::abs(t.hourglass_energy - ref.hourglass_energy), 1e-13 * std::abs(ref.hourglass_energy));
      EXPECT_LE(std::abs(t.hourglass_power - ref.hourglass_power), 1e-13 * std::abs(ref.hourglass_power));
      EXPECT_LE(std::abs(t.min_jacobian - ref.min_jacobian), 1e-14);
    }
  std::printf("[forces3] box vs element3d assembled: f %.2e of max |f|\n", worst);
}

// The batched pass (kLanes cells at once) equals its arithmetic run one cell at a time, every
// element type and law, on boxes whose cell counts leave a partial last batch (18 hexahedra,
// 108 tetrahedra); and the threaded pass's layout (ForceScratch) gives the same bits.
TEST(InternalForces3, LanesEqualTheOneCellArithmetic) {
  double worst = 0.0;
  for (const Kind kind : kAllKinds)
    for (const Law& law : all_laws()) {
      SCOPED_TRACE(std::string(kind_name(kind)) + ", " + law.name);
      const Model<3> model = model_of(kind, law, distorted_box(3, 3, 2, is_tet(kind), 0.15, 31));
      ASSERT_NE(model.num_cells() % kLanes, 0);
      const Eigen::VectorXd u = smooth_field(model, 0.05), v = smooth_field(model, 3.0);
      const Reference ref = one_cell_forces(model, u.data(), v.data());
      Eigen::VectorXd f(model.num_dofs());
      const ForceTotals t = internal_forces(model, u.data(), v.data(), f.data(), true);
      const double scale = max_abs(ref.f);
      ASSERT_GT(scale, 0.0);
      worst = std::max(worst, max_abs(f - ref.f) / scale);
      EXPECT_LE(max_abs(f - ref.f), kLaneTol * scale);
      EXPECT_NEAR(t.strain_energy, ref.strain_energy, kLaneTol * ref.strain_energy);
      EXPECT_NEAR(t.hourglass_energy, ref.hourglass_energy, kLaneTol * std::abs(ref.hourglass_energy));
      EXPECT_NEAR(t.hourglass_power, ref.hourglass_power, kLaneTol * std::abs(ref.hourglass_power));
      EXPECT_NEAR(t.min_jacobian, ref.min_jacobian, kLawTol);
      if (kind == Kind::hex8_viscous) {
        EXPECT_GT(ref.hourglass_power, 0.0);
      }
      if (kind == Kind::hex8_stiffness) {
        EXPECT_GT(ref.hourglass_energy, 0.0);
      }

      ForceScratch scratch = make_force_scratch(model);
      Eigen::VectorXd g(model.num_dofs());
      const ForceTotals ts = internal_forces(model, u.data(), v.data(), g.data(), true, nullptr, &scratch);
      EXPECT_EQ(0, std::memcmp(f.data(), g.data(), sizeof(double) * f.size()));
      EXPECT_EQ(t.min_jacobian, ts.min_jacobian);
    }
  std::printf("[forces3] lanes vs one cell at a time: %.2e of max |f| (bound %.0e)\n", worst, kLaneTol);
}

// The 3D laws on lanes (material_lanes3.hpp) equal the scalar laws lane by lane.
TEST(InternalForces3, MaterialLawsOnLanesEqualTheScalarLaws) {
  for (const Law& law : all_laws()) {
    SCOPED_TRACE(law.name);
    LaneMat3 F, P;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> d(-0.3, 0.3);
    for (int l = 0; l < kLanes; ++l) {
      Mat3 f = Mat3::Identity();
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) f(i, j) += d(rng);
      if (f.determinant() < 0.2) f = Mat3::Identity() + 0.1 * f;
      F.set(l, f);
    }
    std::visit([&](const auto& mat) { first_piola_lanes(mat, F, P); }, law.m);
    alignas(64) double det[kLanes];
    determinant_lanes(F, det);
    for (int l = 0; l < kLanes; ++l) {
      const Mat3 expected = std::visit([&](const auto& mat) { return mat.first_piola(F.lane(l)); }, law.m);
      EXPECT_LE((P.lane(l) - expected).cwiseAbs().maxCoeff(), kLawTol * expected.cwiseAbs().maxCoeff()) << "lane " << l;
      EXPECT_NEAR(det[l], F.lane(l).determinant(), kLawTol);
    }
  }
}

// A rotation of 60 degrees about a skew axis plus a translation, and the rigid velocity
// W x + c: no force, no strain or hourglass energy, no hourglass power, det F = 1, to round-off.
// Bounds: F = R to a few ulps, so E and P are ~1e-15 of (mu + |lambda|) and the nodal forces
// ~1e-15 (mu + |lambda|) h^2 (h the cell size); 1e-12 leaves three decades.
TEST(InternalForces3, RigidMotionGivesNoForceAndNoEnergy) {
  const Mat3 R = Eigen::AngleAxisd(M_PI / 3.0, Vec3(0.3, -1.0, 0.6).normalized()).toRotationMatrix();
  const Vec3 c(0.4, -0.7, 0.2), w(0.5, 1.5, -2.0);
  double worst_f = 0.0, worst_e = 0.0;
  for (const Kind kind : kAllKinds)
    for (const Law& law : all_laws()) {
      SCOPED_TRACE(std::string(kind_name(kind)) + ", " + law.name);
      const Model<3> model = model_of(kind, law, distorted_box(3, 2, 2, is_tet(kind), 0.15, 41));
      Eigen::VectorXd u(model.num_dofs()), v(model.num_dofs());
      for (int p = 0; p < model.num_nodes(); ++p) {
        const Vec3 x = model.ref.col(p);
        u.segment<3>(3 * p) = (R - Mat3::Identity()) * x + c;
        v.segment<3>(3 * p) = w.cross(x) + c;
      }
      Eigen::VectorXd f(model.num_dofs());
      const ForceTotals t = internal_forces(model, u.data(), v.data(), f.data(), true);
      const double h = 0.3;  // cell size [m]
      const double volume = model.mass.sum() / 3.0 / kDensity;
      const double ef = max_abs(f) / (law.scale() * h * h), ee = (t.strain_energy + t.hourglass_energy) / (law.scale() * volume);
      worst_f = std::max(worst_f, ef);
      worst_e = std::max(worst_e, std::abs(ee));
      EXPECT_LE(ef, 1e-12);
      EXPECT_LE(std::abs(ee), 1e-12);
      // The power sum Q . qdot: qdot ~ 1e-16 |v| ~ 1e-15 m/s, Q = c qdot with c = 0.1 rho c_p V^(2/3)
      // ~ 30 kg/s, so ~1e-28 W.
      EXPECT_LE(std::abs(t.hourglass_power), 1e-20);
      EXPECT_NEAR(t.min_jacobian, 1.0, 1e-14);
    }
  std::printf("[forces3] rigid motion: |f| %.2e (mu + |lambda|) h^2, energy %.2e (mu + |lambda|) V\n", worst_f, worst_e);
}

// The patch test: u = (F0 - I) X + c on a box of distorted cells gives F = F0 at every point,
// so the interior nodes' forces vanish, the energy is V W(F0), the smallest det F is det F0, and
// a one-point cell's hourglass forces, energy and power vanish (u and the velocity (F0 - I) X
// are linear). Bounds: F = F0 to a few ulps of the cells' gradients (~1e-15), the interior
// forces cancel the cells' forces of size |P0| h^2 to round-off: 1e-12 of the largest nodal force.
TEST(InternalForces3, PatchTestInteriorForcesVanish) {
  Mat3 F0;
  F0 << 1.1, 0.15, -0.05, 0.08, 0.92, 0.12, -0.1, 0.05, 1.05;
  F0 = Eigen::AngleAxisd(0.4, Vec3(1.0, 1.0, -0.5).normalized()).toRotationMatrix() * F0;
  const Vec3 c(0.01, -0.02, 0.03);
  double worst_f = 0.0, worst_e = 0.0;
  for (const Kind kind : kAllKinds)
    for (const Law& law : all_laws()) {
      SCOPED_TRACE(std::string(kind_name(kind)) + ", " + law.name);
      const Model<3> model = model_of(kind, law, distorted_box(3, 3, 3, is_tet(kind), 0.15, 51));
      Eigen::VectorXd u(model.num_dofs()), v(model.num_dofs());
      for (int p = 0; p < model.num_nodes(); ++p) {
        const Vec3 x = model.ref.col(p);
        u.segment<3>(3 * p) = (F0 - Mat3::Identity()) * x + c;
        v.segment<3>(3 * p) = (F0 - Mat3::Identity()) * x;
      }
      Eigen::VectorXd f(model.num_dofs());
      const ForceTotals t = internal_forces(model, u.data(), v.data(), f.data(), true);
      const std::vector<int>& boundary = model.bodies[0].boundary_nodes;
      const double scale = max_abs(f);
      ASSERT_GT(scale, 0.0);
      int interior = 0;
      double e_int = 0.0;
      for (int p = 0; p < model.num_nodes(); ++p)
        if (!std::binary_search(boundary.begin(), boundary.end(), p)) {
          ++interior;
          e_int = std::max(e_int, f.segment<3>(3 * p).cwiseAbs().maxCoeff() / scale);
        }
      EXPECT_EQ(interior, 8);
      worst_f = std::max(worst_f, e_int);
      EXPECT_LE(e_int, 1e-12);
      const double volume = model.mass.sum() / 3.0 / kDensity;
      const double w0 = std::visit([&](const auto& mat) { return mat.energy_density(F0); }, law.m);
      worst_e = std::max(worst_e, rel(t.strain_energy, volume * w0));
      EXPECT_LE(rel(t.strain_energy, volume * w0), 1e-12);
      EXPECT_NEAR(t.min_jacobian, F0.determinant(), 1e-12);
      EXPECT_LE(std::abs(t.hourglass_energy), 1e-12 * t.strain_energy);
      EXPECT_LE(std::abs(t.hourglass_power), 1e-18);
    }
  std::printf("[forces3] patch test: interior |f| %.2e of max |f|, energy %.2e\n", worst_f, worst_e);
}

// f = dE/du by central differences of the pass's own energy (strain + stored hourglass energy;
// v = 0, so the viscous form adds nothing), on small distorted boxes at a random u of up to
// 0.02 m (cells of about 0.5 m: ~4 % strain). Bound as tests/solver/elements/test_elements3d.cpp's
// ForcesAreEnergyGradient: truncation (h / 0.02)^2 ~ 3e-9 and round-off eps E / (h |f|) ~ 1e-11
// of the largest force; 1e-6 leaves room for any seed or compiler.
TEST(InternalForces3, ForcesAreTheEnergyGradient) {
  double worst = 0.0;
  for (const Kind kind : kAllKinds)
    for (const Law& law : all_laws()) {
      SCOPED_TRACE(std::string(kind_name(kind)) + ", " + law.name);
      const Model<3> model = model_of(kind, law, distorted_box(2, 1, 1, is_tet(kind), 0.15, 61));
      const Eigen::VectorXd u0 = random_field(model.num_dofs(), 0.05 * 0.4, 62);
      const Eigen::VectorXd v = Eigen::VectorXd::Zero(model.num_dofs());
      Eigen::VectorXd f(model.num_dofs()), scratch(model.num_dofs());
      internal_forces(model, u0.data(), v.data(), f.data(), true);
      auto energy = [&](const Eigen::VectorXd& u) {
        const ForceTotals t = internal_forces(model, u.data(), v.data(), scratch.data(), true);
        return t.strain_energy + t.hourglass_energy;
      };
      const double h = 1e-6;
      double err = 0.0;
      for (int k = 0; k < model.num_dofs(); ++k) {
        Eigen::VectorXd up = u0, um = u0;
        up(k) += h;
        um(k) -= h;
        err = std::max(err, std::abs((energy(up) - energy(um)) / (2.0 * h) - f(k)));
      }
      err /= max_abs(f);
      worst = std::max(worst, err);
      EXPECT_LE(err, 1e-6);
    }
  std::printf("[forces3] f vs dE/du: %.2e of max |f|\n", worst);
}

// The threaded pass with 1 and 2 threads (ThreadScope): the same bits for the forces and every
// total, the stress tracking included, and the forces equal the serial pass's. The boxes have
// more than kForceParallelChunks chunks, so 2 threads do run in parallel.
TEST(InternalForces3, ThreadedPassIsBitIdenticalForOneAndTwoThreads) {
  for (const Kind kind : kAllKinds) {
    SCOPED_TRACE(kind_name(kind));
    const Law law = all_laws()[1];
    const Model<3> model = is_tet(kind) ? model_of(kind, law, distorted_box(6, 6, 5, true, 0.1, 71))
                                      : model_of(kind, law, distorted_box(11, 10, 10, false, 0.1, 71));
    ForceScratch scratch = make_force_scratch(model);
    ASSERT_GE(scratch.chunks.size(), kForceParallelChunks);
    const Eigen::VectorXd u = smooth_field(model, 0.02), v = smooth_field(model, 3.0);
    std::vector<std::uint8_t> contact(model.num_cells(), 0);
    for (std::size_t k = 0; k < contact.size(); k += 7) contact[k] = 1;
    struct Run {
      Eigen::VectorXd f;
      ForceTotals t;
      VonMises2 sampled{0.0, 0.0, 0.0};
      std::vector<double> cells;
    };
    auto run = [&](int threads) {
      ThreadScope scope(threads);
      EXPECT_EQ(omp_get_max_threads(), threads);
      Run r;
      r.f.resize(model.num_dofs());
      r.cells.assign(model.num_cells(), -1.0);
      StressTracking s;
      s.contact_cell = contact.data();
      s.sampled_max = &r.sampled;
      s.cell_von_mises = r.cells.data();
      r.t = internal_forces(model, u.data(), v.data(), r.f.data(), true, &s, &scratch);
      return r;
    };
    const Run one = run(1), two = run(2);
    EXPECT_EQ(0, std::memcmp(one.f.data(), two.f.data(), sizeof(double) * one.f.size()));
    EXPECT_EQ(one.t.strain_energy, two.t.strain_energy);
    EXPECT_EQ(one.t.hourglass_energy, two.t.hourglass_energy);
    EXPECT_EQ(one.t.hourglass_power, two.t.hourglass_power);
    EXPECT_EQ(one.t.min_jacobian, two.t.min_jacobian);
    EXPECT_EQ(one.t.stress.all, two.t.stress.all);
    EXPECT_EQ(one.t.stress.all_cell, two.t.stress.all_cell);
    EXPECT_EQ(one.t.stress.interior, two.t.stress.interior);
    EXPECT_EQ(one.t.stress.interior_cell, two.t.stress.interior_cell);
    EXPECT_EQ(one.sampled, two.sampled);
    EXPECT_EQ(one.cells, two.cells);
    EXPECT_GT(one.t.stress.all, 0.0);
    Eigen::VectorXd serial(model.num_dofs());
    internal_forces(model, u.data(), v.data(), serial.data(), false);
    EXPECT_EQ(0, std::memcmp(one.f.data(), serial.data(), sizeof(double) * serial.size()));
  }
}

// The stress peaks and samples the pass tracks equal the separate passes' (stress_peaks,
// von_mises_maxima, cell_von_mises) for every measure, element type and law. The pass ranks a
// point's ratio from the lanes' F and P, the separate passes the scalar law's: the same bits
// without contraction, a few ulps apart with it (1e-13).
TEST(InternalForces3, StressTrackingEqualsTheSeparatePasses) {
  for (const Kind kind : kAllKinds)
    for (const Law& law : all_laws())
      for (const StressMeasure measure : {StressMeasure::cauchy, StressMeasure::pk2, StressMeasure::kirchhoff}) {
        SCOPED_TRACE(std::string(kind_name(kind)) + ", " + law.name + ", " + stress_measure_name(measure));
        const Model<3> model = model_of(kind, law, distorted_box(3, 3, 2, is_tet(kind), 0.15, 81));
        const Eigen::VectorXd u = smooth_field(model, 0.05), v = smooth_field(model, 3.0);
        std::vector<std::uint8_t> contact(model.num_cells(), 0);
        for (std::size_t c = 0; c < contact.size(); c += 4) contact[c] = 1;
        VonMises2 sampled{0.0, 0.0, 0.0};
        std::vector<double> cells(model.num_cells(), -1.0);
        StressTracking s;
        s.contact_cell = contact.data();
        s.measure = measure;
        s.sampled_max = &sampled;
        s.cell_von_mises = cells.data();
        Eigen::VectorXd f(model.num_dofs());
        const ForceTotals t = internal_forces(model, u.data(), v.data(), f.data(), false, &s);

        StressTracking plain = s;
        plain.sampled_max = nullptr;
        plain.cell_von_mises = nullptr;
        const StressPeaks p = stress_peaks(model, u.data(), plain);
        ASSERT_GE(p.all_cell, 0);
        ASSERT_GE(p.interior_cell, 0);
        EXPECT_EQ(t.stress.all_cell, p.all_cell);
        EXPECT_EQ(t.stress.interior_cell, p.interior_cell);
        EXPECT_NEAR(t.stress.all, p.all, 1e-13 * p.all);
        EXPECT_NEAR(t.stress.interior, p.interior, 1e-13 * p.interior);
        // The plain tracking pass (no sample) ranks the same peaks through the bound's screen.
        const ForceTotals tp = internal_forces(model, u.data(), v.data(), f.data(), false, &plain);
        EXPECT_EQ(tp.stress.all_cell, p.all_cell);
        EXPECT_NEAR(tp.stress.all, p.all, 1e-13 * p.all);
        // A threshold just below the peak: only that cell passes.
        StressTracking high = plain;
        high.threshold = 0.999 * p.all;
        const ForceTotals th = internal_forces(model, u.data(), v.data(), f.data(), false, &high);
        EXPECT_EQ(th.stress.all_cell, p.all_cell);

        const VonMises2 maxima = von_mises_maxima(model, u.data());
        for (int m = 0; m < kStressMeasures; ++m) EXPECT_NEAR(std::sqrt(sampled[m]), maxima[m], 1e-13 * maxima[m]);
        std::vector<double> expected(model.num_cells());
        cell_von_mises(model, u.data(), measure, expected.data());
        for (int c = 0; c < model.num_cells(); ++c) EXPECT_NEAR(cells[c], expected[c], 1e-13 * expected[c]) << "cell " << c;
      }
}

// The 3D von Mises (stress.hpp) against an independent computation with Eigen: sigma = P F^T / J,
// S = F^-1 P, tau = P F^T, each symmetrized, vm = sqrt(3/2 dev A : dev A); the Green-Lagrange
// strain (F^T F - I)/2; and the screen's bound never below the exact value. Random F (det F in
// [0.5, 2]) and P of each law. Bound 1e-13 relative: the two compute the same sums of about 20
// products in another order.
TEST(InternalForces3, VonMisesAgainstAnIndependentFormula) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> d(-0.4, 0.4);
  double worst = 0.0, worst_bound = 0.0;
  auto vm = [](Mat3 a) {
    a = 0.5 * (a + a.transpose());
    const Mat3 dev = a - a.trace() / 3.0 * Mat3::Identity();
    return std::sqrt(1.5 * dev.squaredNorm());
  };
  for (const Law& law : all_laws())
    for (int k = 0; k < 200; ++k) {
      Mat3 F = Mat3::Identity();
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) F(i, j) += d(rng);
      const double J = F.determinant();
      if (J < 0.5 || J > 2.0) continue;
      const Mat3 P = std::visit([&](const auto& m) { return m.first_piola(F); }, law.m);
      const Mat3 tau = P * F.transpose();
      double expected[kStressMeasures];
      expected[static_cast<int>(StressMeasure::cauchy)] = vm(tau / J);
      expected[static_cast<int>(StressMeasure::pk2)] = vm(F.inverse() * P);
      expected[static_cast<int>(StressMeasure::kirchhoff)] = vm(tau);
      const VonMises2 got = von_mises_squared(F, P, J);
      for (int m = 0; m < kStressMeasures; ++m) {
        const double e = rel(std::sqrt(got[m]), expected[m]);
        worst = std::max(worst, e);
        EXPECT_LE(e, 1e-13) << law.name << " measure " << m;
        const StressMeasure sm = static_cast<StressMeasure>(m);
        EXPECT_NEAR(von_mises_ratio(F, P, J, sm).value(), got[m], 1e-14 * got[m]);
        // The screen passes every point that exceeds the threshold.
        EXPECT_TRUE(von_mises_may_exceed(F, P, J, sm, 0.9999 * got[m]));
        const double ff = squared_norm(F), pp = squared_norm(P);
        const double bound = sm == StressMeasure::pk2 ? 0.5 * pp * ff * ff / (J * J)
                                                      : 1.5 * pp * ff / (sm == StressMeasure::cauchy ? J * J : 1.0);
        worst_bound = std::max(worst_bound, got[m] / bound);
        EXPECT_LE(got[m], bound);
      }
      SymTensor6 sigma, strain;
      cauchy_and_green_lagrange(F, P, J, sigma, strain);
      const Mat3 s = 0.5 * (tau + tau.transpose()) / J, e = 0.5 * (F.transpose() * F - Mat3::Identity());
      const int idx[6][2] = {{0, 0}, {1, 1}, {2, 2}, {0, 1}, {1, 2}, {0, 2}};
      for (int c = 0; c < 6; ++c) {
        EXPECT_NEAR(sigma[c], s(idx[c][0], idx[c][1]), 1e-13 * s.cwiseAbs().maxCoeff());
        EXPECT_NEAR(strain[c], e(idx[c][0], idx[c][1]), 1e-15);
      }
    }
  std::printf("[forces3] von Mises vs Eigen: %.2e; exact / bound <= %.3f\n", worst, worst_bound);
}

// A homogeneous deformation: every cell's von Mises and tensors are the point's (each element
// type, its points averaged by volume for the 2x2x2 hexahedron). F = F0 to round-off (~1e-15),
// so the stresses to ~(mu / |sigma0|) 1e-15 ~ 1e-14 of |sigma0| and the strains to ~1e-15:
// bounds 1e-11 of |sigma0| and 1e-13.
TEST(InternalForces3, CellStressesOfAHomogeneousDeformation) {
  Mat3 F0;
  F0 << 1.08, 0.1, 0.0, -0.05, 0.95, 0.07, 0.02, 0.0, 1.03;
  for (const Kind kind : kAllKinds) {
    SCOPED_TRACE(kind_name(kind));
    const Law law = all_laws()[1];
    const Model<3> model = model_of(kind, law, distorted_box(2, 2, 2, is_tet(kind), 0.15, 91));
    Eigen::VectorXd u(model.num_dofs());
    for (int p = 0; p < model.num_nodes(); ++p) u.segment<3>(3 * p) = (F0 - Mat3::Identity()) * model.ref.col(p);
    const Mat3 P0 = std::visit([&](const auto& m) { return m.first_piola(F0); }, law.m);
    const double J = F0.determinant();
    const VonMises2 vm2 = von_mises_squared(F0, P0, J);
    SymTensor6 sigma0, strain0;
    cauchy_and_green_lagrange(F0, P0, J, sigma0, strain0);
    std::vector<double> vm(model.num_cells()), sigma(6 * model.num_cells()), strain(6 * model.num_cells());
    cell_tensors(model, u.data(), sigma.data(), strain.data());
    const double ss = *std::max_element(sigma0.begin(), sigma0.end(), [](double a, double b) { return std::abs(a) < std::abs(b); });
    for (const StressMeasure m : {StressMeasure::cauchy, StressMeasure::pk2, StressMeasure::kirchhoff}) {
      cell_von_mises(model, u.data(), m, vm.data());
      for (int c = 0; c < model.num_cells(); ++c) EXPECT_NEAR(vm[c], std::sqrt(vm2[static_cast<int>(m)]), 1e-11 * std::abs(ss));
    }
    for (int c = 0; c < model.num_cells(); ++c)
      for (int k = 0; k < 6; ++k) {
        EXPECT_NEAR(sigma[6 * c + k], sigma0[k], 1e-11 * std::abs(ss)) << "cell " << c;
        EXPECT_NEAR(strain[6 * c + k], strain0[k], 1e-13) << "cell " << c;
      }
    const VonMises2 maxima = von_mises_maxima(model, u.data());
    for (int m = 0; m < kStressMeasures; ++m) EXPECT_NEAR(maxima[m], std::sqrt(vm2[m]), 1e-11 * std::abs(ss));
  }
}

// No heap allocation in a force pass (serial or threaded, with energies, stress tracking and
// samples) or in the stress passes (tests/support/alloc_counter.hpp counts every allocation of this
// program; the first calls, which start OpenMP's threads, are not counted).
TEST(InternalForces3, ForcePassDoesNotAllocate) {
  {  // the counter counts
    const long before = g_allocations.load();
    std::vector<double> x(10, 1.0);
    asm volatile("" : : "g"(x.data()) : "memory");
    ASSERT_GE(g_allocations.load() - before, 1);
  }
  for (const Kind kind : kAllKinds)
    for (const Law& law : all_laws()) {
      SCOPED_TRACE(std::string(kind_name(kind)) + ", " + law.name);
      const Model<3> model = is_tet(kind) ? model_of(kind, law, distorted_box(4, 4, 4, true, 0.1, 101))
                                        : model_of(kind, law, distorted_box(11, 10, 10, false, 0.1, 101));
      ForceScratch scratch = make_force_scratch(model);
      const Eigen::VectorXd u = smooth_field(model, 0.02), v = smooth_field(model, 3.0);
      Eigen::VectorXd f(model.num_dofs());
      std::vector<std::uint8_t> contact(model.num_cells(), 0);
      std::vector<double> cells(model.num_cells()), sigma(6 * model.num_cells()), strain(6 * model.num_cells());
      VonMises2 sampled{0.0, 0.0, 0.0};
      StressTracking plain;
      plain.contact_cell = contact.data();
      StressTracking sample = plain;
      sample.sampled_max = &sampled;
      sample.cell_von_mises = cells.data();
      auto serial = [&] {
        internal_forces(model, u.data(), v.data(), f.data(), false);
        internal_forces(model, u.data(), v.data(), f.data(), true, &plain);
        internal_forces(model, u.data(), v.data(), f.data(), true, &sample);
        cell_von_mises(model, u.data(), StressMeasure::pk2, cells.data());
        cell_tensors(model, u.data(), sigma.data(), strain.data());
        stress_peaks(model, u.data(), sample);
        von_mises_maxima(model, u.data());
      };
      auto threaded = [&] {
        internal_forces(model, u.data(), v.data(), f.data(), false, nullptr, &scratch);
        internal_forces(model, u.data(), v.data(), f.data(), true, &plain, &scratch);
        internal_forces(model, u.data(), v.data(), f.data(), true, &sample, &scratch);
      };
      serial();
      long before = g_allocations.load();
      serial();
      EXPECT_EQ(g_allocations.load() - before, 0) << "serial passes";
      for (const int threads : {1, 2}) {
        const ThreadScope scope(threads);
        threaded();  // the first parallel region starts OpenMP's threads
        before = g_allocations.load();
        threaded();
        EXPECT_EQ(g_allocations.load() - before, 0) << threads << " threads";
      }
    }
}

}  // namespace
}  // namespace ricochet
