// Stability groups of a sweep (docs/sweeps.md, "Stability groups"): each combination of the
// crossed keys is a stability search (`ricochet stability`) run by the sweep like a run: their
// rows in summary.csv and the values behind them (the folders' stability.json), a resume that
// runs nothing again, gates on the search columns, and the sweep-file errors of such a group.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "harness/cli/cli.hpp"
#include "harness/input/input_error.hpp"
#include "harness/outputs/json_io.hpp"
#include "harness/sweeps/sweep.hpp"
#include "harness/sweeps/sweep_spec.hpp"
#include "tests/support/small_cases.hpp"
#include "tests/support/sweep_checks.hpp"
#include "tests/support/summary_table.hpp"
#include "tests/support/temp_dir.hpp"

namespace fs = std::filesystem;
using namespace ricochet;

namespace {

// A 0.1 m x 0.1 m plate of 4 x 4 Q4 cells, left edge fixed, moving up: the plate of
// tests/harness/stability/test_stability.cpp on a coarser mesh. Its estimate min L_e / c_p is 1.7e-4 s at
// young = 1e7 (c_p = 103 m/s), half of it at young = 4e7; a trial of 0.02 s is ~120 steps at the
// estimate, so a whole search takes a fraction of a second.
const std::string kCase = test_support::square_plate_case("stab_plate", 4, true);

const std::string kSweep = R"(name = "stab"
base = "case.toml"

[[group]]
name = "dt"
kind = "stability"
tolerance = 0.05
max_runs = 20
end = 0.02
cross = { "bodies[0].material.young" = [1e7, 4e7] }
)";

class SweepStabilityTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test_support::fresh_test_dir("ricochet_sweep_stability_");
    write("case.toml", kCase);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& text) const {
    return test_support::write_text(dir_ / name, text);
  }
  fs::path out() const { return dir_ / "out"; }

  SweepOutcome run(const std::string& sweep_text, int jobs) {
    const SweepSpec spec = read_sweep(write("sweep.toml", sweep_text));
    SweepOptions o;
    o.out_dir = out();
    o.jobs = jobs;
    o.executable = RICOCHET_BINARY;
    o.log = &log_;
    return run_sweep(spec, expand(spec), o);
  }

  // Expects read_sweep + expand + check_runs to reject the sweep with one line naming the sweep
  // file and each of `parts`.
  void expect_rejected(const std::string& sweep_text, const std::vector<std::string>& parts) {
    test_support::expect_sweep_rejected(write("sweep.toml", sweep_text), sweep_text, parts);
  }

  fs::path dir_;
  std::ostringstream log_;
};

using Table = test_support::SummaryTable;
Table read_table(const fs::path& p) { return test_support::read_summary_table(p); }

using test_support::text_of;

const char* kIds[] = {"dt/000-bodies.0.material.young=1e7", "dt/001-bodies.0.material.young=4e7"};

// Two searches with --jobs 2: one row each, kind stability, whose columns are the values of the
// search's own stability.json; then a resume that runs nothing again, and gates on the rows.
TEST_F(SweepStabilityTest, RunsSearchesAndTablesThem) {
  const SweepOutcome first = run(kSweep, 2);
  EXPECT_EQ(first.total, 2u);
  EXPECT_EQ(first.executed, 2u);
  EXPECT_EQ(first.ok, 2u) << log_.str();
  EXPECT_EQ(first.failed, 0u) << log_.str();
  EXPECT_NE(log_.str().find("sweep stab: 2 runs (2 stability searches), 0 done before, 2 to run, 2 in parallel"),
            std::string::npos) << log_.str();

  const Table t = read_table(out() / "summary.csv");
  ASSERT_EQ(t.rows.size(), 2u) << text_of(out() / "summary.csv");
  for (const char* col : {"stable_dt", "unstable_dt", "estimate_dt", "stable_over_estimate", "outcome", "converged",
                          "trials", "unstable_reason", "bodies[0].material.young", "scheme", "elements"})
    EXPECT_NE(std::find(t.header.begin(), t.header.end(), col), t.header.end()) << col;
  // No run-only columns without a run in the sweep: the timings are the trials', in stability.json.
  EXPECT_EQ(std::find(t.header.begin(), t.header.end(), "energy_error_max"), t.header.end());

  std::vector<double> estimates;
  for (const char* id : kIds) {
    const auto& r = t.row(id);
    EXPECT_EQ(r.at("group"), "dt");
    EXPECT_EQ(r.at("kind"), "stability");
    EXPECT_EQ(r.at("status"), "ok");
    EXPECT_EQ(r.at("reason"), "");
    EXPECT_EQ(r.at("scheme"), "explicit");
    EXPECT_EQ(r.at("elements"), "16");

    const fs::path folder = out() / "runs" / id;
    const Json s = read_json_file(folder / "stability.json");
    ASSERT_EQ(s.at("outcome"), "bracketed") << id;
    EXPECT_EQ(r.at("outcome"), "bracketed");
    const double lo = std::stod(r.at("stable_dt")), hi = std::stod(r.at("unstable_dt"));
    const double est = std::stod(r.at("estimate_dt"));
    EXPECT_EQ(lo, s.at("largest_stable_dt").get<double>()) << id;
    EXPECT_EQ(hi, s.at("smallest_unstable_dt").get<double>()) << id;
    EXPECT_EQ(est, s.at("estimate").get<double>()) << id;
    EXPECT_LT(lo, hi);
    EXPECT_NEAR(std::stod(r.at("stable_over_estimate")), lo / est, 1e-12 * lo / est);
    // The search options reached the command: its tolerance, its trials' end time.
    EXPECT_EQ(s.at("search").at("tolerance").get<double>(), 0.05);
    EXPECT_EQ(s.at("search").at("max_runs").get<int>(), 20);
    EXPECT_EQ(s.at("end_time").get<double>(), 0.02);
    EXPECT_EQ(r.at("converged"), s.at("converged").get<bool>() ? "true" : "false");
    EXPECT_EQ(r.at("converged"), "true");
    EXPECT_LE(hi / lo - 1.0, 0.05);
    // The Q4 estimate is conservative (tests/harness/stability/test_stability.cpp): the limit is ~1.41 x.
    EXPECT_GT(lo / est, 1.2);
    EXPECT_LT(lo / est, 1.5);
    const std::size_t n = s.at("trials").size();
    EXPECT_EQ(r.at("trials"), std::to_string(n));
    char trial[24];
    std::snprintf(trial, sizeof trial, "%02zu", n);
    EXPECT_TRUE(fs::is_directory(folder / "trials" / trial));
    // The reason of the trial at hi.
    std::string reason;
    for (const Json& tr : s.at("trials"))
      if (tr.at("dt").get<double>() == hi) reason = tr.at("reason").get<std::string>();
    EXPECT_FALSE(reason.empty());
    EXPECT_EQ(r.at("unstable_reason"), reason);
    EXPECT_TRUE(fs::exists(folder / "run.lock"));
    EXPECT_NE(text_of(folder / "overrides.json").find("\"kind\": \"stability\""), std::string::npos);
    estimates.push_back(est);
  }
  // Four times the stiffness, twice the wave speed: half the estimate.
  EXPECT_NEAR(estimates[0] / estimates[1], 2.0, 1e-9);

  const Json sweep = read_json_file(out() / "sweep.json");
  EXPECT_EQ(sweep.at("runs").at(0).at("kind"), "stability");

  // Resume: both searches are done (their stability.json is valid); nothing runs again.
  const auto written = fs::last_write_time(out() / "runs" / kIds[0] / "stability.json");
  const std::string table = text_of(out() / "summary.csv");
  const SweepOutcome again = run(kSweep, 2);
  EXPECT_EQ(again.resumed, 2u);
  EXPECT_EQ(again.executed, 0u);
  EXPECT_EQ(fs::last_write_time(out() / "runs" / kIds[0] / "stability.json"), written);
  EXPECT_EQ(text_of(out() / "summary.csv"), table);

  // A changed search option is another search: both run again.
  std::string tighter = kSweep;
  tighter.replace(tighter.find("tolerance = 0.05"), 16, "tolerance = 0.04");
  const SweepOutcome changed = run(tighter, 2);
  EXPECT_EQ(changed.resumed, 0u);
  EXPECT_EQ(changed.executed, 2u);
  EXPECT_EQ(read_json_file(out() / "runs" / kIds[1] / "stability.json").at("search").at("tolerance").get<double>(), 0.04);

  // Gates read the search columns like any other.
  const std::string csv = (out() / "summary.csv").string();
  const std::string pass = write("pass.toml", R"(name = "stab"
require_rows = 2
[[gate]]
name = "stable above the estimate"
kind = "min"
column = "stable_over_estimate"
limit = 1.0
where = { kind = "stability", outcome = "bracketed" }
[[gate]]
name = "both bracketed"
kind = "count"
where = { kind = "stability", converged = "true" }
min = 2
max = 2
)");
  std::ostringstream o1, e1;
  EXPECT_EQ(check_command({csv, pass}, o1, e1), 0) << o1.str() << e1.str();
  EXPECT_NE(o1.str().find("PASS stable above the estimate (2 rows)"), std::string::npos) << o1.str();

  const std::string fail = write("fail.toml", R"(name = "stab"
[[gate]]
name = "stable above twice the estimate"
kind = "min"
column = "stable_over_estimate"
limit = 2.0
where = { kind = "stability" }
)");
  std::ostringstream o2, e2;
  EXPECT_EQ(check_command({csv, fail}, o2, e2), 4) << o2.str() << e2.str();
  EXPECT_NE(o2.str().find("FAIL stable above twice the estimate"), std::string::npos) << o2.str();
  EXPECT_NE(o2.str().find(kIds[0]), std::string::npos) << o2.str();

  // A stability.json that is not a finished search's (a hand edit) is not trusted: that search
  // runs again, with a note naming the file and the key; the other is reused.
  std::ofstream(out() / "runs" / kIds[0] / "stability.json") << "{\"outcome\": \"maybe\"}";
  log_.str("");
  const SweepOutcome redone = run(tighter, 2);
  EXPECT_EQ(redone.resumed, 1u);
  EXPECT_EQ(redone.executed, 1u);
  EXPECT_NE(log_.str().find(kIds[0] + std::string("/stability.json: outcome: expected \"bracketed\"")), std::string::npos)
      << log_.str();
  EXPECT_EQ(read_json_file(out() / "runs" / kIds[0] / "stability.json").at("outcome"), "bracketed");
}

// A stability group next to a run group and a shared [reference]: the runs keep their kind and
// their errors; the searches are not compared with the reference.
TEST_F(SweepStabilityTest, SitsNextToRunsAndASharedReference) {
  const std::string sweep = R"(name = "mixed"
base = "case.toml"
set = { "time.end" = 0.005 }
[reference]
set = { "time.dt" = 1e-5 }
[[group]]
name = "runs"
cross = { "time.dt" = [4e-5] }
[[group]]
name = "dt"
kind = "stability"
end = 0.01
tolerance = 0.2
)";
  const SweepOutcome o = run(sweep, 2);
  EXPECT_EQ(o.total, 3u);
  EXPECT_EQ(o.failed, 0u) << log_.str();
  const Table t = read_table(out() / "summary.csv");
  ASSERT_EQ(t.rows.size(), 3u);
  EXPECT_EQ(t.row("runs/000-time.dt=4e-5").at("kind"), "run");
  EXPECT_EQ(t.row("runs/000-time.dt=4e-5").at("reference_run"), "reference/shared");
  EXPECT_FALSE(t.row("runs/000-time.dt=4e-5").at("error_energy").empty());
  EXPECT_EQ(t.row("runs/000-time.dt=4e-5").at("stable_dt"), "");
  const auto& s = t.row("dt/000");
  EXPECT_EQ(s.at("kind"), "stability");
  EXPECT_EQ(s.at("reference_run"), "");
  EXPECT_EQ(s.at("error_energy"), "");
  EXPECT_EQ(s.at("energy_error_max"), "");
  EXPECT_EQ(s.at("outcome"), "bracketed");
  EXPECT_EQ(std::stod(s.at("stable_dt")),
            read_json_file(out() / "runs/dt/000/stability.json").at("largest_stable_dt").get<double>());
}

// `ricochet stability` exits 5 when no trial up to the cap is unstable (the implicit scheme):
// a finished search, status ok, with no unstable step and no reason.
TEST_F(SweepStabilityTest, NoUnstableStepUpToTheCapIsAFinishedSearch) {
  const SweepOutcome o = run(R"(base = "case.toml"
[[group]]
name = "dt"
kind = "stability"
set = { scheme = "implicit" }
end = 0.02
)", 1);
  EXPECT_EQ(o.ok, 1u) << log_.str();
  const Table t = read_table(out() / "summary.csv");
  ASSERT_EQ(t.rows.size(), 1u);
  const auto& r = t.row("dt/000");
  EXPECT_EQ(r.at("status"), "ok");
  EXPECT_EQ(r.at("outcome"), "no_unstable_up_to_cap");
  EXPECT_EQ(r.at("converged"), "false");
  EXPECT_EQ(r.at("unstable_dt"), "");
  EXPECT_EQ(r.at("unstable_reason"), "");
  // The cap is the trials' time.end: one step of the whole run, and stable.
  EXPECT_EQ(std::stod(r.at("stable_dt")), 0.02);
  EXPECT_EQ(r.at("end_time"), "0.02");
  EXPECT_NEAR(std::stod(r.at("stable_over_estimate")), 0.02 / std::stod(r.at("estimate_dt")), 1e-12);
}

// A search that cannot run (its mesh file is missing: the case passes validation and the
// command fails when it builds the mesh) is a failed row with the command's reason.
TEST_F(SweepStabilityTest, AFailedSearchIsAFailedRow) {
  std::string c = kCase;
  c += "[meshes.bad]\nfile = \"missing.msh\"\n";
  write("case.toml", c);
  const SweepOutcome o = run(R"(base = "case.toml"
[[group]]
name = "dt"
kind = "stability"
cross = { mesh = ["bad"] }
)", 1);
  EXPECT_EQ(o.failed, 1u);
  const Table t = read_table(out() / "summary.csv");
  ASSERT_EQ(t.rows.size(), 1u) << text_of(out() / "summary.csv");
  const auto& r = t.row("dt/000-mesh=bad");
  EXPECT_EQ(r.at("kind"), "stability");
  EXPECT_EQ(r.at("status"), "failed");
  EXPECT_NE(r.at("reason").find("exit "), std::string::npos) << r.at("reason");
  EXPECT_EQ(r.at("stable_dt"), "");
}

TEST_F(SweepStabilityTest, RejectsBadGroups) {
  const std::string head = "base = \"case.toml\"\n[[group]]\nname = \"g\"\n";
  expect_rejected(head + "kind = \"search\"\n", {":4: group[0].kind", "\"search\"", "allowed: \"run\", \"stability\""});
  expect_rejected(head + "kind = \"stability\"\nreference = { \"time.dt\" = 1e-6 }\n",
                  {"group[0].reference", "a stability group", "remove `reference`"});
  expect_rejected(head + "kind = \"stability\"\nreference = false\n", {"group[0].reference", "a stability group"});
  expect_rejected(head + "kind = \"stability\"\ntolerance = 0\n", {":5: group[0].tolerance", "in (0, 10]", "got 0"});
  expect_rejected(head + "kind = \"stability\"\ntolerance = \"1%\"\n", {"group[0].tolerance", "a string"});
  expect_rejected(head + "kind = \"stability\"\nmax_runs = 0\n", {"group[0].max_runs", "[1, 10000]", "got 0"});
  expect_rejected(head + "kind = \"stability\"\nmax_runs = 2.5\n", {"group[0].max_runs", "an integer"});
  expect_rejected(head + "kind = \"stability\"\nend = -1.0\n", {"group[0].end", "> 0"});
  expect_rejected(head + "kind = \"stability\"\nenergy_bound = inf\n", {"group[0].energy_bound", "> 0", "got inf"});
  expect_rejected(head + "kind = \"stability\"\nerror_probe = \"P\"\n", {"group[0].error_probe", "stability group"});
  expect_rejected(head + "kind = \"stability\"\ntolerence = 0.1\n", {"group[0]", "tolerence"});
  expect_rejected(head + "tolerance = 0.1\n", {"group[0].tolerance", "kind = \"stability\""});
  // A shared [reference] that only stability groups would face has nothing to compare.
  expect_rejected("base = \"case.toml\"\n[reference]\nset = { \"time.dt\" = 1e-6 }\n[[group]]\nkind = \"stability\"\n",
                  {"reference", "no group is compared with it", "kind = \"stability\""});
  // Nothing was written.
  EXPECT_FALSE(fs::exists(out()));
}

}  // namespace
