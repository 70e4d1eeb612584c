// Sweeps (docs/sweeps.md): expansion of a sweep file into runs and their overrides, validation
// with one-line errors and nothing written, summary.csv, the JSON reader, and the execution of
// small sweeps of a tiny case with the real `ricochet` program: statuses, failures, resume,
// repeats, errors against a group's reference runs, and errors against a shared [reference]
// with its check run (the oblique plate, shortened); a sweep killed by SIGKILL and resumed at
// once (no orphaned run, one writer per run folder), the run folders' locks, and summary.json
// files that a resumed sweep must not trust.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <omp.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <toml++/toml.h>

#include "harness/cli/cli.hpp"
#include "harness/input/input_error.hpp"
#include "harness/outputs/json_io.hpp"
#include "harness/sweeps/reference_errors.hpp"
#include "harness/sweeps/sweep.hpp"
#include "harness/sweeps/sweep_spec.hpp"
#include "tests/support/run_program.hpp"
#include "tests/support/small_cases.hpp"
#include "tests/support/sweep_checks.hpp"
#include "tests/support/summary_table.hpp"
#include "tests/support/temp_dir.hpp"

namespace fs = std::filesystem;
using namespace ricochet;

namespace {

// A 4 x 2-cell plate held at its left edge and set moving upwards: it vibrates, so its probe
// and energy histories depend on the time step. `bad` names a mesh file that does not exist:
// the case passes validation and the run fails when it builds the mesh.
const std::string kCase = test_support::tiny_plate_case();

class SweepTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test_support::fresh_test_dir("ricochet_sweep_");
    write("case.toml", kCase);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& text) const {
    return test_support::write_text(dir_ / name, text);
  }
  fs::path out() const { return dir_ / "out"; }

  SweepOutcome run(const std::string& sweep_text, int jobs = 1, int repeat = 1, bool force = false,
                   const std::string& program = RICOCHET_BINARY, std::optional<int> threads = std::nullopt) {
    const SweepSpec spec = read_sweep(write("sweep.toml", sweep_text));
    SweepOptions o;
    o.out_dir = out();
    o.jobs = jobs;
    o.repeat = repeat;
    o.force = force;
    o.threads = threads;
    o.executable = program;
    o.log = &log_;
    return run_sweep(spec, expand(spec), o);
  }

  // Expects read_sweep + expand + check_runs to reject the sweep, naming each of `parts`.
  void expect_rejected(const std::string& sweep_text, const std::vector<std::string>& parts) {
    test_support::expect_sweep_rejected(write("sweep.toml", sweep_text), sweep_text, parts);
  }

  fs::path dir_;
  std::ostringstream log_;
};

std::vector<std::string> ids(const std::vector<SweepRun>& runs) {
  std::vector<std::string> v;
  for (const auto& r : runs) v.push_back(r.id);
  return v;
}

using Table = test_support::SummaryTable;
Table read_table(const fs::path& p) { return test_support::read_summary_table(p); }

bool has_column(const Table& t, const std::string& c) {
  return std::find(t.header.begin(), t.header.end(), c) != t.header.end();
}

double num(const std::map<std::string, std::string>& row, const std::string& col) {
  const std::string& s = row.at(col);
  EXPECT_FALSE(s.empty()) << col;
  return std::stod(s);
}

// Modification time in nanoseconds.
long long mtime_ns(const fs::path& p) {
  struct stat st {};
  if (stat(p.c_str(), &st) != 0) return -1;
  return static_cast<long long>(st.st_mtim.tv_sec) * 1000000000LL + st.st_mtim.tv_nsec;
}

}  // namespace

// ---- expansion -----------------------------------------------------------------------------------

TEST_F(SweepTest, CartesianExpansionInWrittenKeyOrder) {
  const SweepSpec spec = read_sweep(write("s.toml", R"(
base = "case.toml"
[[group]]
name = "g"
cross = { "time.dt" = [1e-5, 2e-5, 3e-5], mesh = ["m", "bad"] }
)"));
  EXPECT_EQ(spec.name, "s");
  EXPECT_EQ(spec.base, (dir_ / "case.toml").lexically_normal());
  const auto runs = expand(spec);
  // The first key written (time.dt) varies slowest, although "mesh" sorts first.
  EXPECT_EQ(ids(runs), (std::vector<std::string>{"g/000-time.dt=1e-5_mesh=m", "g/001-time.dt=1e-5_mesh=bad",
                                                 "g/002-time.dt=2e-5_mesh=m", "g/003-time.dt=2e-5_mesh=bad",
                                                 "g/004-time.dt=3e-5_mesh=m", "g/005-time.dt=3e-5_mesh=bad"}));
  EXPECT_EQ(runs[3].set_args(), (std::vector<std::string>{"time.dt=2e-5", "mesh=\"bad\""}));
  EXPECT_EQ(runs[3].folder(), fs::path("runs/g/003-time.dt=2e-5_mesh=bad"));
  EXPECT_EQ(runs[3].group, "g");
  EXPECT_FALSE(runs[3].is_reference);
  EXPECT_EQ(runs[3].swept, (std::vector<std::string>{"time.dt", "mesh"}));
}

TEST_F(SweepTest, GroupsAreUnitedInOrderAndSetPrecedenceIsSweepGroupCross) {
  const SweepSpec spec = read_sweep(write("s.toml", R"(
name = "prec"
base = "case.toml"
set = { "time.end" = 1e-3, "output.interval" = 1e-4 }
[[group]]
name = "a"
set = { "time.end" = 2e-3 }
cross = { bodies.0.element = ["q4", "q4_hourglass"] }
[[group]]
name = "b"
set = { "time.end" = 2e-3 }
cross = { time = { end = [3e-3] } }
[[group]]
)"));
  const auto runs = expand(spec);
  ASSERT_EQ(runs.size(), 4u);
  EXPECT_EQ(ids(runs), (std::vector<std::string>{"a/000-bodies.0.element=q4", "a/001-bodies.0.element=q4_hourglass",
                                                 "b/000-time.end=0.003", "group2/000"}));
  // Group set beats sweep set; a key set twice is passed once, in the place of the later one.
  EXPECT_EQ(runs[1].set_args(),
            (std::vector<std::string>{"output.interval=1e-4", "time.end=0.002", "bodies[0].element=\"q4_hourglass\""}));
  // Crossed values beat both (a nested table is the same as a dotted key).
  EXPECT_EQ(runs[2].set_args(), (std::vector<std::string>{"output.interval=1e-4", "time.end=0.003"}));
  // A group without `cross` is one run with the sweep's set.
  EXPECT_EQ(runs[3].set_args(), (std::vector<std::string>{"time.end=0.001", "output.interval=1e-4"}));
  check_runs(spec, runs);  // all valid for the case
}

TEST_F(SweepTest, ReferenceRunsOnePerCombinationOfTheOtherKeys) {
  const SweepSpec spec = read_sweep(write("s.toml", R"(
base = "case.toml"
[[group]]
name = "acc"
cross = { "bodies[0].element" = ["q4", "q4_hourglass"], "time.dt" = [4e-5, 2e-5] }
reference = { "time.dt" = 5e-6 }
)"));
  const auto runs = expand(spec);
  ASSERT_EQ(runs.size(), 6u);
  EXPECT_TRUE(runs[0].is_reference);
  EXPECT_TRUE(runs[1].is_reference);
  EXPECT_EQ(runs[0].id, "acc/reference-bodies.0.element=q4_time.dt=5e-6");
  EXPECT_EQ(runs[1].id, "acc/reference-bodies.0.element=q4_hourglass_time.dt=5e-6");
  EXPECT_EQ(runs[0].set_args(), (std::vector<std::string>{"bodies[0].element=\"q4\"", "time.dt=5e-6"}));
  EXPECT_EQ(runs[2].id, "acc/000-bodies.0.element=q4_time.dt=4e-5");
  EXPECT_EQ(runs[2].reference_id, runs[0].id);
  EXPECT_EQ(runs[3].reference_id, runs[0].id);
  EXPECT_EQ(runs[4].reference_id, runs[1].id);
  EXPECT_EQ(runs[5].reference_id, runs[1].id);
  EXPECT_EQ(runs[5].error_probe, "P");
  check_runs(spec, runs);
}

// A second case beside kCase, in a subfolder: its mesh is named "m2", so a run that crosses
// mesh = "m2" is only valid on it.
std::string other_case() {
  std::string text = kCase;
  text.replace(text.find("name = \"tiny\""), 13, "name = \"other\"");
  text.replace(text.find("mesh = \"m\""), 10, "mesh = \"m2\"");
  text.replace(text.find("[meshes.m]"), 10, "[meshes.m2]");
  return text;
}

TEST_F(SweepTest, GroupBaseIsUsedForItsRunsAndTheSweepBaseForTheOthers) {
  fs::create_directories(dir_ / "sub");
  write("sub/other.toml", other_case());
  const SweepSpec spec = read_sweep(write("s.toml", R"(
base = "case.toml"
[[group]]
name = "top"
cross = { "time.dt" = [1e-5, 2e-5] }
[[group]]
name = "own"
base = "sub/other.toml"
cross = { mesh = ["m2"] }
reference = { "time.dt" = 5e-6 }
)"));
  EXPECT_EQ(spec.base, (dir_ / "case.toml").lexically_normal());
  ASSERT_EQ(spec.groups.size(), 2u);
  EXPECT_TRUE(spec.groups[0].base.empty());
  EXPECT_EQ(spec.groups[1].base, (dir_ / "sub/other.toml").lexically_normal());
  const auto runs = expand(spec);
  EXPECT_EQ(ids(runs), (std::vector<std::string>{"top/000-time.dt=1e-5", "top/001-time.dt=2e-5",
                                                 "own/reference-mesh=m2_time.dt=5e-6", "own/000-mesh=m2"}));
  for (std::size_t i = 0; i < runs.size(); ++i)
    EXPECT_EQ(runs[i].base, i < 2 ? spec.base : spec.groups[1].base) << runs[i].id;  // reference runs too
  check_runs(spec, runs);  // mesh "m2" exists only in other.toml: each run is read from its own base

  // Without a top-level base, when every group has its own.
  const SweepSpec own = read_sweep(write("s.toml", "[[group]]\nbase = \"sub/other.toml\"\ncross = { mesh = [\"m2\"] }\n"));
  EXPECT_TRUE(own.base.empty());
  const auto own_runs = expand(own);
  ASSERT_EQ(own_runs.size(), 1u);
  EXPECT_EQ(own_runs[0].base, (dir_ / "sub/other.toml").lexically_normal());
  check_runs(own, own_runs);
}

TEST(SweepValues, TomlTextRoundTripsAndDisplays) {
  const toml::table t = toml::parse(R"(
a = 1e-5
b = 2.0
c = 0.1
d = "say \"hi\"\n"
e = [0.0, -9.81]
f = 7
g = true
h = { plate = 0.1 }
i = 1e300
)");
  const std::map<std::string, std::string> expected = {
      {"a", "1e-5"}, {"b", "2.0"}, {"c", "0.1"}, {"d", "\"say \\\"hi\\\"\\n\""}, {"e", "[0.0, -9.81]"},
      {"f", "7"},    {"g", "true"}, {"h", "{ plate = 0.1 }"}, {"i", "1e300"}};
  for (const auto& [k, text] : expected) {
    const toml::node& v = *t.get(k);
    EXPECT_EQ(toml_text(v), text) << k;
    const toml::table back = toml::parse("v = " + toml_text(v));
    EXPECT_EQ(toml_text(*back.get("v")), text) << k;
    if (v.is_floating_point()) {
      EXPECT_EQ(*back.get("v")->value<double>(), *v.value<double>()) << k;
    }
  }
  EXPECT_EQ(display_text(*t.get("d")), "say \"hi\"\n");
  EXPECT_EQ(canonical_key("bodies.0.material.young"), "bodies[0].material.young");
  EXPECT_EQ(slug({{"obstacles[0].friction", "0.1", "0.1", ""}, {"gravity", "[0.0, -9.81]", "[0.0, -9.81]", ""},
                  {"description", "\"a b/c\"", "a b/c", ""}}),
            "obstacles.0.friction=0.1_gravity=0.0_-9.81_description=a_b_c");
}

// ---- validation -----------------------------------------------------------------------------------

TEST_F(SweepTest, BadSweepFilesAreRejectedWithFileAndKey) {
  const std::string g = "\n[[group]]\ncross = { mesh = [\"m\"] }\n";
  expect_rejected("base = \"case.toml\"\nbogus = 1" + g, {"sweep.toml:2", "bogus", "unknown key", "allowed"});
  expect_rejected("base = \"case.toml\"\n[[group]]\ncrosss = { mesh = [\"m\"] }\n", {":3", "group[0].crosss", "unknown key"});
  expect_rejected("base = \"case.toml\"\n[[group]]\ncross = { mesh = [] }\n", {":3", "group[0].cross.mesh", "empty list"});
  expect_rejected("base = \"case.toml\"\n[[group]]\ncross = { mesh = \"m\" }\n", {"group[0].cross.mesh", "list"});
  expect_rejected("base = \"nowhere.toml\"" + g, {":1", "base", "nowhere.toml", "not found"});
  expect_rejected("name = \"x\"" + g, {"base", "missing"});
  expect_rejected("base = \"case.toml\"\n", {"group", "missing"});
  expect_rejected("base = \"case.toml\"\n[[group]]\nname = \"a\"\n[[group]]\nname = \"a\"\n", {":5", "group[1].name", "already"});
  expect_rejected("base = \"case.toml\"\n[[group]]\nname = \"../up\"\n", {"group[0].name", "allowed"});
  expect_rejected("base = \"case.toml\"\n[[group]]\ncross = { \"time.dt\" = [1e-5, 1e-5] }\n", {"time.dt", "twice"});
  expect_rejected("base = \"case.toml\"\n[[group]]\ncross = { time.dt = [1e-5], \"time.dt\" = [2e-5] }\n", {"time.dt", "twice"});
  expect_rejected("base = \"case.toml\"\nset = { when = 1979-05-27 }" + g, {"set.when", "date"});
  expect_rejected("base = \"case.toml\" oops" + g, {":1", "TOML syntax error"});
  // Keys and values the case rejects: found before anything runs, naming the sweep file's line.
  expect_rejected("base = \"case.toml\"\n[[group]]\ncross = { \"time.dtt\" = [1e-5] }\n",
                  {"sweep.toml:3", "group[0].cross.time.dtt", "time.dtt: unknown key", "case.toml"});
  expect_rejected("base = \"case.toml\"\n[[group]]\ncross = { mesh = [\"m\", \"q\"] }\n",
                  {"run group0/001-mesh=q", "no mesh named \"q\""});
  expect_rejected("base = \"case.toml\"\n[[group]]\nset = { \"time.dt\" = -1.0 }\n", {"set.time.dt", "> 0"});
  expect_rejected("base = \"case.toml\"\n[[group]]\ncross = { \"time.dt\" = [1e-5] }\nreference = { \"time.dt\" = 1e-6 }\n"
                  "error_probe = \"Q\"\n",
                  {"error_probe", "no probe \"Q\"", "P"});
  expect_rejected("base = \"case.toml\"\n[[group]]\nerror_probe = \"P\"\n", {"error_probe", "reference"});
}

TEST_F(SweepTest, BadGroupBasesAreRejectedNamingTheGroup) {
  expect_rejected("base = \"case.toml\"\n[[group]]\n[[group]]\nbase = \"nowhere.toml\"\n",
                  {"sweep.toml:4: group[1].base: case file '", "nowhere.toml' not found"});
  expect_rejected("[[group]]\nbase = \"case.toml\"\n[[group]]\nname = \"lost\"\n",
                  {"sweep.toml:3: group[1].base", "missing", "top-level `base`"});
  expect_rejected("[[group]]\nbase = 3\n", {"sweep.toml:2: group[0].base", "string"});
  // The group's base, not the sweep's, is the case a run's override is checked against.
  write("other.toml", other_case());
  expect_rejected("base = \"other.toml\"\n[[group]]\nbase = \"case.toml\"\ncross = { mesh = [\"m2\"] }\n",
                  {"sweep.toml:4: group[0].cross.mesh", "run group0/000-mesh=m2", "case.toml", "no mesh named \"m2\""});
}

TEST_F(SweepTest, CommandRejectsBadInputWithOneLineAndWritesNothing) {
  const std::string bad = write("bad.toml", "base = \"case.toml\"\n[[group]]\ncross = { \"time.dt\" = [1e-5, -1.0] }\n");
  const std::string good = write("good.toml", "base = \"case.toml\"\n[[group]]\ncross = { \"time.dt\" = [1e-5] }\n");
  const std::string bad_gates = write("gates.toml", "bogus = 1\n");
  const std::vector<std::vector<std::string>> cases = {
      {bad, "--out", out().string()},
      {good, "--out", out().string(), "--jobs", "0"},
      {good, "--out", out().string(), "--repeat", "x"},
      {good, "--out", out().string(), "--bogus"},
      {(dir_ / "absent.toml").string(), "--out", out().string()},
      {"--out", out().string()},
      {good, "--out", out().string(), "--check", bad_gates},
      {write("bad_ref.toml", "base = \"case.toml\"\n[reference]\nset = { \"time.dt\" = 1e-6 }\nbogus = 1\n[[group]]\n"),
       "--out", out().string()},
      {write("no_set.toml", "base = \"case.toml\"\n[reference]\ncheck = { \"time.dt\" = 1e-6 }\n[[group]]\n"), "--out",
       out().string()},
  };
  for (const auto& args : cases) {
    ::testing::internal::CaptureStderr();
    const int status = sweep_command(args);
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(status, 2) << args[0] << ": " << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_EQ(err.rfind("ricochet: ", 0), 0u) << err;
    EXPECT_FALSE(fs::exists(out())) << "nothing may be written on bad input: " << err;
  }
}

// ---- summary table ---------------------------------------------------------------------------

TEST(SummaryTable, UnionOfColumnsPlaceholdersAndNameClashes) {
  SummaryRow ok{"g/000", "g", "run", "ok", "", {{"scheme", "explicit"}, {"time.dt", "1e-5"}}, {}, {{"repeats", "1"}}};
  ok.summary = flatten_summary(parse_json(
      R"({"case":"c","scheme":"explicit","status":"ok","diverged":null,"probes":[{"name":"P","x":0}],"final":{"time":1,"energy":2},"friction_coeff":null})"));
  SummaryRow div{"g/001", "g", "run", "diverged", "energy growth", {{"scheme", "explicit"}, {"time.dt", "1e-3"}}, {}, {}};
  div.summary = flatten_summary(parse_json(
      R"({"case":"c","scheme":"explicit","status":"diverged","diverged":{"reason":"energy growth","step":3},"probes":[],"final":{"time":0.5,"energy":9,"extra":1},"friction_coeff":null})"));
  SummaryRow failed{"g/002", "g", "run", "failed", "exit 2: ricochet: x, y", {{"scheme", "implicit"}, {"time.dt", "1e-3"}}, {}, {}};
  const std::string csv = format_summary_csv({ok, div, failed}, {{"scheme", "time.dt"}, {"repeats", "error_energy"}});
  const auto lines = test_support::csv_records(csv);
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[0], (std::vector<std::string>{"run_id", "group", "kind", "status", "reason", "scheme", "time.dt", "case",
                                                "summary.scheme", "diverged.reason", "diverged.step", "probes", "final.time",
                                                "final.energy", "final.extra", "friction_coeff", "repeats", "error_energy"}));
  EXPECT_EQ(lines[1], (std::vector<std::string>{"g/000", "g", "run", "ok", "", "explicit", "1e-5", "c", "explicit", "", "",
                                                R"([{"name":"P","x":0}])", "1", "2", "", "", "1", ""}));
  EXPECT_EQ(lines[2][9], "energy growth");
  EXPECT_EQ(lines[2][10], "3");
  EXPECT_EQ(lines[3][4], "exit 2: ricochet: x, y");
  EXPECT_EQ(lines[3][7], "");
  EXPECT_NE(csv.find("\"exit 2: ricochet: x, y\""), std::string::npos);
}

TEST(ReferenceErrors, ZeroForTheSameHistoryAndInterpolatedOtherwise) {
  HistoryTable ref{{"time", "total_energy", "P_ux", "P_uy"}, {{0, 10, 0, 0}, {1, 10, 1, 0}, {2, 12, 2, 0}}};
  const ReferenceErrors same = reference_errors(ref, ref, "P", 10.0);
  EXPECT_EQ(same.samples, 3u);
  EXPECT_EQ(*same.probe, 0.0);
  EXPECT_EQ(*same.energy, 0.0);
  // Samples at 0.5 and 1.5 (and 3, after the reference's end: skipped).
  HistoryTable run{{"time", "P_ux", "P_uy", "total_energy"}, {{0.5, 0.5, 0.3, 10}, {1.5, 1.5, -0.4, 10}, {3, 9, 9, 99}}};
  const ReferenceErrors e = reference_errors(run, ref, "P", 10.0);
  EXPECT_EQ(e.samples, 2u);
  EXPECT_DOUBLE_EQ(*e.probe, 0.4);
  EXPECT_DOUBLE_EQ(*e.energy, 0.1);  // |10 - 11| / 10 at t = 1.5
  EXPECT_FALSE(reference_errors(run, ref, "Q", 10.0).probe.has_value());
}

// ---- execution ------------------------------------------------------------------------------------

TEST_F(SweepTest, SmallSweepWritesOneRowPerRunWithSweptColumnsAndSummaryKeys) {
  const SweepOutcome o = run(R"(
name = "four"
base = "case.toml"
[[group]]
name = "g"
cross = { "time.dt" = [1e-5, 2e-5], "bodies[0].element" = ["q4", "q4_hourglass"] }
)");
  EXPECT_EQ(o.total, 4u);
  EXPECT_EQ(o.executed, 4u);
  EXPECT_EQ(o.ok, 4u);
  const Table t = read_table(out() / "summary.csv");
  ASSERT_EQ(t.rows.size(), 4u);
  ASSERT_GE(t.header.size(), 7u);
  EXPECT_EQ(std::vector<std::string>(t.header.begin(), t.header.begin() + 7),
            (std::vector<std::string>{"run_id", "group", "kind", "status", "reason", "time.dt", "bodies[0].element"}));
  for (const char* c : {"case", "overrides", "scheme", "steps", "dt", "wall_seconds", "cpu_seconds", "element_steps_per_second",
                        "contact_iterations.mean", "final.kinetic_energy", "final.momentum_y", "probes", "build.compiler",
                        "written_at", "implicit", "diverged", "friction_coeff", "repeats", "wall_seconds_min",
                        "wall_seconds_max", "error_probe_P", "error_energy", "reference_run", "reference_dt"})
    EXPECT_TRUE(has_column(t, c)) << c;
  const auto& r = t.row("g/003-time.dt=2e-5_bodies.0.element=q4_hourglass");
  EXPECT_EQ(r.at("status"), "ok");
  EXPECT_EQ(r.at("kind"), "run");
  EXPECT_EQ(r.at("time.dt"), "2e-5");
  EXPECT_EQ(r.at("bodies[0].element"), "q4_hourglass");
  EXPECT_EQ(r.at("element"), "q4_hourglass");
  EXPECT_EQ(r.at("steps"), "100");
  EXPECT_EQ(r.at("repeats"), "1");
  EXPECT_EQ(r.at("error_energy"), "");
  EXPECT_NE(r.at("overrides").find("time.dt=2e-5"), std::string::npos);
  EXPECT_EQ(t.rows[0].at("run_id"), "g/000-time.dt=1e-5_bodies.0.element=q4");  // rows in run order

  // sweep.json and each run's folder.
  const Json s = read_json_file(out() / "sweep.json");
  EXPECT_EQ(s.at("sweep").get<std::string>(), "four");
  EXPECT_EQ(s.at("runs").size(), 4u);
  EXPECT_FALSE(s.at("finished_at").is_null());
  const fs::path f = out() / "runs/g/003-time.dt=2e-5_bodies.0.element=q4_hourglass";
  for (const char* file : {"summary.json", "history.csv", "overrides.json", "stderr.txt"})
    EXPECT_TRUE(fs::exists(f / file)) << file;
  // Progress: one line per run, "[k/total] id status wall ... | elapsed ..., left ~...".
  const std::string log = log_.str();
  EXPECT_NE(log.find("[1/4] g/000-time.dt=1e-5_bodies.0.element=q4 ok wall "), std::string::npos) << log;
  EXPECT_NE(log.find("[4/4] "), std::string::npos) << log;
  EXPECT_NE(log.find(" | elapsed "), std::string::npos) << log;
  EXPECT_NE(log.find(", left ~"), std::string::npos) << log;
}

TEST_F(SweepTest, ResumeRerunsOnlyUnfinishedRuns) {
  const std::string sweep = R"(
base = "case.toml"
[[group]]
name = "g"
cross = { "time.dt" = [1e-5, 2e-5, 4e-5, 5e-5] }
)";
  ASSERT_EQ(run(sweep).executed, 4u);
  std::vector<fs::path> summaries;
  for (const auto& e : fs::directory_iterator(out() / "runs" / "g")) summaries.push_back(e.path() / "summary.json");
  std::sort(summaries.begin(), summaries.end());
  ASSERT_EQ(summaries.size(), 4u);
  std::vector<long long> before;
  for (const auto& p : summaries) before.push_back(mtime_ns(p));

  // Nothing to do.
  const SweepOutcome again = run(sweep);
  EXPECT_EQ(again.resumed, 4u);
  EXPECT_EQ(again.executed, 0u);
  EXPECT_EQ(read_table(out() / "summary.csv").rows.size(), 4u);

  // An interrupted run (no summary.json) is the only one run again.
  fs::remove(summaries[2]);
  const SweepOutcome resumed = run(sweep);
  EXPECT_EQ(resumed.resumed, 3u);
  EXPECT_EQ(resumed.executed, 1u);
  for (std::size_t i = 0; i < summaries.size(); ++i) {
    ASSERT_TRUE(fs::exists(summaries[i]));
    if (i == 2) EXPECT_GT(mtime_ns(summaries[i]), before[i]);
    else EXPECT_EQ(mtime_ns(summaries[i]), before[i]) << summaries[i];
  }
  const Table t = read_table(out() / "summary.csv");
  ASSERT_EQ(t.rows.size(), 4u);
  for (const auto& r : t.rows) EXPECT_EQ(r.at("status"), "ok");

  // Other overrides for a run: that run is done again; --force: all of them.
  const std::string changed = R"(
base = "case.toml"
[[group]]
name = "g"
cross = { "time.dt" = [1e-5, 2e-5, 4e-5, 5e-5] }
set = { "bodies[0].thickness" = 2.0 }
)";
  EXPECT_EQ(run(changed).executed, 4u);
  EXPECT_EQ(run(changed, 1, 1, true).executed, 4u);
}

// The threads of each child run (its summary.json, and the table's `threads` column): 1 by
// default, in parallel or one at a time, --threads when given, the sweep file's `threads` over
// the default. Threads are not part of a run's identity: a sweep resumed with other threads
// reuses its finished runs.
TEST_F(SweepTest, ChildRunsGetOneThreadUnlessTheSweepSaysOtherwise) {
  const std::string sweep = R"(
base = "case.toml"
[[group]]
name = "g"
cross = { "time.dt" = [1e-5, 2e-5, 4e-5] }
)";
  const std::vector<std::string> runs = {"g/000-time.dt=1e-5", "g/001-time.dt=2e-5", "g/002-time.dt=4e-5"};
  auto threads_of = [&](const std::string& id) {
    return read_json_file(out() / "runs" / id / "summary.json").at("threads").get<int>();
  };
  // `column`: summary.csv's column of the summaries' `threads` ("summary.threads" when the sweep
  // file sets `threads`, whose own column holds the value it asks for).
  auto expect_threads = [&](int expected, const std::string& column = "threads") {
    const Table t = read_table(out() / "summary.csv");
    for (const std::string& id : runs) {
      EXPECT_EQ(threads_of(id), expected) << id;
      EXPECT_EQ(t.row(id).at(column), std::to_string(expected)) << id;
    }
  };
  ASSERT_EQ(run(sweep, 2).executed, 3u);
  expect_threads(1);
  EXPECT_EQ(read_text(out() / "runs" / runs[0] / "overrides.json").find("threads"), std::string::npos);
  EXPECT_TRUE(read_json_file(out() / "sweep.json").at("threads").is_null());

  // Resumed one at a time, or with --threads: nothing runs again.
  EXPECT_EQ(run(sweep, 1).executed, 0u);
  EXPECT_EQ(run(sweep, 2, 1, false, RICOCHET_BINARY, 2).executed, 0u);

  ASSERT_EQ(run(sweep, 1, 1, true).executed, 3u);
  expect_threads(1);
  ASSERT_EQ(run(sweep, 1, 1, true, RICOCHET_BINARY, 0).executed, 3u);
  expect_threads(omp_get_num_procs());
  ASSERT_EQ(run(sweep, 2, 1, true, RICOCHET_BINARY, 2).executed, 3u);
  expect_threads(2);
  EXPECT_EQ(read_json_file(out() / "sweep.json").at("threads").get<int>(), 2);

  // The sweep file's `threads` wins over the default, and --threads over it.
  const std::string with_threads = R"(
base = "case.toml"
set = { threads = 3 }
[[group]]
name = "g"
cross = { "time.dt" = [1e-5, 2e-5, 4e-5] }
)";
  EXPECT_EQ(run(with_threads, 2).executed, 0u) << "`threads` is not part of a run's identity";
  ASSERT_EQ(run(with_threads, 2, 1, true).executed, 3u);
  expect_threads(3, "summary.threads");
  ASSERT_EQ(run(with_threads, 2, 1, true, RICOCHET_BINARY, 1).executed, 3u);
  expect_threads(1, "summary.threads");
  EXPECT_EQ(read_table(out() / "summary.csv").row(runs[0]).at("threads"), "3");
}

TEST_F(SweepTest, ResumeRerunsOnlyTheRunsOfAChangedBase) {
  write("other.toml", other_case());
  const std::string sweep = R"(
base = "case.toml"
[[group]]
name = "top"
cross = { "time.dt" = [1e-5, 2e-5] }
[[group]]
name = "own"
base = "other.toml"
cross = { "time.dt" = [1e-5, 2e-5] }
)";
  ASSERT_EQ(run(sweep).executed, 4u);
  const fs::path top = out() / "runs/top/000-time.dt=1e-5/summary.json", own = out() / "runs/own/000-time.dt=1e-5/summary.json";
  const long long top_before = mtime_ns(top), own_before = mtime_ns(own);

  // Each run records its own base: in sweep.json (the top-level `base` is the sweep's), in
  // overrides.json (what resume compares) and in summary.csv (`case_file`, from the run).
  const Json s = read_json_file(out() / "sweep.json");
  EXPECT_EQ(s.at("base").get<std::string>(), (dir_ / "case.toml").lexically_normal().string());
  ASSERT_EQ(s.at("runs").size(), 4u);
  EXPECT_EQ(s.at("runs")[0].at("base").get<std::string>(), (dir_ / "case.toml").lexically_normal().string());
  EXPECT_EQ(s.at("runs")[3].at("base").get<std::string>(), (dir_ / "other.toml").lexically_normal().string());
  EXPECT_EQ(read_json_file(out() / "runs/own/001-time.dt=2e-5/overrides.json").at("base").get<std::string>(),
            (dir_ / "other.toml").lexically_normal().string());
  const Table t = read_table(out() / "summary.csv");
  EXPECT_EQ(t.row("top/001-time.dt=2e-5").at("case"), "tiny");
  EXPECT_EQ(t.row("own/001-time.dt=2e-5").at("case"), "other");
  EXPECT_EQ(fs::path(t.row("own/001-time.dt=2e-5").at("case_file")), (dir_ / "other.toml").lexically_normal());

  // A changed group base reruns that group's runs only.
  write("other.toml", other_case() + "# edited\n");
  const SweepOutcome a = run(sweep);
  EXPECT_EQ(a.resumed, 2u);
  EXPECT_EQ(a.executed, 2u);
  EXPECT_EQ(mtime_ns(top), top_before);
  EXPECT_GT(mtime_ns(own), own_before);

  // A changed sweep base reruns the runs made from it only.
  const long long own_after = mtime_ns(own);
  write("case.toml", kCase + "# edited\n");
  const SweepOutcome b = run(sweep);
  EXPECT_EQ(b.resumed, 2u);
  EXPECT_EQ(b.executed, 2u);
  EXPECT_GT(mtime_ns(top), top_before);
  EXPECT_EQ(mtime_ns(own), own_after);
  EXPECT_EQ(run(sweep).executed, 0u);

  // Without a top-level base, sweep.json's `base` is null.
  ASSERT_EQ(run("[[group]]\nname = \"own\"\nbase = \"other.toml\"\ncross = { \"time.dt\" = [1e-5, 2e-5] }\n").resumed, 2u);
  EXPECT_TRUE(read_json_file(out() / "sweep.json").at("base").is_null());
}

TEST_F(SweepTest, DivergedAndFailedRunsAreRecordedAndTheSweepGoesOn) {
  // A program that dies by a signal for runs whose description is "crash", and runs ricochet
  // otherwise.
  const std::string program = write("crashy.sh", std::string("#!/bin/sh\ncase \"$*\" in *crash*) kill -s KILL $$ ;; esac\nexec '") +
                                                     RICOCHET_BINARY + "' \"$@\"\n");
  fs::permissions(program, fs::perms::owner_all);
  const SweepOutcome o = run(R"(
base = "case.toml"
[[group]]
name = "mix"
cross = { mesh = ["m", "bad"], description = ["fine", "crash"] }
[[group]]
name = "div"
set = { "time.dt" = 4e-3, "time.end" = 0.4, "output.interval" = 4e-3 }
)",
                             1, 1, false, program);
  EXPECT_EQ(o.total, 5u);
  EXPECT_EQ(o.executed, 5u);
  EXPECT_EQ(o.ok, 1u);
  EXPECT_EQ(o.diverged, 1u);
  EXPECT_EQ(o.failed, 3u);
  const Table t = read_table(out() / "summary.csv");
  ASSERT_EQ(t.rows.size(), 5u);
  EXPECT_EQ(t.row("mix/000-mesh=m_description=fine").at("status"), "ok");
  const auto& missing = t.row("mix/002-mesh=bad_description=fine");
  EXPECT_EQ(missing.at("status"), "failed");
  EXPECT_EQ(missing.at("reason").rfind("exit 2: ricochet: ", 0), 0u) << missing.at("reason");
  EXPECT_NE(missing.at("reason").find("missing.msh"), std::string::npos) << missing.at("reason");
  EXPECT_EQ(missing.at("steps"), "");
  EXPECT_EQ(missing.at("mesh"), "bad");
  for (const char* id : {"mix/001-mesh=m_description=crash", "mix/003-mesh=bad_description=crash"}) {
    EXPECT_EQ(t.row(id).at("status"), "failed");
    EXPECT_EQ(t.row(id).at("reason").rfind("killed by signal 9", 0), 0u) << t.row(id).at("reason");
  }
  const auto& div = t.row("div/000");
  EXPECT_EQ(div.at("status"), "diverged");
  EXPECT_FALSE(div.at("reason").empty());
  EXPECT_EQ(div.at("reason"), div.at("diverged.reason"));
  EXPECT_NE(log_.str().find("killed by signal 9"), std::string::npos);

  // Failed runs have no summary.json: a second invocation tries them again, and only them.
  const SweepOutcome again = run(R"(
base = "case.toml"
[[group]]
name = "mix"
cross = { mesh = ["m", "bad"], description = ["fine", "crash"] }
[[group]]
name = "div"
set = { "time.dt" = 4e-3, "time.end" = 0.4, "output.interval" = 4e-3 }
)",
                                 1, 1, false, program);
  EXPECT_EQ(again.resumed, 2u);
  EXPECT_EQ(again.executed, 3u);
}

TEST_F(SweepTest, RepeatGivesMedianAndSpread) {
  const SweepOutcome o = run(R"(
base = "case.toml"
[[group]]
name = "r"
cross = { "time.dt" = [1e-5] }
)",
                             1, 3);
  EXPECT_EQ(o.executed, 1u);
  const Table t = read_table(out() / "summary.csv");
  ASSERT_EQ(t.rows.size(), 1u);
  const auto& r = t.rows[0];
  EXPECT_EQ(r.at("repeats"), "3");
  const double lo = num(r, "wall_seconds_min"), med = num(r, "wall_seconds"), hi = num(r, "wall_seconds_max");
  EXPECT_LE(lo, med);
  EXPECT_LE(med, hi);
  EXPECT_GT(num(r, "cpu_seconds"), 0.0);
  const fs::path f = out() / "runs/r/000-time.dt=1e-5";
  for (int k = 1; k <= 3; ++k) EXPECT_TRUE(fs::exists(f / ("repeat-" + std::to_string(k)) / "summary.json")) << k;
  EXPECT_TRUE(fs::exists(f / "summary.json"));
  EXPECT_TRUE(fs::exists(f / "history.csv"));
  // The median is one of the three repeats' times.
  std::vector<double> walls;
  for (int k = 1; k <= 3; ++k)
    walls.push_back(read_json_file(f / ("repeat-" + std::to_string(k)) / "summary.json").at("wall_seconds").get<double>());
  std::sort(walls.begin(), walls.end());
  EXPECT_DOUBLE_EQ(med, walls[1]);
  EXPECT_DOUBLE_EQ(lo, walls[0]);
  EXPECT_DOUBLE_EQ(hi, walls[2]);
  // Resumed with the same repeat count: the statistics come back from the repeats' summaries.
  EXPECT_EQ(run("base = \"case.toml\"\n[[group]]\nname = \"r\"\ncross = { \"time.dt\" = [1e-5] }\n", 1, 3).resumed, 1u);
  EXPECT_EQ(read_table(out() / "summary.csv").rows[0].at("wall_seconds"), r.at("wall_seconds"));
}

// A reference run is run once whatever --repeat says: its timing is not compared with anything.
TEST_F(SweepTest, ReferenceRunsAreNotRepeated) {
  const std::string sweep = R"(
base = "case.toml"
[[group]]
name = "r"
cross = { "time.dt" = [2e-5] }
reference = { "time.dt" = 1e-5 }
)";
  const SweepOutcome o = run(sweep, 1, 3);
  EXPECT_EQ(o.executed, 2u);
  const Table t = read_table(out() / "summary.csv");
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.row("r/reference-time.dt=1e-5").at("repeats"), "1");
  EXPECT_EQ(t.row("r/000-time.dt=2e-5").at("repeats"), "3");
  EXPECT_FALSE(fs::exists(out() / "runs/r/reference-time.dt=1e-5/repeat-1"));
  EXPECT_TRUE(fs::exists(out() / "runs/r/000-time.dt=2e-5/repeat-3/summary.json"));
  EXPECT_FALSE(t.row("r/000-time.dt=2e-5").at("error_probe_P").empty());
  // Resumed with the same --repeat: nothing runs again.
  EXPECT_EQ(run(sweep, 1, 3).resumed, 2u);
}

TEST_F(SweepTest, ErrorsAgainstTheReferenceAreZeroAtItsStepAndShrinkWithDt) {
  const SweepOutcome o = run(R"(
base = "case.toml"
[[group]]
name = "acc"
cross = { "bodies[0].element" = ["q4", "q4_hourglass"], "time.dt" = [5e-5, 2.5e-5, 1e-5] }
reference = { "time.dt" = 1e-5 }
)",
                             2);
  EXPECT_EQ(o.total, 8u);
  EXPECT_EQ(o.ok, 8u);
  const Table t = read_table(out() / "summary.csv");
  ASSERT_EQ(t.rows.size(), 8u);
  for (const std::string el : {"q4", "q4_hourglass"}) {
    const std::string ref = "acc/reference-bodies.0.element=" + el + "_time.dt=1e-5";
    const auto& rr = t.row(ref);
    EXPECT_EQ(rr.at("kind"), "reference");
    EXPECT_EQ(rr.at("error_energy"), "");
    const int base = el == "q4" ? 0 : 3;
    auto id = [&](int i, const char* dt) {
      return "acc/00" + std::to_string(base + i) + "-bodies.0.element=" + el + "_time.dt=" + dt;
    };
    const auto& coarse = t.row(id(0, "5e-5"));
    const auto& mid = t.row(id(1, "2.5e-5"));
    const auto& same = t.row(id(2, "1e-5"));
    for (const auto* r : {&coarse, &mid, &same}) {
      EXPECT_EQ(r->at("reference_run"), ref);
      EXPECT_EQ(num(*r, "reference_dt"), 1e-5);
    }
    EXPECT_EQ(num(same, "error_probe_P"), 0.0);
    EXPECT_EQ(num(same, "error_energy"), 0.0);
    EXPECT_GT(num(mid, "error_probe_P"), 0.0);
    EXPECT_GT(num(coarse, "error_probe_P"), num(mid, "error_probe_P")) << el;
    EXPECT_GT(num(mid, "error_energy"), 0.0);
    EXPECT_GT(num(coarse, "error_energy"), num(mid, "error_energy")) << el;
    EXPECT_LT(num(coarse, "error_probe_P"), 1e-2);  // a few % of the probe's motion at most
  }
}

// ---- the shared reference ([reference]) ----------------------------------------------------------

TEST_F(SweepTest, SharedReferenceRunsComeFirstAndGroupsWithoutTheirOwnAreComparedWithIt) {
  const SweepSpec spec = read_sweep(write("s.toml", R"(
base = "case.toml"
set = { "time.end" = 1e-3, "output.interval" = 1e-4 }

[reference]
name = "converged"
set = { "time.dt" = 2.5e-6, "output.interval" = 5e-5 }
check = { "bodies[0].element" = "q4_hourglass" }

[[group]]
name = "a"
cross = { "time.dt" = [1e-5, 2e-5] }

[[group]]
name = "own"
cross = { "time.dt" = [1e-5] }
reference = { "time.dt" = 5e-6 }
error_probe = "P"

[[group]]
name = "out"
reference = false
)"));
  ASSERT_TRUE(spec.reference.present);
  EXPECT_EQ(spec.reference.name, "converged");
  EXPECT_EQ(spec.reference.error_probe, "P");
  const auto runs = expand(spec);
  EXPECT_EQ(ids(runs), (std::vector<std::string>{"reference/converged", "reference/converged-check", "a/000-time.dt=1e-5",
                                                 "a/001-time.dt=2e-5", "own/reference-time.dt=5e-6", "own/000-time.dt=1e-5",
                                                 "out/000"}));
  // The sweep's set, then the reference's; the check run adds its own keys on top.
  EXPECT_EQ(runs[0].set_args(), (std::vector<std::string>{"time.end=0.001", "time.dt=2.5e-6", "output.interval=5e-5"}));
  EXPECT_EQ(runs[1].set_args(), (std::vector<std::string>{"time.end=0.001", "time.dt=2.5e-6", "output.interval=5e-5",
                                                          "bodies[0].element=\"q4_hourglass\""}));
  EXPECT_EQ(runs[0].folder(), fs::path("runs/reference/converged"));
  EXPECT_EQ(runs[0].group, "reference");
  EXPECT_TRUE(runs[0].is_reference);
  EXPECT_TRUE(runs[1].is_reference);
  EXPECT_EQ(runs[0].base, spec.base);
  EXPECT_EQ(runs[0].reference_id, "");
  EXPECT_EQ(runs[1].reference_id, "reference/converged");
  EXPECT_EQ(runs[1].reference_kind, "shared");
  for (int i : {2, 3}) {
    EXPECT_EQ(runs[i].reference_id, "reference/converged") << runs[i].id;
    EXPECT_EQ(runs[i].reference_kind, "shared") << runs[i].id;
    EXPECT_EQ(runs[i].error_probe, "P");
  }
  EXPECT_EQ(runs[5].reference_id, "own/reference-time.dt=5e-6");
  EXPECT_EQ(runs[5].reference_kind, "group");
  EXPECT_EQ(runs[6].reference_id, "");  // opted out
  EXPECT_EQ(runs[6].reference_kind, "");
  check_runs(spec, runs);

  // Defaults: name "shared", no check run; a reference on its own base case.
  write("other.toml", other_case());
  const SweepSpec d = read_sweep(write("s.toml", "[reference]\nbase = \"other.toml\"\nset = { \"time.dt\" = 5e-6 }\n"
                                                 "[[group]]\nbase = \"case.toml\"\n"));
  const auto druns = expand(d);
  EXPECT_EQ(ids(druns), (std::vector<std::string>{"reference/shared", "group0/000"}));
  EXPECT_EQ(druns[0].base, (dir_ / "other.toml").lexically_normal());
  EXPECT_EQ(druns[1].reference_id, "reference/shared");
  check_runs(d, druns);
}

TEST_F(SweepTest, BadSharedReferencesAreRejectedWithFileLineAndKey) {
  const std::string top = "base = \"case.toml\"\n";
  const std::string g = "[[group]]\ncross = { \"time.dt\" = [1e-5] }\n";
  const std::string set = "set = { \"time.dt\" = 1e-6 }\n";
  expect_rejected(top + "[reference]\n" + set + "bogus = 1\n" + g,
                  {"sweep.toml:4: reference.bogus", "unknown key", "allowed here: base, check, error_probe, name, set"});
  expect_rejected(top + "[reference]\ncheck = { \"time.dt\" = 2e-6 }\n" + g, {"sweep.toml:2: reference.set", "missing"});
  expect_rejected(top + "[reference]\nset = {}\n" + g, {":3: reference.set", "empty table"});
  expect_rejected(top + "[reference]\n" + set + "check = {}\n" + g, {":4: reference.check", "empty table"});
  expect_rejected(top + "[reference]\n" + set + "check = { \"time.dt\" = 1e-6 }\n" + g,
                  {":4: reference.check", "the reference run itself"});
  expect_rejected(top + "set = { \"bodies[0].element\" = \"q4\" }\n[reference]\n" + set +
                      "check = { \"bodies.0.element\" = \"q4\" }\n" + g,
                  {"reference.check", "the reference run itself"});
  expect_rejected(top + "[reference]\nname = \"a b\"\n" + set + g, {":3: reference.name", "letters"});
  expect_rejected(top + "[reference]\nbase = \"nowhere.toml\"\n" + set + g, {"reference.base", "nowhere.toml' not found"});
  expect_rejected("[reference]\n" + set + "[[group]]\nbase = \"case.toml\"\n", {"sweep.toml:1: reference.base", "missing"});
  expect_rejected(top + "reference = 3\n" + g, {":2: reference", "expected a table"});
  expect_rejected(top + "[reference]\n" + set + "error_probe = \"a-b\"\n" + g, {"reference.error_probe", "probe name"});
  // Groups.
  expect_rejected(top + g + "reference = true\n", {":4: group[0].reference", "or false", "got true"});
  expect_rejected(top + g + "reference = \"yes\"\n", {"group[0].reference", "a table of case keys", "a string"});
  expect_rejected(top + g + "reference = false\n", {"group[0].reference", "this sweep has none"});
  expect_rejected(top + "[reference]\n" + set + g + "name = \"reference\"\n", {":6: group[0].name", "reference/shared"});
  expect_rejected(top + "[reference]\n" + set + g + "error_probe = \"P\"\n",
                  {"group[0].error_probe", "the group's own `reference`", "[reference]"});
  expect_rejected(top + "[reference]\n" + set + g + "reference = false\n" + g + "reference = { \"time.dt\" = 5e-6 }\n",
                  {"sweep.toml:2: reference", "no group is compared with it"});
  // What the case rejects: the run and the sweep file's line.
  expect_rejected(top + "[reference]\nset = { \"time.dtt\" = 1e-6 }\n" + g,
                  {"sweep.toml:3: reference.set.time.dtt", "run reference/shared:", "time.dtt: unknown key"});
  expect_rejected(top + "[reference]\n" + set + "check = { mesh = \"q\" }\n" + g,
                  {"sweep.toml:4: reference.check.mesh", "run reference/shared-check", "no mesh named \"q\""});
  expect_rejected(top + "[reference]\n" + set + "error_probe = \"Q\"\n" + g,
                  {"sweep.toml:2: reference.error_probe", "run reference/shared", "no probe \"Q\"", "its probes: P"});
}

namespace {

const Json& at(const Json& v, const std::string& key) {
  const auto m = v.find(key);
  if (m == v.end()) throw std::logic_error("no key " + key);
  return *m;
}

const Json* maybe(const Json& v, const std::string& key) {
  const auto m = v.find(key);
  return m != v.end() && m->is_number() ? &*m : nullptr;
}

double column_of(const HistoryTable& h, std::size_t row, const std::string& col) {
  const int c = h.column(col);
  if (c < 0) throw std::logic_error("no column " + col);
  return h.rows.at(row).at(static_cast<std::size_t>(c));
}

double trapezoid(const HistoryTable& h, const std::string& col) {
  double sum = 0.0;
  for (std::size_t i = 1; i < h.rows.size(); ++i)
    sum += 0.5 * (column_of(h, i - 1, col) + column_of(h, i, col)) * (column_of(h, i, "time") - column_of(h, i - 1, "time"));
  return sum;
}

// The run's outputs in DIR/runs/<id>.
struct Outputs {
  Json summary;
  HistoryTable history;
};
Outputs outputs_of(const fs::path& out, const std::string& id) {
  return {read_json_file(out / "runs" / id / "summary.json"), read_history_csv(out / "runs" / id / "history.csv")};
}

// The metrics of `run` against `ref` computed here from the two runs' files, independently of
// harness/sweeps/reference_errors.cpp, for runs sampled at the same times: name -> value, or absent
// when an input is missing.
std::map<std::string, double> expected_errors(const Outputs& run, const Outputs& ref, const std::string& probe) {
  std::map<std::string, double> e;
  EXPECT_EQ(run.history.rows.size(), ref.history.rows.size());
  double du = 0.0, de = 0.0;
  const double e0 = at(ref.summary, "initial_energy").get<double>();
  for (std::size_t i = 0; i < run.history.rows.size() && i < ref.history.rows.size(); ++i) {
    EXPECT_DOUBLE_EQ(column_of(run.history, i, "time"), column_of(ref.history, i, "time"));
    du = std::max(du, std::hypot(column_of(run.history, i, probe + "_ux") - column_of(ref.history, i, probe + "_ux"),
                                 column_of(run.history, i, probe + "_uy") - column_of(ref.history, i, probe + "_uy")));
    de = std::max(de, std::abs(column_of(run.history, i, "total_energy") - column_of(ref.history, i, "total_energy")) / e0);
  }
  e["probe_" + probe] = du;
  e["energy"] = de;
  e["angular_momentum"] = std::abs(at(at(run.summary, "final"), "angular_momentum").get<double>() -
                                   at(at(ref.summary, "final"), "angular_momentum").get<double>());
  if (maybe(run.summary, "contact_impulse_normal") && maybe(ref.summary, "contact_impulse_normal") &&
      maybe(run.summary, "contact_impulse_tangential") && maybe(ref.summary, "contact_impulse_tangential")) {
    e["impulse_normal"] = std::abs(at(run.summary, "contact_impulse_normal").get<double>() - at(ref.summary, "contact_impulse_normal").get<double>());
    e["impulse_tangential"] =
        std::abs(at(run.summary, "contact_impulse_tangential").get<double>() - at(ref.summary, "contact_impulse_tangential").get<double>());
  } else {
    e["impulse_normal"] = std::abs(trapezoid(run.history, "normal_force") - trapezoid(ref.history, "normal_force"));
    e["impulse_tangential"] = std::abs(trapezoid(run.history, "tangential_force") - trapezoid(ref.history, "tangential_force"));
  }
  auto velocity = [](const Json& s) -> std::optional<std::pair<double, double>> {
    if (maybe(s, "rebound_velocity_x") && maybe(s, "rebound_velocity_y"))
      return std::pair{at(s, "rebound_velocity_x").get<double>(), at(s, "rebound_velocity_y").get<double>()};
    if (maybe(s, "total_mass") && at(s, "total_mass").get<double>() > 0.0)
      return std::pair{at(at(s, "final"), "momentum_x").get<double>() / at(s, "total_mass").get<double>(),
                       at(at(s, "final"), "momentum_y").get<double>() / at(s, "total_mass").get<double>()};
    return std::nullopt;
  };
  if (const auto a = velocity(run.summary), b = velocity(ref.summary); a && b)
    e["rebound_velocity"] = std::hypot(a->first - b->first, a->second - b->second);
  for (const auto& [metric, key] : std::vector<std::pair<std::string, std::string>>{
           {"contact_duration", "contact_duration"},
           {"von_mises_interior", "von_mises_interior_max"},
           {"von_mises_interior_time", "von_mises_interior_max_time"}})
    if (maybe(run.summary, key) && maybe(ref.summary, key))
      e[metric] = std::abs(at(run.summary, key).get<double>() - at(ref.summary, key).get<double>());
  return e;
}

// Expects the row's `prefix`<metric> columns to hold `expected` (empty where it has no value).
void expect_metrics(const std::map<std::string, std::string>& row, const std::string& prefix,
                    const std::map<std::string, double>& expected, const std::vector<std::string>& metrics) {
  for (const auto& m : metrics) {
    const std::string col = prefix + m;
    ASSERT_TRUE(row.count(col)) << col;
    const auto it = expected.find(m);
    if (it == expected.end()) {
      EXPECT_EQ(row.at(col), "") << row.at("run_id") << " " << col;
    } else {
      ASSERT_FALSE(row.at(col).empty()) << row.at("run_id") << " " << col;
      EXPECT_DOUBLE_EQ(std::stod(row.at(col)), it->second) << row.at("run_id") << " " << col;
    }
  }
}

}  // namespace

TEST_F(SweepTest, SharedReferenceWithCheckRunGivesErrorsFloorsAndKinds) {
  // The oblique plate on M1 over its first 0.5 ms (the impact), with friction so that both
  // impulses are non-zero. The reference: the semi-explicit scheme at dt = 2.5e-6; its check, the
  // implicit scheme at the same dt.
  const std::string plate = std::string(RICOCHET_SOURCE_DIR) + "/cases/oblique_plate.toml";
  const std::string sweep = "name = \"shared\"\nbase = \"" + plate + R"("
set = { mesh = "M1", "time.end" = 5e-4, "output.fields" = [], "obstacles[0].friction" = 0.3 }

[reference]
name = "converged"
set = { "time.dt" = 2.5e-6 }
check = { scheme = "implicit" }
error_probe = "top_right"

[[group]]
name = "semi"
cross = { "time.dt" = [1e-5, 5e-6] }

[[group]]
name = "conv"
cross = { "time.dt" = [1e-5] }
reference = { "time.dt" = 5e-6 }

[[group]]
name = "alone"
reference = false
)";
  const SweepOutcome o = run(sweep);
  EXPECT_EQ(o.total, 7u);
  EXPECT_EQ(o.ok, 7u);
  const Table t = read_table(out() / "summary.csv");
  ASSERT_EQ(t.rows.size(), 7u);
  EXPECT_EQ(t.rows[0].at("run_id"), "reference/converged");  // reference runs first, in the sweep's order
  EXPECT_EQ(t.rows[1].at("run_id"), "reference/converged-check");
  for (const char* id : {"reference/converged", "reference/converged-check"}) {
    EXPECT_TRUE(fs::exists(out() / "runs" / id / "summary.json")) << id;
    EXPECT_EQ(t.row(id).at("kind"), "reference");
    EXPECT_EQ(t.row(id).at("group"), "reference");
  }
  EXPECT_EQ(t.row("reference/converged").at("reference_run"), "");
  EXPECT_EQ(t.row("reference/converged").at("error_energy"), "");
  EXPECT_EQ(t.row("reference/converged-check").at("summary.scheme"), "implicit");

  // The floor: the check run against the reference, from their files.
  const Outputs ref = outputs_of(out(), "reference/converged"), check = outputs_of(out(), "reference/converged-check");
  const std::map<std::string, double> floor = expected_errors(check, ref, "top_right");
  EXPECT_GT(floor.at("probe_top_right"), 0.0);
  EXPECT_GT(floor.at("energy"), 0.0);
  EXPECT_GT(floor.at("impulse_normal"), 0.0);
  const std::vector<std::string> floored = {"probe_top_right",  "energy",           "rebound_velocity",
                                            "angular_momentum", "impulse_normal",   "impulse_tangential",
                                            "contact_duration", "von_mises_interior", "von_mises_interior_time"};
  for (const auto& m : floored) EXPECT_TRUE(has_column(t, "floor_" + m)) << m;
  EXPECT_FALSE(has_column(t, "floor_penetration"));  // penetration is measured against 0, not the reference

  // Every run compared with the shared reference: its kind, its errors from the two runs' files,
  // and the same floor on every row.
  const std::string source = maybe(ref.summary, "contact_impulse_normal") ? "summary" : "history";
  for (const char* id : {"reference/converged-check", "semi/000-time.dt=1e-5", "semi/001-time.dt=5e-6"}) {
    const auto& r = t.row(id);
    EXPECT_EQ(r.at("status"), "ok") << id;
    EXPECT_EQ(r.at("reference_run"), "reference/converged") << id;
    EXPECT_EQ(r.at("reference_kind"), "shared") << id;
    EXPECT_EQ(r.at("reference_dt"), "2.5e-06") << id;
    EXPECT_EQ(r.at("impulse_source"), source) << id;
    expect_metrics(r, "error_", expected_errors(outputs_of(out(), id), ref, "top_right"), floored);
    expect_metrics(r, "floor_", floor, floored);
    EXPECT_EQ(r.at("error_penetration"), r.at("penetration_max")) << id;  // the run's own
    EXPECT_EQ(r.at("error_probe_P"), "") << id;  // the shared reference's probe is top_right
  }
  // The coarser semi-explicit run is further from the reference in the probe and the energy.
  EXPECT_GT(num(t.row("semi/000-time.dt=1e-5"), "error_energy"), num(t.row("semi/001-time.dt=5e-6"), "error_energy"));

  // A group with its own reference keeps it, with its probe and no floor.
  const auto& conv = t.row("conv/000-time.dt=1e-5");
  EXPECT_EQ(conv.at("reference_run"), "conv/reference-time.dt=5e-6");
  EXPECT_EQ(conv.at("reference_kind"), "group");
  EXPECT_EQ(conv.at("reference_dt"), "5e-06");
  EXPECT_FALSE(conv.at("error_probe_P").empty());
  EXPECT_EQ(conv.at("error_probe_top_right"), "");
  EXPECT_EQ(conv.at("error_penetration"), conv.at("penetration_max"));
  for (const auto& m : floored) EXPECT_EQ(conv.at("floor_" + m), "") << m;
  expect_metrics(conv, "error_",
                 expected_errors(outputs_of(out(), "conv/000-time.dt=1e-5"), outputs_of(out(), "conv/reference-time.dt=5e-6"),
                                 "P"),
                 {"angular_momentum", "impulse_normal", "impulse_tangential"});
  // Opted out: no reference, no errors.
  const auto& alone = t.row("alone/000");
  for (const char* c : {"reference_run", "reference_kind", "reference_dt", "error_energy", "error_penetration",
                        "error_probe_top_right", "floor_energy"})
    EXPECT_EQ(alone.at(c), "") << c;

  // sweep.json: the reference, its check run and its floor; each run's reference kind.
  const Json s = read_json_file(out() / "sweep.json");
  const Json& sr = at(s, "reference");
  EXPECT_EQ(at(sr, "id").get<std::string>(), "reference/converged");
  EXPECT_EQ(at(sr, "name").get<std::string>(), "converged");
  EXPECT_EQ(at(sr, "error_probe").get<std::string>(), "top_right");
  EXPECT_EQ(at(at(sr, "check"), "id").get<std::string>(), "reference/converged-check");
  EXPECT_EQ(at(at(sr, "floor"), "impulse_source").get<std::string>(), source);
  for (const auto& m : {"probe_top_right", "energy", "angular_momentum", "impulse_normal"})
    EXPECT_DOUBLE_EQ(at(at(sr, "floor"), m).get<double>(), floor.at(m)) << m;
  const Json& list = at(s, "runs");
  ASSERT_EQ(list.size(), 7u);
  EXPECT_EQ(at(list[2], "reference_kind").get<std::string>(), "shared");
  EXPECT_EQ(at(list[5], "id").get<std::string>(), "conv/000-time.dt=1e-5");
  EXPECT_EQ(at(list[5], "reference_kind").get<std::string>(), "group");
  EXPECT_TRUE(at(list[6], "reference_kind").is_null());

  // A changed reference: only the reference and its check run again; the runs compared with it
  // are resumed and their errors and floors measured against the new reference.
  std::string finer = sweep;
  finer.replace(finer.find("\"time.dt\" = 2.5e-6"), 18, "\"time.dt\" = 2e-6");
  const SweepOutcome again = run(finer);
  EXPECT_EQ(again.executed, 2u);
  EXPECT_EQ(again.resumed, 5u);
  const Table t2 = read_table(out() / "summary.csv");
  const Outputs ref2 = outputs_of(out(), "reference/converged"), check2 = outputs_of(out(), "reference/converged-check");
  EXPECT_EQ(at(ref2.summary, "dt").get<double>(), 2e-6);
  const auto& semi = t2.row("semi/000-time.dt=1e-5");
  EXPECT_EQ(semi.at("reference_dt"), "2e-06");
  expect_metrics(semi, "error_", expected_errors(outputs_of(out(), "semi/000-time.dt=1e-5"), ref2, "top_right"), floored);
  expect_metrics(semi, "floor_", expected_errors(check2, ref2, "top_right"), floored);
  EXPECT_NE(semi.at("floor_energy"), t.row("semi/000-time.dt=1e-5").at("floor_energy"));

  // A changed check run: it alone runs again, and every floor follows it.
  std::string other_check = finer;
  other_check.replace(other_check.find("check = { scheme = \"implicit\" }"), 31, "check = { \"time.dt\" = 1e-6 }");
  const SweepOutcome third = run(other_check);
  EXPECT_EQ(third.executed, 1u);
  EXPECT_EQ(third.resumed, 6u);
  const Table t3 = read_table(out() / "summary.csv");
  const Outputs check3 = outputs_of(out(), "reference/converged-check");
  EXPECT_EQ(at(check3.summary, "dt").get<double>(), 1e-6);
  const std::map<std::string, double> floor3 = expected_errors(check3, ref2, "top_right");
  for (const char* id : {"reference/converged-check", "semi/000-time.dt=1e-5", "semi/001-time.dt=5e-6"})
    expect_metrics(t3.row(id), "floor_", floor3, floored);
  EXPECT_NE(t3.row("semi/000-time.dt=1e-5").at("floor_energy"), semi.at("floor_energy"));
}

// ---- interruption and resume (docs/reliability.md, "Interruption and resume") ---------------------

namespace {

// The tiny plate on a 40 x 20 mesh with one thread: a run of about a second per 0.1 s of
// simulated time, long enough to be killed in the middle.
std::string slow_case(double end) {
  std::string s = kCase;
  s.replace(s.find("nx = 4"), 6, "nx = 40");
  s.replace(s.find("ny = 2"), 6, "ny = 20");
  s.replace(s.find("end = 2e-3"), 10, "end = " + std::to_string(end));
  s.replace(s.find("interval = 1e-4"), 15, "interval = 1e-3\nfields = [0.01]");
  return "threads = 1\n" + s;
}

using test_support::start_process;

// A live process of this machine: its parent, its state (R, S, Z, ...) and its arguments.
struct Process {
  pid_t pid = 0, ppid = 0;
  char state = '?';
  std::vector<std::string> argv;
  // The value of its --out option, if any.
  std::string out() const {
    for (std::size_t i = 0; i + 1 < argv.size(); ++i)
      if (argv[i] == "--out") return argv[i + 1];
    return {};
  }
};

// The processes with an argument that starts with `dir` (a zombie has no arguments: not listed).
std::vector<Process> processes_using(const fs::path& dir) {
  std::vector<Process> found;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator("/proc", ec)) {
    const std::string name = e.path().filename().string();
    if (name.empty() || name.find_first_not_of("0123456789") != std::string::npos) continue;
    Process p;
    p.pid = std::stoi(name);
    std::stringstream cmd;
    cmd << std::ifstream(e.path() / "cmdline").rdbuf();
    std::string word;
    while (std::getline(cmd, word, '\0')) p.argv.push_back(word);
    bool uses = false;
    for (const auto& w : p.argv) uses = uses || w.rfind(dir.string(), 0) == 0;
    if (!uses) continue;
    std::stringstream stat;
    stat << std::ifstream(e.path() / "stat").rdbuf();
    const std::string st = stat.str();
    const auto close = st.rfind(')');
    if (close == std::string::npos) continue;  // it ended meanwhile
    std::istringstream rest(st.substr(close + 1));
    rest >> p.state >> p.ppid;
    if (p.state != 'Z') found.push_back(p);
  }
  return found;
}

using test_support::text_of;

// Checks that a finished run folder holds one complete, consistent set of outputs: summary.json
// ok, its history_rows the rows of history.csv (times strictly increasing: no row written twice),
// its field_files the .vtu files of fields/, and nothing half-written or staged.
void expect_complete_run_folder(const fs::path& f) {
  SCOPED_TRACE(f.string());
  ASSERT_TRUE(fs::is_regular_file(f / "summary.json"));
  for (const char* file : {"history.csv", "overrides.json", "stderr.txt"}) EXPECT_TRUE(fs::is_regular_file(f / file)) << file;
  const Json s = read_json_file(f / "summary.json");
  EXPECT_EQ(s.at("status").get<std::string>(), "ok");
  const auto lines = test_support::csv_records(text_of(f / "history.csv"));
  ASSERT_GE(lines.size(), 2u);
  EXPECT_EQ(static_cast<long>(lines.size()) - 1, s.at("history_rows").get<long>());
  double last = -1.0;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const double t = std::stod(lines[i].at(0));
    EXPECT_GT(t, last) << "history row " << i;
    last = t;
  }
  long vtu = 0;
  if (fs::exists(f / "fields"))
    for (const auto& e : fs::directory_iterator(f / "fields")) vtu += e.path().extension() == ".vtu";
  EXPECT_EQ(vtu, s.at("field_files").get<long>());
  for (const auto& e : fs::directory_iterator(f)) {
    const std::string name = e.path().filename().string();
    EXPECT_EQ(name.find(".tmp"), std::string::npos) << name;
    EXPECT_NE(name.rfind(".staging", 0), 0u) << name;
  }
}

}  // namespace

// `ricochet sweep` killed by SIGKILL in the middle of a run, and resumed at once: the killed
// sweep's run ends with it (no orphan keeps writing), the resumed sweep reuses the finished run
// and runs each other run once, in one process per folder, and every run folder ends complete.
TEST_F(SweepTest, SigkilledSweepLeavesNoOrphanAndResumesWithOneWriterPerRun) {
  // About 2 s a run (40 x 20 cells, 1e5 steps): 0.25 s of simulated time (0.55 s a run) left the
  // 0.5 s below too close to a run's end on a lightly loaded machine.
  write("slow.toml", slow_case(1.0));
  const std::string file = write("kill.toml", R"(
name = "kill"
base = "slow.toml"
[[group]]
name = "g"
cross = { "output.interval" = [1e-3, 2e-3, 4e-3] }
)");
  const std::vector<std::string> ids = {"g/000-output.interval=0.001", "g/001-output.interval=0.002",
                                        "g/002-output.interval=0.004"};
  const std::vector<std::string> args = {RICOCHET_BINARY, "sweep", file, "--out", out().string()};
  using Clock = std::chrono::steady_clock;
  auto wait_for = [](const std::function<bool()>& done, double seconds) {
    const auto until = Clock::now() + std::chrono::duration<double>(seconds);
    while (!done() && Clock::now() < until) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    return done();
  };

  // Kill the sweep 0.5 s into its second run.
  const pid_t first = start_process(args, dir_ / "first.log");
  const fs::path second = out() / "runs" / ids[1];
  const bool started = wait_for([&] { return fs::exists(second / "stderr.txt"); }, 120.0);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const bool unfinished = !fs::exists(second / "summary.json");
  kill(first, SIGKILL);
  int status = 0;
  waitpid(first, &status, 0);
  const auto killed = Clock::now();
  ASSERT_TRUE(started) << text_of(dir_ / "first.log");
  ASSERT_TRUE(unfinished) << "the runs are too short for this machine: make slow_case() longer";
  ASSERT_TRUE(fs::exists(out() / "runs" / ids[0] / "summary.json"));
  const long long first_done = mtime_ns(out() / "runs" / ids[0] / "summary.json");

  // Resume at once, watching every process that uses the sweep's folder: each `ricochet run`
  // must be a child of the resumed sweep, one per run folder.
  const pid_t resumed = start_process(args, dir_ / "resumed.log");
  std::map<std::string, std::set<pid_t>> writers;  // run folder -> its run processes
  std::set<std::string> orphans;
  int exit_status = -1;
  for (;;) {
    const pid_t r = waitpid(resumed, &status, WNOHANG);
    if (r == resumed) {
      exit_status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      break;
    }
    // A run killed with its sweep takes a moment to end; one still there 0.5 s later is an orphan.
    // A process whose parent is one of the resumed sweep's runs belongs to that run, not to the
    // killed sweep: in the sanitizer build, LeakSanitizer's tracer, which a run starts as it
    // exits, shares the run's memory and open files and so shows the run's command line.
    const bool settled = Clock::now() - killed > std::chrono::milliseconds(500);
    const std::vector<Process> using_out = processes_using(out());
    std::set<pid_t> resumed_runs;
    for (const Process& p : using_out)
      if (p.ppid == resumed) resumed_runs.insert(p.pid);
    for (const Process& p : using_out) {
      if (p.pid == resumed || p.argv.size() < 2 || p.argv[1] != "run") continue;
      if (p.ppid == resumed) writers[p.out()].insert(p.pid);
      else if (settled && !resumed_runs.count(p.ppid))
        orphans.insert("pid " + std::to_string(p.pid) + " (parent " + std::to_string(p.ppid) + ") -> " + p.out());
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const std::string log = text_of(dir_ / "resumed.log");
  EXPECT_EQ(exit_status, 0) << log;
  for (const std::string& o : orphans) ADD_FAILURE() << "a run of the killed sweep still writes: " << o;
  EXPECT_TRUE(wait_for([&] { return processes_using(out()).empty(); }, 5.0)) << "processes left in the sweep's folder";
  EXPECT_TRUE(writers[(out() / "runs" / ids[0]).string()].empty()) << "the finished run is reused";
  for (const auto& [folder, pids] : writers) EXPECT_LE(pids.size(), 1u) << folder;
  EXPECT_NE(log.find("1 done before, 2 to run"), std::string::npos) << log;

  // Every run folder complete and consistent, summary.csv from the same files.
  EXPECT_EQ(mtime_ns(out() / "runs" / ids[0] / "summary.json"), first_done);
  const Table t = read_table(out() / "summary.csv");
  ASSERT_EQ(t.rows.size(), 3u);
  for (const std::string& id : ids) {
    expect_complete_run_folder(out() / "runs" / id);
    const Json s = read_json_file(out() / "runs" / id / "summary.json");
    const double wall = s.at("wall_seconds").get<double>();
    EXPECT_EQ(t.row(id).at("status"), "ok");
    EXPECT_DOUBLE_EQ(num(t.row(id), "wall_seconds"), wall);
    // The time loop's wall time is within the process's, as the resumed sweep measured it.
    const auto at = log.find("] " + id + " ok wall ");
    if (id != ids[0] && at != std::string::npos) {
      const double process_wall = std::stod(log.substr(at + id.size() + 11));
      EXPECT_LE(wall, process_wall + 0.01) << id;
    }
  }
  const Json sj = read_json_file(out() / "sweep.json");
  EXPECT_EQ(sj.at("resumed_runs").get<int>(), 1);
  EXPECT_EQ(sj.at("counts").at("executed").get<int>(), 2);
}

// A run folder whose lock is held (a process of an interrupted sweep still writing it): the
// resumed sweep says so and waits for it; if it does not end in time, the sweep stops with an
// error naming the folder, and starts nothing.
TEST_F(SweepTest, ResumeWaitsForTheProcessStillWritingARunFolder) {
  const std::string sweep = R"(
base = "case.toml"
[[group]]
name = "g"
cross = { "time.dt" = [1e-5, 2e-5] }
)";
  ASSERT_EQ(run(sweep).executed, 2u);
  const fs::path f = out() / "runs" / "g" / "001-time.dt=2e-5";
  ASSERT_TRUE(fs::exists(f / "run.lock"));
  fs::remove(f / "summary.json");
  const int fd = ::open((f / "run.lock").c_str(), O_RDWR | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(flock(fd, LOCK_EX | LOCK_NB), 0);

  // Held for longer than the sweep waits: an error, and nothing started.
  const SweepSpec spec = read_sweep(write("sweep.toml", sweep));
  SweepOptions o;
  o.out_dir = out();
  o.executable = RICOCHET_BINARY;
  o.log = &log_;
  o.writer_wait = 0.3;
  try {
    run_sweep(spec, expand(spec), o);
    ADD_FAILURE() << "a sweep started a run in a folder that another process writes";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_EQ(dynamic_cast<const InputError*>(&e), nullptr) << "not bad input: exit 1";
    EXPECT_NE(msg.find(f.string()), std::string::npos) << msg;
    EXPECT_NE(msg.find("still"), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
  EXPECT_FALSE(fs::exists(f / "summary.json"));
  EXPECT_TRUE(fs::exists(f / "history.csv")) << "the folder was left alone";

  // Released after a second: the sweep waits, says so, then runs it.
  std::thread release([fd] {
    std::this_thread::sleep_for(std::chrono::seconds(1));
    close(fd);
  });
  log_.str("");
  o.writer_wait = 60.0;
  const auto t0 = std::chrono::steady_clock::now();
  const SweepOutcome again = run_sweep(spec, expand(spec), o);
  const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  release.join();
  EXPECT_EQ(again.executed, 1u);
  EXPECT_EQ(again.resumed, 1u);
  EXPECT_GE(waited, 0.9);
  EXPECT_NE(log_.str().find("waiting"), std::string::npos) << log_.str();
  expect_complete_run_folder(f);
}

// A summary.json that a resumed sweep reads is checked: a value of the wrong type in a key the
// sweep reads makes the run not done, so it is run again, with a note naming the file and key.
TEST_F(SweepTest, ResumeRerunsARunWhoseSummaryIsInvalid) {
  const std::string sweep = R"(
base = "case.toml"
[[group]]
name = "g"
cross = { "time.dt" = [1e-5, 2e-5] }
)";
  ASSERT_EQ(run(sweep).executed, 2u);
  const fs::path s = out() / "runs" / "g" / "000-time.dt=1e-5" / "summary.json";
  const std::string good = text_of(s);
  auto edit = [&](const std::string& from, const std::string& to) {
    std::string t = good;
    const auto at = t.find(from);
    if (at == std::string::npos) throw std::logic_error("test setup: '" + from + "' not in summary.json");
    return t.replace(at, from.size(), to);
  };
  const std::string wall = good.substr(good.find("\"wall_seconds\": "), good.find(',', good.find("\"wall_seconds\": ")) - good.find("\"wall_seconds\": "));
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"wall_seconds", edit(wall, "\"wall_seconds\": \"x\"")},
      {"cpu_seconds", edit("\"cpu_seconds\": ", "\"cpu_seconds\": null, \"was\": ")},
      {"status", edit("\"status\": \"ok\"", "\"status\": 5")},
      {"status", edit("\"status\": \"ok\"", "\"status\": \"fine\"")},
      {"diverged", edit("\"diverged\": null", "\"diverged\": \"no\"")},
      {"steps", edit("\"steps\": ", "\"steps\": -3, \"was\": ")},
      {"not a JSON object", "[1, 2]"},
  };
  for (const auto& [key, text] : bad) {
    SCOPED_TRACE(key + ": " + text.substr(0, 80));
    std::ofstream(s) << text;
    log_.str("");
    const SweepOutcome o = run(sweep);
    EXPECT_EQ(o.resumed, 1u);
    EXPECT_EQ(o.executed, 1u);
    EXPECT_NE(log_.str().find(s.string() + ": " + key), std::string::npos) << log_.str();
    EXPECT_NE(log_.str().find("run again"), std::string::npos) << log_.str();
    const Json now = read_json_file(s);
    EXPECT_TRUE(now.at("wall_seconds").is_number());
    EXPECT_EQ(now.at("status").get<std::string>(), "ok");
  }
}
