// exploration draft
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "solver/implicit.hpp"
#include "solver/run.hpp"
#include "verification_meshes.hpp"

namespace ricochet {
namespace {

using verification::ElementKind;
using verification::grid_mesh;
using verification::single_body_model;

constexpr double kYoung = 200e9, kPoisson = 0.3, kDensity = 7800.0;

Model vibrating_slab(double distortion = 0.0) {
  const Mesh mesh = grid_mesh(4.0, 1.0, 16, 4, distortion, false);
  Model model = single_body_model(
      mesh, StVenantKirchhoff::make(kYoung, kPoisson, kDensity, PlaneMode::strain),
      PlaneMode::strain, ElementKind::q4_full);
  for (int i = 0; i < model.num_nodes(); ++i) {
    const double x = model.ref(0, i);
    model.initial_velocity[2 * i] = 0.5 * (x - 2.0) / 2.0;
    model.initial_velocity[2 * i + 1] = 1.0 * std::cos(2.0 * M_PI * x / 4.0);
  }
  return model;
}

TEST(Explore, Energy) {
  const Model model = vibrating_slab();
  std::printf("critical %.4e\n", model.critical_dt);
  for (double f : {1.0, 5.0}) {
    for (double th : {0.5, 0.6, 1.0}) {
      RunSettings s;
      s.dt = f * model.critical_dt;
      s.end_time = 24e-3;
      s.probes = {{"tip", 16}};
      ImplicitSettings im;
      im.theta = im.xi = th;
      const RunResult r = run_implicit(model, s, im);
      const History& h = r.history;
      const std::size_t e = h.column("total_energy");
      double maxup = 0, minE = 1e300, maxE = 0;
      int crossings = 0;
      for (std::size_t row = 1; row < h.rows(); ++row) {
        maxup = std::max(maxup, h.at(row, e) - h.at(row - 1, e));
        minE = std::min(minE, h.at(row, e));
        maxE = std::max(maxE, h.at(row, e));
        if (h.at(row, h.column("tip_uy")) * h.at(row - 1, h.column("tip_uy")) < 0) ++crossings;
      }
      std::printf("f %.0f th %.1f: %s steps %ld E0 %.6e final %.6e errmax %.3e maxup/E0 %.3e range/E0 %.3e crossings %d newton %ld lin %ld wall %.2f\n",
                  f, th, r.status == RunStatus::ok ? "ok" : r.reason.c_str(), r.steps, r.initial_energy,
                  h.at(h.rows() - 1, e), r.energy_error_max, maxup / r.initial_energy, (maxE - minE) / r.initial_energy,
                  crossings, r.newton_iterations, r.linear_iterations, r.wall_seconds);
    }
  }
}

TEST(Explore, Fail) {
  const Model model = vibrating_slab();
  RunSettings s;
  s.dt = 5 * model.critical_dt;
  s.end_time = 24e-3;
  ImplicitSettings im;
  im.theta = im.xi = 1.0;
  ImplicitIntegrator it(model, s, im);
  for (int n = 0; n < 70; ++n) {
    const bool ok = it.step(true);
    const auto& st = it.state();
    if (n > 55 || !ok) {
      std::printf("step %d ok %d |u|inf %.3e |v|inf %.3e strain %.3e res:", n, ok, st.u.lpNorm<Eigen::Infinity>(), st.v_half.lpNorm<Eigen::Infinity>(), st.forces.strain_energy);
      for (double r : it.residuals()) std::printf(" %.2e", r);
      std::printf("\n");
    }
    if (!ok) { std::printf("%s\n", it.failure().c_str()); break; }
  }
}
TEST(Explore, Newton) {
  for (int mat = 0; mat < 2; ++mat)
  for (double speed : {0.2, 0.4, 0.6}) 
  for (double f : {5.0, 10.0, 20.0}) 
  for (LinearSolverKind ls : {LinearSolverKind::pcg, LinearSolverKind::ldlt}) {
    const Mesh mesh = grid_mesh(1.0, 1.0, 6, 6, 0.15, false);
    const Material m = mat == 0 ? Material(NeoHookean::make(kYoung, kPoisson, kDensity, PlaneMode::strain))
                                : Material(StVenantKirchhoff::make(kYoung, kPoisson, kDensity, PlaneMode::strain));
    Model model = single_body_model(mesh, m, PlaneMode::strain, ElementKind::q4_full);
    const double c = std::sqrt(kYoung / kDensity);
    for (int i = 0; i < model.num_nodes(); ++i) {
      const Vec2 x = model.ref.col(i) - Vec2(0.5, 0.5);
      // compression along x, rotation
      model.initial_velocity.segment<2>(2 * i) = speed * c * (Vec2(-2.0 * x.x(), 0.3 * x.y()) + Vec2(-x.y(), x.x()));
    }
    RunSettings s;
    s.dt = f * model.critical_dt;
    s.end_time = s.dt;
    ImplicitSettings im;
    im.linear_solver = ls;
    im.newton_tolerance = 1e-14;
    ImplicitIntegrator it(model, s, im);
    const bool ok = it.step(true);
    std::printf("mat %d speed %.2f f %.0f %s ok %d minJ %.3f shifted %ld res:", mat, speed, f, ls == LinearSolverKind::pcg ? "pcg " : "ldlt", ok, it.state().forces.min_jacobian, it.shifted_iterations());
    for (double r : it.residuals()) std::printf(" %.2e", r);
    std::printf(" %s\n", it.failure().c_str());
  }
}
Vec2 momentum0(const Model& model) {
  Vec2 p = Vec2::Zero();
  for (int i = 0; i < model.num_nodes(); ++i) p += model.mass[2 * i] * model.initial_velocity.segment<2>(2 * i);
  return p;
}
TEST(Explore, Momentum) {
  Model model = vibrating_slab(0.2);
  for (int i = 0; i < model.num_nodes(); ++i) model.initial_velocity.segment<2>(2 * i) += Vec2(3.0, -2.0);
  double scale = 0.0;
  for (int d = 0; d < model.num_dofs(); ++d) scale += model.mass[d] * std::abs(model.initial_velocity[d]);
  const Vec2 p0 = momentum0(model);
  for (double f : {0.5, 2.0, 5.0})
  for (LinearSolverKind ls : {LinearSolverKind::pcg, LinearSolverKind::ldlt}) {
    RunSettings s;
    s.dt = f * model.critical_dt;
    s.end_time = 400 * s.dt;
    ImplicitSettings im;
    im.linear_solver = ls;
    const RunResult r = run_implicit(model, s, im);
    const History& h = r.history;
    double worst = 0;
    for (std::size_t row = 0; row < h.rows(); ++row)
      worst = std::max(worst, (Vec2(h.at(row, h.column("momentum_x")), h.at(row, h.column("momentum_y"))) - p0).norm() / scale);
    std::printf("f %.1f %s: %s steps %ld worst %.2e newton %ld lin %ld\n", f, ls == LinearSolverKind::pcg ? "pcg " : "ldlt",
                r.status == RunStatus::ok ? "ok" : r.reason.c_str(), r.steps, worst, r.newton_iterations, r.linear_iterations);
  }
}
TEST(Explore, Solvers) {
  const Model model = vibrating_slab(0.2);
  for (double f : {0.5, 2.0})
  for (double nt : {1e-10, 1e-13}) {
    std::vector<RunResult> rr;
    for (LinearSolverKind ls : {LinearSolverKind::pcg, LinearSolverKind::ldlt}) {
      RunSettings s;
      s.dt = f * model.critical_dt;
      s.end_time = 100 * s.dt;
      s.field_times = {s.end_time};
      ImplicitSettings im;
      im.linear_solver = ls;
      im.newton_tolerance = nt;
      rr.push_back(run_implicit(model, s, im));
    }
    std::printf("sizes %zu %zu status %d %d %s / %s\n", rr[0].fields.size(), rr[1].fields.size(), (int)rr[0].status, (int)rr[1].status, rr[0].reason.c_str(), rr[1].reason.c_str()); fflush(stdout); if (rr[0].fields.empty()) continue;
    const auto& a = rr[0].fields.back();
    const auto& b = rr[1].fields.back();
    std::printf("f %.1f nt %.0e: du %.3e (|u| %.3e) dv %.3e (|v| %.3e) newton %ld %ld\n", f, nt, (a.u - b.u).lpNorm<Eigen::Infinity>(),
                a.u.lpNorm<Eigen::Infinity>(), (a.v - b.v).lpNorm<Eigen::Infinity>(), a.v.lpNorm<Eigen::Infinity>(), rr[0].newton_iterations, rr[1].newton_iterations);
  }
}
TEST(Explore, Gravity) {
  const Vec2 g(2.0, -9.81), v0(1.5, 2.0);
  const Mesh mesh = grid_mesh(1.0, 0.5, 4, 2, 0.2, false);
  Model model = single_body_model(mesh, NeoHookean::make(kYoung, kPoisson, kDensity, PlaneMode::stress), PlaneMode::stress, ElementKind::q4_full, 0.01, 0.1, g);
  for (int i = 0; i < model.num_nodes(); ++i) model.initial_velocity.segment<2>(2 * i) = v0;
  double mass = 0.5 * model.mass.sum();
  for (double f : {0.5, 3.0})
  for (double th : {0.5, 1.0}) {
    RunSettings s;
    s.dt = f * model.critical_dt;
    s.end_time = 300 * s.dt;
    s.field_times = {s.end_time};
    s.probes = {{"a", 0}, {"b", 7}};
    ImplicitSettings im;
    im.theta = im.xi = th;
    const RunResult r = run_implicit(model, s, im);
    const History& h = r.history;
    double worst = 0;
    for (std::size_t row = 1; row < h.rows(); ++row) {
      const double t = h.at(row, 0);
      const Vec2 e = v0 * t + 0.5 * g * t * t;
      worst = std::max(worst, (Vec2(h.at(row, h.column("b_ux")), h.at(row, h.column("b_uy"))) - e).norm() / e.norm());
    }
    const double t = r.end_time;
    const double w = mass * g.dot(v0 * t + 0.5 * g * t * t);
    std::printf("f %.1f th %.1f: %s worst %.2e W %.6e expect %.6e rel %.2e errmax %.2e E0 %.3e\n", f, th, r.status == RunStatus::ok ? "ok" : r.reason.c_str(), worst,
                h.at(h.rows() - 1, h.column("external_work")), w, h.at(h.rows() - 1, h.column("external_work")) / w - 1, r.energy_error_max, r.initial_energy);
  }
}
TEST(Explore, Bar) {
  const Mesh mesh = grid_mesh(2.0, 0.1, 40, 2, 0.0, false);
  const Model model = single_body_model(mesh, StVenantKirchhoff::make(kYoung, 0.0, kDensity, PlaneMode::stress), PlaneMode::stress, ElementKind::q4_full);
  std::vector<PrescribedDof> p;
  for (int n : mesh.node_sets.at("left")) p.push_back({2 * n, PrescribedDof::Kind::velocity, 0.0});
  for (int n : mesh.node_sets.at("right")) p.push_back({2 * n, PrescribedDof::Kind::velocity, 1.0});
  const double c = std::sqrt(kYoung / kDensity), length = 2.0, area = 0.1, speed = 1.0;
  for (double f : {0.5, 1.0, 4.0}) {
    RunSettings s;
    s.dt = f * model.critical_dt;
    s.end_time = 1e-3;
    s.prescribed = p;
    s.probes = {{"end", mesh.node_sets.at("right").back()}};
    const RunResult r = run_implicit(model, s, ImplicitSettings{});
    const History& h = r.history;
    const std::size_t last = h.rows() - 1;
    const double t = h.at(last, 0);
    const double wt = kDensity * c * speed * speed * area * (3.0 * t - 4.0 * length / c);
    double endu = 0, endv = 0;
    for (std::size_t row = 0; row < h.rows(); ++row) {
      endu = std::max(endu, std::abs(h.at(row, h.column("end_ux")) - speed * h.at(row, 0)));
      endv = std::max(endv, std::abs(h.at(row, h.column("end_vx")) - speed));
    }
    std::printf("bar f %.1f: %s t %.4e W %.5e theory %.5e rel %.2e final err %.2e max %.2e endu %.1e endv %.1e\n", f, r.status == RunStatus::ok ? "ok" : r.reason.c_str(), t,
                h.at(last, h.column("external_work")), wt, h.at(last, h.column("external_work")) / wt - 1, h.at(last, h.column("energy_error")), r.energy_error_max, endu, endv);
  }
}
TEST(Explore, Amp) {
  for (double amp : {1.0, 0.5, 0.25})
  for (double f : {1.0, 5.0}) {
    Model model = vibrating_slab();
    model.initial_velocity *= amp;
    RunSettings s;
    s.dt = f * model.critical_dt;
    s.end_time = 37e-3;
    const RunResult r = run_implicit(model, s, ImplicitSettings{});
    const History& h = r.history;
    const std::size_t e = h.column("total_energy");
    double maxup = 0;
    for (std::size_t row = 1; row < h.rows(); ++row) maxup = std::max(maxup, h.at(row, e) - h.at(row - 1, e));
    std::printf("amp %.2f f %.0f: %s steps %ld errmax %.3e final %.3e maxup %.3e\n", amp, f, r.status == RunStatus::ok ? "ok" : r.reason.c_str(), r.steps, r.energy_error_max, h.at(h.rows()-1, h.column("energy_error")), maxup / r.initial_energy);
  }
}
TEST(Explore, BarAmp) {
  const Mesh mesh = grid_mesh(2.0, 0.1, 40, 2, 0.0, false);
  const Model model = single_body_model(mesh, StVenantKirchhoff::make(kYoung, 0.0, kDensity, PlaneMode::stress), PlaneMode::stress, ElementKind::q4_full);
  for (double speed : {1.0, 0.5})
  for (double f : {1.0, 4.0}) {
    std::vector<PrescribedDof> p;
    for (int n : mesh.node_sets.at("left")) p.push_back({2 * n, PrescribedDof::Kind::velocity, 0.0});
    for (int n : mesh.node_sets.at("right")) p.push_back({2 * n, PrescribedDof::Kind::velocity, speed});
    RunSettings s;
    s.dt = f * model.critical_dt;
    s.end_time = 1e-3;
    s.prescribed = p;
    const RunResult r = run_implicit(model, s, ImplicitSettings{});
    std::printf("bar V %.1f f %.1f: errmax %.3e\n", speed, f, r.energy_error_max);
  }
}
TEST(Explore, Theta) {
  const Model model = vibrating_slab();
  for (double f : {1.0, 5.0})
  for (double th : {0.5, 0.6, 1.0}) {
    RunSettings s;
    s.dt = f * model.critical_dt;
    s.end_time = 37e-3;
    ImplicitSettings im;
    im.theta = im.xi = th;
    const RunResult r = run_implicit(model, s, im);
    const History& h = r.history;
    const std::size_t e = h.column("total_energy");
    double maxup = 0;
    for (std::size_t row = 1; row < h.rows(); ++row) maxup = std::max(maxup, h.at(row, e) - h.at(row - 1, e));
    std::printf("th %.1f f %.0f: %s steps %ld loss %.4f maxup %.3e\n", th, f, r.status == RunStatus::ok ? "ok" : r.reason.c_str(), r.steps, 1 - h.at(h.rows()-1, e) / r.initial_energy, maxup / r.initial_energy);
  }
}
}  // namespace
}  // namespace ricochet
