// The vectorized force kernels (element_kernels2.hpp, material_lanes.hpp) against the serial
// formulation written out here with Eigen, cell by cell, as the kernels computed it before
// they were batched: every element type x every material x plane stress and strain, on a
// distorted mesh whose cell count (35) leaves a partial last batch. Built with
// -ffp-contract=off (as ci/compare_results builds; RICOCHET_NO_FP_CONTRACT) the two must give
// the same bits. In the default build the compiler may fuse a multiply and an add into one
// FMA in one of them and not in the other, so there the comparison allows round-off: 1e-13 of
// the largest nodal force (cells' forces cancel at shared nodes) and 1e-14 of the largest
// stress component.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <variant>
#include <vector>

#include "solver/forces/internal_forces.hpp"
#include "solver/elements/kinematics.hpp"
#include "solver/materials/material_lanes.hpp"
#include "tests/support/matrix_checks.hpp"
#include "tests/support/verification_meshes.hpp"

using namespace ricochet;
using namespace ricochet::verification;

namespace {

#ifdef RICOCHET_NO_FP_CONTRACT
constexpr double kForceTol = 0.0, kPointTol = 0.0;
#else
constexpr double kForceTol = 1e-13, kPointTol = 1e-14;
#endif

struct Reference {
  Eigen::VectorXd f;
  double strain_energy = 0.0, hourglass_energy = 0.0, hourglass_power = 0.0;
  double min_jacobian = 1e300;
};

// The serial force pass: gather, F, P(F), fe = sum vol dN/dX P^T (+ hourglass forces), scatter.
Reference serial_forces(const Model<2>& model, const double* u, const double* v) {
  Reference r;
  r.f = Eigen::VectorXd::Zero(model.num_dofs());
  auto point = [&](const auto& mat, const auto& ue, const auto& dndx, double vol, auto& fe) {
    const Mat2 F = deformation_gradient(ue, dndx);
    r.min_jacobian = std::min(r.min_jacobian, F.determinant());
    fe.noalias() += vol * dndx * mat.first_piola(F).transpose();
    r.strain_energy += vol * mat.energy_density(F);
  };
  for (const Q4HourglassBlock& b : model.q4_hourglass)
    std::visit(
        [&](const auto& mat) {
          for (std::size_t e = 0; e < b.conn.size(); ++e) {
            const Q4HourglassGeom& g = b.geom[e];
            const Grad4 ue = gather<4>(u, b.conn[e]);
            Grad4 fe = Grad4::Zero();
            point(mat, ue, g.dndx, g.vol, fe);
            const bool viscous = b.form == HourglassForm::viscous;
            const Vec2 q = (viscous ? gather<4>(v, b.conn[e]) : ue).transpose() * g.gamma;
            const Vec2 Q = g.hourglass_coeff * q;
            fe.noalias() += g.gamma * Q.transpose();
            if (viscous)
              r.hourglass_power += Q.dot(q);
            else
              r.hourglass_energy += 0.5 * g.hourglass_coeff * q.squaredNorm();
            scatter<4>(r.f.data(), b.conn[e], fe);
          }
        },
        b.material);
  for (const Q4FullBlock& b : model.q4_full)
    std::visit(
        [&](const auto& mat) {
          for (std::size_t e = 0; e < b.conn.size(); ++e) {
            const Grad4 ue = gather<4>(u, b.conn[e]);
            Grad4 fe = Grad4::Zero();
            for (int q = 0; q < 4; ++q) point(mat, ue, b.geom[e].dndx[q], b.geom[e].vol[q], fe);
            scatter<4>(r.f.data(), b.conn[e], fe);
          }
        },
        b.material);
  for (const T3Block& b : model.t3)
    std::visit(
        [&](const auto& mat) {
          for (std::size_t e = 0; e < b.conn.size(); ++e) {
            Grad3 fe = Grad3::Zero();
            point(mat, gather<3>(u, b.conn[e]), b.geom[e].dndx, b.geom[e].vol, fe);
            scatter<3>(r.f.data(), b.conn[e], fe);
          }
        },
        b.material);
  return r;
}

std::vector<std::pair<std::string, Material>> materials(PlaneMode plane) {
  return {{"St Venant-Kirchhoff", StVenantKirchhoff::make(1e7, 0.3, 1000.0, plane)},
          {"neo-Hookean", NeoHookean::make(1e7, 0.3, 1000.0, plane)},
          {"Blatz-Ko", BlatzKo::make(4e6, 1000.0, plane)},
          {"Mooney-Rivlin", MooneyRivlin::make(3e5, 5e4, 2e7, 1000.0, plane)}};
}

// A smooth field of strain ~ amplitude on the mesh's nodes (2n, interleaved).
Eigen::VectorXd field(const Model<2>& model, double amplitude) {
  Eigen::VectorXd a(model.num_dofs());
  for (int i = 0; i < model.num_nodes(); ++i) {
    const double x = model.ref(0, i), y = model.ref(1, i);
    a(2 * i) = amplitude * (0.3 * x + 0.2 * std::sin(3.0 * y) + 0.1 * x * y);
    a(2 * i + 1) = amplitude * (-0.25 * y + 0.15 * std::cos(2.0 * x) + 0.2 * x * x);
  }
  return a;
}

using test_support::max_abs;

}  // namespace

// Forces, energies, hourglass power and the smallest det F of the vectorized pass equal the
// serial formulation's, for every element type, material and plane mode.
TEST(ElementLanes, ForcePassEqualsTheSerialFormulation) {
  for (const PlaneMode plane : {PlaneMode::stress, PlaneMode::strain})
    for (const auto& [name, material] : materials(plane))
      for (const ElementKind kind : all_element_kinds()) {
        SCOPED_TRACE(std::string(element_name(kind)) + ", " + name + (plane == PlaneMode::stress ? ", plane stress" : ", plane strain"));
        // 7 x 5 quads (35 cells, 35 % 8 = 3) or 70 triangles (70 % 8 = 6): a partial last batch.
        const Model<2> model = single_body_model(grid_mesh(1.4, 1.0, 7, 5, 0.2, kind), material, plane, kind, 0.01, 0.1);
        const Eigen::VectorXd u = field(model, 0.05), v = field(model, 3.0);
        const Reference ref = serial_forces(model, u.data(), v.data());
        Eigen::VectorXd f(model.num_dofs());
        const ForceTotals t = internal_forces(model, u.data(), v.data(), f.data(), /*with_energy=*/true);
        const double scale = max_abs(ref.f);
        ASSERT_GT(scale, 0.0);
        EXPECT_LE(max_abs(f - ref.f), kForceTol * scale);
        EXPECT_NEAR(t.strain_energy, ref.strain_energy, kForceTol * ref.strain_energy);
        EXPECT_NEAR(t.hourglass_energy, ref.hourglass_energy, kForceTol * std::abs(ref.hourglass_energy));
        EXPECT_NEAR(t.hourglass_power, ref.hourglass_power, kForceTol * std::abs(ref.hourglass_power));
        if (kind == ElementKind::q4_viscous) {
          EXPECT_GT(ref.hourglass_power, 0.0);
        }
        if (kind == ElementKind::q4_stiffness) {
          EXPECT_GT(ref.hourglass_energy, 0.0);
        }
        EXPECT_NEAR(t.min_jacobian, ref.min_jacobian, kPointTol);
        EXPECT_NE(ref.min_jacobian, 1.0);  // the field deforms the cells

        // The threaded pass's layout (ForceScratch) gives the same bits as the direct one.
        ForceScratch scratch = make_force_scratch(model);
        Eigen::VectorXd g(model.num_dofs());
        const ForceTotals ts = internal_forces(model, u.data(), v.data(), g.data(), true, nullptr, &scratch);
        EXPECT_EQ(0, std::memcmp(f.data(), g.data(), sizeof(double) * f.size()));
        EXPECT_EQ(t.min_jacobian, ts.min_jacobian);
      }
}

// The stress peaks and sample values the vectorized pass tracks equal those of the separate
// serial passes (stress_peaks, von_mises_maxima, cell_von_mises), per measure.
TEST(ElementLanes, StressTrackingEqualsTheSeparatePasses) {
  const PlaneMode plane = PlaneMode::stress;
  for (const auto& [name, material] : materials(plane))
    for (const ElementKind kind : all_element_kinds())
      for (const StressMeasure measure : {StressMeasure::cauchy, StressMeasure::pk2, StressMeasure::kirchhoff}) {
        SCOPED_TRACE(std::string(element_name(kind)) + ", " + name + ", measure " + std::to_string(static_cast<int>(measure)));
        const Model<2> model = single_body_model(grid_mesh(1.4, 1.0, 7, 5, 0.2, kind), material, plane, kind, 0.01, 0.1);
        const Eigen::VectorXd u = field(model, 0.05), v = field(model, 3.0);
        std::vector<std::uint8_t> contact_cell(model.num_cells(), 0);
        for (std::size_t c = 0; c < contact_cell.size(); c += 4) contact_cell[c] = 1;
        VonMises2 sampled{0.0, 0.0, 0.0};
        std::vector<double> cells(model.num_cells(), -1.0);
        StressTracking s;
        s.contact_cell = contact_cell.data();
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

        const VonMises2 maxima = von_mises_maxima(model, u.data());
        for (int m = 0; m < kStressMeasures; ++m) EXPECT_NEAR(std::sqrt(sampled[m]), maxima[m], 1e-13 * maxima[m]);
        std::vector<double> expected(model.num_cells());
        cell_von_mises(model, u.data(), measure, expected.data());
        for (int c = 0; c < model.num_cells(); ++c) EXPECT_NEAR(cells[c], expected[c], 1e-13 * expected[c]) << "cell " << c;
      }
}

// The laws on lanes equal the scalar laws lane by lane.
TEST(ElementLanes, MaterialLawsOnLanesEqualTheScalarLaws) {
  for (const PlaneMode plane : {PlaneMode::stress, PlaneMode::strain})
    for (const auto& [name, material] : materials(plane)) {
      SCOPED_TRACE(name);
      LaneMat2 F, P;
      for (int l = 0; l < kLanes; ++l) {
        Mat2 f;
        f << 1.0 + 0.03 * l, 0.02 - 0.01 * l, -0.04 + 0.005 * l, 0.9 + 0.02 * l;
        F.set(l, f);
      }
      std::visit([&](const auto& mat) { first_piola_lanes(mat, F, P); }, material);
      alignas(64) double det[kLanes];
      determinant_lanes(F, det);
      for (int l = 0; l < kLanes; ++l) {
        const Mat2 expected = std::visit([&](const auto& mat) { return mat.first_piola(F.lane(l)); }, material);
        EXPECT_LE((P.lane(l) - expected).cwiseAbs().maxCoeff(), kPointTol * expected.cwiseAbs().maxCoeff()) << "lane " << l;
        EXPECT_NEAR(det[l], F.lane(l).determinant(), kPointTol);
      }
    }
}
