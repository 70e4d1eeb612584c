// Stress measures and the per-step stress peaks (solver/materials/stress.hpp, internal_forces.hpp):
// the three von Mises equivalents against closed forms, the upper bound that lets points skip,
// the force pass's peaks against a separate stress pass, the sample values the force pass
// computes against the separate passes they replace, and von_mises_max on the oblique
// plate independent of the history sampling interval.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "harness/input/case_setup.hpp"
#include "harness/input/case_spec.hpp"
#include "solver/forces/internal_forces.hpp"
#include "solver/schemes/explicit.hpp"
#include "solver/materials/stress.hpp"
#include "tests/support/verification_meshes.hpp"

namespace ricochet {
namespace {

const std::string kCase = std::string(RICOCHET_SOURCE_DIR) + "/cases/oblique_plate.toml";

// Uniaxial-strain stretch F = diag(a, 1) of St Venant-Kirchhoff in plane strain: E11 = (a^2 -
// 1)/2, S11 = (lambda + 2 mu) E11, S22 = S33 = lambda E11, so S has the deviator of a uniaxial
// state: vm(S) = |S11 - S22| = 2 mu E11. tau = F S F^T: tau11 = a^2 S11, tau22 = tau33 = S22,
// sigma = tau / a.
TEST(StressMeasures, UniaxialStrainClosedForms) {
  const double young = 1e7, poisson = 0.25;
  const StVenantKirchhoff mat = StVenantKirchhoff::make(young, poisson, 1000.0, PlaneMode::strain);
  const double lambda = mat.lambda_3d, mu = mat.shear_modulus;
  for (const double a : {0.8, 0.95, 1.0, 1.1, 1.3}) {
    Mat2 F = Mat2::Identity();
    F(0, 0) = a;
    const Mat2 P = mat.first_piola(F);
    const double e11 = 0.5 * (a * a - 1.0);
    const double s11 = (lambda + 2.0 * mu) * e11, s22 = lambda * e11;
    const double vm_pk2 = std::abs(s11 - s22);
    const double vm_kirchhoff = std::abs(a * a * s11 - s22);
    const double vm_cauchy = vm_kirchhoff / a;
    const double scale = std::max(1.0, vm_pk2);
    EXPECT_NEAR(std::sqrt(von_mises_ratio(mat, F, P, a, StressMeasure::pk2).value()), vm_pk2, 1e-9 * scale) << a;
    EXPECT_NEAR(std::sqrt(von_mises_ratio(mat, F, P, a, StressMeasure::kirchhoff).value()), vm_kirchhoff, 1e-9 * scale)
        << a;
    EXPECT_NEAR(std::sqrt(von_mises_ratio(mat, F, P, a, StressMeasure::cauchy).value()), vm_cauchy, 1e-9 * scale) << a;
  }
}

// Cauchy against sigma = P F^T / J written out with Eigen (3D state with sigma33 = F33^2 S33 / J),
// in plane stress and plane strain and for two laws; tau = J sigma; and the upper bound of von_mises_may_exceed never lets a point skip whose
// value is above the threshold, on random deformation gradients.
TEST(StressMeasures, CauchyKirchhoffAndTheBoundOnRandomStates) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> d(-0.25, 0.25);
  std::vector<Material> materials;
  for (const PlaneMode plane : {PlaneMode::stress, PlaneMode::strain}) {
    materials.push_back(StVenantKirchhoff::make(1e7, 0.25, 1000.0, plane));
    materials.push_back(NeoHookean::make(1e7, 0.3, 1000.0, plane));
  }
  int skipped = 0, checked = 0;
  for (const Material& material : materials)
    for (int k = 0; k < 200; ++k) {
      Mat2 F;
      F << 1.0 + d(rng), d(rng), d(rng), 1.0 + d(rng);
      if (!(F.determinant() > 0.2)) continue;
      std::visit(
          [&](const auto& mat) {
            const Mat2 P = mat.first_piola(F);
            const double det = F.determinant();
            const double cauchy = von_mises_ratio(mat, F, P, det, StressMeasure::cauchy).value();
            const double kirchhoff = von_mises_ratio(mat, F, P, det, StressMeasure::kirchhoff).value();
            const double j = det * mat.out_of_plane(F).stretch;
            const auto o = mat.out_of_plane(F);
            const Mat2 sigma = P * F.transpose() / j;
            const double s33 = o.stretch * o.stretch * o.pk2 / j;
            const double d1 = sigma(0, 0) - sigma(1, 1), d2 = sigma(1, 1) - s33, d3 = s33 - sigma(0, 0);
            const double shear = 0.5 * (sigma(0, 1) + sigma(1, 0));
            const double reference = std::sqrt(0.5 * (d1 * d1 + d2 * d2 + d3 * d3) + 3.0 * shear * shear);
            EXPECT_NEAR(std::sqrt(cauchy), reference, 1e-9 * reference);
            // The material's entry point is this formula (up to the compiler's contractions).
            EXPECT_NEAR(von_mises(material, F), std::sqrt(cauchy), 1e-12 * reference);
            EXPECT_NEAR(kirchhoff, j * j * cauchy, 1e-9 * kirchhoff);
            for (int m = 0; m < kStressMeasures; ++m) {
              const auto measure = static_cast<StressMeasure>(m);
              const double exact = von_mises_ratio(mat, F, P, det, measure).value();
              // Just below the exact value: the bound must say "may exceed".
              EXPECT_TRUE(von_mises_may_exceed(mat, F, P, det, measure, exact * (1.0 - 1e-9)));
              // Far above it most points skip (the bound exceeds 10x the exact value only near
              // hydrostatic states, whose von Mises equivalent is small against |A|).
              const bool skip = !von_mises_may_exceed(mat, F, P, det, measure, 10.0 * exact);
              skipped += skip;
              ++checked;
            }
          },
          material);
    }
  EXPECT_GT(checked, 1000);
  // 82 % measured.
  EXPECT_GT(skipped, 0.75 * checked) << "the bound is too loose to let points ten times below the threshold skip";
}

struct PlateRun {
  PreparedCase prepared;
  RunResult result;
};

PlateRun plate(const std::vector<std::string>& sets) {
  std::vector<std::string> all = {"mesh=M1", "time.dt=2e-6", "time.end=1.2e-3", "output.fields=[]"};
  all.insert(all.end(), sets.begin(), sets.end());
  PlateRun run;
  run.prepared = prepare_case(read_case(kCase, all));
  run.result = run_explicit(run.prepared.model<2>(), run.prepared.settings);
  return run;
}

// von_mises_max is the peak over every step: the same whatever the history interval. Sampled
// (stress_every_step = false) with a coarse interval, it misses the peak, which is what the
// every-step tracking is for.
TEST(StressPeaks, VonMisesMaxIndependentOfOutputInterval) {
  for (const char* measure : {"cauchy", "pk2", "kirchhoff"}) {
    const std::string m = std::string("output.stress_measure=\"") + measure + "\"";
    const PlateRun fine = plate({m, "output.interval=2e-6"});
    const PlateRun coarse = plate({m, "output.interval=1e-3"});
    const PlateRun sampled = plate({m, "output.interval=1e-3", "output.stress_every_step=false"});
    const RunResult &a = fine.result, &b = coarse.result;
    ASSERT_EQ(a.status, RunStatus::ok);
    EXPECT_NEAR(b.stress.von_mises_max, a.stress.von_mises_max, 1e-3 * a.stress.von_mises_max) << measure;
    EXPECT_EQ(b.stress.von_mises_max_time, a.stress.von_mises_max_time) << measure;
    EXPECT_NEAR(b.stress.interior_peak.value, a.stress.interior_peak.value, 1e-3 * a.stress.von_mises_max) << measure;
    // Every step was sampled in the fine run: its largest history value is the peak itself.
    const History& h = a.history;
    double hist_max = 0.0;
    for (std::size_t r = 0; r < h.rows(); ++r) hist_max = std::max(hist_max, h.at(r, h.column("von_mises_max")));
    EXPECT_NEAR(hist_max, a.stress.von_mises_max, 1e-12 * a.stress.von_mises_max) << measure;
    // The sampled maximum of a 1 ms interval misses the peak by far more than 0.1 %.
    EXPECT_LT(sampled.result.stress.von_mises_max, 0.98 * a.stress.von_mises_max) << measure;
    // Where: a cell of the plate, inside its bounding box at that time, interior peak no larger.
    EXPECT_EQ(a.stress.peak.body, 0);
    EXPECT_GE(a.stress.peak.element, 0);
    EXPECT_LT(a.stress.peak.element, fine.prepared.model<2>().num_cells());
    EXPECT_GT(a.stress.peak.y, -1e-3);
    EXPECT_LT(a.stress.peak.y, 0.09);
    EXPECT_LE(a.stress.interior_peak.value, a.stress.peak.value);
    EXPECT_GT(a.stress.interior_peak.value, 0.0);
  }
}

// The force pass's peaks equal those of a separate stress pass on the same displacement, cell
// and value, with and without a threshold below the peak.
TEST(StressPeaks, ForcePassMatchesStressPass) {
  const PlateRun run = plate({"time.end=6e-4", "output.fields=[6e-4]"});
  ASSERT_EQ(run.result.fields.size(), 1u);
  const Model<2>& model = run.prepared.model<2>();
  const Eigen::VectorXd& u = run.result.fields[0].u;
  std::vector<std::uint8_t> contact_cell(model.num_cells(), 0);
  for (int c = 0; c < model.num_cells(); c += 3) contact_cell[c] = 1;
  Eigen::VectorXd f(model.num_dofs());
  for (int m = 0; m < kStressMeasures; ++m) {
    StressTracking tracking;
    tracking.contact_cell = contact_cell.data();
    tracking.measure = static_cast<StressMeasure>(m);
    const StressPeaks ref = stress_peaks(model, u.data(), tracking);
    ASSERT_GT(ref.all, 0.0);
    for (const double threshold : {0.0, 0.5 * ref.interior}) {
      tracking.threshold = threshold;
      const StressPeaks got = internal_forces(model, u.data(), u.data(), f.data(), false, &tracking).stress;
      EXPECT_EQ(got.all_cell, ref.all_cell);
      EXPECT_EQ(got.interior_cell, ref.interior_cell);
      EXPECT_NEAR(got.all, ref.all, 1e-12 * ref.all);
      EXPECT_NEAR(got.interior, ref.interior, 1e-12 * ref.all);
    }
    // Above every point: nothing is ranked, though some points pass the bound.
    tracking.threshold = 2.0 * ref.all;
    EXPECT_EQ(internal_forces(model, u.data(), u.data(), f.data(), false, &tracking).stress.all_cell, -1);
  }
}

// A history sample's and a field snapshot's stresses, computed in the step's own force pass
// (StressTracking::sampled_max, cell_von_mises), equal those of the separate passes they
// replace (von_mises_maxima, cell_von_mises), for every element formulation, material law and
// measure; the forces and the peaks are those of the pass without them. The same for the
// implicit scheme's stress pass (stress_peaks). Equal up to a few ulps: GCC may fuse the
// multiply-adds of the same expressions differently in each kernel (-march=native).
TEST(StressPeaks, SampleInTheForcePassEqualsTheSeparatePasses) {
  using namespace verification;
  const std::vector<Material> materials = {
      StVenantKirchhoff::make(1e7, 0.3, 1000.0, PlaneMode::stress), NeoHookean::make(1e7, 0.3, 1000.0, PlaneMode::strain),
      BlatzKo::make(4e6, 1000.0, PlaneMode::strain), MooneyRivlin::make(2e6, 5e5, 5e7, 1000.0, PlaneMode::stress)};
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> d(-0.015, 0.015);  // [m]: strains up to about 15 %, no cell inverted
  auto near = [](double a, double b) { return std::abs(a - b) <= 1e-13 * std::max(std::abs(a), std::abs(b)); };
  for (const Material& material : materials)
    for (const ElementKind kind : all_element_kinds()) {
      const Model<2> model = single_body_model(grid_mesh(1.0, 0.8, 5, 4, 0.2, kind), material,
                                            std::visit([](const auto& m) { return m.plane; }, material), kind);
      Eigen::VectorXd u(model.num_dofs()), v(model.num_dofs());
      for (int i = 0; i < model.num_dofs(); ++i) {
        u[i] = d(rng);
        v[i] = 10.0 * d(rng);
      }
      std::vector<std::uint8_t> contact_cell(model.num_cells(), 0);
      for (int c = 0; c < model.num_cells(); c += 4) contact_cell[c] = 1;
      const VonMises2 maxima = von_mises_maxima(model, u.data());
      for (int m = 0; m < kStressMeasures; ++m) {
        SCOPED_TRACE(std::string(element_name(kind)) + ", material " + std::to_string(material.index()) + ", measure " +
                     std::to_string(m));
        StressTracking tracking;
        tracking.contact_cell = contact_cell.data();
        tracking.measure = static_cast<StressMeasure>(m);
        std::vector<double> cells_ref(model.num_cells()), cells(model.num_cells(), -1.0), cells_implicit(model.num_cells(), -1.0);
        cell_von_mises(model, u.data(), tracking.measure, cells_ref.data());
        Eigen::VectorXd f_ref(model.num_dofs()), f(model.num_dofs());
        const ForceTotals ref = internal_forces(model, u.data(), v.data(), f_ref.data(), true, &tracking);
        ASSERT_GT(ref.min_jacobian, 0.0);
        const StressPeaks implicit_ref = stress_peaks(model, u.data(), tracking);

        VonMises2 sampled{0.0, 0.0, 0.0}, sampled_implicit{0.0, 0.0, 0.0};
        tracking.sampled_max = &sampled;
        tracking.cell_von_mises = cells.data();
        const ForceTotals got = internal_forces(model, u.data(), v.data(), f.data(), true, &tracking);
        tracking.sampled_max = &sampled_implicit;
        tracking.cell_von_mises = cells_implicit.data();
        const StressPeaks implicit_got = stress_peaks(model, u.data(), tracking);

        ASSERT_GT(maxima[m], 0.0);
        for (int k = 0; k < kStressMeasures; ++k) {
          EXPECT_TRUE(near(std::sqrt(sampled[k]), maxima[k])) << k << ": " << std::sqrt(sampled[k]) << " vs " << maxima[k];
          EXPECT_TRUE(near(std::sqrt(sampled_implicit[k]), maxima[k])) << k;
        }
        for (int c = 0; c < model.num_cells(); ++c) {
          EXPECT_TRUE(near(cells[c], cells_ref[c])) << "cell " << c << ": " << cells[c] << " vs " << cells_ref[c];
          EXPECT_TRUE(near(cells_implicit[c], cells_ref[c])) << "cell " << c;
        }
        EXPECT_EQ(f, f_ref);
        EXPECT_TRUE(near(got.strain_energy, ref.strain_energy));
        EXPECT_EQ(got.stress.all_cell, ref.stress.all_cell);
        EXPECT_EQ(got.stress.interior_cell, ref.stress.interior_cell);
        EXPECT_TRUE(near(got.stress.all, ref.stress.all));
        EXPECT_TRUE(near(got.stress.interior, ref.stress.interior));
        EXPECT_EQ(implicit_got.all_cell, implicit_ref.all_cell);
        EXPECT_EQ(implicit_got.interior_cell, implicit_ref.interior_cell);
        EXPECT_TRUE(near(implicit_got.all, implicit_ref.all));
      }
    }
}

}  // namespace
}  // namespace ricochet
