// exploration
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "harness/case_setup.hpp"
#include "harness/case_spec.hpp"
#include "solver/run.hpp"

namespace ricochet {
namespace {

const std::string kCase = std::string(RICOCHET_SOURCE_DIR) + "/cases/oblique_plate.toml";

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

TEST(Explore, Schemes) {
  for (double mu : {0.0, 0.1})
  for (std::string scheme : {"semi_explicit", "implicit", "explicit_penalty"}) {
    std::vector<std::string> ov = {"mesh=M1", "scheme=" + scheme, "obstacles[0].friction=" + number(mu)};
    if (scheme == "explicit_penalty") ov.push_back("time.dt=\"auto\"");
    const CaseSpec spec = read_case(kCase, ov);
    const PreparedCase pc = prepare_case(spec);
    const RunResult r = run_case(pc);
    const History& h = r.history;
    const double mass = 0.5 * pc.model.mass.sum();
    const double e0 = r.initial_energy;
    double body = 0, sys = 0, brief = 0;
    std::size_t last_contact = 0, first_contact = 0;
    double umax = 0;
    for (std::size_t row = 0; row < h.rows(); ++row) {
      const double E = h.at(row, h.column("total_energy")), D = h.at(row, h.column("friction_dissipation")),
                   W = h.at(row, h.column("contact_work")), U = h.at(row, h.column("contact_energy"));
      body = std::max(body, std::abs(E - e0 - W) / e0);
      sys = std::max(sys, std::abs(E + U + D - e0) / e0);
      brief = std::max(brief, std::abs(E + D - e0 - W + U) / e0);
      umax = std::max(umax, U);
      if (h.at(row, h.column("contact_nodes")) > 0) { last_contact = row; if (!first_contact) first_contact = row; }
    }
    const std::size_t L = h.rows() - 1;
    std::printf("%-16s mu %.1f: %s dt %.4e (crit %.4e pen %.4e) steps %ld pen %.3e errmax %.3e Wc/E0 %.4e D/E0 %.4e body %.3e sys %.3e brief %.3e Umax/E0 %.3e contact %.3e-%.3e v=(%.6f, %.6f) px drift %.2e newton %ld wall %.2f\n",
                scheme.c_str(), mu, r.status == RunStatus::ok ? "ok" : r.reason.c_str(), r.dt, pc.model.critical_dt, pc.penalty_critical_dt, r.steps,
                r.penetration_max, r.energy_error_max, r.contact_work / e0, r.friction_dissipation / e0, body, sys, brief, umax / e0,
                h.at(first_contact, 0), h.at(last_contact, 0), h.at(L, h.column("momentum_x")) / mass, h.at(L, h.column("momentum_y")) / mass,
                0.0, r.newton_iterations, r.wall_seconds);
  }
}


void show(const std::string& label, const std::vector<std::string>& ov) {
  const CaseSpec spec = read_case(kCase, ov);
  const PreparedCase pc = prepare_case(spec);
  const RunResult r = run_case(pc);
  const History& h = r.history;
  const double mass = 0.5 * pc.model.mass.sum();
  const double e0 = r.initial_energy;
  double body = 0, half = 0, corr = 0, Fy = 0, Fx = 0;
  std::size_t first = 0, last = 0; int gaps = 0;
  for (std::size_t row = 0; row < h.rows(); ++row) {
    const double E = h.at(row, h.column("total_energy")), W = h.at(row, h.column("contact_work"));
    const double dW = row ? W - h.at(row - 1, h.column("contact_work")) : W;
    body = std::max(body, std::abs(E - e0 - W) / e0);
    half = std::max(half, 0.5 * std::abs(dW) / e0);
    corr = std::max(corr, std::abs(E - e0 - W + 0.5 * dW) / e0);
    Fy += r.dt * h.at(row, h.column("normal_force"));
    Fx += r.dt * h.at(row, h.column("tangential_force"));
    if (h.at(row, h.column("contact_nodes")) > 0) { if (!first) first = row; last = row; }
  }
  for (std::size_t row = first; row <= last; ++row) gaps += h.at(row, h.column("contact_nodes")) == 0;
  const std::size_t L = h.rows() - 1;
  const double vy = h.at(L, h.column("momentum_y")) / mass, vx = h.at(L, h.column("momentum_x")) / mass;
  std::printf("%-28s %s dt %.3e rows %zu steps %ld pen %.3e body %.3e half %.3e corr %.3e contact %.3e..%.3e gaps %d v=(%.5f, %.5f) Fy-dp %.3e Fx-dp %.3e wall %.2f\n",
              label.c_str(), r.status == RunStatus::ok ? "ok" : r.reason.c_str(), r.dt, h.rows(), r.steps, r.penetration_max, body, half, corr,
              h.at(first, 0), h.at(last, 0), gaps, vx, vy, (Fy - mass * (vy + 5.0)) / (mass * 10), (Fx - mass * (vx - 3.0)) / (mass * 10), r.wall_seconds);
}

TEST(Explore, More) {
  for (double mu : {0.0, 0.1}) {
    const std::string m = "obstacles[0].friction=" + number(mu);
    show("semi M1 mu" + number(mu), {"mesh=M1", m, "output.interval=0"});
    show("impl M1 mu" + number(mu), {"mesh=M1", m, "output.interval=0", "scheme=implicit"});
    show("impl M1 5e-6 mu" + number(mu), {"mesh=M1", m, "output.interval=0", "scheme=implicit", "time.dt=5e-6"});
    show("impl M1 1e-4 mu" + number(mu), {"mesh=M1", m, "output.interval=0", "scheme=implicit", "time.dt=1e-4"});
    show("semi M1 1e-4 mu" + number(mu), {"mesh=M1", m, "output.interval=0", "time.dt=1e-4"});
    show("semi M1 5e-6 mu" + number(mu), {"mesh=M1", m, "output.interval=0", "time.dt=5e-6"});
    for (double f : {0.1, 0.3, 1.0, 3.0, 10.0})
      show("pen M1 fsi " + number(f) + " mu" + number(mu), {"mesh=M1", m, "output.interval=0", "scheme=explicit_penalty", "time.dt=\"auto\"", "penalty.scale_factor=" + number(f)});
    show("semi M2 1e-6 mu" + number(mu), {"mesh=M2", m, "output.interval=0", "time.dt=1e-6"});
    show("pen M2 auto mu" + number(mu), {"mesh=M2", m, "output.interval=0", "scheme=explicit_penalty", "time.dt=\"auto\""});
  }
}

}  // namespace
}  // namespace ricochet
namespace ricochet {
TEST(Explore, Chatter) {
  for (std::string extra : {"contact.level=\"position\"", "contact.level=\"velocity\"", "implicit.theta=0.55", "implicit.theta=1.0"}) {
    const CaseSpec spec = read_case(kCase, {"mesh=M1", "output.interval=0", "scheme=implicit", extra});
    const PreparedCase pc = prepare_case(spec);
    const RunResult r = run_case(pc);
    const History& h = r.history;
    std::size_t first = 0, last = 0;
    double vmax = 0;
    for (std::size_t row = 0; row < h.rows(); ++row) if (h.at(row, h.column("contact_nodes")) > 0) { if (!first) first = row; last = row; }
    std::printf("%s: %s pen %.3e errmax %.3e, zero rows:", extra.c_str(), r.status == RunStatus::ok ? "ok" : r.reason.c_str(), r.penetration_max, r.energy_error_max);
    for (std::size_t row = first; row <= last; ++row) {
      if (h.at(row, h.column("contact_nodes")) == 0) std::printf(" %.2e", h.at(row, 0));
      if (h.at(row, 0) > 2e-4 && h.at(row, 0) < 1.5e-3) vmax = std::max(vmax, std::abs(h.at(row, h.column("P_vy"))));
    }
    const double mass = 0.5 * pc.model.mass.sum();
    std::printf("\n   max |P_vy| in 0.2-1.5 ms: %.4f, rebound vy %.5f\n", vmax, h.at(h.rows() - 1, h.column("momentum_y")) / mass);
  }
}
}
