// The run-level contact and motion observables that the accuracy sweeps compare between runs
// (docs/outputs.md: contact_impulse_normal/_tangential, contact_start/end_time,
// contact_duration, rebound_velocity_x/_y, total_mass), on problems with a known answer:
// - the bar striking a rigid wall (reference/verification.toml [bar_wall]): impulse 2 m v0,
//   contact for 2L/c from t = 0, rebound at +v0, in all three schemes;
// - the oblique plate without friction: the normal impulse is exactly the change of vertical
//   momentum, the tangential impulse is 0 and the horizontal velocity stays 3 m/s.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "harness/case_setup.hpp"
#include "harness/case_spec.hpp"
#include "solver/run.hpp"

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
    EXPECT_NEAR(r.contact_impulse_normal, dp, 1e-9 * dp) << scheme;
    EXPECT_NEAR(r.contact_impulse_normal, 2.0 * m * v0, 0.01 * 2.0 * m * v0) << scheme;
    EXPECT_EQ(r.contact_impulse_tangential, 0.0) << scheme;
    // Rebound: +v0 (the final momentum over the mass).
    EXPECT_NEAR(last(r.history, "momentum_x") / r.total_mass, v0, 0.01 * v0) << scheme;
    // Contact from t = 0 for 2L/c; a penalty spring acts only once the node has penetrated,
    // one step later, and the springs add their delay.
    if (std::string(scheme) == "explicit_penalty")
      EXPECT_NEAR(r.contact_first_time, r.dt, 1e-12) << scheme;
    else
      EXPECT_EQ(r.contact_first_time, 0.0) << scheme;
    const double d = r.contact_last_time - r.contact_first_time;
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
  EXPECT_NEAR(m, 0.5 * pc.model.mass.sum(), 1e-15);
  const double vy = last(r.history, "momentum_y") / m, vx = last(r.history, "momentum_x") / m;
  EXPECT_NEAR(r.contact_impulse_normal, m * (vy - (-5.0)), 1e-9 * m * 5.0);
  EXPECT_EQ(r.contact_impulse_tangential, 0.0);
  EXPECT_NEAR(vx, 3.0, 1e-12);
  EXPECT_GT(vy, 4.0);  // it bounces: about 4.73 m/s on M2x4, nearly elastic
  // The plate touches at t = 0 and leaves before the end (3 ms).
  EXPECT_EQ(r.contact_first_time, 0.0);
  EXPECT_GT(r.contact_last_time, 1.5e-3);
  EXPECT_LT(r.contact_last_time, 2.9e-3);
}

}  // namespace
}  // namespace ricochet
