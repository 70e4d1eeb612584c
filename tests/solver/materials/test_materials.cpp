// Verification of the hyperelastic materials (solver/materials/material.hpp): P = dW/dF, stress-free
// reference state, objectivity, the small-strain limit, the plane-stress elimination of S33,
// wave speeds and the von Mises equivalent stress.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "solver/materials/material.hpp"
#include "tests/support/deformations.hpp"
#include "tests/support/finite_difference.hpp"

namespace ricochet {
namespace {

constexpr double kYoung = 200e9;  // [Pa]
constexpr double kPoisson = 0.3;  // [-]
constexpr double kDensity = 7800.0;  // [kg/m^3]

using test_support::random_deformations;
using test_support::rotation;

struct Case {
  std::string name;
  Material material;
  PlaneMode plane;
};

std::vector<Case> all_cases() {
  std::vector<Case> c;
  for (PlaneMode p : {PlaneMode::stress, PlaneMode::strain}) {
    const std::string suffix = p == PlaneMode::stress ? " plane stress" : " plane strain";
    c.push_back({"StVenantKirchhoff" + suffix,
                 StVenantKirchhoff::make(kYoung, kPoisson, kDensity, p), p});
    c.push_back({"NeoHookean" + suffix, NeoHookean::make(kYoung, kPoisson, kDensity, p), p});
  }
  return c;
}

double energy(const Material& m, const Mat2& f) {
  return std::visit([&f](const auto& x) { return x.energy_density(f); }, m);
}
Mat2 piola(const Material& m, const Mat2& f) {
  return std::visit([&f](const auto& x) { return x.first_piola(f); }, m);
}
OutOfPlane out_of_plane(const Material& m, const Mat2& f) {
  return std::visit([&f](const auto& x) { return x.out_of_plane(f); }, m);
}

TEST(Materials, FirstPiolaIsEnergyDerivative) {
  // Central differences with step h = 1e-5 (F is O(1)): truncation error ~ h^2 W''' ~ 1e-10
  // relative, round-off ~ eps W / h ~ 1e-11 relative, so 1e-6 leaves a wide margin yet
  // catches any wrong term (a wrong coefficient is an O(1) error).
  const double h = 1e-5;
  for (const Case& c : all_cases()) {
    double worst = 0.0;
    for (const Mat2& f : random_deformations(50, 7)) {
      const Mat2 p = piola(c.material, f);
      const Mat2 fd = test_support::fd_gradient([&](const Mat2& g) { return energy(c.material, g); }, f, h);
      worst = std::max(worst, (fd - p).norm() / p.norm());
    }
    EXPECT_LT(worst, 1e-6) << c.name;
    std::printf("[materials] %-32s max rel. error of P vs dW/dF: %.2e\n", c.name.c_str(), worst);
  }
}

TEST(Materials, ReferenceStateIsStressFree) {
  // At F = I every term of W and P cancels exactly in floating point (E = 0, ln 1 = 0, the
  // Newton solve starts and stays at s = 0); allow a few ulps of the modulus.
  for (const Case& c : all_cases()) {
    const Mat2 id = Mat2::Identity();
    EXPECT_LE(std::abs(energy(c.material, id)), 1e-15 * kYoung) << c.name;
    EXPECT_LE(piola(c.material, id).norm(), 1e-15 * kYoung) << c.name;
    const OutOfPlane o = out_of_plane(c.material, id);
    EXPECT_NEAR(o.stretch, 1.0, 1e-15) << c.name;
    EXPECT_LE(std::abs(o.pk2), 1e-15 * kYoung) << c.name;
  }
}

TEST(Materials, Objectivity) {
  // W and P are built from F^T F (or its invariants) plus one final product with F, so a
  // superposed rotation changes them only by round-off: 1e-12 relative is ~1e4 ulps.
  for (const Case& c : all_cases()) {
    for (const Mat2& f : random_deformations(20, 11)) {
      for (double angle : {0.3, 1.7, -2.9}) {
        const Mat2 r = rotation(angle);
        const double w = energy(c.material, f);
        EXPECT_NEAR(energy(c.material, r * f), w, 1e-12 * std::abs(w)) << c.name;
        const Mat2 p = piola(c.material, f);
        EXPECT_LE((piola(c.material, r * f) - r * p).norm(), 1e-12 * p.norm()) << c.name;
      }
    }
  }
}

TEST(Materials, SmallStrainLimitIsLinearElasticity) {
  // F = I + H with |H| ~ 1e-6: P = C:sym(H) + O(|H|^2 E), so the relative difference is
  // ~|H| = 1e-6 (geometric and material nonlinearity), plus round-off eps/|H| ~ 1e-10.
  // 2e-5 is twenty times the expected size and far below any error in a modulus.
  const Lame l = lame_from_young_poisson(kYoung, kPoisson);
  std::mt19937 gen(3);
  std::uniform_real_distribution<double> entry(-1e-6, 1e-6);
  for (const Case& c : all_cases()) {
    for (int k = 0; k < 20; ++k) {
      Mat2 grad;
      grad << entry(gen), entry(gen), entry(gen), entry(gen);
      const Mat2 eps = 0.5 * (grad + grad.transpose());
      Mat2 sigma;
      if (c.plane == PlaneMode::stress) {
        const double a = kYoung / (1.0 - kPoisson * kPoisson);
        sigma(0, 0) = a * (eps(0, 0) + kPoisson * eps(1, 1));
        sigma(1, 1) = a * (eps(1, 1) + kPoisson * eps(0, 0));
        sigma(0, 1) = sigma(1, 0) = kYoung / (1.0 + kPoisson) * eps(0, 1);
      } else {
        sigma = 2.0 * l.shear_modulus * eps;
        sigma.diagonal().array() += l.lambda * eps.trace();
      }
      const Mat2 p = piola(c.material, Mat2::Identity() + grad);
      EXPECT_LE((p - sigma).norm(), 2e-5 * sigma.norm()) << c.name;
    }
  }
}

TEST(Materials, PlaneStressEliminatesS33) {
  // The 3D laws evaluated by hand with F33 from out_of_plane(): S33 must vanish and the 3D
  // energy must equal the reduced 2D one. Both are sums of O(mu * strain) terms that cancel,
  // so the residual is compared with the size of those terms; the Newton solve (neo-Hookean)
  // and the closed form (SVK) are accurate to round-off, 1e-12 is ~1e4 ulps.
  const Lame l = lame_from_young_poisson(kYoung, kPoisson);
  const double lam = l.lambda, mu = l.shear_modulus;
  const auto svk = StVenantKirchhoff::make(kYoung, kPoisson, kDensity, PlaneMode::stress);
  const auto nh = NeoHookean::make(kYoung, kPoisson, kDensity, PlaneMode::stress);
  double worst_svk = 0.0, worst_nh = 0.0;
  for (const Mat2& f : random_deformations(50, 5)) {
    // SVK: S33 = lambda (tr E2 + E33) + 2 mu E33.
    {
      const OutOfPlane o = svk.out_of_plane(f);
      EXPECT_EQ(o.pk2, 0.0);
      const Mat2 e2 = 0.5 * (f.transpose() * f - Mat2::Identity());
      const double e33 = 0.5 * (o.stretch * o.stretch - 1.0);
      const double s33 = lam * (e2.trace() + e33) + 2.0 * mu * e33;
      const double scale = std::abs(lam * (e2.trace() + e33)) + std::abs(2.0 * mu * e33);
      worst_svk = std::max(worst_svk, std::abs(s33) / scale);
      const double tr = e2.trace() + e33;
      const double w3 = 0.5 * lam * tr * tr + mu * (e2.squaredNorm() + e33 * e33);
      EXPECT_NEAR(svk.energy_density(f), w3, 1e-12 * w3);
    }
    // Neo-Hookean: S33 = mu (1 - 1/C33) + lambda ln J / C33, J = det F * F33.
    {
      const OutOfPlane o = nh.out_of_plane(f);
      EXPECT_EQ(o.pk2, 0.0);
      const double c33 = o.stretch * o.stretch;
      const double log_j = std::log(f.determinant() * o.stretch);
      const double s33 = mu * (1.0 - 1.0 / c33) + lam * log_j / c33;
      const double scale = std::abs(mu * (1.0 - 1.0 / c33)) + std::abs(lam * log_j / c33);
      worst_nh = std::max(worst_nh, std::abs(s33) / scale);
      const double w3 = 0.5 * mu * (f.squaredNorm() + c33 - 3.0) - mu * log_j +
                        0.5 * lam * log_j * log_j;
      EXPECT_NEAR(nh.energy_density(f), w3, 1e-12 * w3);
    }
  }
  EXPECT_LT(worst_svk, 1e-12);
  EXPECT_LT(worst_nh, 1e-12);
  std::printf("[materials] plane stress: max |S33|/scale SVK %.2e, neo-Hookean %.2e\n", worst_svk,
              worst_nh);
}

TEST(Materials, PlaneStrainOutOfPlaneStress) {
  // Plane strain: F33 = 1 and S33 from the 3D laws (SVK: lambda tr E; neo-Hookean:
  // lambda ln J). Closed forms, so agreement to round-off (1e-12 relative).
  const Lame l = lame_from_young_poisson(kYoung, kPoisson);
  const auto svk = StVenantKirchhoff::make(kYoung, kPoisson, kDensity, PlaneMode::strain);
  const auto nh = NeoHookean::make(kYoung, kPoisson, kDensity, PlaneMode::strain);
  for (const Mat2& f : random_deformations(20, 9)) {
    const double tr_e = 0.5 * (f.squaredNorm() - 2.0);
    const OutOfPlane a = svk.out_of_plane(f);
    EXPECT_EQ(a.stretch, 1.0);
    EXPECT_NEAR(a.pk2, l.lambda * tr_e, 1e-12 * std::abs(l.lambda * tr_e));
    const OutOfPlane b = nh.out_of_plane(f);
    EXPECT_EQ(b.stretch, 1.0);
    const double expect = l.lambda * std::log(f.determinant());
    EXPECT_NEAR(b.pk2, expect, 1e-12 * std::abs(expect));
  }
}

TEST(Materials, WaveSpeeds) {
  // Closed forms; 1e-14 relative allows a few ulps from the different operation order.
  const Lame l = lame_from_young_poisson(kYoung, kPoisson);
  const double c_stress = std::sqrt(kYoung / (kDensity * (1.0 - kPoisson * kPoisson)));
  const double c_strain = std::sqrt((l.lambda + 2.0 * l.shear_modulus) / kDensity);
  for (const Case& c : all_cases()) {
    const double expect = c.plane == PlaneMode::stress ? c_stress : c_strain;
    EXPECT_NEAR(material_wave_speed(c.material), expect, 1e-14 * expect) << c.name;
    EXPECT_EQ(material_density(c.material), kDensity) << c.name;
  }
}

// Solves g(x) = 0 for an increasing g by bisection on [lo, hi], to the last bit.
template <class G>
double bisect(G g, double lo, double hi) {
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi) break;
    (g(mid) < 0.0 ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

TEST(Materials, VonMisesOfUniaxialStress) {
  // Plane stress: F = diag(s, t) with t chosen so that P_yy = 0 (bisection to the last bit)
  // is a uniaxial stress state, sigma_xx = P_xx s / J with J = s t F33; its von Mises value is
  // |sigma_xx|, also after a superposed rotation. The residual sigma_yy is round-off of the
  // bisection (~1e-16 of sigma_xx), so 1e-12 relative is safe.
  for (const Case& c : all_cases()) {
    if (c.plane != PlaneMode::stress) continue;
    for (double s : {0.8, 0.97, 1.001, 1.2}) {
      const double t = bisect(
          [&](double y) { return piola(c.material, Eigen::Vector2d(s, y).asDiagonal())(1, 1); },
          0.5, 1.5);
      const Mat2 f = Eigen::Vector2d(s, t).asDiagonal();
      const Mat2 p = piola(c.material, f);
      const double j = s * t * out_of_plane(c.material, f).stretch;
      const double sigma = p(0, 0) * s / j;
      for (double angle : {0.0, 0.4, 2.2}) {
        const double vm = von_mises(c.material, rotation(angle) * f);
        EXPECT_NEAR(vm, std::abs(sigma), 1e-12 * std::abs(sigma)) << c.name << " s=" << s;
      }
    }
  }
}

TEST(Materials, VonMisesPlaneStrainUsesS33) {
  // Plane strain: choose F = diag(s, t) with sigma_yy = sigma_33 (sigma_33 = S33 / J with
  // F33 = 1, from the 3D laws). Then the 3D stress is sigma_xx on x and a common lateral value,
  // so von Mises = |sigma_xx - sigma_yy|. This exercises the out-of-plane term; tolerance as above.
  const Lame l = lame_from_young_poisson(kYoung, kPoisson);
  for (const Case& c : all_cases()) {
    if (c.plane != PlaneMode::strain) continue;
    const bool is_svk = std::holds_alternative<StVenantKirchhoff>(c.material);
    auto cauchy = [&](double s, double t) {
      const Mat2 f = Eigen::Vector2d(s, t).asDiagonal();
      const double j = s * t;
      const Mat2 sig = piola(c.material, f) * f.transpose() / j;
      const double s33 =
          is_svk ? l.lambda * 0.5 * (s * s + t * t - 2.0) : l.lambda * std::log(j);
      return Eigen::Vector3d(sig(0, 0), sig(1, 1), s33 / j);
    };
    for (double s : {0.85, 1.003, 1.15}) {
      const double t = bisect(
          [&](double y) {
            const Eigen::Vector3d sig = cauchy(s, y);
            return sig(1) - sig(2);
          },
          0.5, 1.5);
      const Eigen::Vector3d sig = cauchy(s, t);
      const double expect = std::abs(sig(0) - sig(1));
      const double vm = von_mises(c.material, rotation(0.7) * Mat2(Eigen::Vector2d(s, t).asDiagonal()));
      EXPECT_NEAR(vm, expect, 1e-12 * expect) << c.name << " s=" << s;
    }
  }
}

}  // namespace
}  // namespace ricochet
