// Verification of the Blatz-Ko and compressible Mooney-Rivlin laws (solver/materials/material.hpp), in
// plane strain and plane stress: P = dW/dF and A = dP/dF against central differences, the
// stress-free reference state, objectivity, the small-strain limit (linear elasticity with the
// law's mu and lambda), the plane-stress elimination S33 = 0 checked with the 3D laws written
// out independently, plane-strain S33, wave speeds, the case-file keys, and one small explicit
// run per law and plane mode through read_case / prepare_case / run_case.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <unistd.h>

#include "harness/input/case_setup.hpp"
#include "harness/input/input_error.hpp"
#include "solver/materials/material.hpp"
#include "tests/support/deformations.hpp"
#include "tests/support/finite_difference.hpp"
#include "tests/support/matrix_checks.hpp"

namespace ricochet {
namespace {

constexpr double kMu = 4e5;         // [Pa] Blatz-Ko shear modulus (E = 1 MPa)
constexpr double kC10 = 1.5e5;      // [Pa]
constexpr double kC01 = 0.5e5;      // [Pa]
constexpr double kKappa = 2e6;      // [Pa]
constexpr double kDensity = 1000.0; // [kg/m^3]

using test_support::rotation;

// F = R(theta) Q diag(l1, l2) Q^T with stretches in [lo, hi] and |theta| <= 0.6 rad.
std::vector<Mat2> random_deformations(int count, unsigned seed, double lo = 0.75,
                                      double hi = 1.35) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> stretch(lo, hi);
  std::uniform_real_distribution<double> angle(-0.6, 0.6);
  std::uniform_real_distribution<double> axis(0.0, 3.14159);
  std::vector<Mat2> out;
  while (static_cast<int>(out.size()) < count) {
    const Mat2 q = rotation(axis(gen));
    out.push_back(rotation(angle(gen)) * q *
                  Eigen::Vector2d(stretch(gen), stretch(gen)).asDiagonal() * q.transpose());
  }
  return out;
}

struct Case {
  std::string name;
  Material material;
  PlaneMode plane;
  double mu, lambda;  // small-strain shear modulus and 3D first Lame constant [Pa]
};

std::vector<Case> all_cases() {
  std::vector<Case> c;
  for (PlaneMode p : {PlaneMode::stress, PlaneMode::strain}) {
    const std::string suffix = p == PlaneMode::stress ? " plane stress" : " plane strain";
    c.push_back({"BlatzKo" + suffix, BlatzKo::make(kMu, kDensity, p), p, kMu, kMu});
    const double mu = 2.0 * (kC10 + kC01);
    c.push_back({"MooneyRivlin" + suffix, MooneyRivlin::make(kC10, kC01, kKappa, kDensity, p), p,
                 mu, kKappa - 2.0 * mu / 3.0});
    // Pure c01 (the non-convex-in-F33 term alone) with a low bulk modulus (nu < 0).
    c.push_back({"MooneyRivlin c01 only" + suffix, MooneyRivlin::make(0.0, kC01, 0.2 * kC01, kDensity, p),
                 p, 2.0 * kC01, 0.2 * kC01 - 4.0 * kC01 / 3.0});
    // Pure c10 (compressible neo-Hookean-like), nearly incompressible (nu = 0.49).
    const double mu10 = 2.0 * kC10, kap = mu10 * 2.0 * 1.49 / (3.0 * 0.02);
    c.push_back({"MooneyRivlin c10 only" + suffix, MooneyRivlin::make(kC10, 0.0, kap, kDensity, p),
                 p, mu10, kap - 2.0 * mu10 / 3.0});
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
using test_support::max_abs;

// Plane-reduced first Lame constant.
double plane_lambda(const Case& c) {
  return c.plane == PlaneMode::stress ? 2.0 * c.lambda * c.mu / (c.lambda + 2.0 * c.mu)
                                      : c.lambda;
}

TEST(Hyperelastic, FirstPiolaIsEnergyDerivative) {
  // Central differences, h = 1e-5 on F ~ 1: truncation ~ h^2 ~ 1e-10 relative, round-off
  // ~ eps W / (h |P|) ~ 1e-10 (the plane-stress Newton converges to ~1e-15 in ln F33, and W is
  // stationary in F33, so its error enters W only quadratically). 1e-6 catches any wrong term.
  const double h = 1e-5;
  for (const Case& c : all_cases()) {
    double worst = 0.0;
    std::vector<Mat2> fs = random_deformations(50, 7);
    for (const Mat2& f : random_deformations(20, 8, 0.55, 1.8)) fs.push_back(f);
    for (const Mat2& f : fs) {
      const Mat2 p = piola(c.material, f);
      const Mat2 fd = test_support::fd_gradient([&](const Mat2& g) { return energy(c.material, g); }, f, h);
      worst = std::max(worst, (fd - p).norm() / p.norm());
    }
    EXPECT_LT(worst, 1e-6) << c.name;
    std::printf("[hyperelastic] %-36s max rel. error of P vs dW/dF: %.2e\n", c.name.c_str(), worst);
  }
}

Eigen::Matrix4d fd_tangent(const Material& m, const Mat2& F, double h) {
  return test_support::fd_tangent<2>([&](const Mat2& g) { return piola(m, g); }, F, h);
}

TEST(Hyperelastic, TangentIsFirstPiolaDerivative) {
  // Central differences with h = 1e-6: truncation ~ 1e-12, round-off ~ eps |P| / (h |A|)
  // ~ 1e-10 relative. 1e-6 catches any missing term (the plane-stress Schur complement of the
  // eliminated F33 is an O(lambda/(lambda + 2 mu)) change). The tangent is symmetric (to
  // round-off), and the fused P equals first_piola.
  const double h = 1e-6;
  for (const Case& c : all_cases()) {
    double worst = 0.0;
    std::vector<Mat2> fs = random_deformations(40, 17);
    for (const Mat2& f : random_deformations(20, 18, 0.55, 1.8)) fs.push_back(f);
    for (const Mat2& F : fs) {
      const Eigen::Matrix4d a = material_tangent(c.material, F);
      const Eigen::Matrix4d fd = fd_tangent(c.material, F, h);
      const double err = max_abs(a - fd) / max_abs(fd);
      worst = std::max(worst, err);
      EXPECT_LT(err, 1e-6) << c.name << "\nF =\n" << F;
      EXPECT_LT(max_abs(a - a.transpose()), 1e-13 * max_abs(a)) << c.name;
      std::visit(
          [&](const auto& x) {
            Mat2 p;
            Eigen::Matrix4d a2;
            x.first_piola_and_tangent(F, p, a2);
            EXPECT_LE(max_abs(a2 - a), 1e-14 * max_abs(a)) << c.name;
            const Mat2 pr = x.first_piola(F);
            EXPECT_LE((p - pr).cwiseAbs().maxCoeff(), 1e-13 * pr.cwiseAbs().maxCoeff()) << c.name;
          },
          c.material);
    }
    std::printf("[hyperelastic] %-36s max rel. error of A vs dP/dF: %.2e\n", c.name.c_str(), worst);
  }
}

TEST(Hyperelastic, ReferenceStateIsStressFree) {
  // At F = I the terms cancel up to the rounding of the 2/3, 4/3 ... coefficients: a few ulps
  // of the moduli.
  for (const Case& c : all_cases()) {
    const Mat2 id = Mat2::Identity();
    const double scale = c.mu + std::abs(c.lambda);
    EXPECT_LE(std::abs(energy(c.material, id)), 1e-14 * scale) << c.name;
    EXPECT_LE(piola(c.material, id).norm(), 1e-14 * scale) << c.name;
    const OutOfPlane o = out_of_plane(c.material, id);
    EXPECT_NEAR(o.stretch, 1.0, 1e-14) << c.name;
    EXPECT_LE(std::abs(o.pk2), 1e-14 * scale) << c.name;
  }
}

TEST(Hyperelastic, Objectivity) {
  // Functions of |F|^2 and det F only, plus one product with F: rotation changes W and P by
  // round-off (1e-12 relative ~ 1e4 ulps).
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

TEST(Hyperelastic, SmallStrainLimitIsLinearElasticity) {
  // F = I + H, |H| ~ 1e-6: P = lambda' tr(eps) I + 2 mu eps + O(|H|^2), lambda' the
  // plane-reduced lambda in plane stress. Relative difference ~1e-6 (nonlinearity) plus
  // round-off eps/|H| ~ 1e-10; 2e-5 is far below any modulus error. Blatz-Ko: lambda = mu
  // (nu = 1/4); Mooney-Rivlin: mu = 2 (c10 + c01), lambda = kappa - 2 mu / 3.
  std::mt19937 gen(3);
  std::uniform_real_distribution<double> entry(-1e-6, 1e-6);
  for (const Case& c : all_cases()) {
    const double lam = plane_lambda(c);
    for (int k = 0; k < 20; ++k) {
      Mat2 grad;
      grad << entry(gen), entry(gen), entry(gen), entry(gen);
      const Mat2 eps = 0.5 * (grad + grad.transpose());
      Mat2 sigma = 2.0 * c.mu * eps;
      sigma.diagonal().array() += lam * eps.trace();
      const Mat2 p = piola(c.material, Mat2::Identity() + grad);
      // The O(|H|^2) remainder scales with the largest modulus (kappa for nearly
      // incompressible Mooney-Rivlin), sigma with mu: allow for that ratio.
      EXPECT_LE((p - sigma).norm(), 2e-5 * (1.0 + std::abs(c.lambda) / c.mu) * sigma.norm())
          << c.name;
    }
    // The tangent at F = I is the Hooke tensor.
    Eigen::Matrix4d hooke;
    for (int i = 0; i < 2; ++i)
      for (int J = 0; J < 2; ++J)
        for (int kk = 0; kk < 2; ++kk)
          for (int L = 0; L < 2; ++L)
            hooke(2 * i + J, 2 * kk + L) =
                lam * (i == J) * (kk == L) + c.mu * ((i == kk) * (J == L) + (i == L) * (kk == J));
    EXPECT_LT(max_abs(material_tangent(c.material, Mat2::Identity()) - hooke),
              1e-12 * (c.mu + std::abs(c.lambda)))
        << c.name;
  }
}

// The 3D laws with C = diag(F^T F, C33), written out independently of solver/materials/material.cpp.
struct ThreeD {
  double w, s33, s33_scale;
};
ThreeD blatz_ko_3d(double mu, const Mat2& f, double f33) {
  const Mat2 c2 = f.transpose() * f;
  const double c33 = f33 * f33, jj = f.determinant() * f33;
  const double w = 0.5 * mu * (c2.inverse().trace() + 1.0 / c33 + 2.0 * jj - 5.0);
  // S = mu (J C^-1 - C^-2).
  const double a = mu * jj / c33, b = mu / (c33 * c33);
  return {w, a - b, std::abs(a) + std::abs(b)};
}
ThreeD mooney_rivlin_3d(double c10, double c01, double kappa, const Mat2& f, double f33) {
  const Mat2 c2 = f.transpose() * f;
  const double c33 = f33 * f33, jj = f.determinant() * f33;
  Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
  c.topLeftCorner<2, 2>() = c2;
  c(2, 2) = c33;
  const double i1 = c.trace(), i2 = 0.5 * (i1 * i1 - (c * c).trace());
  const double w = c10 * (std::pow(jj, -2.0 / 3.0) * i1 - 3.0) +
                   c01 * (std::pow(jj, -4.0 / 3.0) * i2 - 3.0) + 0.5 * kappa * (jj - 1.0) * (jj - 1.0);
  // S33 = 2 dW/dC33 with dI1 = 1, dI2 = I1 - C33, dJ = J / (2 C33).
  const double t1 = 2.0 * c10 * std::pow(jj, -2.0 / 3.0);
  const double t2 = -2.0 * c10 * i1 * std::pow(jj, -2.0 / 3.0) / (3.0 * c33);
  const double t3 = 2.0 * c01 * std::pow(jj, -4.0 / 3.0) * (i1 - c33);
  const double t4 = -4.0 * c01 * i2 * std::pow(jj, -4.0 / 3.0) / (3.0 * c33);
  const double t5 = kappa * (jj - 1.0) * jj / c33;
  return {w, t1 + t2 + t3 + t4 + t5,
          std::abs(t1) + std::abs(t2) + std::abs(t3) + std::abs(t4) + std::abs(t5)};
}
ThreeD three_d(const Material& m, const Mat2& f, double f33) {
  if (const auto* bk = std::get_if<BlatzKo>(&m)) return blatz_ko_3d(bk->shear_modulus, f, f33);
  const auto& mr = std::get<MooneyRivlin>(m);
  return mooney_rivlin_3d(mr.c10, mr.c01, mr.bulk_modulus, f, f33);
}

TEST(Hyperelastic, PlaneStressEliminatesS33) {
  // F33 from out_of_plane() in the 3D law: S33 must vanish relative to the size of its terms
  // (Blatz-Ko closed form, Mooney-Rivlin Newton to ~1e-15: 1e-12 is ~1e4 ulps), and the 3D
  // energy must equal the reduced 2D one.
  for (const Case& c : all_cases()) {
    if (c.plane != PlaneMode::stress) continue;
    double worst = 0.0;
    std::vector<Mat2> fs = random_deformations(50, 5);
    for (const Mat2& f : random_deformations(20, 6, 0.55, 1.8)) fs.push_back(f);
    for (const Mat2& f : fs) {
      const OutOfPlane o = out_of_plane(c.material, f);
      EXPECT_EQ(o.pk2, 0.0);
      const ThreeD t = three_d(c.material, f, o.stretch);
      worst = std::max(worst, std::abs(t.s33) / t.s33_scale);
      EXPECT_NEAR(energy(c.material, f), t.w, 1e-11 * std::max(std::abs(t.w), 1e-3 * c.mu))
          << c.name;
    }
    EXPECT_LT(worst, 1e-12) << c.name;
    std::printf("[hyperelastic] %-36s max |S33|/scale %.2e\n", c.name.c_str(), worst);
  }
}

TEST(Hyperelastic, PlaneStrainMatches3DLaw) {
  // F33 = 1; energy and S33 against the 3D laws (closed forms: 1e-11 relative).
  for (const Case& c : all_cases()) {
    if (c.plane != PlaneMode::strain) continue;
    for (const Mat2& f : random_deformations(30, 9)) {
      const OutOfPlane o = out_of_plane(c.material, f);
      EXPECT_EQ(o.stretch, 1.0);
      const ThreeD t = three_d(c.material, f, 1.0);
      EXPECT_NEAR(o.pk2, t.s33, 1e-11 * t.s33_scale) << c.name;
      EXPECT_NEAR(energy(c.material, f), t.w, 1e-11 * std::max(std::abs(t.w), 1e-3 * c.mu))
          << c.name;
    }
  }
}

TEST(Hyperelastic, PlaneStressBlatzKoStretchIsClosedForm) {
  // S33 = 0 gives C33 = (det F)^(-2/3).
  const auto bk = BlatzKo::make(kMu, kDensity, PlaneMode::stress);
  for (const Mat2& f : random_deformations(20, 4)) {
    const double expect = std::pow(f.determinant(), -1.0 / 3.0);
    EXPECT_NEAR(bk.out_of_plane(f).stretch, expect, 1e-14 * expect);
  }
}

TEST(Hyperelastic, WaveSpeeds) {
  // c_p = sqrt((lambda' + 2 mu) / rho). Blatz-Ko: plane strain sqrt(3 mu / rho), plane stress
  // sqrt(8 mu / (3 rho)). Mooney-Rivlin: plane strain sqrt((kappa + 4 mu / 3) / rho).
  for (const Case& c : all_cases()) {
    const double expect = std::sqrt((plane_lambda(c) + 2.0 * c.mu) / kDensity);
    EXPECT_NEAR(material_wave_speed(c.material), expect, 1e-14 * expect) << c.name;
    EXPECT_EQ(material_density(c.material), kDensity) << c.name;
  }
  const double strain = material_wave_speed(BlatzKo::make(kMu, kDensity, PlaneMode::strain));
  const double stress = material_wave_speed(BlatzKo::make(kMu, kDensity, PlaneMode::stress));
  EXPECT_NEAR(strain, std::sqrt(3.0 * kMu / kDensity), 1e-14 * strain);
  EXPECT_NEAR(stress, std::sqrt(8.0 * kMu / (3.0 * kDensity)), 1e-14 * stress);
  const double mu = 2.0 * (kC10 + kC01);
  const double mr = material_wave_speed(MooneyRivlin::make(kC10, kC01, kKappa, kDensity, PlaneMode::strain));
  EXPECT_NEAR(mr, std::sqrt((kKappa + 4.0 * mu / 3.0) / kDensity), 1e-14 * mr);
}

TEST(Hyperelastic, VonMisesOfUniaxialStress) {
  // Plane stress, F = diag(s, t) with t from P_yy = 0 (bisection to the last bit): uniaxial
  // stress sigma_xx = P_xx s / J, J = s t F33, whose von Mises value is |sigma_xx|, also after a
  // superposed rotation (1e-12 relative: the residual sigma_yy is bisection round-off, plus
  // ~100 ulps of the moduli, the round-off of the cancelling terms of P when |sigma| << kappa).
  for (const Case& c : all_cases()) {
    if (c.plane != PlaneMode::stress) continue;
    for (double s : {0.8, 0.97, 1.001, 1.2}) {
      double lo = 0.5, hi = 1.5;
      for (int it = 0; it < 200; ++it) {
        const double mid = 0.5 * (lo + hi);
        if (mid <= lo || mid >= hi) break;
        (piola(c.material, Eigen::Vector2d(s, mid).asDiagonal())(1, 1) < 0.0 ? lo : hi) = mid;
      }
      const double t = 0.5 * (lo + hi);
      const Mat2 f = Eigen::Vector2d(s, t).asDiagonal();
      const double j = s * t * out_of_plane(c.material, f).stretch;
      const double sigma = piola(c.material, f)(0, 0) * s / j;
      for (double angle : {0.0, 0.4, 2.2})
        EXPECT_NEAR(von_mises(c.material, rotation(angle) * f), std::abs(sigma),
                    1e-12 * std::abs(sigma) + 1e-14 * (c.mu + std::abs(c.lambda)))
            << c.name << " s=" << s;
    }
  }
}

// ------------------------------------------------------------------------- case files and runs

std::string write_case(const std::string& name, const std::string& plane,
                       const std::string& material, const std::string& dt = "\"auto\"") {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("ricochet_hyperelastic_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::filesystem::path file = dir / (name + ".toml");
  std::ofstream out(file);
  // A cantilever clamped on its left edge, set in motion by a uniform initial velocity (the cases/examples/cantilever_gravity.toml setup, shorter and coarser).
  out << "name = \"" << name << "\"\nplane = \"" << plane << "\"\nmesh = \"beam\"\n"
      << "\n"
      << "[meshes.beam]\ngenerator = \"rectangle\"\nwidth = 0.2\nheight = 0.02\nnx = 20\nny = 2\n\n"
      << "[[bodies]]\nname = \"beam\"\nthickness = 0.01\nvelocity = [0.0, -0.5]\n\n"
      << "[bodies.material]\n" << material << "\n\n"
      << "[[boundary]]\nnodes = \"left\"\ntype = \"displacement\"\nx = 0.0\ny = 0.0\n\n"
      << "[time]\nend = 0.05\ndt = " << dt << "\nsafety = 0.9\n";
  return file.string();
}

const std::string kBlatzKo =
    "model = \"blatz_ko\"\nshear_modulus = 4e5\ndensity = 1000.0";
const std::string kMooneyRivlin =
    "model = \"mooney_rivlin\"\nc10 = 1.5e5\nc01 = 0.5e5\nbulk_modulus = 2e6\ndensity = 1000.0";

TEST(Hyperelastic, CaseFileKeysAndRestrictions) {
  {
    const CaseSpec spec = read_case(write_case("bk_keys", "stress", kBlatzKo), {});
    EXPECT_EQ(spec.bodies[0].material.model, "blatz_ko");
    EXPECT_EQ(spec.bodies[0].material.shear_modulus, 4e5);
    const PreparedCase pc = prepare_case(spec);
    EXPECT_TRUE(std::holds_alternative<BlatzKo>(pc.model<2>().bodies[0].material));
  }
  {
    const CaseSpec spec = read_case(write_case("mr_keys", "strain", kMooneyRivlin), {});
    const MaterialSpec& m = spec.bodies[0].material;
    EXPECT_EQ(m.model, "mooney_rivlin");
    EXPECT_EQ(m.c10, 1.5e5);
    EXPECT_EQ(m.c01, 0.5e5);
    EXPECT_EQ(m.bulk_modulus, 2e6);
  }
  // young / poisson are unknown keys for these laws; missing or out-of-range parameters fail.
  auto rejects = [](const std::string& name, const std::string& material, const std::string& word) {
    try {
      read_case(write_case(name, "stress", material), {});
      ADD_FAILURE() << name << ": accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << name << ": " << e.what();
    }
  };
  rejects("bk_young", kBlatzKo + "\nyoung = 1e6", "young");
  rejects("bk_missing", "model = \"blatz_ko\"\ndensity = 1000.0", "shear_modulus");
  rejects("bk_negative", "model = \"blatz_ko\"\nshear_modulus = -1.0\ndensity = 1000.0",
          "shear_modulus");
  rejects("mr_poisson", kMooneyRivlin + "\npoisson = 0.3", "poisson");
  rejects("mr_zero", "model = \"mooney_rivlin\"\nc10 = 0.0\nc01 = 0.0\nbulk_modulus = 1e6\ndensity = 1.0",
          "c10 + c01");
  rejects("mr_negative", "model = \"mooney_rivlin\"\nc10 = -1.0\nc01 = 1e5\nbulk_modulus = 1e6\ndensity = 1.0",
          "c10");
  rejects("mr_kappa", "model = \"mooney_rivlin\"\nc10 = 1e5\nc01 = 0.0\ndensity = 1.0", "bulk_modulus");
  rejects("nh_shear", "model = \"neo_hookean\"\nyoung = 1e6\npoisson = 0.3\nshear_modulus = 1e5\ndensity = 1.0",
          "shear_modulus");
}

TEST(Hyperelastic, CantileverRunsWithEachLaw) {
  // Explicit central differences conserve energy to O(dt^2): with the automatic step (safety
  // 0.9) the relative energy error of this run is 0.6e-3..1.6e-3, as for neo-Hookean with the same
  // small-strain moduli (measured 1.6e-3); with dt = 2e-5 s (about 10x smaller) it must drop
  // by (dt ratio)^2 = 40..95x. Bounds: 5e-3 and 1e-4, and a reduction of at least 20x.
  const std::vector<std::pair<std::string, std::string>> laws = {{"blatz_ko", kBlatzKo},
                                                                   {"mooney_rivlin", kMooneyRivlin}};
  for (const std::string plane : {"stress", "strain"}) {
    for (const auto& [law, material] : laws) {
      double err[2] = {0.0, 0.0};
      for (int fine = 0; fine < 2; ++fine) {
        const std::string name = law + "_" + plane + (fine ? "_fine" : "");
        const PreparedCase pc = prepare_case(
            read_case(write_case(name, plane, material, fine ? "2e-5" : "\"auto\""), {}));
        const RunResult r = run_case(pc);
        EXPECT_EQ(r.status, RunStatus::ok) << name << ": " << r.reason;
        EXPECT_GT(r.steps, 100) << name;
        EXPECT_GT(r.initial_energy, 0.0) << name;
        err[fine] = r.energy_error_max;
        std::printf("[hyperelastic] run %-28s dt %.3e s, %ld steps, energy error max %.2e, "
                    "von Mises max %.3e Pa\n",
                    name.c_str(), r.dt, r.steps, r.energy_error_max, r.stress.von_mises_max);
      }
      EXPECT_LT(err[0], 5e-3) << law << " " << plane;
      EXPECT_LT(err[1], 1e-4) << law << " " << plane;
      EXPECT_GT(err[0], 20.0 * err[1]) << law << " " << plane;
    }
  }
  std::filesystem::remove_all(std::filesystem::temp_directory_path() /
                              ("ricochet_hyperelastic_" + std::to_string(::getpid())));
}

}  // namespace
}  // namespace ricochet
