// Verification of the element kernels (solver/internal_forces, solver/model): forces are the
// gradient of the stored energy, rigid motions and homogeneous deformations (patch test) give
// no spurious forces, hourglass control acts on the hourglass mode only, lumped masses, the
// critical-step estimate against the true element eigenvalue, and mesh validation.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "solver/forces/internal_forces.hpp"
#include "tests/support/finite_difference.hpp"
#include "tests/support/verification_meshes.hpp"

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

std::vector<MaterialCase> material_cases() {
  std::vector<MaterialCase> c;
  for (PlaneMode p : {PlaneMode::stress, PlaneMode::strain}) {
    const std::string suffix = p == PlaneMode::stress ? ", plane stress" : ", plane strain";
    c.push_back({"SVK" + suffix, StVenantKirchhoff::make(kYoung, kPoisson, kDensity, p), p});
    c.push_back({"neo-Hookean" + suffix, NeoHookean::make(kYoung, kPoisson, kDensity, p), p});
  }
  return c;
}

Mat2 rotation(double angle) {
  Mat2 r;
  r << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
  return r;
}

// u_I = (G) X_I + c for every node: a homogeneous displacement gradient G plus a translation.
Eigen::VectorXd affine_field(const Model<2>& model, const Mat2& g, const Vec2& c) {
  Eigen::VectorXd u(model.num_dofs());
  for (int i = 0; i < model.num_nodes(); ++i) u.segment<2>(2 * i) = g * model.ref.col(i) + c;
  return u;
}

// Total stored energy: strain energy plus the stiffness-form hourglass energy.
double stored_energy(const Model<2>& model, const Eigen::VectorXd& u, Eigen::VectorXd& f) {
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(model.num_dofs());
  const ForceTotals t = internal_forces(model, u.data(), v.data(), f.data(), true);
  return t.strain_energy + t.hourglass_energy;
}

Eigen::VectorXd forces(const Model<2>& model, const Eigen::VectorXd& u, const Eigen::VectorXd& v) {
  Eigen::VectorXd f(model.num_dofs());
  internal_forces(model, u.data(), v.data(), f.data(), false);
  return f;
}

double total_area(const Mesh& m) {
  double a = 0.0;
  for (const auto& q : m.quads) a += signed_area(m, q.data(), 4);
  for (const auto& t : m.tris) a += signed_area(m, t.data(), 3);
  return a;
}

// Mesh of 1 m x 0.8 m, 4 x 3 cells, interior nodes moved by up to 20 % of a cell.
Mesh distorted_mesh(ElementKind kind) { return grid_mesh(1.0, 0.8, 4, 3, 0.2, kind); }

TEST(Elements, ForcesAreEnergyGradient) {
  // Central differences of E = strain + stored hourglass energy with step 1e-7 m around a
  // random displacement of up to 4 % of the mesh size (strains of ~10 %, well inside the
  // nonlinear range). Truncation ~ (1e-7 / 0.04)^2 ~ 1e-11 relative, round-off
  // ~ eps E / (h f) ~ 1e-16 * 0.04 / 1e-7 ~ 4e-11 relative; 1e-6 of the largest nodal force
  // catches any missing or wrong force term.
  const double h = 1e-7;
  for (const MaterialCase& mc : material_cases())
    for (ElementKind kind : all_element_kinds()) {
      const Mesh mesh = distorted_mesh(kind);
      const Model<2> model = single_body_model(mesh, mc.material, mc.plane, kind, kThickness);
      std::mt19937 gen(42);
      std::uniform_real_distribution<double> amp(-0.04, 0.04);
      Eigen::VectorXd u(model.num_dofs());
      for (int d = 0; d < u.size(); ++d) u[d] = amp(gen);
      Eigen::VectorXd f(model.num_dofs()), scratch(model.num_dofs());
      stored_energy(model, u, f);
      const Eigen::VectorXd fd =
          test_support::fd_gradient([&](const Eigen::VectorXd& w) { return stored_energy(model, w, scratch); }, u, h);
      const double err = (fd - f).lpNorm<Eigen::Infinity>() / f.lpNorm<Eigen::Infinity>();
      EXPECT_LT(err, 1e-6) << element_name(kind) << ", " << mc.name;
      std::printf("[elements] dE/du vs f_int  %-20s %-26s rel. error %.2e\n", element_name(kind),
                  mc.name.c_str(), err);
    }
}

TEST(Elements, RigidMotionGivesNoForce) {
  // Under a rigid translation F = I + (c x sum_I dN_I/dX) = I up to round-off, and under a
  // rotation F = R up to round-off, so every stress is ~eps E and every nodal force
  // ~eps E t L. The force scale is E * t * sqrt(A) (a stress times a cross-section); 1e-12 of
  // it is ~1e4 ulps, while any real error (e.g. a linearised strain) gives O(1e-1) at 60 deg.
  for (const MaterialCase& mc : material_cases())
    for (ElementKind kind : all_element_kinds()) {
      const Mesh mesh = distorted_mesh(kind);
      const Model<2> model = single_body_model(mesh, mc.material, mc.plane, kind, kThickness);
      const double scale = kYoung * kThickness * std::sqrt(total_area(mesh));
      const Vec2 c(0.37, -0.81);
      const Mat2 r = rotation(M_PI / 3.0);
      // Velocities of the same rigid motions (translation rate, spin W X) for the viscous form.
      Mat2 spin;
      spin << 0.0, -25.0, 25.0, 0.0;
      const Eigen::VectorXd u_t = affine_field(model, Mat2::Zero(), c);
      const Eigen::VectorXd v_t = affine_field(model, Mat2::Zero(), Vec2(3.0, -4.0));
      const Eigen::VectorXd u_r = affine_field(model, r - Mat2::Identity(), c);
      const Eigen::VectorXd v_r = affine_field(model, spin * r, Vec2(3.0, -4.0));
      const double ft = forces(model, u_t, v_t).lpNorm<Eigen::Infinity>() / scale;
      const double fr = forces(model, u_r, v_r).lpNorm<Eigen::Infinity>() / scale;
      EXPECT_LT(ft, 1e-12) << element_name(kind) << ", " << mc.name;
      EXPECT_LT(fr, 1e-12) << element_name(kind) << ", " << mc.name;
      std::printf("[elements] rigid motion %-20s %-26s max|f|/(E t sqrt A): translation %.1e, "
                  "60 deg rotation %.1e\n",
                  element_name(kind), mc.name.c_str(), ft, fr);
    }
}

TEST(Elements, PatchTestHomogeneousDeformation) {
  // u = (F - I) X with a finite F (stretch, shear, rotation): every integration point sees
  // exactly F, so interior nodal forces are sums of vol * dN/dX P^T that cancel exactly in
  // exact arithmetic (2x2 Gauss integrates grad N exactly; the mean gradients telescope; the
  // hourglass vectors are orthogonal to linear fields). Compared with the boundary forces
  // (O(E t L |F - I|)), interior forces must be round-off: 1e-12 relative.
  Mat2 f;
  f << 1.12, 0.21, -0.07, 0.93;
  for (const MaterialCase& mc : material_cases())
    for (ElementKind kind : all_element_kinds()) {
      const Mesh mesh = distorted_mesh(kind);
      const Model<2> model = single_body_model(mesh, mc.material, mc.plane, kind, kThickness);
      const Eigen::VectorXd u = affine_field(model, f - Mat2::Identity(), Vec2(0.1, 0.2));
      Mat2 l;  // a homogeneous velocity gradient for the viscous hourglass form
      l << 30.0, -12.0, 7.0, -21.0;
      const Eigen::VectorXd v = affine_field(model, l, Vec2(1.0, 2.0));
      const Eigen::VectorXd fi = forces(model, u, v);
      double interior = 0.0, boundary = 0.0;
      const int nx = 4, ny = 3;
      for (int j = 0; j <= ny; ++j)
        for (int i = 0; i <= nx; ++i) {
          const int k = j * (nx + 1) + i;
          const double m = fi.segment<2>(2 * k).norm();
          if (i > 0 && i < nx && j > 0 && j < ny)
            interior = std::max(interior, m);
          else
            boundary = std::max(boundary, m);
        }
      EXPECT_GT(boundary, 1e-3 * kYoung * kThickness * 0.2) << element_name(kind);
      EXPECT_LT(interior, 1e-12 * boundary) << element_name(kind) << ", " << mc.name;
      std::printf("[elements] patch test %-20s %-26s max interior |f| / max boundary |f| %.1e\n",
                  element_name(kind), mc.name.c_str(), interior / boundary);
    }
}

// A distorted convex quadrilateral (counter-clockwise) and its documented hourglass data,
// computed independently of model.cpp: gamma from Flanagan-Belytschko eq. (72) (docs/background.md,
// Hourglass control), B_I = b_I / A with b_I = (y_{I+1} - y_{I-1}, x_{I-1} - x_{I+1}) / 2.
struct QuadData {
  Eigen::Matrix<double, 2, 4> x;
  double area = 0.0;
  Eigen::Vector4d gamma;
  double bb = 0.0;  // B:B [1/m^2]
};

QuadData distorted_quad() {
  QuadData d;
  d.x << 0.0, 1.1, 1.3, -0.2,  //
      0.0, 0.15, 0.9, 0.7;
  const auto xs = [&](int i) { return d.x(0, ((i % 4) + 4) % 4); };
  const auto ys = [&](int i) { return d.x(1, ((i % 4) + 4) % 4); };
  d.area = 0.5 * ((xs(2) - xs(0)) * (ys(3) - ys(1)) - (xs(3) - xs(1)) * (ys(2) - ys(0)));
  for (int i = 0; i < 4; ++i) {
    // gamma_1 = [x2(y3 - y4) + x3(y4 - y2) + x4(y2 - y3)] / (4A), cyclically.
    const double x2 = xs(i + 1), x3 = xs(i + 2), x4 = xs(i + 3);
    const double y2 = ys(i + 1), y3 = ys(i + 2), y4 = ys(i + 3);
    const double sign = i % 2 == 0 ? 1.0 : -1.0;  // gamma_I carries the sign of h_I
    d.gamma[i] = sign * (x2 * (y3 - y4) + x3 * (y4 - y2) + x4 * (y2 - y3)) / (4.0 * d.area);
    const double bx = 0.5 * (ys(i + 1) - ys(i - 1)) / d.area;
    const double by = 0.5 * (xs(i - 1) - xs(i + 1)) / d.area;
    d.bb += bx * bx + by * by;
  }
  return d;
}

Mesh single_quad_mesh(const Eigen::Matrix<double, 2, 4>& x) {
  Mesh m;
  m.nodes = x;
  m.quads.push_back({0, 1, 2, 3});
  return m;
}

TEST(Elements, HourglassForcesActOnTheHourglassModeOnly) {
  // The hourglass force of the one-point Q4 is isolated exactly: viscous form with u = 0
  // (no strain, P(I) = 0), stiffness form as f(stiffness) - f(viscous, v = 0) for the same u
  // (identical mean-gradient parts). On rigid and linear fields it must be round-off
  // (gamma . x_i = 0 analytically): 1e-12 of c |field|. On the hourglass mode
  // h = (1, -1, 1, -1) in x (or y), q = gamma . h = 1 exactly, so f_I = gamma_I c, compared
  // with gamma and c from the documented formulas to 1e-12 relative (closed forms).
  const QuadData qd = distorted_quad();
  const Mesh mesh = single_quad_mesh(qd.x);
  const double coeff = 0.1;
  const Eigen::Vector4d h(1.0, -1.0, 1.0, -1.0);
  for (const MaterialCase& mc : material_cases()) {
    const Model<2> visc =
        single_body_model(mesh, mc.material, mc.plane, ElementKind::q4_viscous, kThickness, coeff);
    const Model<2> stiff = single_body_model(mesh, mc.material, mc.plane, ElementKind::q4_stiffness,
                                          kThickness, coeff);
    const double cp = material_wave_speed(mc.material);
    const double c_visc = coeff * kDensity * cp * kThickness * std::sqrt(qd.area);
    const double c_stiff = coeff * kDensity * cp * cp * kThickness * qd.area * qd.bb / 2.0;
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(8);
    auto hg_viscous = [&](const Eigen::VectorXd& v, ForceTotals* t) {
      Eigen::VectorXd f(8);
      const ForceTotals tt = internal_forces(visc, zero.data(), v.data(), f.data(), true);
      if (t) *t = tt;
      return f;
    };
    auto hg_stiffness = [&](const Eigen::VectorXd& u, ForceTotals* t) {
      Eigen::VectorXd fs(8), fv(8);
      const ForceTotals tt = internal_forces(stiff, u.data(), zero.data(), fs.data(), true);
      internal_forces(visc, u.data(), zero.data(), fv.data(), false);
      if (t) *t = tt;
      return Eigen::VectorXd(fs - fv);
    };

    // Rigid and linear fields (small amplitudes: 1e-3 m, 1 m/s scale).
    Mat2 g;
    g << 0.8, -0.3, 0.5, 0.2;
    const Mat2 r = rotation(1.0);
    for (const Eigen::VectorXd& field :
         {affine_field(visc, Mat2::Zero(), Vec2(1e-3, -2e-3)),
          affine_field(visc, 1e-3 * g, Vec2(1e-3, 0.5e-3)),
          affine_field(visc, 1e-3 * (r - Mat2::Identity()), Vec2::Zero())}) {
      const double scale = field.norm();
      EXPECT_LT(hg_viscous(field * 1e3, nullptr).norm(), 1e-12 * c_visc * 1e3 * scale) << mc.name;
      EXPECT_LT(hg_stiffness(field, nullptr).norm(), 1e-12 * c_stiff * scale) << mc.name;
    }

    // The hourglass mode, in x and in y.
    for (int comp = 0; comp < 2; ++comp) {
      const double amp_v = 2.0, amp_u = 1e-4;
      Eigen::VectorXd mode = Eigen::VectorXd::Zero(8);
      for (int i = 0; i < 4; ++i) mode[2 * i + comp] = h[i];
      Eigen::VectorXd expect_v = Eigen::VectorXd::Zero(8), expect_u = Eigen::VectorXd::Zero(8);
      for (int i = 0; i < 4; ++i) {
        expect_v[2 * i + comp] = qd.gamma[i] * c_visc * amp_v;
        expect_u[2 * i + comp] = qd.gamma[i] * c_stiff * amp_u;
      }
      ForceTotals tv, ts;
      const Eigen::VectorXd fv = hg_viscous(amp_v * mode, &tv);
      const Eigen::VectorXd fs = hg_stiffness(amp_u * mode, &ts);
      EXPECT_LT((fv - expect_v).norm(), 1e-12 * expect_v.norm()) << mc.name;
      EXPECT_LT((fs - expect_u).norm(), 1e-12 * expect_u.norm()) << mc.name;
      // Q.qdot = c qdot^2 and the stored energy c q^2 / 2, with q = amplitude.
      EXPECT_NEAR(tv.hourglass_power, c_visc * amp_v * amp_v, 1e-12 * c_visc * amp_v * amp_v);
      EXPECT_NEAR(ts.hourglass_energy, 0.5 * c_stiff * amp_u * amp_u,
                  1e-12 * c_stiff * amp_u * amp_u);
    }
  }
}

TEST(Elements, LumpedMassesSumToBodyMass) {
  // Row-sum lumping of the consistent mass: the sum is rho t A exactly in exact arithmetic;
  // 1e-13 relative is the round-off of summing a few dozen terms.
  for (ElementKind kind : all_element_kinds()) {
    const Mesh mesh = distorted_mesh(kind);
    const Model<2> model = single_body_model(mesh, StVenantKirchhoff::make(kYoung, kPoisson, kDensity,
                                                                        PlaneMode::stress),
                                          PlaneMode::stress, kind, kThickness);
    const double expect = kDensity * kThickness * total_area(mesh);
    double mx = 0.0, my = 0.0;
    for (int i = 0; i < model.num_nodes(); ++i) {
      mx += model.mass[2 * i];
      my += model.mass[2 * i + 1];
      EXPECT_GT(model.mass[2 * i], 0.0);
    }
    EXPECT_NEAR(mx, expect, 1e-13 * expect) << element_name(kind);
    EXPECT_NEAR(my, expect, 1e-13 * expect) << element_name(kind);
  }
}

// Largest angular frequency of one free element: K = d f_int / du at u = 0 by central
// differences, then the largest eigenvalue of M^-1/2 K M^-1/2.
double omega_max(const Model<2>& model) {
  const int n = model.num_dofs();
  const double h = 1e-9;  // [m]; elements are ~1 m, so the nonlinear part is ~1e-9 relative
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
  const Eigen::MatrixXd k =
      test_support::fd_jacobian([&](const Eigen::VectorXd& w) { return forces(model, w, zero); }, zero, h);
  const Eigen::VectorXd s = model.inv_mass.cwiseSqrt();
  const Eigen::MatrixXd a = s.asDiagonal() * (0.5 * (k + k.transpose())) * s.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(a, Eigen::EigenvaluesOnly);
  return std::sqrt(es.eigenvalues().maxCoeff());
}

TEST(Elements, CriticalStepEstimateIsConservative) {
  // The estimate L_e / c_p must not exceed the true central-difference limit 2 / omega_max of
  // the free element (the finite-difference K is accurate to ~1e-7, far inside any margin
  // that matters). Poisson ratios 0.3 and 0.45 (stiffer volumetric response) are both checked.
  struct Shape {
    std::string name;
    Mesh mesh;
  };
  std::vector<Shape> quads, tris;
  {
    Eigen::Matrix<double, 2, 4> sq;
    sq << 0, 1, 1, 0, 0, 0, 1, 1;
    quads.push_back({"square", single_quad_mesh(sq)});
    quads.push_back({"distorted", single_quad_mesh(distorted_quad().x)});
    Eigen::Matrix<double, 2, 4> thin;
    thin << 0, 2, 2, 0, 0, 0, 0.5, 0.5;
    quads.push_back({"4:1 rectangle", single_quad_mesh(thin)});
    auto tri = [](std::initializer_list<double> xy) {
      Mesh m;
      m.nodes.resize(2, 3);
      auto it = xy.begin();
      for (int i = 0; i < 3; ++i) {
        m.nodes(0, i) = *it++;
        m.nodes(1, i) = *it++;
      }
      m.tris.push_back({0, 1, 2});
      return m;
    };
    tris.push_back({"right isosceles", tri({0, 0, 1, 0, 0, 1})});
    tris.push_back({"equilateral", tri({0, 0, 1, 0, 0.5, std::sqrt(0.75)})});
    tris.push_back({"distorted", tri({0, 0, 1.3, 0.2, 0.4, 0.7})});
  }
  for (double nu : {0.3, 0.45})
    for (PlaneMode plane : {PlaneMode::stress, PlaneMode::strain})
      for (int mat = 0; mat < 2; ++mat) {
        const Material material =
            mat == 0 ? Material(StVenantKirchhoff::make(kYoung, nu, kDensity, plane))
                     : Material(NeoHookean::make(kYoung, nu, kDensity, plane));
        for (ElementKind kind : all_element_kinds())
          for (const Shape& s : kind == ElementKind::t3 ? tris : quads) {
            const Model<2> model = single_body_model(s.mesh, material, plane, kind, kThickness);
            const double dt_true = 2.0 / omega_max(model);
            const double ratio = model.cell_dt[0] / dt_true;
            EXPECT_LE(ratio, 1.0) << element_name(kind) << " " << s.name << " nu " << nu;
            std::printf("[elements] dt_crit estimate / true  %-20s %-16s %s nu=%.2f %s: %.3f\n",
                        element_name(kind), s.name.c_str(),
                        plane == PlaneMode::stress ? "stress" : "strain", nu,
                        mat == 0 ? "SVK" : "NH ", ratio);
          }
      }
}

TEST(Elements, BuildModelRejectsBadCells) {
  const Material mat = StVenantKirchhoff::make(kYoung, kPoisson, kDensity, PlaneMode::stress);
  auto build = [&](const Mesh& m) {
    BodyInput<2> b;
    b.name = "plate";
    b.mesh = m;
    b.material = mat;
    return build_model({b}, PlaneMode::stress, Vec2::Zero());
  };
  Eigen::Matrix<double, 2, 4> flat;  // zero area: all corners on one line
  flat << 0, 1, 2, 1, 0, 0, 0, 0;
  EXPECT_THROW(build(single_quad_mesh(flat)), std::invalid_argument);
  Eigen::Matrix<double, 2, 4> dart;  // non-convex: corner 2 is re-entrant, area > 0
  dart << 0, 2, 0.6, 0, 0, 0, 0.6, 2;
  EXPECT_THROW(build(single_quad_mesh(dart)), std::invalid_argument);
  Eigen::Matrix<double, 2, 4> bowtie;  // self-intersecting
  bowtie << 0, 1, 0, 1, 0, 0, 1, 1;
  EXPECT_THROW(build(single_quad_mesh(bowtie)), std::invalid_argument);
  Mesh line;  // zero-area triangle
  line.nodes.resize(2, 3);
  line.nodes << 0, 1, 2, 0, 0.5, 1;
  line.tris.push_back({0, 1, 2});
  EXPECT_THROW(build(line), std::invalid_argument);
  // The message names the body and the cell.
  try {
    build(single_quad_mesh(dart));
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("plate"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cell 0"), std::string::npos) << e.what();
  }
  // A valid convex quad is accepted (the checks are not simply always failing).
  Eigen::Matrix<double, 2, 4> ok;
  ok << 0, 2, 1.5, 0, 0, 0, 1.2, 2;
  EXPECT_NO_THROW(build(single_quad_mesh(ok)));
}

}  // namespace
}  // namespace ricochet
