// The run-level contact and motion observables that the accuracy sweeps compare between runs
// (docs/outputs.md: contact_impulse_normal/_tangential, contact_start/end_time,
// contact_duration, rebound_velocity_x/_y, total_mass), on problems with a known answer:
// - the bar striking a rigid wall (reference/verification.toml [bar_wall]): impulse 2 m v0,
//   contact for 2L/c from t = 0, rebound at +v0, in all three schemes;
// - the oblique plate without friction: the normal impulse is exactly the change of vertical
//   momentum, the tangential impulse is 0 and the horizontal velocity stays 3 m/s.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "harness/input/case_setup.hpp"
#include "harness/input/case_spec.hpp"
#include "solver/schemes/explicit.hpp"

namespace ricochet {
namespace {

const std::string kSource = RICOCHET_SOURCE_DIR;

RunResult run(const std::string& file, const std::vector<std::string>& overrides, PreparedCase* out = nullptr) {
  const PreparedCase pc = prepare_case(read_case(kSource + "/" + file, overrides));
  RunResult r = run_case(pc);
  if (out) *out = pc;
  return r;
}

double last(const History& h, const char* column) { return h.at(h.rows() - 1, h.column(column)); }

// reference/verification.toml [bar_wall]: m = 0.64 kg, v0 = 1 m/s towards the wall, c = 5000 m/s.
TEST(ContactObservables, BarOnRigidWallImpulseDurationRebound) {
  const double m = 0.64, v0 = 1.0, duration = 8.0e-5;
  for (const char* scheme : {"semi_explicit", "implicit", "explicit_penalty"}) {
    std::vector<std::string> sets = {std::string("scheme=\"") + scheme + "\""};
    if (std::string(scheme) == "implicit") sets.push_back("time.dt=1e-7");
    const RunResult r = run("cases/verification/bar_wall.toml", sets);
    ASSERT_EQ(r.status, RunStatus::ok) << scheme << ": " << r.reason;
    EXPECT_NEAR(r.total_mass, m, 1e-12) << scheme;
    // Impulse 2 m v0 = 1.28 N s. The wall's impulse is the change of momentum exactly (no other
    // horizontal force): check both against each other to round-off and against 2 m v0.
    const double dp = last(r.history, "momentum_x") - (-m * v0);
    EXPECT_NEAR(r.contact.impulse_normal, dp, 1e-9 * dp) << scheme;
    EXPECT_NEAR(r.contact.impulse_normal, 2.0 * m * v0, 0.01 * 2.0 * m * v0) << scheme;
    EXPECT_EQ(r.contact.impulse_tangential, 0.0) << scheme;
    // Rebound: +v0 (the final momentum over the mass).
    EXPECT_NEAR(last(r.history, "momentum_x") / r.total_mass, v0, 0.01 * v0) << scheme;
    // Contact from t = 0 for 2L/c; a penalty spring acts only once the node has penetrated,
    // one step later, and the springs add their delay.
    if (std::string(scheme) == "explicit_penalty")
      EXPECT_NEAR(r.contact.first_time, r.dt, 1e-12) << scheme;
    else
      EXPECT_EQ(r.contact.first_time, 0.0) << scheme;
    const double d = r.contact.last_time - r.contact.first_time;
    const double tol = std::string(scheme) == "explicit_penalty" ? 0.15 : 0.03;
    EXPECT_NEAR(d, duration, tol * duration) << scheme;
  }
}

TEST(ContactObservables, FrictionlessPlateImpulseIsTheMomentumChange) {
  PreparedCase pc;
  const RunResult r = run("cases/oblique_plate.toml",
                          {"obstacles[0].friction=0.0", "output.fields=[]", "time.dt=2e-6"}, &pc);
  ASSERT_EQ(r.status, RunStatus::ok);
  const double m = r.total_mass;
  EXPECT_NEAR(m, 0.5 * pc.model<2>().mass.sum(), 1e-15);
  const double vy = last(r.history, "momentum_y") / m, vx = last(r.history, "momentum_x") / m;
  EXPECT_NEAR(r.contact.impulse_normal, m * (vy - (-5.0)), 1e-9 * m * 5.0);
  EXPECT_EQ(r.contact.impulse_tangential, 0.0);
  EXPECT_NEAR(vx, 3.0, 1e-12);
  EXPECT_GT(vy, 4.0);  // it bounces: about 4.73 m/s on M2x4, nearly elastic
  // The plate touches at t = 0 and leaves before the end (3 ms).
  EXPECT_EQ(r.contact.first_time, 0.0);
  EXPECT_GT(r.contact.last_time, 1.5e-3);
  EXPECT_LT(r.contact.last_time, 2.9e-3);
}

// The per-step count of status changes (history contact_status_changes), in every scheme, on the
// oblique plate with friction sampled at every step. A change of the closed contacts' number, or
// of the stick or slip counts, needs at least as many status changes; the plate lands and
// leaves, so contacts close and open; after it has left nothing changes. The run's totals are
// the sums of the rows.
TEST(ContactObservables, StatusChangesBoundTheCountChanges) {
  for (const char* scheme : {"semi_explicit", "implicit", "explicit_penalty"}) {
    const RunResult r = run("cases/oblique_plate.toml", {std::string("scheme=\"") + scheme + "\"", "mesh=\"M1\"",
                                                          "output.fields=[]", "output.interval=0", "time.dt=2e-6"});
    ASSERT_EQ(r.status, RunStatus::ok) << scheme << ": " << r.reason;
    const History& h = r.history;
    const std::size_t ch = h.column("contact_status_changes"), st = h.column("contact_stick"),
                      sl = h.column("contact_slip");
    ASSERT_EQ(h.rows(), static_cast<std::size_t>(r.steps + 1)) << scheme;
    double total = 0.0, closed_max = 0.0;
    long last_change = -1, steps_with_changes = 0;
    for (std::size_t i = 1; i < h.rows(); ++i) {
      const double changes = h.at(i, ch);
      steps_with_changes += changes > 0.0;
      const double d_stick = std::abs(h.at(i, st) - h.at(i - 1, st)), d_slip = std::abs(h.at(i, sl) - h.at(i - 1, sl));
      const double d_closed = std::abs(h.at(i, st) + h.at(i, sl) - h.at(i - 1, st) - h.at(i - 1, sl));
      ASSERT_GE(changes, std::max({d_stick, d_slip, d_closed})) << scheme << " row " << i;
      total += changes;
      closed_max = std::max(closed_max, h.at(i, st) + h.at(i, sl));
      if (changes > 0.0) last_change = static_cast<long>(i);
    }
    EXPECT_GT(closed_max, 0.0) << scheme;
    EXPECT_GE(total, 2.0 * closed_max) << scheme << ": every closed contact closed and opened again";
    EXPECT_EQ(last(h, "contact_stick") + last(h, "contact_slip"), 0.0) << scheme << ": the plate has left";
    EXPECT_LT(last_change, static_cast<long>(h.rows()) - 10) << scheme << ": no changes in free flight";
    // The run's totals (summary.json contact_iterations.status_changes, status_change_steps)
    // are the sums over every step: here every step is a history row.
    EXPECT_EQ(static_cast<double>(r.contact.status_changes), total) << scheme;
    EXPECT_EQ(r.contact.status_change_steps, steps_with_changes) << scheme;
  }
}

}  // namespace
}  // namespace ricochet
