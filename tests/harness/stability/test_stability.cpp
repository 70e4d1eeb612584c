// The stability search (harness/stability/stability.hpp, docs/stability.md): on a small explicit case the
// bracket [lo, hi] contains the true linear limit 2 / omega_max, computed here independently
// from the eigenvalues of M^-1 K on the free DOFs; the bisection converges to the tolerance and
// respects --max-runs; the implicit scheme reports no instability up to the cap; the command
// writes stability.json and rejects bad input with exit status 2, writing nothing.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <sys/wait.h>

#include "harness/input/case_setup.hpp"
#include "harness/cli/cli.hpp"
#include "harness/input/input_error.hpp"
#include "harness/stability/stability.hpp"
#include "solver/forces/tangent.hpp"
#include "tests/support/run_program.hpp"
#include "tests/support/small_cases.hpp"
#include "tests/support/temp_dir.hpp"

namespace fs = std::filesystem;

namespace ricochet {
namespace {

// A 0.1 m x 0.1 m plate of 10 x 10 square Q4 (2x2) cells, left edge fixed, moving up at
// 0.1 m/s (strains ~ v / c_p ~ 1e-3: the response is linear). Plane stress, c_p = 103 m/s,
// estimate min L_e / c_p = h / (sqrt(2) c_p) = 6.85e-5 s; the run lasts ~730 estimate steps.
const std::string kSquare = test_support::square_plate_case("stab_square", 10, false);

class StabilityTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test_support::fresh_test_dir("ricochet_stability_");
    file_ = (dir_ / "square.toml").string();
    std::ofstream(file_) << kSquare;
  }
  void TearDown() override { fs::remove_all(dir_); }

  PreparedCase square(const std::vector<std::string>& sets = {}) const {
    return prepare_case(read_case(file_, sets));
  }
  std::string out() const { return (dir_ / "out").string(); }

  fs::path dir_;
  std::string file_;
};

// The exact linear stability limit of central differences: 2 / omega_max, with omega_max^2 the
// largest eigenvalue of M^-1/2 K M^-1/2 on the free DOFs (K the tangent at the reference state).
double true_critical_dt(const PreparedCase& pc) {
  const Model<2>& m = pc.model<2>();
  const int n = m.num_dofs();
  SystemMatrix sys = make_system_matrix(m);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd f(n);
  assemble_system(m, zero.data(), zero.data(), 0.0, 1.0, 0.0, sys, f.data(), false);
  const Eigen::MatrixXd k = Eigen::MatrixXd(sys.matrix);
  std::set<int> fixed;
  for (const PrescribedDof& p : pc.settings.prescribed) fixed.insert(p.dof);
  std::vector<int> free;
  for (int d = 0; d < n; ++d)
    if (!fixed.count(d)) free.push_back(d);
  const int nf = static_cast<int>(free.size());
  Eigen::MatrixXd a(nf, nf);
  for (int i = 0; i < nf; ++i)
    for (int j = 0; j < nf; ++j)
      a(i, j) = k(free[i], free[j]) / std::sqrt(m.mass[free[i]] * m.mass[free[j]]);
  const double omega2 = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(a, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
  return 2.0 / std::sqrt(omega2);
}

const StabilityTrial& trial_at(const StabilityResult& r, double dt) {
  const auto it = std::find_if(r.trials.begin(), r.trials.end(), [&](const StabilityTrial& t) { return t.dt == dt; });
  EXPECT_NE(it, r.trials.end()) << "no trial at dt = " << dt;
  return *it;
}

using test_support::text_of;

// The Flanagan-Belytschko estimate h / (sqrt(2) c_p) of a square Q4 cell is conservative: the
// true limit 2 / omega_max of the 2x2 Q4 with lumped mass on this mesh is 1.4137 x the
// estimate (eigenvalues below; close to sqrt(2), i.e. h / c_p). The search must bracket it:
// hi at or above it, lo below it or at most a hair above (0.2 %: a run of ~520 steps cannot
// see growth that slow; measured lo = 1.4066 x, below).
TEST_F(StabilityTest, BracketsTheTrueLimitOfAnExplicitCase) {
  const PreparedCase pc = square();
  const double est = stability_estimate(pc);
  EXPECT_EQ(est, pc.model<2>().critical_dt);
  EXPECT_NEAR(est, 0.01 / (std::sqrt(2.0) * std::sqrt(1e7 / (1000.0 * (1.0 - 0.25 * 0.25)))), 1e-9);
  const double exact = true_critical_dt(pc);
  EXPECT_GT(exact / est, 1.40);  // measured 1.41372
  EXPECT_LT(exact / est, 1.42);

  StabilityOptions opt;  // defaults: tolerance 0.01, 30 runs, energy bound 0.1
  const StabilityResult r = find_stable_dt(pc, opt);
  ASSERT_EQ(r.outcome, StabilityOutcome::bracketed);
  ASSERT_TRUE(r.lo && r.hi);
  EXPECT_TRUE(r.converged);
  EXPECT_LE(*r.hi / *r.lo - 1.0, opt.tolerance);
  EXPECT_LT(*r.lo, *r.hi);
  // Measured: lo = 1.407 x, hi = 1.414 x the estimate, 9 runs.
  EXPECT_GE(*r.lo / est, 1.0);
  EXPECT_LE(*r.hi / est, 1.5);
  EXPECT_GT(*r.lo / est, 1.39);
  EXPECT_LT(*r.hi / est, 1.43);
  EXPECT_LE(*r.lo, exact * 1.002);
  EXPECT_GE(*r.hi, exact);
  EXPECT_LE(r.trials.size(), 12u);
  std::printf("true limit %.5f x estimate; found lo %.5f x, hi %.5f x in %zu runs\n", exact / est,
              *r.lo / est, *r.hi / est, r.trials.size());

  // The run at lo is ok with a small energy error, the run at hi diverges.
  const StabilityTrial& at_lo = trial_at(r, *r.lo);
  EXPECT_TRUE(at_lo.stable);
  EXPECT_EQ(at_lo.status, RunStatus::ok);
  EXPECT_LT(at_lo.energy_error_max, 0.02);
  EXPECT_EQ(at_lo.steps, at_lo.planned_steps);
  // The signed balance from the history: the largest gain or loss is the energy error (no
  // external work here, so both use the reference E_0).
  EXPECT_GE(at_lo.energy_gain_max, 0.0);
  EXPECT_LE(at_lo.energy_loss_max, 0.0);
  EXPECT_NEAR(std::max(at_lo.energy_gain_max, -at_lo.energy_loss_max), at_lo.energy_error_max, 1e-12);
  const StabilityTrial& at_hi = trial_at(r, *r.hi);
  EXPECT_FALSE(at_hi.stable);
  EXPECT_EQ(at_hi.status, RunStatus::diverged);
  EXPECT_LT(at_hi.steps, at_hi.planned_steps);
  // Re-running reproduces the verdicts (the runs are deterministic).
  EXPECT_TRUE(stability_trial(pc, *r.lo, opt).stable);
  EXPECT_FALSE(stability_trial(pc, *r.hi, opt).stable);

  // Every trial was judged consistently with the final bracket.
  for (const StabilityTrial& t : r.trials) {
    if (t.dt <= *r.lo) {
      EXPECT_TRUE(t.stable) << t.dt;
    }
    if (t.dt >= *r.hi) {
      EXPECT_FALSE(t.stable) << t.dt;
    }
  }
}

TEST_F(StabilityTest, TighterToleranceNarrowsTheBracketAroundTheTrueLimit) {
  const PreparedCase pc = square();
  const double exact = true_critical_dt(pc);
  StabilityOptions opt;
  opt.tolerance = 1e-3;
  const StabilityResult r = find_stable_dt(pc, opt);
  ASSERT_EQ(r.outcome, StabilityOutcome::bracketed);
  EXPECT_TRUE(r.converged);
  EXPECT_LE(*r.hi / *r.lo - 1.0, 1e-3);
  // Bisection halves log(hi/lo): from the doubling bracket [1, 2] x estimate, 10 bisections
  // reach 2^(1/1024) - 1 < 1e-3, so 12 runs in all.
  EXPECT_EQ(r.trials.size(), 12u);
  EXPECT_LE(*r.lo, exact * 1.002);
  EXPECT_GE(*r.hi, exact);
}

TEST_F(StabilityTest, RespectsMaxRuns) {
  const PreparedCase pc = square();
  for (int max_runs : {1, 2, 3, 5}) {
    StabilityOptions opt;
    opt.max_runs = max_runs;
    const StabilityResult r = find_stable_dt(pc, opt);
    EXPECT_LE(static_cast<int>(r.trials.size()), max_runs);
    EXPECT_FALSE(r.converged);
    if (max_runs == 1) {
      EXPECT_EQ(r.outcome, StabilityOutcome::run_limit);  // the estimate is stable; no unstable dt yet
      EXPECT_TRUE(r.lo && !r.hi);
    } else {
      EXPECT_EQ(r.outcome, StabilityOutcome::bracketed);
      EXPECT_EQ(static_cast<int>(r.trials.size()), max_runs);
      // log-space bisection: width 2^(1/2^(runs - 2)) - 1
      EXPECT_NEAR(*r.hi / *r.lo, std::pow(2.0, 1.0 / std::pow(2.0, max_runs - 2)), 1e-12);
    }
  }
  // Through the command: --max-runs 3 gives 3 trials in stability.json, and a bracket (exit 0).
  EXPECT_EQ(stability_command({file_, "--max-runs", "3", "--out", out(), "--quiet"}), 0);
  const std::string json = text_of(fs::path(out()) / "stability.json");
  EXPECT_NE(json.find("\"runs\": 3,"), std::string::npos) << json;
  EXPECT_NE(json.find("\"converged\": false"), std::string::npos) << json;
  EXPECT_TRUE(fs::exists(fs::path(out()) / "trials" / "03" / "summary.json"));
  EXPECT_FALSE(fs::exists(fs::path(out()) / "trials" / "04"));
}

TEST_F(StabilityTest, StartsBelowWhenTheEstimateIsUnstable) {
  // When the run at the estimate fails the criterion, the search halves down to a stable dt.
  // Forced here with an energy bound below the run's own error at the estimate (0.004; the
  // central-difference energy error grows like dt^2, so dt / 2 passes).
  const PreparedCase pc = square();
  StabilityOptions opt;
  opt.energy_bound = 0.002;  // the run at the estimate has energy_error_max 0.004
  const StabilityResult r = find_stable_dt(pc, opt);
  ASSERT_GE(r.trials.size(), 2u);
  EXPECT_FALSE(r.trials[0].stable);
  EXPECT_NE(r.trials[0].reason.find("energy error"), std::string::npos) << r.trials[0].reason;
  EXPECT_EQ(r.trials[0].status, RunStatus::ok);
  EXPECT_EQ(r.trials[1].dt, 0.5 * r.trials[0].dt);
  EXPECT_NE(stability_summary_line(pc, r).find("[energy rule]"), std::string::npos);
  ASSERT_EQ(r.outcome, StabilityOutcome::bracketed);
  EXPECT_LT(*r.hi, r.estimate * 1.0000001);
  EXPECT_TRUE(r.converged);
  std::printf("energy bound 0.002: lo %.4f x, hi %.4f x the estimate\n", *r.lo / r.estimate, *r.hi / r.estimate);
}

TEST_F(StabilityTest, ImplicitSchemeHasNoInstabilityUpToTheCap) {
  // theta = xi = 1/2 (the trapezoidal rule) is unconditionally stable on a linear problem.
  // time.end = 20 x estimate caps the search: estimate, 2, 4, 8, 16, 20 x, all stable.
  const PreparedCase pc = square({"scheme=implicit"});
  StabilityOptions opt;
  opt.end_time = 20.0 * pc.model<2>().critical_dt;
  const StabilityResult r = find_stable_dt(pc, opt);
  EXPECT_EQ(r.outcome, StabilityOutcome::no_unstable_up_to_cap);
  EXPECT_DOUBLE_EQ(r.cap, *opt.end_time);
  ASSERT_TRUE(r.lo);
  EXPECT_EQ(*r.lo, r.cap);
  EXPECT_FALSE(r.hi);
  EXPECT_EQ(r.trials.size(), 6u);
  for (const StabilityTrial& t : r.trials) {
    EXPECT_TRUE(t.stable) << t.dt << " " << t.reason;
    EXPECT_LT(t.energy_error_max, 0.01) << t.dt;
  }
  EXPECT_NE(stability_summary_line(pc, r).find("no unstable dt up to"), std::string::npos);

  // The command: exit 5 and an honest report.
  char end[32];
  std::snprintf(end, sizeof end, "%.17g", *opt.end_time);
  EXPECT_EQ(stability_command({file_, "--set", "scheme=implicit", "--end", end, "--out", out(), "--quiet"}), 5);
  const std::string json = text_of(fs::path(out()) / "stability.json");
  EXPECT_NE(json.find("\"outcome\": \"no_unstable_up_to_cap\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"smallest_unstable_dt\": null"), std::string::npos) << json;
}

TEST_F(StabilityTest, CapIsAThousandEstimatesWhenTheRunIsLonger) {
  const PreparedCase pc = square();
  StabilityOptions opt;
  opt.end_time = 0.2;  // 0.2 s > 1e3 x 6.85e-5 s
  opt.max_runs = 1;    // only the search range matters here
  const StabilityResult r = find_stable_dt(pc, opt);
  EXPECT_DOUBLE_EQ(r.cap, 1e3 * pc.model<2>().critical_dt);
  EXPECT_DOUBLE_EQ(r.floor, 1e-3 * pc.model<2>().critical_dt);
  EXPECT_DOUBLE_EQ(r.end_time, 0.2);
  EXPECT_EQ(r.outcome, StabilityOutcome::run_limit);
  ASSERT_EQ(r.trials.size(), 1u);
  EXPECT_EQ(r.trials[0].planned_steps, static_cast<long>(std::ceil(0.2 / pc.model<2>().critical_dt)));
}

TEST_F(StabilityTest, CommandWritesTheReport) {
  EXPECT_EQ(stability_command({file_, "--out", out(), "--quiet"}), 0);
  const std::string json = text_of(fs::path(out()) / "stability.json");
  for (const char* key :
       {"\"case\": \"stab_square\"", "\"scheme\": \"explicit\"", "\"mesh\": \"m\"", "\"element\": \"q4\"",
        "\"critical_dt\":", "\"penalty_critical_dt\": null", "\"estimate\":", "\"criterion\":",
        "\"energy_error_max_bound\": 0.1", "\"outcome\": \"bracketed\"", "\"converged\": true",
        "\"largest_stable_dt\":", "\"smallest_unstable_dt\":", "\"stable_over_estimate\": 1.4",
        "\"runs\": 9,", "\"trials\": [", "\"reason\": \"diverged: energy growth", "\"steps\":",
        "\"unstable_by\": \"diverged\"", "\"energy_gain_max\":", "\"energy_loss_max\":"})
    EXPECT_NE(json.find(key), std::string::npos) << key << " in " << json;
  EXPECT_FALSE(fs::exists(fs::path(out()) / "stability.json.tmp"));
  // Without --out nothing is written.
  const fs::path cwd = fs::current_path();
  fs::current_path(dir_);
  EXPECT_EQ(stability_command({file_, "--quiet", "--max-runs", "2"}), 0);
  fs::current_path(cwd);
  std::size_t entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir_)) ++entries;
  EXPECT_EQ(entries, 2u);  // square.toml and out/
}

TEST_F(StabilityTest, PenaltyEstimateCombinesElementsAndSprings) {
  const std::string file = (dir_ / "drop.toml").string();
  std::ofstream(file) << kSquare << R"(
[[obstacles]]
normal = [0.0, 1.0]
point = [0.0, -0.001]
[penalty]
scale_factor = 1.0
)";
  const PreparedCase pc = prepare_case(read_case(file, {"scheme=explicit_penalty"}));
  ASSERT_GT(pc.penalty_critical_dt, 0.0);
  const double de = pc.model<2>().critical_dt, dp = pc.penalty_critical_dt;
  EXPECT_NEAR(stability_estimate(pc), 1.0 / std::sqrt(1.0 / (de * de) + 1.0 / (dp * dp)), 1e-15);
  EXPECT_LT(stability_estimate(pc), de);
}

// The command line as the `ricochet` program runs it (harness/cli/cli.cpp wires the word).
TEST_F(StabilityTest, ProgramRunsTheCommand) {
  auto run = [](const std::string& args, std::string& output) {
    const test_support::ProgramOutcome o = test_support::run_ricochet("stability " + args);
    output = o.output;
    return o.status;
  };
  std::string output;
  EXPECT_EQ(run(file_ + " --max-runs 2 --quiet --out " + out(), output), 0) << output;
  EXPECT_NE(output.find("stab_square: explicit m q4  estimate 6.847e-05 s  largest stable 6.847e-05 s (1 x)"),
            std::string::npos) << output;
  EXPECT_TRUE(fs::exists(fs::path(out()) / "stability.json"));
  EXPECT_EQ(run(file_ + " --tolerance 0", output), 2) << output;
  EXPECT_EQ(std::count(output.begin(), output.end(), '\n'), 1) << output;
}

TEST_F(StabilityTest, RejectsBadInput) {
  const std::vector<std::vector<std::string>> bad = {
      {},
      {(dir_ / "missing.toml").string(), "--out", out()},
      {file_, "--out", out(), "--tolerance", "0"},
      {file_, "--out", out(), "--tolerance", "fast"},
      {file_, "--out", out(), "--tolerance"},
      {file_, "--out", out(), "--max-runs", "2.5"},
      {file_, "--out", out(), "--max-runs", "0"},
      {file_, "--out", out(), "--energy-bound", "-1"},
      {file_, "--out", out(), "--end", "0"},
      {file_, "--out", out(), "--end=1e-3x"},
      {file_, "--out", out(), "--bogus"},
      {file_, file_, "--out", out()},
      {file_, "--out", out(), "--set", "time.dt=fast"},
      {file_, "--out", out(), "--set", "time.dtt=1e-5"},
  };
  for (const auto& args : bad) {
    std::string joined;
    for (const auto& a : args) joined += a + " ";
    testing::internal::CaptureStderr();
    const int status = stability_command(args);
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_EQ(status, 2) << joined << "\n" << err;
    EXPECT_EQ(err.rfind("ricochet: ", 0), 0u) << err;
    EXPECT_FALSE(fs::exists(out())) << "nothing may be written on bad input: " << joined;
  }
  StabilityOptions opt;
  opt.tolerance = -1;
  EXPECT_THROW(find_stable_dt(square(), opt), InputError);
}

}  // namespace
}  // namespace ricochet
