// Sharded sweeps (docs/sweeps.md, "Sharded sweeps"): the assignment of runs to shards (disjoint,
// covering, balanced, the documented rule, the same on a fresh run and on a resume), shards run
// one after another and two at once into one folder and merged into the summary.csv of a sweep
// without --shard (errors against a shared reference with its check run and a group's own
// reference included, a failed run included), a missing shard (listed, exit 3, gates not
// checked), runs of another sweep definition (refused), a shard killed by SIGKILL and run again
// (nothing lost, nothing run twice), the locks between shards, sweeps and merges, and the
// command line's checks of --shard and --merge.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <numeric>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "harness/input/input_error.hpp"
#include "harness/outputs/json_io.hpp"
#include "harness/sweeps/sweep.hpp"
#include "harness/sweeps/sweep_shard.hpp"
#include "harness/sweeps/sweep_spec.hpp"
#include "tests/support/run_program.hpp"
#include "tests/support/small_cases.hpp"
#include "tests/support/summary_table.hpp"
#include "tests/support/temp_dir.hpp"

namespace fs = std::filesystem;
using namespace ricochet;

namespace {

// The tiny vibrating plate of the sweep tests: `bad` names a mesh file that does not exist (the run
// passes validation and fails when it builds the mesh).
const std::string kCase = test_support::tiny_plate_case();

// A shared reference with its check run, a group compared with it (with a failed run), a group
// with its own reference runs, and a group compared with nothing: 13 runs.
const std::string kSweep = R"(
name = "shardy"
base = "case.toml"
[reference]
name = "conv"
set = { "time.dt" = 2.5e-6 }
check = { "time.dt" = 5e-6 }
[[group]]
name = "g"
cross = { "time.dt" = [1e-5, 2e-5, 4e-5], "bodies[0].element" = ["q4", "q4_hourglass"] }
[[group]]
name = "own"
cross = { "time.dt" = [1e-5, 2e-5] }
reference = { "time.dt" = 5e-6 }
[[group]]
name = "plain"
cross = { mesh = ["m", "bad"] }
reference = false
)";

const std::string kGates = R"(
[[gate]]
name = "energy"
kind = "max"
column = "error_energy"
limit = 1.0
where = { group = "g" }
[[gate]]
name = "rows"
kind = "count"
min = 13
)";

using test_support::text_of;

using Table = test_support::SummaryTable;
Table read_table(const fs::path& p) { return test_support::read_summary_table(p); }

// Two summary.csv files are the same table but for the timing columns: the same header, the same
// rows in the same order, every other cell equal.
void expect_same_table(const fs::path& a, const fs::path& b) {
  const Table x = read_table(a), y = read_table(b);
  ASSERT_EQ(x.header, y.header);
  ASSERT_EQ(x.ids(), y.ids());
  std::size_t compared = 0;
  for (std::size_t r = 0; r < x.rows.size(); ++r) {
    for (const std::string& column : x.header) {
      if (test_support::is_measurement_column(column)) continue;
      EXPECT_EQ(x.cell(r, column), y.cell(r, column)) << x.cell(r, "run_id") << " " << column;
      ++compared;
    }
  }
  EXPECT_GT(compared, 500u);
}

using test_support::start_process;
using test_support::wait_exit;

using Outcome = test_support::ProgramOutcome;

// `ricochet ARGS` through /bin/sh.
Outcome program(const std::string& args) { return test_support::run_ricochet(args); }

long long mtime_ns(const fs::path& p) {
  struct stat st {};
  if (stat(p.c_str(), &st) != 0) return -1;
  return static_cast<long long>(st.st_mtim.tv_sec) * 1000000000LL + st.st_mtim.tv_nsec;
}

// The processes with an argument that starts with `dir` (zombies left out).
std::vector<pid_t> processes_using(const fs::path& dir) {
  std::vector<pid_t> found;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator("/proc", ec)) {
    const std::string name = e.path().filename().string();
    if (name.empty() || name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::stringstream cmd;
    cmd << std::ifstream(e.path() / "cmdline").rdbuf();
    bool uses = false;
    std::string word;
    while (std::getline(cmd, word, '\0')) uses = uses || word.rfind(dir.string(), 0) == 0;
    const std::string st = text_of(e.path() / "stat");
    const auto close = st.rfind(')');
    if (uses && close != std::string::npos && st.size() > close + 2 && st[close + 2] != 'Z') found.push_back(std::stoi(name));
  }
  return found;
}

class SweepShardTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test_support::fresh_test_dir("ricochet_shard_");
    write("case.toml", kCase);
    write("gates.toml", kGates);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& text) const {
    return test_support::write_text(dir_ / name, text);
  }
  fs::path out(const std::string& name = "out") const { return dir_ / name; }

  SweepOptions options(const fs::path& out_dir, std::optional<SweepShard> shard = std::nullopt, int repeat = 1) {
    SweepOptions o;
    o.out_dir = out_dir;
    o.shard = shard;
    o.repeat = repeat;
    o.executable = RICOCHET_BINARY;
    o.log = &log_;
    return o;
  }

  // Runs shard k/n (or the whole sweep) of `file` in this process.
  SweepOutcome run(const std::string& file, const fs::path& out_dir, std::optional<SweepShard> shard = std::nullopt) {
    const SweepSpec spec = read_sweep(file);
    return run_sweep(spec, expand(spec), options(out_dir, shard));
  }

  MergeOutcome merge(const std::string& file, const fs::path& out_dir, int repeat = 1) {
    const SweepSpec spec = read_sweep(file);
    return merge_sweep(spec, expand(spec), options(out_dir, std::nullopt, repeat));
  }

  // The ids of the runs of shard k of n, from the assignment.
  std::vector<std::string> shard_ids(const std::string& file, int k, int n) const {
    const std::vector<SweepRun> runs = expand(read_sweep(file));
    const std::vector<bool> in = shard_scope(runs, {k, n});
    std::vector<std::string> ids;
    for (std::size_t i = 0; i < runs.size(); ++i)
      if (in[i]) ids.push_back(runs[i].id);
    return ids;
  }

  fs::path dir_;
  std::ostringstream log_;
};

std::vector<std::string> json_strings(const Json& a) {
  std::vector<std::string> v;
  for (const Json& x : a) v.push_back(x.get<std::string>());
  return v;
}

std::uint64_t fnv1a64(const std::string& s) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

}  // namespace

// ---- the assignment ----------------------------------------------------------------------------

// For several sweeps and several N: every run in exactly one shard, the shards' sizes differ by at
// most one, and the assignment is the documented rule (runs ordered by the FNV-1a hash of their
// id, dealt out in turn), computed again from a fresh read of the sweep file.
TEST_F(SweepShardTest, ShardsAreDisjointCoverTheRunsAndFollowTheDocumentedRule) {
  const std::string big = write("big.toml", R"(
base = "case.toml"
[reference]
set = { "time.dt" = 2.5e-6 }
check = { "time.dt" = 5e-6 }
[[group]]
name = "a"
cross = { "time.dt" = [1e-5, 2e-5, 4e-5, 5e-5], "bodies[0].element" = ["q4", "q4_hourglass", "t3"], description = ["x", "y", "z"] }
[[group]]
name = "b"
cross = { "time.dt" = [1e-5, 2e-5] }
reference = { "time.dt" = 5e-6 }
)");
  const std::string small = write("small.toml", kSweep);
  for (const std::string& file : {small, big}) {
    const std::vector<SweepRun> runs = expand(read_sweep(file));
    const std::size_t total = runs.size();
    for (const int n : {1, 2, 3, 4, 5, 7, 13, 40, 100}) {
      SCOPED_TRACE(file + " N = " + std::to_string(n));
      std::vector<int> owners(total, 0);
      std::size_t smallest = total, largest = 0;
      for (int k = 1; k <= n; ++k) {
        const std::vector<bool> in = shard_scope(runs, {k, n});
        ASSERT_EQ(in.size(), total);
        const auto size = static_cast<std::size_t>(std::count(in.begin(), in.end(), true));
        smallest = std::min(smallest, size);
        largest = std::max(largest, size);
        for (std::size_t i = 0; i < total; ++i) owners[i] += in[i];
      }
      for (std::size_t i = 0; i < total; ++i) EXPECT_EQ(owners[i], 1) << runs[i].id;
      EXPECT_EQ(smallest, total / static_cast<std::size_t>(n));
      EXPECT_EQ(largest, (total + static_cast<std::size_t>(n) - 1) / static_cast<std::size_t>(n));

      // The rule of docs/sweeps.md.
      std::vector<std::size_t> order(total);
      std::iota(order.begin(), order.end(), std::size_t{0});
      std::stable_sort(order.begin(), order.end(),
                       [&](std::size_t a, std::size_t b) { return fnv1a64(runs[a].id) < fnv1a64(runs[b].id); });
      const std::vector<int> shard = shard_assignment(expand(read_sweep(file)), n);
      for (std::size_t j = 0; j < total; ++j)
        EXPECT_EQ(shard[order[j]], static_cast<int>(j % static_cast<std::size_t>(n)) + 1) << runs[order[j]].id;
    }
  }
  EXPECT_EQ(expand(read_sweep(big)).size(), 2u + 36u + 2u + 1u);
}

TEST(SweepShardValue, KOfNIsParsedAndBadValuesAreOneLineNamingTheOption) {
  const SweepShard s = parse_shard("3/8");
  EXPECT_EQ(s.k, 3);
  EXPECT_EQ(s.n, 8);
  EXPECT_EQ(s.name(), "3-of-8");
  EXPECT_EQ(parse_shard("1/1").n, 1);
  EXPECT_EQ(parse_shard("100000/100000").k, 100000);
  for (const std::string bad : {"", "0/2", "3/2", "1/0", "2", "/2", "1/", "a/b", "1/2/3", "-1/2", "1.5/2", "1/100001", " 1/2",
                                "1/2 ", "+1/2", "0x1/2"}) {
    try {
      parse_shard(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind("ricochet sweep: --shard: ", 0), 0u) << msg;
      EXPECT_NE(msg.find("'" + bad + "'"), std::string::npos) << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
  }
}

// A shard runs exactly its runs, and the same ones when it is run again after some of them were
// lost: the assignment does not depend on what is done. It writes nothing of other shards' runs
// and no DIR/summary.csv or DIR/sweep.json.
TEST_F(SweepShardTest, AShardRunsItsRunsAndTheSameOnesWhenResumed) {
  const std::string file = write("sweep.toml", kSweep);
  const std::vector<std::string> mine = shard_ids(file, 2, 3);
  ASSERT_GE(mine.size(), 4u);
  const SweepOutcome fresh = run(file, out(), SweepShard{2, 3});
  EXPECT_EQ(fresh.total, mine.size());
  EXPECT_EQ(fresh.executed, mine.size());
  const Json m1 = read_json_file(out() / "shards/2-of-3/shard.json");
  EXPECT_EQ(json_strings(m1.at("runs")), mine);
  EXPECT_EQ(m1.at("shard").get<int>(), 2);
  EXPECT_EQ(m1.at("shards").get<int>(), 3);
  EXPECT_EQ(m1.at("total_runs").get<std::size_t>(), 13u);
  EXPECT_FALSE(m1.at("finished_at").is_null());
  EXPECT_EQ(m1.at("counts").at("executed").get<std::size_t>(), mine.size());
  EXPECT_FALSE(fs::exists(out() / "summary.csv"));
  EXPECT_FALSE(fs::exists(out() / "sweep.json"));
  // Its own table: its runs, without errors (a reference may be another shard's).
  const Table t = read_table(out() / "shards/2-of-3/summary.csv");
  EXPECT_EQ(t.ids(), mine);
  for (std::size_t r = 0; r < t.rows.size(); ++r) EXPECT_EQ(t.cell(r, "error_energy"), "") << t.cell(r, "run_id");
  // Only its run folders.
  std::set<std::string> folders;
  for (const auto& e : fs::recursive_directory_iterator(out() / "runs"))
    if (fs::exists(e.path() / "overrides.json")) folders.insert(fs::relative(e.path(), out() / "runs").string());
  EXPECT_EQ(folders, std::set<std::string>(mine.begin(), mine.end()));

  // Two of its runs lost: the same shard runs those two again, nothing else.
  fs::remove(out() / "runs" / mine[0] / "summary.json");
  fs::remove_all(out() / "runs" / mine[1]);
  const long long kept = mtime_ns(out() / "runs" / mine[2] / "summary.json");
  log_.str("");
  const SweepOutcome resumed = run(file, out(), SweepShard{2, 3});
  EXPECT_EQ(resumed.total, mine.size());
  EXPECT_EQ(resumed.resumed, mine.size() - 2);
  EXPECT_EQ(resumed.executed, 2u);
  EXPECT_EQ(json_strings(read_json_file(out() / "shards/2-of-3/shard.json").at("runs")), mine);
  EXPECT_EQ(mtime_ns(out() / "runs" / mine[2] / "summary.json"), kept);
  EXPECT_NE(log_.str().find("sweep shardy, shard 2 of 3: " + std::to_string(mine.size()) + " of 13 runs"), std::string::npos)
      << log_.str();
  EXPECT_NE(log_.str().find("[" + std::to_string(mine.size()) + "/" + std::to_string(mine.size()) + "] "), std::string::npos)
      << log_.str();
}

// ---- shards and the merge ------------------------------------------------------------------------

// The shards run one after another, or two at once into one folder, then merged: the summary.csv
// of a sweep without --shard, cell for cell but for the timings, errors against both kinds of
// reference and the floors included; the same sweep.json run list and reference; gates pass on it
// through --merge --check and through `ricochet check`.
TEST_F(SweepShardTest, MergedShardsGiveTheTableOfASweepWithoutShards) {
  const std::string file = write("sweep.toml", kSweep);
  const SweepOutcome single = run(file, out("single"));
  EXPECT_EQ(single.total, 13u);
  EXPECT_EQ(single.failed, 1u);

  // One after another.
  std::size_t executed = 0, failed = 0;
  for (int k = 1; k <= 3; ++k) {
    const SweepOutcome s = run(file, out("seq"), SweepShard{k, 3});
    executed += s.executed;
    failed += s.failed;
  }
  EXPECT_EQ(executed, 13u);
  EXPECT_EQ(failed, 1u);
  const Outcome m = program("sweep " + file + " --out " + out("seq").string() + " --merge --check " + (dir_ / "gates.toml").string());
  EXPECT_EQ(m.status, 0) << m.output;
  EXPECT_NE(m.output.find("merged 13 of 13 runs (12 ok, 0 diverged, 1 failed)"), std::string::npos) << m.output;
  EXPECT_NE(m.output.find("failed: plain/001-mesh=bad: exit 2: ricochet: "), std::string::npos) << m.output;
  EXPECT_TRUE(fs::exists(out("seq") / "gates-junit.xml"));
  expect_same_table(out("single") / "summary.csv", out("seq") / "summary.csv");

  // Two at once.
  std::vector<pid_t> shards;
  for (int k = 1; k <= 2; ++k)
    shards.push_back(start_process({RICOCHET_BINARY, "sweep", file, "--out", out("par").string(), "--shard",
                                    std::to_string(k) + "/2"},
                                   dir_ / ("par" + std::to_string(k) + ".log")));
  for (int k = 1; k <= 2; ++k) EXPECT_EQ(wait_exit(shards[k - 1]), 0) << text_of(dir_ / ("par" + std::to_string(k) + ".log"));
  const MergeOutcome mp = merge(file, out("par"));
  EXPECT_TRUE(mp.complete());
  EXPECT_EQ(mp.ok, 12u);
  EXPECT_EQ(mp.failed, 1u);
  expect_same_table(out("single") / "summary.csv", out("par") / "summary.csv");

  // The errors are there: every ok run compared with a reference has them, the floors too.
  const Table t = read_table(out("par") / "summary.csv");
  std::size_t with_errors = 0;
  for (std::size_t r = 0; r < t.rows.size(); ++r)
    if (t.cell(r, "status") == "ok" && !t.cell(r, "reference_run").empty()) {
      EXPECT_NE(t.cell(r, "error_energy"), "") << t.cell(r, "run_id");
      EXPECT_NE(t.cell(r, "error_probe_P"), "") << t.cell(r, "run_id");
      if (t.cell(r, "reference_kind") == "shared") {
        EXPECT_NE(t.cell(r, "floor_energy"), "") << t.cell(r, "run_id");
      }
      ++with_errors;
    }
  EXPECT_EQ(with_errors, 1u + 6u + 2u);  // the check run, group g, group own

  // sweep.json: the same sweep, runs and reference; the merge's own record.
  const Json a = read_json_file(out("single") / "sweep.json"), b = read_json_file(out("par") / "sweep.json");
  for (const char* key : {"sweep", "sweep_file", "base", "total_runs", "runs", "reference", "repeat"})
    EXPECT_EQ(a.at(key), b.at(key)) << key;
  EXPECT_EQ(b.at("counts").at("ok").get<int>(), 12);
  EXPECT_EQ(b.at("counts").at("failed").get<int>(), 1);
  EXPECT_FALSE(b.at("finished_at").is_null());
  EXPECT_FALSE(a.contains("merge"));
  const Json& mj = b.at("merge");
  EXPECT_TRUE(mj.at("complete").get<bool>());
  EXPECT_EQ(mj.at("shards").size(), 2u);
  EXPECT_EQ(mj.at("missing").size(), 0u);
  ASSERT_EQ(mj.at("failed").size(), 1u);
  EXPECT_EQ(mj.at("failed")[0].at("id").get<std::string>(), "plain/001-mesh=bad");
  // Both shards ran on this host at the same time: two runs at once, as --jobs 2 would.
  EXPECT_EQ(b.at("jobs").get<int>(), 2);
  EXPECT_EQ(read_json_file(out("seq") / "sweep.json").at("jobs").get<int>(), 1);

  const Outcome c = program("check " + (out("par") / "summary.csv").string() + " " + (dir_ / "gates.toml").string());
  EXPECT_EQ(c.status, 0) << c.output;
}

// A shard that has not run: the merge lists each of its runs, names the shard and the command
// that runs it, checks no gates, leaves no gate report, and exits 3; once it has run, the merge is
// complete.
TEST_F(SweepShardTest, AMissingShardIsListedAndTheMergeExitsThree) {
  const std::string file = write("sweep.toml", kSweep);
  run(file, out(), SweepShard{1, 3});
  run(file, out(), SweepShard{3, 3});
  std::ofstream(out() / "gates-junit.xml") << "<testsuites/>\n";  // an earlier merge's report
  const std::string merge_args =
      "sweep " + file + " --out " + out().string() + " --merge --check " + (dir_ / "gates.toml").string();
  const Outcome m = program(merge_args);
  EXPECT_EQ(m.status, 3) << m.output;
  const std::vector<std::string> missing = shard_ids(file, 2, 3);
  for (const std::string& id : missing)
    EXPECT_NE(m.output.find("missing: " + id + " (shard 2 of 3): not run"), std::string::npos) << id << ": " << m.output;
  for (const std::string& id : shard_ids(file, 1, 3)) EXPECT_EQ(m.output.find("missing: " + id + " "), std::string::npos) << id;
  EXPECT_NE(m.output.find("shard 2 of 3: " + std::to_string(missing.size()) + " run(s) missing; it has not run"),
            std::string::npos)
      << m.output;
  EXPECT_NE(m.output.find("--out " + out().string() + " --shard 2/3"), std::string::npos) << m.output;
  EXPECT_NE(m.output.find("gates not checked"), std::string::npos) << m.output;
  EXPECT_FALSE(fs::exists(out() / "gates-junit.xml"));
  const Table t = read_table(out() / "summary.csv");
  EXPECT_EQ(t.rows.size(), 13u - missing.size());
  for (const std::string& id : t.ids()) EXPECT_EQ(std::count(missing.begin(), missing.end(), id), 0) << id;
  const Json sj = read_json_file(out() / "sweep.json");
  EXPECT_TRUE(sj.at("finished_at").is_null());
  EXPECT_FALSE(sj.at("merge").at("complete").get<bool>());
  ASSERT_EQ(sj.at("merge").at("missing").size(), missing.size());
  EXPECT_EQ(sj.at("merge").at("missing")[0].at("shard").get<int>(), 2);

  run(file, out(), SweepShard{2, 3});
  const Outcome done = program(merge_args);
  EXPECT_EQ(done.status, 0) << done.output;
  EXPECT_EQ(read_table(out() / "summary.csv").rows.size(), 13u);
  EXPECT_TRUE(fs::exists(out() / "gates-junit.xml"));
}

// Run folders written by another definition of the sweep (another value in the sweep file,
// another base case text, another --repeat) are never merged: each is listed as refused, with
// what differs, and the merge exits 3. Running the shards of the current definition replaces them.
TEST_F(SweepShardTest, RunsOfAnotherSweepDefinitionAreRefused) {
  const std::string file = write("sweep.toml", kSweep);
  run(file, out(), SweepShard{1, 2});
  // The definition changes before shard 2 runs: group g's runs get another end time.
  std::string changed = kSweep;
  changed.replace(changed.find("name = \"g\"\n"), 11, "name = \"g\"\nset = { \"time.end\" = 1e-3 }\n");
  write("sweep.toml", changed);
  run(file, out(), SweepShard{2, 2});
  const std::vector<std::string> first = shard_ids(file, 1, 2);
  std::vector<std::string> refused;
  for (const std::string& id : first)
    if (id.rfind("g/", 0) == 0) refused.push_back(id);
  ASSERT_FALSE(refused.empty());

  const Outcome m = program("sweep " + file + " --out " + out().string() + " --merge");
  EXPECT_EQ(m.status, 3) << m.output;
  for (const std::string& id : refused)
    EXPECT_NE(m.output.find("missing: " + id + " (shard 1 of 2): from another sweep definition, not merged: it ran with "
                            "the overrides"),
              std::string::npos)
        << id << ": " << m.output;
  EXPECT_NE(m.output.find("shards/1-of-2/shard.json: its last run was of another sweep definition"), std::string::npos)
      << m.output;
  const Table t = read_table(out() / "summary.csv");
  EXPECT_EQ(t.rows.size(), 13u - refused.size());
  const std::vector<std::string> merged = t.ids();
  for (const std::string& id : refused) EXPECT_EQ(std::count(merged.begin(), merged.end(), id), 0) << id << " was merged";
  for (std::size_t r = 0; r < t.rows.size(); ++r)
    if (t.cell(r, "group") == "g") {
      EXPECT_EQ(t.cell(r, "time.end"), "0.001") << t.cell(r, "run_id");
    }

  // Shard 1 of the current definition runs them again; then the merge is complete.
  run(file, out(), SweepShard{1, 2});
  EXPECT_TRUE(merge(file, out()).complete());

  // Another base case text, and another --repeat: refused too, saying so.
  write("case.toml", kCase + "\n# edited\n");
  log_.str("");
  const MergeOutcome edited = merge(file, out());
  EXPECT_EQ(edited.missing.size(), 13u);
  for (const MissingRun& r : edited.missing) EXPECT_TRUE(r.foreign) << r.id;
  EXPECT_NE(log_.str().find("has changed since it ran"), std::string::npos) << log_.str();
  EXPECT_EQ(read_table(out() / "summary.csv").rows.size(), 0u);
  write("case.toml", kCase);
  log_.str("");
  const MergeOutcome repeated = merge(file, out(), 3);
  EXPECT_FALSE(repeated.complete());
  EXPECT_NE(log_.str().find("it ran with --repeat 1, this merge has --repeat 3"), std::string::npos) << log_.str();
  EXPECT_TRUE(merge(file, out()).complete());
}

// A shard killed by SIGKILL in the middle of a run while the other shard runs beside it, then
// run again: its finished run is reused, the killed run runs again, the other shard's runs are
// never touched, and the merge is complete. Every run completed exactly once over the three
// invocations (their progress lines), each run folder is complete, and no run of the killed shard
// outlives it.
TEST_F(SweepShardTest, ASigkilledShardRunAgainCompletesTheSweepWithNothingLostOrRunTwice) {
  std::string slow = kCase;
  slow.replace(slow.find("nx = 4"), 6, "nx = 40");
  slow.replace(slow.find("ny = 2"), 6, "ny = 20");
  slow.replace(slow.find("end = 2e-3"), 10, "end = 0.4");
  slow.replace(slow.find("interval = 1e-4"), 15, "interval = 1e-3\nfields = [0.01]");
  write("slow.toml", "threads = 1\n" + slow);
  const std::string file = write("kill.toml", R"(
name = "kill"
base = "slow.toml"
[[group]]
name = "g"
cross = { "output.interval" = [1e-3, 2e-3, 4e-3, 5e-3] }
)");
  const std::vector<std::string> one = shard_ids(file, 1, 2), two = shard_ids(file, 2, 2);
  ASSERT_EQ(one.size(), 2u);
  ASSERT_EQ(two.size(), 2u);
  auto args = [&](int k) {
    return std::vector<std::string>{RICOCHET_BINARY, "sweep", file, "--out", out().string(), "--shard", std::to_string(k) + "/2"};
  };
  using Clock = std::chrono::steady_clock;
  auto wait_for = [](const std::function<bool()>& done, double seconds) {
    const auto until = Clock::now() + std::chrono::duration<double>(seconds);
    while (!done() && Clock::now() < until) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    return done();
  };

  const pid_t other = start_process(args(2), dir_ / "two.log");
  const pid_t killed = start_process(args(1), dir_ / "one-killed.log");
  const fs::path second = out() / "runs" / one[1];
  const bool started = wait_for([&] { return fs::exists(second / "stderr.txt"); }, 120.0);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const bool unfinished = !fs::exists(second / "summary.json");
  kill(killed, SIGKILL);
  wait_exit(killed);
  ASSERT_TRUE(started) << text_of(dir_ / "one-killed.log");
  ASSERT_TRUE(unfinished) << "the runs are too short for this machine: make the case longer";
  ASSERT_TRUE(fs::exists(out() / "runs" / one[0] / "summary.json"));
  const long long first_done = mtime_ns(out() / "runs" / one[0] / "summary.json");
  // Its run dies with it (PR_SET_PDEATHSIG): nothing writes the killed run's folder.
  EXPECT_TRUE(wait_for([&] { return processes_using(second).empty(); }, 5.0)) << "a run of the killed shard lives on";
  EXPECT_TRUE(read_json_file(out() / "shards/1-of-2/shard.json").at("finished_at").is_null());

  // The merge meanwhile: the killed shard's run is missing, and it says the shard did not finish.
  log_.str("");
  const MergeOutcome during = merge(file, out());
  EXPECT_FALSE(during.complete());
  EXPECT_NE(log_.str().find("missing: " + one[1] + " (shard 1 of 2): "), std::string::npos) << log_.str();

  EXPECT_EQ(wait_exit(other), 0) << text_of(dir_ / "two.log");
  const std::map<std::string, long long> other_done = {
      {two[0], mtime_ns(out() / "runs" / two[0] / "summary.json")}, {two[1], mtime_ns(out() / "runs" / two[1] / "summary.json")}};
  const pid_t again = start_process(args(1), dir_ / "one-again.log");
  EXPECT_EQ(wait_exit(again), 0) << text_of(dir_ / "one-again.log");
  EXPECT_NE(text_of(dir_ / "one-again.log").find("2 of 4 runs, 1 done before, 1 to run"), std::string::npos)
      << text_of(dir_ / "one-again.log");
  EXPECT_EQ(mtime_ns(out() / "runs" / one[0] / "summary.json"), first_done);
  for (const auto& [id, t] : other_done) EXPECT_EQ(mtime_ns(out() / "runs" / id / "summary.json"), t) << id;

  const MergeOutcome m = merge(file, out());
  EXPECT_TRUE(m.complete());
  EXPECT_EQ(m.ok, 4u);
  // Each run completed once: one progress line over the three shard invocations.
  const std::string logs = text_of(dir_ / "one-killed.log") + text_of(dir_ / "two.log") + text_of(dir_ / "one-again.log");
  for (const auto& ids : {one, two})
    for (const std::string& id : ids) {
      std::size_t count = 0;
      for (auto at = logs.find("] " + id + " ok wall "); at != std::string::npos; at = logs.find("] " + id + " ok wall ", at + 1))
        ++count;
      EXPECT_EQ(count, 1u) << id << " completed " << count << " times:\n" << logs;
    }
  const Table t = read_table(out() / "summary.csv");
  ASSERT_EQ(t.rows.size(), 4u);
  std::set<std::string> written;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    const std::string id = t.cell(r, "run_id");
    EXPECT_EQ(t.cell(r, "status"), "ok") << id;
    const fs::path f = out() / "runs" / id;
    const Json s = read_json_file(f / "summary.json");
    EXPECT_EQ(t.cell(r, "written_at"), s.at("written_at").get<std::string>()) << id;
    EXPECT_EQ(static_cast<long>(test_support::csv_records(text_of(f / "history.csv")).size()) - 1, s.at("history_rows").get<long>()) << id;
    for (const auto& e : fs::directory_iterator(f)) {
      const std::string name = e.path().filename().string();
      EXPECT_EQ(name.find(".tmp"), std::string::npos) << id << ": " << name;
      EXPECT_NE(name.rfind(".staging", 0), 0u) << id << ": " << name;
    }
    EXPECT_FALSE(fs::exists(f / "failure.json")) << id;
  }
  EXPECT_TRUE(wait_for([&] { return processes_using(out()).empty(); }, 5.0)) << "processes left in the sweep's folder";
}

// ---- locks -------------------------------------------------------------------------------------

namespace {

// Holds an flock on `file` while it lives, as another process would.
struct HeldLock {
  int fd = -1;
  HeldLock(const fs::path& file, bool exclusive) {
    fs::create_directories(file.parent_path());
    fd = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    EXPECT_EQ(flock(fd, exclusive ? LOCK_EX : LOCK_SH), 0);
  }
  ~HeldLock() { ::close(fd); }
};

}  // namespace

// A shard never runs twice at once; shards and merges run beside each other (sweep.lock shared);
// a sweep without --shard runs beside none of them; two merges never run at once. Each refusal is
// one line, exit 1 (std::runtime_error, not bad input), with nothing run.
TEST_F(SweepShardTest, LocksKeepAShardSingleAndSweepsWithoutShardsAlone) {
  const std::string file = write("sweep.toml", kSweep);
  fs::create_directories(out());
  auto refused = [&](const std::function<void()>& f, const std::string& part) {
    try {
      f();
      ADD_FAILURE() << "not refused: " << part;
    } catch (const InputError& e) {
      ADD_FAILURE() << "bad input: " << e.what();
    } catch (const std::runtime_error& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(part), std::string::npos) << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
  };
  {
    const HeldLock shard(out() / "shards/1-of-2/shard.lock", true);
    refused([&] { run(file, out(), SweepShard{1, 2}); }, "shard 1 of 2 is already running in this folder");
  }
  EXPECT_FALSE(fs::exists(out() / "runs"));
  {
    const HeldLock shard(out() / "sweep.lock", false);  // a shard running
    refused([&] { run(file, out()); }, "another sweep is running in this folder");
    EXPECT_EQ(run(file, out(), SweepShard{2, 2}).executed, shard_ids(file, 2, 2).size());
    EXPECT_FALSE(merge(file, out()).complete());
  }
  {
    const HeldLock single(out() / "sweep.lock", true);  // a sweep without --shard running
    refused([&] { run(file, out(), SweepShard{1, 2}); }, "a sweep without --shard is running in this folder");
    refused([&] { merge(file, out()); }, "a sweep without --shard is running in this folder");
  }
  {
    const HeldLock other_merge(out() / "merge.lock", true);
    refused([&] { merge(file, out()); }, "another merge is running in this folder");
  }
}

// A run folder still being written (its run.lock held) is a missing run to the merge, which does
// not wait for it.
TEST_F(SweepShardTest, TheMergeDoesNotWaitForARunBeingWritten) {
  const std::string file = write("sweep.toml", kSweep);
  run(file, out(), SweepShard{1, 1});
  const std::string id = shard_ids(file, 1, 1)[3];
  const HeldLock writer(out() / "runs" / id / "run.lock", true);
  log_.str("");
  const auto t0 = std::chrono::steady_clock::now();
  const MergeOutcome m = merge(file, out());
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
  ASSERT_EQ(m.missing.size(), 1u);
  EXPECT_EQ(m.missing[0].id, id);
  EXPECT_NE(m.missing[0].why.find("being written by"), std::string::npos) << m.missing[0].why;
  EXPECT_EQ(read_table(out() / "summary.csv").rows.size(), 12u);
}

// ---- the command line ----------------------------------------------------------------------------

// --shard's value, and the options that do not go together, are bad input: one line naming the
// option, exit 2, nothing written.
TEST_F(SweepShardTest, CommandLineRejectsBadShardsAndOptionsThatDoNotGoTogether) {
  const std::string file = write("sweep.toml", kSweep);
  const std::string o = " --out " + out().string();
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"--shard 0/4", "--shard"},
      {"--shard 5/4", "--shard"},
      {"--shard 1/0", "--shard"},
      {"--shard 2", "--shard"},
      {"--shard a/b", "--shard"},
      {"--shard", "--shard"},
      {"--shard 1/2 --merge", "--shard and --merge"},
      {"--merge --jobs 2", "--jobs"},
      {"--merge --threads 1", "--threads"},
      {"--merge --force", "--force"},
      {"--shard 1/2 --check " + (dir_ / "gates.toml").string(), "--check"},
      {"--merge", "no such folder"},
  };
  for (const auto& [args, part] : bad) {
    const Outcome r = program("sweep " + file + o + " " + args);
    EXPECT_EQ(r.status, 2) << args << ": " << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << args << ": " << r.output;
    EXPECT_NE(r.output.find(part), std::string::npos) << args << ": " << r.output;
    EXPECT_FALSE(fs::exists(out())) << args << " wrote " << out();
  }
  const Outcome ok = program("sweep " + file + o + " --shard=2/2 --quiet");
  EXPECT_EQ(ok.status, 0) << ok.output;
  EXPECT_EQ(ok.output, "");
}
