// Sweeps submitted to Slurm (docs/sweeps.md, "Running on a cluster"), without Slurm: the two
// sbatch scripts (their #SBATCH lines, the shard and merge commands, every path quoted, run by
// bash from another folder with paths holding spaces and quotes), the --slurm-option checks,
// --dry-run (prints, writes nothing), the submission through a stand-in sbatch on PATH (its
// arguments, the dependency, the job ids printed, its failures), a missing sbatch, the options
// that do not go together, and the scripts run by hand as Slurm would run them giving the
// summary.csv of a sweep without shards. ci/slurm-test runs them on a real one-node Slurm.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "harness/input/input_error.hpp"
#include "harness/outputs/csv_reader.hpp"
#include "harness/outputs/json_io.hpp"
#include "harness/sweeps/sweep_slurm.hpp"
#include "tests/support/run_program.hpp"
#include "tests/support/small_cases.hpp"
#include "tests/support/summary_table.hpp"
#include "tests/support/temp_dir.hpp"

namespace fs = std::filesystem;
using namespace ricochet;

namespace {

// The tiny vibrating plate of the sweep tests (runs of a few milliseconds).
const std::string kCase = test_support::tiny_plate_case(false);

// Three runs against their group's own reference run, and two compared with nothing: 6 runs.
const std::string kSweep = R"(
name = "slurmy"
base = "case.toml"
[[group]]
name = "g"
cross = { "time.dt" = [1e-5, 2e-5, 4e-5] }
reference = { "time.dt" = 5e-6 }
[[group]]
name = "e"
cross = { "bodies[0].element" = ["q4", "q4_hourglass"] }
)";

const std::string kGates = R"(
[[gate]]
name = "rows"
kind = "count"
min = 6
)";

using test_support::text_of;

void write_file(const fs::path& p, const std::string& text, bool executable = false) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
  if (executable) fs::permissions(p, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec, fs::perm_options::replace);
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> v;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) v.push_back(l);
  return v;
}

bool has_line(const std::string& text, const std::string& line) {
  const std::vector<std::string> v = lines_of(text);
  return std::find(v.begin(), v.end(), line) != v.end();
}

// The #SBATCH lines of a script, in order.
std::vector<std::string> sbatch_lines(const std::string& script) {
  std::vector<std::string> v;
  for (const std::string& l : lines_of(script))
    if (l.rfind("#SBATCH ", 0) == 0) v.push_back(l.substr(8));
  return v;
}

struct Outcome {
  int status = -1;
  std::string out, err;
};

// `ricochet ARGS` through /bin/sh, after `prefix` (e.g. "cd DIR && PATH=... "), stdout and stderr apart.
Outcome program(const std::string& args, const std::string& prefix, const fs::path& err_file) {
  const std::string cmd = prefix + " " + shell_quote(RICOCHET_BINARY) + " " + args + " 2>" + shell_quote(err_file.string());
  const test_support::ProgramOutcome r = test_support::run_shell(cmd);
  return {r.status, r.output, text_of(err_file)};
}

class SweepSlurmTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // Spaces and a single quote in every path the scripts name.
    dir_ = test_support::fresh_test_dir("ricochet_slurm_") / "it's a dir";
    fs::create_directories(dir_);
    write_file(dir_ / "case.toml", kCase);
    write_file(dir_ / "sweep.toml", kSweep);
    write_file(dir_ / "gates.toml", kGates);
  }
  void TearDown() override { fs::remove_all(dir_.parent_path()); }

  // A stand-in for sbatch in DIR/fake bin/: records each call's arguments (one line each, words
  // separated by '|') in DIR/sbatch.log and answers the job id 100 + the call's number (as
  // `--parsable` does, with a cluster name after ';'); calls number `fail_at` and later exit 1
  // with Slurm's message.
  fs::path fake_sbatch(int fail_at = 0) const {
    const fs::path bin = dir_ / "fake bin";
    const std::string log = shell_quote((dir_ / "sbatch.log").string());
    std::string s = "#!/bin/bash\n";
    s += "line=''; for a in \"$@\"; do line=\"$line|$a\"; done; printf '%s\\n' \"$line\" >> " + log + "\n";
    s += "n=$(/usr/bin/wc -l < " + log + ")\n";
    if (fail_at > 0)
      s += "if [ \"$n\" -ge " + std::to_string(fail_at) +
           " ]; then echo 'sbatch: error: Batch job submission failed: Invalid partition name specified' >&2; exit 1; fi\n";
    s += "echo \"$((100 + n));cluster\"\n";
    write_file(bin / "sbatch", s, true);
    return bin;
  }

  // "cd DIR && PATH=BIN:$PATH" for program().
  std::string in_dir(const fs::path& bin = {}) const {
    std::string p = "cd " + shell_quote(dir_.string()) + " &&";
    if (!bin.empty()) p += " PATH=" + shell_quote(bin.string()) + ":\"$PATH\"";
    return p;
  }

  fs::path dir_;
};

SlurmJobs sample_jobs(const fs::path& dir) {
  SlurmJobs j;
  j.sweep_name = "slurmy";
  j.sweep_file = "cases/my sweep.toml";
  j.out_dir = "results/it's 100%";
  j.workdir = dir;
  j.program = dir / "bin dir" / "ricochet";
  j.shards = 4;
  j.jobs = 2;
  j.threads = 3;
  j.repeat = 5;
  j.force = true;
  j.quiet = true;
  j.gates_file = "ci/my gates.toml";
  j.options = {"--partition=short", "--time=0:30:00", "--array=2", "--account=proj 1"};
  return j;
}

}  // namespace

// ---- the scripts -------------------------------------------------------------------------------

// The array script: one task per shard (1 ... N), one CPU per thread of each of the shard's
// --jobs runs, its log in DIR/slurm/ (% doubled, in double quotes; appended to when Slurm
// requeues the task), the --slurm-option values
// last (so that they override ours, --array included), and the shard command with every option
// of the submitting command; the merge script: one CPU, no --array option, the merge with
// --repeat and --check. Every path in single quotes.
TEST_F(SweepSlurmTest, TheScriptsHoldTheShardAndMergeCommandsAndTheOptions) {
  const SlurmJobs j = sample_jobs(dir_);
  const SlurmScripts s = slurm_scripts(j);
  const std::string abs_slurm = (dir_ / "results/it's 100%/slurm").string();
  EXPECT_EQ(j.array_file(), fs::path(abs_slurm) / "array.sbatch");
  EXPECT_EQ(j.merge_file(), fs::path(abs_slurm) / "merge.sbatch");

  EXPECT_EQ(lines_of(s.array).front(), "#!/bin/bash");
  const std::vector<std::string> a = sbatch_lines(s.array);
  const std::vector<std::string> a_expected = {"--job-name=ricochet-slurmy",
                                               "--array=1-4",
                                               "--ntasks=1",
                                               "--cpus-per-task=6",
                                               "--output=\"" + (dir_ / "results/it's 100%%/slurm/shard-%a-%A.out").string() + "\"",
                                               "--open-mode=append",
                                               "--partition=short",
                                               "--time=0:30:00",
                                               "--array=2",
                                               "--account=proj 1"};
  EXPECT_EQ(a, a_expected);
  const std::string q = "'\\''";  // a single quote inside single quotes
  const std::string d = "'" + std::string(dir_.string()).replace(dir_.string().find('\''), 1, q);
  EXPECT_TRUE(has_line(s.array, "cd " + d + "'")) << s.array;
  EXPECT_TRUE(has_line(s.array, "exec " + d + "/bin dir/ricochet' sweep 'cases/my sweep.toml' --out 'results/it" + q +
                                    "s 100%' --shard \"${SLURM_ARRAY_TASK_ID}/4\" --jobs 2 --threads 3 --repeat 5 --force --quiet"))
      << s.array;

  EXPECT_EQ(lines_of(s.merge).front(), "#!/bin/bash");
  const std::vector<std::string> m = sbatch_lines(s.merge);
  const std::vector<std::string> m_expected = {"--job-name=ricochet-slurmy-merge",
                                               "--ntasks=1",
                                               "--cpus-per-task=1",
                                               "--output=\"" + (dir_ / "results/it's 100%%/slurm/merge-%j.out").string() + "\"",
                                               "--open-mode=append",
                                               "--partition=short",
                                               "--time=0:30:00",
                                               "--account=proj 1"};
  EXPECT_EQ(m, m_expected);
  EXPECT_TRUE(has_line(s.merge, "cd " + d + "'")) << s.merge;
  EXPECT_TRUE(has_line(s.merge, "exec " + d + "/bin dir/ricochet' sweep 'cases/my sweep.toml' --out 'results/it" + q +
                                    "s 100%' --merge --repeat 5 --check 'ci/my gates.toml' --quiet"))
      << s.merge;
  // Nothing after the command: exec replaces the shell, so that Slurm's signals reach the sweep.
  EXPECT_EQ(lines_of(s.array).back().rfind("exec ", 0), 0u);
  EXPECT_EQ(lines_of(s.merge).back().rfind("exec ", 0), 0u);

  // Defaults: one job, one thread; --threads 0 asks for no CPU count.
  SlurmJobs plain = sample_jobs(dir_);
  plain.jobs = 1, plain.threads = 1, plain.repeat = 1, plain.force = false, plain.quiet = false, plain.gates_file.clear();
  plain.options.clear();
  const SlurmScripts p = slurm_scripts(plain);
  EXPECT_NE(p.array.find("\n#SBATCH --cpus-per-task=1\n"), std::string::npos);
  EXPECT_NE(p.array.find("--shard \"${SLURM_ARRAY_TASK_ID}/4\" --threads 1\n"), std::string::npos) << p.array;
  EXPECT_NE(p.merge.find("' --merge\n"), std::string::npos) << p.merge;
  plain.threads = 0;
  const SlurmScripts all = slurm_scripts(plain);
  EXPECT_EQ(all.array.find("--cpus-per-task"), std::string::npos) << all.array;
  EXPECT_NE(all.array.find(" --threads 0\n"), std::string::npos) << all.array;
}

// The scripts run by bash as Slurm runs them (from another folder, SLURM_ARRAY_TASK_ID set) start
// the program with exactly the intended words, in the submitting command's folder: the quoting
// holds for spaces, a single quote and a %.
TEST_F(SweepSlurmTest, BashRunsTheScriptsWithTheExactArguments) {
  SlurmJobs j = sample_jobs(dir_);
  // A program that writes its working folder and its arguments, one per line.
  const fs::path record = dir_.parent_path() / "args.txt";
  write_file(j.program, "#!/bin/bash\npwd > " + shell_quote(record.string()) +
                            "\nfor a in \"$@\"; do printf '%s\\n' \"$a\" >> " + shell_quote(record.string()) + "; done\n",
                          true);
  const SlurmScripts s = slurm_scripts(j);
  write_file(dir_.parent_path() / "array.sbatch", s.array);
  write_file(dir_.parent_path() / "merge.sbatch", s.merge);

  setenv("SLURM_ARRAY_TASK_ID", "3", 1);
  const ProgramOutput r = run_program({"/bin/bash", (dir_.parent_path() / "array.sbatch").string()});
  unsetenv("SLURM_ARRAY_TASK_ID");
  ASSERT_EQ(r.status, 0) << r.err;
  const std::vector<std::string> expected = {dir_.string(), "sweep", "cases/my sweep.toml", "--out", "results/it's 100%",
                                             "--shard", "3/4", "--jobs", "2", "--threads", "3", "--repeat", "5", "--force",
                                             "--quiet"};
  EXPECT_EQ(lines_of(text_of(record)), expected);

  fs::remove(record);
  const ProgramOutput m = run_program({"/bin/bash", (dir_.parent_path() / "merge.sbatch").string()});
  ASSERT_EQ(m.status, 0) << m.err;
  const std::vector<std::string> merge_expected = {dir_.string(), "sweep", "cases/my sweep.toml", "--out", "results/it's 100%",
                                                   "--merge", "--repeat", "5", "--check", "ci/my gates.toml", "--quiet"};
  EXPECT_EQ(lines_of(text_of(record)), merge_expected);

  // Without SLURM_ARRAY_TASK_ID (not in an array task), the script stops before the program.
  fs::remove(record);
  unsetenv("SLURM_ARRAY_TASK_ID");
  const ProgramOutput outside = run_program({"/bin/bash", (dir_.parent_path() / "array.sbatch").string()});
  EXPECT_NE(outside.status, 0);
  EXPECT_FALSE(fs::exists(record));
}

// A folder that an #SBATCH line cannot name is refused, one line, before anything is written.
TEST_F(SweepSlurmTest, ALogFolderThatSbatchCannotReadIsRefused) {
  for (const std::string bad : {"a\"b", "a\\b", "a\nb"}) {
    SlurmJobs j = sample_jobs(dir_);
    j.out_dir = bad;
    try {
      slurm_scripts(j);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("--out"), std::string::npos) << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
  }
}

// --slurm-option: an option ("-" first), one line; --array (and -a) goes to the array only.
TEST(SweepSlurmOption, OptionsAreCheckedAndArrayOptionsFound) {
  for (const std::string good : {"--partition=x", "-p x", "--time 1:00", "--account=a b", "-a 3", "--array=1,3"})
    EXPECT_NO_THROW(check_slurm_option(good)) << good;
  for (const std::string& bad :
       std::vector<std::string>{"", "-", "--", "partition=x", "--time=1\n#SBATCH --x", "--a\tb", std::string(1001, '-')}) {
    try {
      check_slurm_option(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.rfind("ricochet sweep: --slurm-option '", 0), 0u) << msg;
      EXPECT_NE(msg.find("--partition=NAME"), std::string::npos) << msg;
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
  }
  for (const std::string a : {"--array=2", "--array 2-3", "-a 2", "-a2", "--array"}) EXPECT_TRUE(is_array_option(a)) << a;
  for (const std::string n : {"--arrays=2", "--account=a", "--partition=array", "-p array"}) EXPECT_FALSE(is_array_option(n)) << n;
}

TEST(SweepSlurmQuote, ShellQuoteGivesOneBashWord) {
  EXPECT_EQ(shell_quote(""), "''");
  EXPECT_EQ(shell_quote("a b"), "'a b'");
  EXPECT_EQ(shell_quote("it's"), "'it'\\''s'");
  EXPECT_EQ(shell_quote("$HOME `x` \"y\""), "'$HOME `x` \"y\"'");
  const ProgramOutput r = run_program({"/bin/bash", "-c", "printf '%s|' " + shell_quote("it's $x `y` \\ \"z\"") + " " + shell_quote("")});
  EXPECT_EQ(r.out, "it's $x `y` \\ \"z\"||");
}

// ---- the command ---------------------------------------------------------------------------------

// --dry-run prints both scripts (the shards: one per run by default) and writes and submits
// nothing, with no sbatch anywhere on PATH.
TEST_F(SweepSlurmTest, DryRunPrintsTheScriptsAndWritesNothing) {
  const fs::path bin = fake_sbatch();
  const Outcome o = program("sweep sweep.toml --out 'out dir' --slurm --dry-run --check gates.toml --slurm-option=--partition=x",
                            in_dir(bin), dir_.parent_path() / "err.txt");
  ASSERT_EQ(o.status, 0) << o.err;
  EXPECT_EQ(o.err, "");
  EXPECT_NE(o.out.find("# ---- " + (dir_ / "out dir/slurm/array.sbatch").string() + ": submitted as `sbatch --parsable "),
            std::string::npos)
      << o.out;
  EXPECT_NE(o.out.find("\n#SBATCH --array=1-6\n"), std::string::npos) << o.out;  // 6 runs
  EXPECT_NE(o.out.find("\n#SBATCH --partition=x\n"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("--out 'out dir' --shard \"${SLURM_ARRAY_TASK_ID}/6\" --threads 1\n"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("--dependency=afterany:ARRAY_JOB_ID"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("--out 'out dir' --merge --check 'gates.toml'\n"), std::string::npos) << o.out;
  EXPECT_NE(o.out.find("exec " + shell_quote(fs::canonical(RICOCHET_BINARY).string()) + " sweep 'sweep.toml'"), std::string::npos)
      << o.out;
  EXPECT_FALSE(fs::exists(dir_ / "out dir"));
  EXPECT_FALSE(fs::exists(dir_ / "sbatch.log"));

  // The same with PATH holding no sbatch at all.
  const Outcome bare = program("sweep sweep.toml --out o --slurm --shards 2 --dry-run", in_dir() + " PATH=/nonexistent",
                               dir_.parent_path() / "err.txt");
  EXPECT_EQ(bare.status, 0) << bare.err;
  EXPECT_NE(bare.out.find("\n#SBATCH --array=1-2\n"), std::string::npos) << bare.out;
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}

// Submitted through sbatch: the array, then the merge with --dependency=afterany on the array's id,
// both with --parsable; the job ids printed; the scripts kept in DIR/slurm/ as --dry-run printed them.
TEST_F(SweepSlurmTest, SubmissionRunsSbatchTwiceAndPrintsTheJobIds) {
  const fs::path bin = fake_sbatch();
  const std::string args = "sweep sweep.toml --out 'out dir' --slurm --shards 3 --jobs 2 --slurm-option --time=10 --check gates.toml";
  const Outcome o = program(args, in_dir(bin), dir_.parent_path() / "err.txt");
  ASSERT_EQ(o.status, 0) << o.err;
  EXPECT_EQ(o.err, "");
  const fs::path slurm = dir_ / "out dir/slurm";
  const std::vector<std::string> calls = lines_of(text_of(dir_ / "sbatch.log"));
  const std::vector<std::string> expected = {"|--parsable|" + (slurm / "array.sbatch").string(),
                                             "|--parsable|--dependency=afterany:101|" + (slurm / "merge.sbatch").string()};
  EXPECT_EQ(calls, expected);
  const std::vector<std::string> out = lines_of(o.out);
  ASSERT_EQ(out.size(), 2u) << o.out;
  EXPECT_EQ(out[0].rfind("slurm array job 101: 3 shards of sweep slurmy (6 runs) -> out dir (", 0), 0u) << o.out;
  EXPECT_EQ(out[1].rfind("slurm merge job 102: after job 101 has ended (afterany), then the gates of gates.toml (", 0), 0u) << o.out;

  // The files are what --dry-run prints.
  const Outcome dry = program(args + " --dry-run", in_dir(bin), dir_.parent_path() / "err.txt");
  ASSERT_EQ(dry.status, 0) << dry.err;
  EXPECT_NE(dry.out.find(text_of(slurm / "array.sbatch")), std::string::npos);
  EXPECT_NE(dry.out.find(text_of(slurm / "merge.sbatch")), std::string::npos);
  EXPECT_NE(text_of(slurm / "array.sbatch").find("\n#SBATCH --cpus-per-task=2\n"), std::string::npos);
  EXPECT_NE(text_of(slurm / "array.sbatch").find("\n#SBATCH --time=10\n"), std::string::npos);
  EXPECT_NE(text_of(slurm / "merge.sbatch").find("\n#SBATCH --time=10\n"), std::string::npos);
  // Only the scripts: the shards write the rest.
  std::set<std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(dir_ / "out dir")) files.insert(fs::relative(e.path(), dir_ / "out dir").string());
  EXPECT_EQ(files, (std::set<std::string>{"slurm", "slurm/array.sbatch", "slurm/merge.sbatch"}));
}

// sbatch missing (nothing written) or failing (its message, and for the merge the array job that
// was submitted): one line, exit 1.
TEST_F(SweepSlurmTest, AMissingOrFailingSbatchIsOneLineAndExitOne) {
  const Outcome none = program("sweep sweep.toml --out o --slurm", in_dir() + " PATH=/nonexistent", dir_.parent_path() / "err.txt");
  EXPECT_EQ(none.status, 1) << none.err;
  EXPECT_EQ(none.err, "ricochet: error: --slurm: sbatch not found on PATH (Slurm's client commands); nothing written or "
                      "submitted (--dry-run prints the scripts without it)\n");
  EXPECT_FALSE(fs::exists(dir_ / "o"));

  const fs::path first = fake_sbatch(1);
  const Outcome refused = program("sweep sweep.toml --out o --slurm", in_dir(first), dir_.parent_path() / "err.txt");
  EXPECT_EQ(refused.status, 1) << refused.err;
  EXPECT_EQ(std::count(refused.err.begin(), refused.err.end(), '\n'), 1) << refused.err;
  EXPECT_NE(refused.err.find("array.sbatch failed (exit 1: sbatch: error: Batch job submission failed: Invalid partition name "
                             "specified); nothing submitted"),
            std::string::npos)
      << refused.err;
  EXPECT_EQ(refused.out, "");

  fs::remove(dir_ / "sbatch.log");
  const fs::path second = fake_sbatch(2);
  const Outcome half = program("sweep sweep.toml --out o --slurm", in_dir(second), dir_.parent_path() / "err.txt");
  EXPECT_EQ(half.status, 1) << half.err;
  EXPECT_EQ(std::count(half.err.begin(), half.err.end(), '\n'), 1) << half.err;
  EXPECT_NE(half.err.find("merge.sbatch failed (exit 1: "), std::string::npos) << half.err;
  EXPECT_NE(half.err.find("the array job 101 was submitted: cancel it (scancel 101)"), std::string::npos) << half.err;
}

// Options that do not go together, or a bad value: bad input, one line naming the option, exit 2,
// nothing written or submitted.
TEST_F(SweepSlurmTest, CommandLineRejectsSlurmOptionsThatDoNotGoTogether) {
  const fs::path bin = fake_sbatch();
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"--dry-run", "--dry-run goes with --slurm"},
      {"--shards 2", "--shards goes with --slurm"},
      {"--slurm-option=--time=1", "--slurm-option goes with --slurm"},
      {"--slurm --merge", "not with --merge"},
      {"--slurm --shard 1/2", "not with --shard"},
      {"--slurm --shards 0", "--shards: expected an integer in [1, 100000]"},
      {"--slurm --shards x", "--shards"},
      {"--slurm --slurm-option=partition=x", "--slurm-option 'partition=x'"},
      {"--slurm --slurm-option", "--slurm-option needs a value (an sbatch option, e.g. --slurm-option --time=2:00:00)"},
      {"--slurm --check absent.toml", "absent.toml"},
      {"--slurm --out sweep.toml", "--out"},
  };
  for (const auto& [args, part] : bad) {
    const Outcome o = program("sweep sweep.toml --out o " + args, in_dir(bin), dir_.parent_path() / "err.txt");
    EXPECT_EQ(o.status, 2) << args << ": " << o.err;
    EXPECT_EQ(std::count(o.err.begin(), o.err.end(), '\n'), 1) << args << ": " << o.err;
    EXPECT_NE(o.err.find(part), std::string::npos) << args << ": " << o.err;
    EXPECT_FALSE(fs::exists(dir_ / "o")) << args;
    EXPECT_FALSE(fs::exists(dir_ / "sbatch.log")) << args;
  }
  // A case that does not validate is found before anything is submitted.
  write_file(dir_ / "broken.toml", std::string(kSweep).replace(kSweep.find("1e-5, "), 6, "-1.0, "));
  const Outcome o = program("sweep broken.toml --out o --slurm", in_dir(bin), dir_.parent_path() / "err.txt");
  EXPECT_EQ(o.status, 2) << o.err;
  EXPECT_FALSE(fs::exists(dir_ / "sbatch.log"));
}

// The scripts run as Slurm would run them (each array task from another folder, then the
// merge): the merged summary.csv is the table of the same sweep run without shards, cell for cell
// but the timings, and the gates of --check pass; run again (a resubmission), every shard finds
// its runs done.
TEST_F(SweepSlurmTest, TheScriptsRunByHandGiveTheTableOfASweepWithoutShards) {
  const fs::path bin = fake_sbatch();
  const Outcome single = program("sweep sweep.toml --out single --threads 1 --quiet", in_dir(), dir_.parent_path() / "err.txt");
  ASSERT_EQ(single.status, 0) << single.err;
  const Outcome sub = program("sweep sweep.toml --out 'out dir' --slurm --shards 3 --check gates.toml", in_dir(bin),
                              dir_.parent_path() / "err.txt");
  ASSERT_EQ(sub.status, 0) << sub.err;
  const fs::path slurm = dir_ / "out dir/slurm";
  auto run_tasks = [&] {
    for (int k = 1; k <= 3; ++k) {
      setenv("SLURM_ARRAY_TASK_ID", std::to_string(k).c_str(), 1);
      const ProgramOutput r = run_program({"/bin/bash", (slurm / "array.sbatch").string()});
      unsetenv("SLURM_ARRAY_TASK_ID");
      EXPECT_EQ(r.status, 0) << "task " << k << ": " << r.err;
    }
  };
  run_tasks();
  const ProgramOutput m = run_program({"/bin/bash", (slurm / "merge.sbatch").string()});
  ASSERT_EQ(m.status, 0) << m.out << m.err;
  EXPECT_NE(m.out.find("gates: "), std::string::npos) << m.out;  // the gate lines of --check

  const CsvTable a = read_csv(dir_ / "single/summary.csv"), b = read_csv(dir_ / "out dir/summary.csv");
  ASSERT_EQ(a.rows.size(), 6u);  // 6 runs
  ASSERT_EQ(b.rows.size(), a.rows.size());
  ASSERT_EQ(a.columns, b.columns);
  std::size_t compared = 0;
  for (std::size_t r = 0; r < a.rows.size(); ++r)
    for (std::size_t c = 0; c < a.columns.size(); ++c) {
      if (test_support::is_measurement_column(a.columns[c])) continue;
      EXPECT_EQ(a.rows[r][c], b.rows[r][c]) << a.rows[r][0] << " " << a.columns[c];
      ++compared;
    }
  EXPECT_GT(compared, 300u);

  // Submitted again and run: every shard resumes all its runs, runs none.
  const Outcome again = program("sweep sweep.toml --out 'out dir' --slurm --shards 3 --check gates.toml", in_dir(bin),
                                dir_.parent_path() / "err.txt");
  ASSERT_EQ(again.status, 0) << again.err;
  run_tasks();
  std::size_t executed = 0, resumed = 0;
  for (int k = 1; k <= 3; ++k) {
    const Json manifest = read_json_file(dir_ / "out dir/shards" / (std::to_string(k) + "-of-3") / "shard.json");
    executed += manifest.at("counts").at("executed").get<std::size_t>();
    resumed += manifest.at("resumed_runs").get<std::size_t>();
  }
  EXPECT_EQ(executed, 0u);
  EXPECT_EQ(resumed, 6u);
}
