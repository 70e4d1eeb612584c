// A run's errors against its reference (harness/sweeps/reference_errors.hpp, docs/sweeps.md "Accuracy
// against cost"), on synthetic summaries and histories whose answers are known exactly: linear
// displacement histories, force histories whose trapezoid integrals are sums of triangles, and
// scalar summary keys. Missing or mistyped inputs leave a metric empty.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "harness/outputs/json_io.hpp"
#include "harness/sweeps/reference_errors.hpp"

using namespace ricochet;

namespace {

// A reference on [0, 2]: probe P moves as u = (t, 0), the total energy stays 10 J, the normal
// force is a triangle 0 -> 10 N -> 0 (impulse 10 N s), no tangential force.
HistoryTable reference_history() {
  return {{"time", "total_energy", "P_ux", "P_uy", "normal_force", "tangential_force"},
          {{0, 10, 0, 0, 0, 0}, {1, 10, 1, 0, 10, 0}, {2, 10, 2, 0, 0, 0}}};
}

// The run, sampled twice as often: u = (2t, 0.5t), so |u - u_ref| = t·sqrt(1 + 0.25) is largest at
// t = 2; E = 10 + t; the normal force 0, 4, 8, 4, 0 (impulse 8 N s); a tangential force of 3 N
// throughout (impulse 6 N s).
HistoryTable run_history() {
  HistoryTable h{{"time", "P_ux", "P_uy", "total_energy", "normal_force", "tangential_force"}, {}};
  const double normal[] = {0, 4, 8, 4, 0};
  for (int i = 0; i < 5; ++i) {
    const double t = 0.5 * i;
    h.rows.push_back({t, 2 * t, 0.5 * t, 10 + t, normal[i], 3});
  }
  return h;
}

const char* kRefSummary = R"({"status": "ok", "dt": 1e-3, "initial_energy": 10, "penetration_max": 1e-9,
  "final": {"momentum_x": 0, "momentum_y": 0, "angular_momentum": 0.25},
  "rebound_velocity_x": 1.0, "rebound_velocity_y": -2.0,
  "contact_duration": 0.004, "von_mises_interior_max": 2.5e6, "von_mises_interior_max_time": 1e-3})";

const char* kRunSummary = R"({"status": "ok", "dt": 2e-3, "initial_energy": 10, "penetration_max": 3e-7,
  "final": {"momentum_x": 0, "momentum_y": 0, "angular_momentum": -0.5},
  "rebound_velocity_x": 4.0, "rebound_velocity_y": 2.0,
  "contact_duration": 0.0055, "von_mises_interior_max": 2.0e6, "von_mises_interior_max_time": 1.5e-3})";

}  // namespace

TEST(CompareWithReference, HistoryMetricsOfLinearHistoriesAreKnownExactly) {
  const HistoryTable ref = reference_history(), run = run_history();
  const Json rs = parse_json(kRefSummary), s = parse_json(kRunSummary);
  const ReferenceMetrics m = compare_with_reference({&s, &run}, {&rs, &ref}, "P");
  EXPECT_EQ(m.samples, 5u);
  // u - u_ref = (t, 0.5 t): largest at t = 2, |(2, 1)| = sqrt(5).
  ASSERT_TRUE(m.probe);
  EXPECT_DOUBLE_EQ(*m.probe, std::sqrt(5.0));
  // |E - E_ref| / E0_ref = t / 10: 0.2 at t = 2.
  ASSERT_TRUE(m.energy);
  EXPECT_DOUBLE_EQ(*m.energy, 0.2);

  // The same history against itself: exactly 0.
  const ReferenceMetrics same = compare_with_reference({&rs, &ref}, {&rs, &ref}, "P");
  EXPECT_EQ(*same.probe, 0.0);
  EXPECT_EQ(*same.energy, 0.0);
  EXPECT_EQ(*same.impulse_normal, 0.0);
  EXPECT_EQ(*same.rebound_velocity, 0.0);
}

TEST(CompareWithReference, EnergyIsScaledByTheReferencesInitialEnergyElseItsFirstSample) {
  const HistoryTable ref = reference_history(), run = run_history();
  // initial_energy 20 J: the error halves.
  const Json twenty = parse_json(R"({"status": "ok", "initial_energy": 20})");
  EXPECT_DOUBLE_EQ(*compare_with_reference({nullptr, &run}, {&twenty, &ref}, "P").energy, 0.1);
  // No initial_energy: |E_total,ref| at its first sample, 10 J.
  const Json none = parse_json(R"({"status": "ok"})");
  EXPECT_DOUBLE_EQ(*compare_with_reference({nullptr, &run}, {&none, &ref}, "P").energy, 0.2);
  // Both 0: an absolute error in J.
  HistoryTable zero = ref;
  for (auto& r : zero.rows) r[1] = 0.0;
  EXPECT_DOUBLE_EQ(*compare_with_reference({nullptr, &run}, {&none, &zero}, "P").energy, 12.0);
}

TEST(CompareWithReference, ImpulsesByTheTrapezoidRuleWhenTheSummariesLackThem) {
  const HistoryTable ref = reference_history(), run = run_history();
  EXPECT_DOUBLE_EQ(*trapezoid_integral(ref, "normal_force"), 10.0);
  EXPECT_DOUBLE_EQ(*trapezoid_integral(run, "normal_force"), 8.0);
  EXPECT_DOUBLE_EQ(*trapezoid_integral(run, "tangential_force"), 6.0);
  EXPECT_FALSE(trapezoid_integral(run, "no_such_column"));
  EXPECT_EQ(*trapezoid_integral(HistoryTable{{"time", "f"}, {{1.0, 5.0}}}, "f"), 0.0);  // one sample: no interval

  const Json rs = parse_json(kRefSummary), s = parse_json(kRunSummary);
  const ReferenceMetrics m = compare_with_reference({&s, &run}, {&rs, &ref}, "P");
  EXPECT_EQ(m.impulse_source, "history");
  EXPECT_DOUBLE_EQ(*m.impulse_normal, 2.0);      // |8 - 10|
  EXPECT_DOUBLE_EQ(*m.impulse_tangential, 6.0);  // |6 - 0|
}

TEST(CompareWithReference, ImpulsesFromTheSummariesWhenBothHaveThem) {
  const HistoryTable ref = reference_history(), run = run_history();
  const Json rs = parse_json(R"({"status": "ok", "contact_impulse_normal": 1.25, "contact_impulse_tangential": -0.5})");
  const Json s = parse_json(R"({"status": "ok", "contact_impulse_normal": 1.0, "contact_impulse_tangential": 0.25})");
  const ReferenceMetrics m = compare_with_reference({&s, &run}, {&rs, &ref}, "P");
  EXPECT_EQ(m.impulse_source, "summary");
  EXPECT_DOUBLE_EQ(*m.impulse_normal, 0.25);
  EXPECT_DOUBLE_EQ(*m.impulse_tangential, 0.75);
  // One run without them: both from the histories, never one source against the other.
  const Json bare = parse_json(R"({"status": "ok"})");
  const ReferenceMetrics mixed = compare_with_reference({&bare, &run}, {&rs, &ref}, "P");
  EXPECT_EQ(mixed.impulse_source, "history");
  EXPECT_DOUBLE_EQ(*mixed.impulse_normal, 2.0);
  // Neither source: empty.
  const ReferenceMetrics neither = compare_with_reference({&bare, nullptr}, {&rs, &ref}, "P");
  EXPECT_EQ(neither.impulse_source, "");
  EXPECT_FALSE(neither.impulse_normal);
  EXPECT_FALSE(neither.impulse_tangential);
}

TEST(CompareWithReference, ScalarMetricsAreAbsoluteDifferencesOfTheSummaries) {
  const Json rs = parse_json(kRefSummary), s = parse_json(kRunSummary);
  const ReferenceMetrics m = compare_with_reference({&s, nullptr}, {&rs, nullptr}, "P");
  EXPECT_DOUBLE_EQ(*m.penetration, 3e-7);               // the run's own, not a difference
  EXPECT_DOUBLE_EQ(*m.rebound_velocity, 5.0);           // |(4, 2) - (1, -2)| = |(3, 4)|
  EXPECT_DOUBLE_EQ(*m.angular_momentum, 0.75);          // |-0.5 - 0.25|
  EXPECT_DOUBLE_EQ(*m.contact_duration, 0.0015);        // |5.5 ms - 4 ms|
  EXPECT_DOUBLE_EQ(*m.von_mises_interior, 0.5e6);       // |2.0 - 2.5| MPa
  EXPECT_DOUBLE_EQ(*m.von_mises_interior_time, 0.5e-3);  // |1.5 ms - 1 ms|
  // No histories: no history metrics, and no impulses.
  EXPECT_FALSE(m.probe);
  EXPECT_FALSE(m.energy);
  EXPECT_FALSE(m.impulse_normal);
  EXPECT_EQ(m.samples, 0u);
}

TEST(CompareWithReference, ReboundVelocityFallsBackToMomentumOverMass) {
  const Json ref = parse_json(R"({"status": "ok", "rebound_velocity_x": 0.0, "rebound_velocity_y": 0.0})");
  // (6, -8) kg m/s over 2 kg = (3, -4) m/s.
  const Json by_mass = parse_json(R"({"status": "ok", "total_mass": 2.0, "final": {"momentum_x": 6.0, "momentum_y": -8.0}})");
  EXPECT_DOUBLE_EQ(*compare_with_reference({&by_mass, nullptr}, {&ref, nullptr}, "P").rebound_velocity, 5.0);
  // Without total_mass (or with a zero mass), and without the rebound keys: empty.
  const Json no_mass = parse_json(R"({"status": "ok", "final": {"momentum_x": 6.0, "momentum_y": -8.0}})");
  EXPECT_FALSE(compare_with_reference({&no_mass, nullptr}, {&ref, nullptr}, "P").rebound_velocity);
  const Json zero_mass = parse_json(R"({"status": "ok", "total_mass": 0, "final": {"momentum_x": 6.0, "momentum_y": -8.0}})");
  EXPECT_FALSE(compare_with_reference({&zero_mass, nullptr}, {&ref, nullptr}, "P").rebound_velocity);
  // Only one component: not a velocity.
  const Json half = parse_json(R"({"status": "ok", "rebound_velocity_x": 1.0})");
  EXPECT_FALSE(compare_with_reference({&half, nullptr}, {&ref, nullptr}, "P").rebound_velocity);
}

TEST(CompareWithReference, MissingOrMistypedInputsLeaveMetricsEmpty) {
  // Nothing at all.
  const ReferenceMetrics none = compare_with_reference({}, {}, "P");
  for (const auto& [name, value] : metric_values(none, "P")) EXPECT_FALSE(value) << name;
  EXPECT_EQ(none.impulse_source, "");

  // Keys of the wrong type, or null, count as absent.
  const Json odd = parse_json(R"({"status": "ok", "penetration_max": "deep", "final": null,
    "contact_duration": null, "von_mises_interior_max": [1], "rebound_velocity_x": true, "rebound_velocity_y": 1})");
  const Json rs = parse_json(kRefSummary);
  const ReferenceMetrics m = compare_with_reference({&odd, nullptr}, {&rs, nullptr}, "P");
  for (const auto& [name, value] : metric_values(m, "P")) EXPECT_FALSE(value) << name;

  // A probe that one history lacks: only that metric is empty.
  const HistoryTable ref = reference_history(), run = run_history();
  const ReferenceMetrics q = compare_with_reference({&rs, &run}, {&rs, &ref}, "Q");
  EXPECT_FALSE(q.probe);
  EXPECT_TRUE(q.energy);
}

TEST(CompareWithReference, DivergedRunsGetHistoryMetricsOnly) {
  const HistoryTable ref = reference_history(), run = run_history();
  const Json rs = parse_json(kRefSummary), s = parse_json(kRunSummary);
  const Json diverged = parse_json(R"({"status": "diverged", "penetration_max": 1, "contact_duration": 1,
    "final": {"angular_momentum": 9}})");
  // A diverged run: its histories are compared up to where it stopped; nothing else.
  const ReferenceMetrics m = compare_with_reference({&diverged, &run}, {&rs, &ref}, "P");
  EXPECT_TRUE(m.probe);
  EXPECT_TRUE(m.energy);
  EXPECT_FALSE(m.penetration);
  EXPECT_FALSE(m.angular_momentum);
  EXPECT_FALSE(m.contact_duration);
  EXPECT_FALSE(m.impulse_normal);
  // A diverged reference: the run's own penetration still counts (its exact value is 0).
  const ReferenceMetrics r = compare_with_reference({&s, &run}, {&diverged, &ref}, "P");
  EXPECT_DOUBLE_EQ(*r.penetration, 3e-7);
  EXPECT_FALSE(r.angular_momentum);
  EXPECT_FALSE(r.rebound_velocity);
}

TEST(CompareWithReference, NonFiniteDifferencesAreInfinite) {
  HistoryTable ref = reference_history(), run = run_history();
  run.rows[2][1] = std::numeric_limits<double>::quiet_NaN();  // P_ux at t = 1
  run.rows[3][4] = std::numeric_limits<double>::infinity();   // normal_force at t = 1.5
  const Json rs = parse_json(kRefSummary), s = parse_json(kRunSummary);
  const ReferenceMetrics m = compare_with_reference({&s, &run}, {&rs, &ref}, "P");
  EXPECT_EQ(*m.probe, std::numeric_limits<double>::infinity());
  EXPECT_EQ(*m.impulse_normal, std::numeric_limits<double>::infinity());
  EXPECT_DOUBLE_EQ(*m.impulse_tangential, 6.0);
}

TEST(CompareWithReference, MetricNamesAndFloors) {
  EXPECT_EQ(metric_names("top"),
            (std::vector<std::string>{"probe_top", "energy", "energy_bodies", "penetration", "rebound_velocity", "angular_momentum",
                                      "impulse_normal", "impulse_tangential", "contact_duration", "von_mises_interior",
                                      "von_mises_interior_time"}));
  EXPECT_FALSE(has_floor("penetration"));
  EXPECT_TRUE(has_floor("probe_top"));
  EXPECT_TRUE(has_floor("energy"));
  ReferenceMetrics m;
  m.contact_duration = 0.5;
  const auto v = metric_values(m, "P");
  ASSERT_EQ(v.size(), 11u);
  EXPECT_EQ(v[8].first, "contact_duration");
  EXPECT_EQ(*v[8].second, 0.5);
}

// A penalty run whose springs hold energy: its total_energy dips by the contact_energy, which
// counts with it, so against a reference that keeps 10 J in the bodies the error is 0; without
// the contact_energy column the dip itself is the error.
TEST(CompareWithReference, EnergyCountsThePenaltySpringEnergy) {
  const HistoryTable ref = reference_history();
  HistoryTable run{{"time", "total_energy", "contact_energy", "P_ux", "P_uy"}, {}};
  for (int i = 0; i <= 4; ++i) {
    const double t = 0.5 * i, held = i == 2 ? 1.5 : 0.25 * i * (4 - i) * 0.5;
    run.rows.push_back({t, 10.0 - held, held, t, 0.0});
  }
  const Json rs = parse_json(kRefSummary), s = parse_json(kRunSummary);
  const ReferenceMetrics m = compare_with_reference({&s, &run}, {&rs, &ref}, "P");
  ASSERT_TRUE(m.energy);
  EXPECT_NEAR(*m.energy, 0.0, 1e-15);
  HistoryTable bodies_only{{"time", "total_energy", "P_ux", "P_uy"}, {}};
  for (const auto& r : run.rows) bodies_only.rows.push_back({r[0], r[1], r[3], r[4]});
  const ReferenceMetrics without = compare_with_reference({&s, &bodies_only}, {&rs, &ref}, "P");
  ASSERT_TRUE(without.energy);
  EXPECT_DOUBLE_EQ(*without.energy, 0.15);  // the 1.5 J held at t = 1, over E0 = 10 J
  // error_energy_bodies leaves the springs out (the paper's E_t = E_c + E_e): the dip counts.
  ASSERT_TRUE(m.energy_bodies);
  EXPECT_DOUBLE_EQ(*m.energy_bodies, 0.15);
}
