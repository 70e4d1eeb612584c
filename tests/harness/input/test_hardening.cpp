// Values that pass each key's own validation but are extreme: the run they plan (steps, history
// rows, memory, the automatic step against time.end) is checked before anything is built or
// written, with one line naming the keys and exit status 2 (docs/reliability.md). Each case
// here crashed, hung or exhausted memory before these checks; a hang fails through the
// `timeout` every command runs under. Also: integers beyond what a double holds, one-line
// messages, and the history schedule made step by step.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "harness/input/case_setup.hpp"
#include "harness/input/input_error.hpp"
#include "harness/input/run_plan.hpp"
#include "harness/outputs/csv_reader.hpp"
#include "tests/support/run_program.hpp"
#include "tests/support/temp_dir.hpp"

namespace fs = std::filesystem;

namespace {

using Outcome = ricochet::test_support::ProgramOutcome;

// `ricochet ARGS` under a 120 s timeout (exit 124 if it hangs). RICOCHET_UNDER_TEST, if set,
// names another build of the program to check (e.g. an older one, to see these tests fail).
Outcome ricochet(const std::string& args) {
  const char* other = std::getenv("RICOCHET_UNDER_TEST");
  const std::string binary = other && *other ? other : RICOCHET_BINARY;
  Outcome o = ricochet::test_support::run_shell("timeout 120 " + binary + " " + args + " 2>&1");
  if (!WIFEXITED(o.wait_status)) o.status = 128 + WTERMSIG(o.wait_status);
  return o;
}

const std::string kCantilever = std::string(RICOCHET_SOURCE_DIR) + "/cases/examples/cantilever_gravity.toml";

class Hardening : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = ricochet::test_support::fresh_test_dir("ricochet_hardening_");
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string out() const { return (dir_ / "out").string(); }

  // `ricochet run FILE --set ...` must be rejected: exit 2, one line naming the file and each
  // of `names`, no output folder.
  void expect_rejected(const std::string& file, const std::string& sets, const std::vector<std::string>& names) {
    const Outcome o = ricochet("run " + file + " " + sets + " --out " + out() + " -q");
    EXPECT_EQ(o.status, 2) << sets << ": " << o.output;
    EXPECT_EQ(std::count(o.output.begin(), o.output.end(), '\n'), 1) << o.output;
    EXPECT_NE(o.output.find(file), std::string::npos) << "names the file: " << o.output;
    for (const std::string& n : names) EXPECT_NE(o.output.find(n), std::string::npos) << n << " in: " << o.output;
    EXPECT_FALSE(fs::exists(out())) << "nothing may be written on bad input";
  }
  std::string write(const std::string& name, const std::string& text) {
    return ricochet::test_support::write_text(dir_ / name, text);
  }

  fs::path dir_;
};

// The automatic step of an extreme material or mesh: far too many steps (segfault before: the
// step count overflowed its conversion to long), or more than time.end (an endless loop).
TEST_F(Hardening, ExtremeMaterialsAndMeshesAreRejectedByTheirPlan) {
  expect_rejected(kCantilever, "--set 'bodies[0].material.density=1e-300'", {"limits.max_steps", "time.dt = \"auto\" (", "of bodies[0]"});
  expect_rejected(kCantilever, "--set 'bodies[0].material.young=1e300'", {"time.dt: \"auto\" gives 0 s", "bodies[0]"});
  expect_rejected(kCantilever, "--set 'bodies[0].material.young=1e-9'", {"time.dt: \"auto\" gives", "more than time.end"});
  expect_rejected(kCantilever, "--set 'bodies[0].material.density=1e15'", {"time.dt: \"auto\" gives", "more than time.end"});
  expect_rejected(kCantilever, "--set meshes.beam.width=1e300", {"meshes.beam"});
  expect_rejected(kCantilever, "--set meshes.beam.width=1e-300", {"limits.max_steps", "set by cell", "of bodies[0]"});
  expect_rejected(kCantilever, "--set meshes.beam.width=1e-300 --set meshes.beam.height=1e-300", {"meshes.beam: the mesh spans 1e-300 m"});
  expect_rejected(kCantilever, "--set meshes.beam.scale=1e300", {"meshes.beam.scale"});
  expect_rejected(kCantilever,
                  "--set 'bodies[0].material={model=\"blatz_ko\", shear_modulus=4e305, density=1000.0}'",
                  {"bodies[0]", "time.dt: \"auto\""});
}

// Fixed steps and ends that plan 1e12 steps and more (a segfault or a bad_alloc before).
TEST_F(Hardening, StepCountsBeyondTheCeilingAreRejected) {
  expect_rejected(kCantilever, "--set time.dt=1e-300", {"limits.max_steps", "time.end", "time.dt = 1e-300 s"});
  expect_rejected(kCantilever, "--set time.end=10 --set time.dt=1e-18", {"limits.max_steps"});
  expect_rejected(kCantilever, "--set time.end=1e300 --set time.dt=1e-6", {"limits.max_steps"});
  expect_rejected(kCantilever, "--set time.end=1e9", {"limits.max_steps"});
  expect_rejected(kCantilever, "--set time.end=1 --set time.dt=1e-12", {"limits.max_steps"});
  expect_rejected(kCantilever, "--set time.end=1e-12", {"time.dt: \"auto\" gives", "time.end"});
  // The ceiling is a key: raised, the same plan passes it (and fails on memory or rows only
  // if those are exceeded: here 1e9 steps sampled 1000 times is within them).
  const Outcome o = ricochet("run " + kCantilever + " --set time.end=1 --set time.dt=1e-9 --set limits.max_steps=1e8 -q --out " + out());
  EXPECT_EQ(o.status, 2) << o.output;
  EXPECT_NE(o.output.find("1e+09 steps, more than limits.max_steps = 1e+08"), std::string::npos) << o.output;
}

// History rows: every step of a long run (2.1 GB before), or an interval far below the step
// (an endless loop before: the sample list was built by k x interval).
TEST_F(Hardening, HistoryRowsAreBoundedAndNeverListedUpFront) {
  expect_rejected(kCantilever, "--set output.interval=0 --set time.dt=1e-7", {"limits.max_history_rows", "output.interval"});
  const Outcome o = ricochet("run " + kCantilever + " --set output.interval=1e-15 --set 'output.fields=[]' -q --out " + out());
  ASSERT_EQ(o.status, 0) << o.output;
  // Sampled at every step: the steps plus the initial row.
  const ricochet::CsvTable h = ricochet::read_csv(fs::path(out()) / "history.csv");
  std::ifstream summary(fs::path(out()) / "summary.json");
  const std::string text((std::istreambuf_iterator<char>(summary)), std::istreambuf_iterator<char>());
  const auto at = text.find("\"steps\": ");
  ASSERT_NE(at, std::string::npos);
  EXPECT_EQ(static_cast<long>(h.rows.size()), std::stol(text.substr(at + 9)) + 1);
}

// A 9999 x 9999 mesh is within each key's range (nx, ny <= 1e5) but not this machine's memory
// (bad_alloc after 30 s at 7 GB before): rejected before it is built, naming the mesh.
TEST_F(Hardening, MeshesBeyondTheMemoryAreRejectedBeforeTheyAreBuilt) {
  // The 9999 x 9999 mesh (an estimated 143 GiB) on machines of less than 179 GiB,
  // whose default ceiling is 80 % of their memory; 99999 x 99999 (14 TiB) on any machine.
  if (ricochet::machine_memory_bytes() < 179.0 * 1024 * 1024 * 1024)
    expect_rejected(kCantilever, "--set meshes.beam.nx=9999 --set meshes.beam.ny=9999",
                    {"meshes.beam", "limits.max_memory", "GiB"});
  expect_rejected(kCantilever, "--set meshes.beam.nx=99999 --set meshes.beam.ny=99999",
                  {"meshes.beam", "limits.max_memory", "GiB"});
  // The limit is a key: a mesh of 1e4 cells does not fit in 1e-3 GiB.
  expect_rejected(kCantilever, "--set limits.max_memory=0.001", {"limits.max_memory = 0.001 GiB"});
}

// toml++ gives no double for an integer beyond 2^53; it was dereferenced unchecked and read
// as garbage (6.95e-310).
TEST_F(Hardening, IntegersBeyondADoubleAreRejectedWithTheirKey) {
  expect_rejected(kCantilever, "--set time.end=9223372036854775807", {"time.end", "9223372036854775807", "2^53"});
  expect_rejected(kCantilever, "--set 'meshes.beam.origin=[9007199254740993, 0]'", {"meshes.beam.origin", "2^53"});
  expect_rejected(kCantilever, "--set 'output.fields=[0.0, 9007199254740993]'", {"output.fields", "2^53"});
  // 2^53 itself is a double: accepted as a number (and here rejected for its value alone).
  const Outcome o = ricochet("run " + kCantilever + " --set time.end=9007199254740992 -q --out " + out());
  EXPECT_EQ(o.status, 2);
  EXPECT_NE(o.output.find("limits.max_steps"), std::string::npos) << o.output;
}

TEST_F(Hardening, GateLimitsBeyondADoubleAreRejected) {
  const std::string csv = write("summary.csv", "kind,status,x\nrun,ok,0.01\n");
  const std::string gates = write("gates.toml", "[[gate]]\nname = \"a\"\nkind = \"max\"\ncolumn = \"x\"\nlimit = 9223372036854775807\n");
  const Outcome o = ricochet("check " + csv + " " + gates);
  EXPECT_EQ(o.status, 2) << o.output;  // was exit 4, "FAIL ... 0.01 > 5.22e-310"
  EXPECT_NE(o.output.find("gate[0].limit"), std::string::npos) << o.output;
  EXPECT_EQ(std::count(o.output.begin(), o.output.end(), '\n'), 1) << o.output;
}

// A misspelt required key is reported at the misspelling.
TEST_F(Hardening, AGateTypoIsNamedAtTheTypo) {
  const std::string csv = write("summary.csv", "kind,status,x\nrun,ok,0.01\n");
  const std::string gates = write("gates.toml", "[[gate]]\nname = \"a\"\nkind = \"max\"\ncolumn = \"x\"\nlimt = 0.1\n");
  const Outcome o = ricochet("check " + csv + " " + gates);
  EXPECT_EQ(o.status, 2) << o.output;
  EXPECT_NE(o.output.find(":5: gate[0].limt: unknown key (did you mean \"limit\"?"), std::string::npos) << o.output;
}

// A number key with no bounds said "expected a number a finite number".
TEST_F(Hardening, UnboundedNumberKeysSayWhatTheyExpectOnce) {
  const std::string csv = write("summary.csv", "kind,status,x\nrun,ok,0.01\n");
  const std::string gates = write("gates.toml", "[[gate]]\nname = \"a\"\nkind = \"max\"\ncolumn = \"x\"\nlimit = \"big\"\n");
  const Outcome o = ricochet("check " + csv + " " + gates);
  EXPECT_EQ(o.status, 2) << o.output;
  EXPECT_NE(o.output.find("gate[0].limit: expected a finite number; got a string"), std::string::npos) << o.output;
}

// A TOML syntax error quoting a line break printed its message over two lines.
TEST_F(Hardening, SyntaxErrorsAreOneLine) {
  for (const std::string bad : {"x = tr\n", "x = in\n", "x = \"a\tb\n"}) {
    const std::string file = write("case.toml", "name = \"n\"\n" + bad);
    const Outcome o = ricochet("run " + file + " --out " + out());
    EXPECT_EQ(o.status, 2) << o.output;
    EXPECT_EQ(std::count(o.output.begin(), o.output.end(), '\n'), 1) << o.output;
    EXPECT_NE(o.output.find(file + ":2: TOML syntax error"), std::string::npos) << o.output;
  }
}

// `ricochet stability --end 1e-300` looped forever building the sample list of a trial whose
// step is the whole run; it now finishes (the search stops at the cap, a one-step run).
TEST_F(Hardening, StabilityWithATinyEndFinishes) {
  const Outcome o = ricochet("stability " + kCantilever + " --end 1e-300 -q");
  EXPECT_TRUE(o.status == 0 || o.status == 5) << o.output;
}

TEST(RunPlan, HistoryRowsAreBoundedWithoutOverflow) {
  EXPECT_EQ(ricochet::planned_history_rows(100.0, 1e-3, 0.0), 101.0);        // every step
  EXPECT_EQ(ricochet::planned_history_rows(100.0, 1e-3, 1e-15), 101.0);      // below one step
  EXPECT_EQ(ricochet::planned_history_rows(100.0, 1e-3, 1e-2), 12.0);        // 10 intervals, the first and last rows
  EXPECT_EQ(ricochet::planned_history_rows(1e15, 1e-6, 1e300), 2.0);         // the first and the last
  EXPECT_EQ(ricochet::machine_memory_bytes() > 0.0, true);
}

// The history's schedule, made one sample at a time, is the list it replaced: steps
// round(k x interval / dt) for k = 0, 1, ... up to the planned step, without repeats, and the
// planned step. Checked on the times of the history rows of short runs.
std::vector<long> listed_schedule(double interval, double dt, long planned) {
  std::vector<long> steps;
  if (interval <= 0.0) {
    for (long n = 0; n <= planned; ++n) steps.push_back(n);
    return steps;
  }
  for (long k = 0;; ++k) {
    const long n = std::lround(static_cast<double>(k) * interval / dt);
    if (n > planned) break;
    if (steps.empty() || n > steps.back()) steps.push_back(n);
  }
  if (steps.back() != planned) steps.push_back(planned);
  return steps;
}

TEST(RunPlan, TheScheduleMadeStepByStepIsTheListedOne) {
  const std::string file = kCantilever;
  const ricochet::CaseSpec base = ricochet::read_case(file, {"meshes.beam.nx=4", "meshes.beam.ny=1", "output.fields=[]"});
  const double dt = 1e-4;
  struct Plan {
    double end, interval;
  };
  // Intervals below, at, just above and well above the step; ends on and off the grid; an
  // interval that does not divide the end; intervals within an ulp of dt.
  for (const Plan p : {Plan{0.01, 0.0}, Plan{0.01, 3e-6}, Plan{0.01, 1e-4}, Plan{0.01, 1.5e-4}, Plan{0.0103, 7e-4},
                       Plan{0.01, 2.5e-4}, Plan{0.01, 3.3e-4}, Plan{0.00999, 1e-3}, Plan{0.01, 0.02},
                       Plan{0.01, std::nextafter(1e-4, 1.0)}, Plan{0.01, std::nextafter(std::nextafter(1e-4, 1.0), 1.0)},
                       Plan{0.01, 1.0000000001e-4}}) {
    ricochet::CaseSpec c = base;
    c.dt = dt;
    c.end_time = p.end;
    c.sample_interval = p.interval;
    const ricochet::PreparedCase pc = ricochet::prepare_case(c);
    const ricochet::RunResult r = ricochet::run_case(pc);
    ASSERT_EQ(r.status, ricochet::RunStatus::ok) << r.reason;
    const std::vector<long> want = listed_schedule(p.interval, dt, r.planned_steps);
    const std::size_t t = r.history.column("time");
    ASSERT_EQ(r.history.rows(), want.size()) << "end " << p.end << " interval " << p.interval;
    for (std::size_t i = 0; i < want.size(); ++i)
      // The row's time is t_n = n dt accumulated step by step: within a few ulps of n dt.
      EXPECT_NEAR(r.history.at(i, t), static_cast<double>(want[i]) * dt, 1e-12) << "row " << i << " interval " << p.interval;
  }
}

}  // namespace

namespace {

// The solver's own guard, below the harness's checks: a run planned beyond 2^53 steps is an
// exception, not an overflowing conversion (a segfault before).
TEST(RunPlan, TheSolverRefusesAStepCountBeyondADouble) {
  const ricochet::CaseSpec c = ricochet::read_case(kCantilever, {"meshes.beam.nx=4", "meshes.beam.ny=1", "output.fields=[]"});
  ricochet::PreparedCase pc = ricochet::prepare_case(c);
  for (const double dt : {1e-300, 1e-17}) {  // 4e299 and 4e16 steps over time.end = 0.4 s
    pc.settings.dt = dt;
    EXPECT_THROW(ricochet::run_case(pc), std::invalid_argument) << dt;
  }
  EXPECT_THROW(ricochet::check_run_plan(pc), ricochet::InputError);
}

}  // namespace
