// What a field snapshot holds besides u and v (docs/outputs.md, fields/*.vtu):
// - the cells' Cauchy stress and Green-Lagrange strain tensors (cell_tensors(), internal_forces.hpp),
//   checked on homogeneous deformations, where both are known in closed form, for every element
//   formulation, both laws with a closed-form Cauchy stress, plane stress and plane strain;
// - the nodes' contact force, gap and status (node_contact_fields(), contact_set.hpp, filled by
//   RunMonitor at each snapshot), checked on a block pressed onto rigid ground by gravity in all
//   three schemes and on two bars meeting head-on (a master body's share).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "harness/input/case_setup.hpp"
#include "harness/input/case_spec.hpp"
#include "solver/forces/internal_forces.hpp"
#include "solver/materials/material.hpp"
#include "tests/support/verification_meshes.hpp"

namespace ricochet {
namespace {

using verification::ElementKind;

// ------------------------------------------------------------------ cell tensors

struct Closed {
  std::array<double, 6> sigma, strain;  // VTK order XX, YY, ZZ, XY, YZ, XZ
};

// 3D St Venant-Kirchhoff, S = lambda tr(E) I + 2 mu E, sigma = F S F^T / J, with E33 = 0 (plane
// strain) or E33 from S33 = lambda (tr E2 + E33) + 2 mu E33 = 0 (plane stress); F33^2 = 1 + 2 E33.
Closed svk(const Mat2& F, double young, double nu, PlaneMode plane) {
  const double lambda = young * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), mu = young / (2.0 * (1.0 + nu));
  const Mat2 E = 0.5 * (F.transpose() * F - Mat2::Identity());
  const double e33 = plane == PlaneMode::strain ? 0.0 : -lambda * E.trace() / (lambda + 2.0 * mu);
  const double tr = E.trace() + e33;
  const Mat2 S = lambda * tr * Mat2::Identity() + 2.0 * mu * E;
  const double s33 = lambda * tr + 2.0 * mu * e33;
  const double f33_2 = 1.0 + 2.0 * e33;
  const double J = F.determinant() * std::sqrt(f33_2);
  const Mat2 sigma = F * S * F.transpose() / J;
  return {{sigma(0, 0), sigma(1, 1), f33_2 * s33 / J, sigma(0, 1), 0.0, 0.0},
          {E(0, 0), E(1, 1), e33, E(0, 1), 0.0, 0.0}};
}

// Compressible neo-Hookean, sigma = mu/J (b - I) + lambda ln J / J I (3D, b = F F^T), with
// F33 = 1 (plane strain) or F33 from sigma33 = 0: mu (F33^2 - 1) + lambda ln(det F F33) = 0,
// solved here by bisection (the left side increases with F33).
Closed neo_hookean(const Mat2& F, double young, double nu, PlaneMode plane) {
  const double lambda = young * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), mu = young / (2.0 * (1.0 + nu));
  double f33 = 1.0;
  if (plane == PlaneMode::stress) {
    double lo = 1e-3, hi = 10.0;
    for (int i = 0; i < 200; ++i) {
      f33 = 0.5 * (lo + hi);
      (mu * (f33 * f33 - 1.0) + lambda * std::log(F.determinant() * f33) > 0.0 ? hi : lo) = f33;
    }
  }
  const double J = F.determinant() * f33;
  const Mat2 b = F * F.transpose();
  const Mat2 sigma = mu / J * (b - Mat2::Identity()) + lambda * std::log(J) / J * Mat2::Identity();
  const double s33 = mu / J * (f33 * f33 - 1.0) + lambda * std::log(J) / J;
  const Mat2 E = 0.5 * (F.transpose() * F - Mat2::Identity());
  return {{sigma(0, 0), sigma(1, 1), s33, sigma(0, 1), 0.0, 0.0},
          {E(0, 0), E(1, 1), 0.5 * (f33 * f33 - 1.0), E(0, 1), 0.0, 0.0}};
}

// u = (F - I) X on a distorted mesh: every integration point has the same F, so every cell's
// tensors are the closed form whatever the averaging over its points.
TEST(FieldTensors, HomogeneousDeformationMatchesClosedForm) {
  const double young = 2.0e7, nu = 0.3, density = 1000.0;
  Mat2 F;
  F << 1.08, 0.05,  //
      -0.03, 0.94;   // stretch, compression and shear (XY terms nonzero)
  for (const PlaneMode plane : {PlaneMode::stress, PlaneMode::strain})
    for (const bool neo : {false, true})
      for (const ElementKind kind : verification::all_element_kinds()) {
        const Material mat = neo ? Material(NeoHookean::make(young, nu, density, plane))
                                 : Material(StVenantKirchhoff::make(young, nu, density, plane));
        const Model<2> model = verification::single_body_model(verification::grid_mesh(0.2, 0.1, 4, 3, 0.15, kind), mat,
                                                            plane, kind);
        Eigen::VectorXd u(2 * model.num_nodes());
        for (int i = 0; i < model.num_nodes(); ++i) u.segment<2>(2 * i) = (F - Mat2::Identity()) * model.ref.col(i);
        std::vector<double> sigma(6 * model.num_cells(), -1.0), strain(6 * model.num_cells(), -1.0);
        cell_tensors(model, u.data(), sigma.data(), strain.data());
        const Closed want = neo ? neo_hookean(F, young, nu, plane) : svk(F, young, nu, plane);
        const std::string what = std::string(plane == PlaneMode::stress ? "plane stress " : "plane strain ") +
                                 (neo ? "neo-Hookean " : "SVK ") + verification::element_name(kind);
        const double scale = std::abs(want.sigma[0]) + std::abs(want.sigma[1]);
        ASSERT_GT(scale, 1e5) << what;
        for (int c = 0; c < model.num_cells(); ++c)
          for (int k = 0; k < 6; ++k) {
            ASSERT_NEAR(sigma[6 * c + k], want.sigma[k], 1e-10 * scale) << what << ", cell " << c << ", component " << k;
            ASSERT_NEAR(strain[6 * c + k], want.strain[k], 1e-13) << what << ", cell " << c << ", component " << k;
          }
        // Plane stress: no out-of-plane stress, a thickness strain; plane strain: the reverse.
        EXPECT_EQ(sigma[2] == 0.0, plane == PlaneMode::stress) << what;
        EXPECT_EQ(strain[2] == 0.0, plane == PlaneMode::strain) << what;
      }
}

// ------------------------------------------------------------------ node contact data

const std::string kSource = RICOCHET_SOURCE_DIR;

struct CaseRun {
  PreparedCase pc;
  RunResult r;
};

CaseRun run(const std::string& file, const std::vector<std::string>& overrides) {
  CaseRun x{prepare_case(read_case(kSource + "/" + file, overrides)), {}};
  x.r = run_case(x.pc);
  return x;
}

// The value of `column` in the history row of the snapshot's step (the runs below sample
// every step, so row k is step k).
double at_snapshot(const CaseRun& x, const FieldSnapshot& f, const char* column) {
  const History& h = x.r.history;
  EXPECT_EQ(h.at(static_cast<std::size_t>(f.step), h.column("time")), f.time);
  return h.at(static_cast<std::size_t>(f.step), h.column(column));
}

// The sliding block (cases/verification/sliding_block.toml) 0.1 ms after it was set down sliding
// at 1 m/s on the ground y = 0 (mu = 0.3) under gravity: its bottom nodes press on the ground
// and slide.
TEST(FieldContact, BlockOnGroundForcesSumToTheHistory) {
  for (const char* scheme : {"semi_explicit", "implicit", "explicit_penalty"}) {
    SCOPED_TRACE(scheme);
    const CaseRun x = run("cases/verification/sliding_block.toml",
                      {std::string("scheme=\"") + scheme + "\"", "time.end=1e-4", "output.interval=0",
                       "output.fields=[1e-4]"});
    ASSERT_EQ(x.r.status, RunStatus::ok) << x.r.reason;
    ASSERT_EQ(x.r.fields.size(), 1u);
    const FieldSnapshot& f = x.r.fields[0];
    const Model<2>& m = x.pc.model<2>();
    const int n = m.num_nodes();
    ASSERT_EQ(f.contact_force.size(), 2u * n);
    ASSERT_EQ(f.contact_gap.size(), static_cast<std::size_t>(n));
    ASSERT_EQ(f.contact_status.size(), static_cast<std::size_t>(n));
    // The ground's normal is +y and its tangent t = (n_y, -n_x) = +x: the summed node forces
    // are (tangential_force, normal_force) of the same step.
    double fx = 0.0, fy = 0.0;
    int stick = 0, slip = 0;
    std::vector<bool> boundary(n, false);
    for (int b : m.bodies[0].boundary_nodes) boundary[b] = true;
    for (int i = 0; i < n; ++i) {
      fx += f.contact_force[2 * i];
      fy += f.contact_force[2 * i + 1];
      const int s = f.contact_status[i];
      const double y = m.ref(1, i) + f.u[2 * i + 1];
      if (!boundary[i]) {
        EXPECT_EQ(s, 0) << "node " << i;
        EXPECT_EQ(f.contact_gap[i], 0.0) << "node " << i;
        EXPECT_EQ(f.contact_force[2 * i], 0.0) << "node " << i;
        EXPECT_EQ(f.contact_force[2 * i + 1], 0.0) << "node " << i;
        continue;
      }
      // Every boundary node is a candidate of the ground: its gap is its height.
      EXPECT_EQ(f.contact_gap[i], y) << "node " << i;
      EXPECT_GE(s, 1) << "node " << i;
      if (s == 1) {
        EXPECT_EQ(f.contact_force[2 * i + 1], 0.0) << "node " << i;
        continue;
      }
      stick += s == 2;
      slip += s == 3;
      EXPECT_EQ(m.ref(1, i), 0.0) << "only bottom nodes touch, node " << i;
      EXPECT_GT(f.contact_force[2 * i + 1], 0.0) << "node " << i;
      // Sliding at about 1 m/s to the right: friction pushes to the left, at most mu times
      // the normal force (on the cone when it slips).
      EXPECT_LT(f.contact_force[2 * i], 0.0) << "node " << i;
      EXPECT_LE(-f.contact_force[2 * i], 0.3 * f.contact_force[2 * i + 1] * (1.0 + 1e-12)) << "node " << i;
      if (std::string(scheme) == "explicit_penalty") {
        EXPECT_LT(f.contact_gap[i], 0.0) << "a penalty spring acts on penetration, node " << i;
      } else {
        // Position-level contact: a node pressed at t_n was brought onto the ground at t_n.
        EXPECT_LE(std::abs(f.contact_gap[i]), 1e-12) << "node " << i;
      }
    }
    const double normal = at_snapshot(x, f, "normal_force"), tangential = at_snapshot(x, f, "tangential_force");
    // The block weighs m g = 0.1 x 0.05 x 0.05 x 1000 x 9.81 = 2.45 N; its vibration on
    // landing moves the reaction between about 0 and twice that.
    EXPECT_GT(normal, 0.1);
    EXPECT_NEAR(fy, normal, 1e-12 * normal);
    EXPECT_NEAR(fx, tangential, 1e-12 * normal);
    EXPECT_EQ(static_cast<double>(stick), at_snapshot(x, f, "contact_stick"));
    EXPECT_EQ(static_cast<double>(slip), at_snapshot(x, f, "contact_slip"));
    EXPECT_GT(slip, 0) << "the block slides";
  }
}

// Two bars meeting head-on (cases/verification/head_on.toml, the striker the slave of a one-way
// pair) in the middle of their contact: the striker's contact nodes carry r = r_n n with n the
// target's outward normal (-1, 0), the target's face nodes carry -r between them, so the forces
// sum to zero over both bodies and to -+ normal_force over each. The target's nodes are no
// candidates (status 0), but carry forces.
TEST(FieldContact, BodyPairMasterCarriesItsShare) {
  for (const char* scheme : {"semi_explicit", "implicit", "explicit_penalty"}) {
    SCOPED_TRACE(scheme);
    const CaseRun x = run("cases/verification/head_on.toml", {std::string("scheme=\"") + scheme + "\"", "time.end=4e-5",
                                                          "output.interval=0", "output.fields=[4e-5]"});
    ASSERT_EQ(x.r.status, RunStatus::ok) << x.r.reason;
    ASSERT_EQ(x.r.fields.size(), 1u);
    const FieldSnapshot& f = x.r.fields[0];
    const Model<2>& m = x.pc.model<2>();
    const int striker_end = m.bodies[1].first_node;  // the striker's nodes come first
    double striker = 0.0, target = 0.0, y = 0.0, target_abs = 0.0;  // x sums; y: the y sum
    int pressed = 0;
    for (int i = 0; i < m.num_nodes(); ++i) {
      const double fx = f.contact_force[2 * i];
      y += f.contact_force[2 * i + 1];
      if (i < striker_end) {
        striker += fx;
        if (f.contact_status[i] >= 2) {
          ++pressed;
          EXPECT_EQ(f.contact_status[i], 3) << "frictionless contacts slip, node " << i;
          EXPECT_LT(std::abs(m.ref(0, i)), 1e-12) << "only the striking face (x = 0) touches, node " << i;
          // A penalty spring acts on penetration: the mid-face node is inside the target. The
          // corner nodes meet the target's corners, where the distance to the target's boundary
          // is to its corner point, not the spring's gap along the face normal.
          if (std::string(scheme) != "explicit_penalty") {
            EXPECT_LE(std::abs(f.contact_gap[i]), 1e-12) << "node " << i;
          } else if (m.ref(1, i) > 1e-12 && m.ref(1, i) < 0.02 - 1e-12) {
            EXPECT_LT(f.contact_gap[i], 0.0) << "node " << i;
          }
        }
        // The far end of the striker is about a bar length (0.2 m) from the target's face.
        if (std::abs(m.ref(0, i) + 0.2) < 1e-12) {
          EXPECT_NEAR(f.contact_gap[i], 0.2, 0.01) << "node " << i;
        }
      } else {
        target += fx;
        target_abs += std::abs(fx);
        EXPECT_EQ(f.contact_status[i], 0) << "node " << i;
        EXPECT_EQ(f.contact_gap[i], 0.0) << "node " << i;
      }
    }
    const double normal = at_snapshot(x, f, "normal_force");
    EXPECT_GT(normal, 1e3);  // rho c v0 A / 2 = 8000 x 5000 x 1 x 4e-4 / 2 = 8000 N
    EXPECT_GT(pressed, 0);
    // Action and reaction: the stencil coefficients sum to zero, so do the forces.
    EXPECT_NEAR(striker + target, 0.0, 1e-12 * normal);
    EXPECT_NEAR(y, 0.0, 1e-12 * normal);
    EXPECT_NEAR(target, target_abs, 1e-12 * normal) << "every master share pushes the target away";
    // -striker = sum r_n (-n_x): normal_force up to the tilt theta of the target's face normals
    // (a factor cos theta); the bars strain by v0/c = 2e-4, which tilts the face by far less
    // than 1e-3 rad, so cos theta > 1 - 1e-6.
    EXPECT_LE(-striker, normal * (1.0 + 1e-12));
    EXPECT_GE(-striker, normal * (1.0 - 1e-6));
  }
}

// A run that diverges keeps a snapshot of its last state with the same arrays: the sliding
// block at 17 x its stable step. In plane strain every value of that state is finite. In plane
// stress (with the 2nd Piola-Kirchhoff von Mises, finite there) St Venant-Kirchhoff has no real
// thickness stretch at the strains the block blows up to, so some cells have no Cauchy stress:
// the state is still kept, those values written as 0.
TEST(FieldContact, DivergedSnapshotCarriesTheArrays) {
  for (const char* plane : {"strain", "stress"}) {
    SCOPED_TRACE(plane);
    const CaseRun x = run("cases/verification/sliding_block.toml",
                          {std::string("plane=\"") + plane + "\"", "output.stress_measure=\"pk2\"", "time.dt=1e-4",
                           "time.end=1e-1", "output.fields=[]"});
    ASSERT_EQ(x.r.status, RunStatus::diverged);
    ASSERT_EQ(x.r.fields.size(), 1u) << x.r.reason;
    const FieldSnapshot& f = x.r.fields[0];
    const Model<2>& m = x.pc.model<2>();
    EXPECT_EQ(f.step, x.r.diverged_step);
    EXPECT_EQ(f.cauchy.size(), 6u * m.num_cells());
    EXPECT_EQ(f.green_lagrange.size(), 6u * m.num_cells());
    EXPECT_EQ(f.contact_force.size(), 2u * m.num_nodes());
    EXPECT_EQ(f.contact_gap.size(), static_cast<std::size_t>(m.num_nodes()));
    ASSERT_EQ(f.contact_status.size(), static_cast<std::size_t>(m.num_nodes()));
    EXPECT_GT(*std::max_element(f.contact_status.begin(), f.contact_status.end()), 0);
    std::vector<double> sigma(f.cauchy.size()), strain(f.cauchy.size());
    cell_tensors(m, f.u.data(), sigma.data(), strain.data());
    int not_finite = 0;
    for (std::size_t k = 0; k < sigma.size(); ++k) {
      not_finite += !std::isfinite(sigma[k]);
      EXPECT_EQ(f.cauchy[k], std::isfinite(sigma[k]) ? sigma[k] : 0.0) << k;
      EXPECT_EQ(f.green_lagrange[k], std::isfinite(strain[k]) ? strain[k] : 0.0) << k;
    }
    EXPECT_EQ(not_finite > 0, std::string(plane) == "stress");
  }
}

}  // namespace
}  // namespace ricochet
