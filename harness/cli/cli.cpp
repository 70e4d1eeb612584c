#include "harness/cli/cli.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <stdexcept>

#include "harness/cli/cli_help.hpp"
#include "harness/cli/commands.hpp"
#include "harness/gates/gates.hpp"
#include "harness/input/input_error.hpp"
#include "harness/outputs/run_outputs.hpp"
#include "harness/stability/stability.hpp"
#include "harness/studies/reproduce.hpp"
#include "harness/sweeps/sweep.hpp"
#include "harness/sweeps/sweep_shard.hpp"
#include "harness/sweeps/sweep_slurm.hpp"
#include "solver/schemes/threads.hpp"

namespace ricochet {
namespace {

constexpr const char* kAllowed = "run, sweep, check, stability, report, plot, reproduce, --version, --help";

// ---- values ----------------------------------------------------------------------------------

// The integer value of option `flag` of `command`, in [lo, hi]; else one line naming both.
long parse_integer(const std::string& command, const std::string& flag, const std::string& v, long lo, long hi) {
  char* end = nullptr;
  errno = 0;
  const long x = std::strtol(v.c_str(), &end, 10);
  if (v.empty() || *end != '\0' || errno != 0 || x < lo || x > hi)
    throw InputError("ricochet " + command + ": " + flag + ": expected an integer in [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "]; got '" + v + "'");
  return x;
}

// --threads N of `command`: 0 (all cores) ... kMaxThreads, as the case key `threads`.
int parse_threads(const std::string& command, const std::string& v) {
  return static_cast<int>(parse_integer(command, "--threads", v, 0, kMaxThreads));
}

double parse_number(const std::string& flag, const std::string& text, const char* expected) {
  double v = 0.0;
  std::size_t used = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(v))
    throw InputError("ricochet stability: " + flag + ": expected " + expected + "; got \"" + text + "\"");
  return v;
}

// ---- the command line --------------------------------------------------------------------------

class CommandLine {
 public:
  CommandLine() {
    app_.formatter(help_formatter());
    app_.set_help_flag("-h,--help", "this text");
    app_.set_version_flag("--version", std::string("ricochet ") + RICOCHET_VERSION, "print the version and exit");
    app_.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);  // --out A --out B: B
    app_.require_subcommand(0, 1);
    app_.allow_extras();

    run_ = command("run", "run a case (docs/case-format.md); writes DIR/summary.json, DIR/history.csv, DIR/fields/*.vtu",
                   "exit status: 0 ok, 3 diverged (outputs written), 2 bad input (nothing written), 1 other error");
    run_->add_option("CASE.toml", run_cmd_.case_file, "the case file");
    sets(run_, run_cmd_.sets, "override a case key, e.g. --set time.dt=1e-6 --set mesh=M2 (repeatable)");
    run_threads_ = threads(run_, run_threads_text_, "threads of the run, 0 ... " + std::to_string(kMaxThreads) +
                                     "; 0 = all cores (default: the case key `threads`, else 0); results do not depend on it");
    run_out_ = run_->add_option("--out", run_cmd_.out_dir, "output folder (default: results/<case name>)")->type_name("DIR");
    run_->add_flag("-q,--quiet", run_cmd_.quiet, "no progress and no summary line");

    sweep_ = command("sweep", "run every case of a sweep file (docs/sweeps.md); writes DIR/summary.csv, DIR/sweep.json, DIR/runs/",
                     "exit status: 0 done (diverged and failed runs are results; with --slurm: submitted), 4 a gate failed, "
                     "3 with --merge: runs missing, 2 bad input, 1 other error (with --slurm: sbatch missing or failed)");
    sweep_->add_option("SWEEP.toml", sweep_cmd_.file, "the sweep file");
    sweep_out_ = sweep_->add_option("--out", out_dir_, "output folder (default: results/<sweep name>)")->type_name("DIR");
    jobs_ = sweep_->add_option("-j,--jobs", jobs_text_,
                               "runs at the same time, 1 ... " + std::to_string(kMaxSweepJobs) +
                                   " (default 1: one at a time, for clean timings)")
                ->type_name("N");
    sweep_threads_ = threads(sweep_, sweep_threads_text_, "threads of every run, 0 ... " + std::to_string(kMaxThreads) +
                                         "; 0 = all cores (default: 1 when --jobs > 1, else the case's own)");
    repeat_ = sweep_->add_option("--repeat", repeat_text_,
                                 "run each case K times, 1 ... 1000; summary.csv gets the median and the spread of the timings")
                  ->type_name("K");
    sweep_->add_option("--check", sweep_cmd_.gates_file,
                       "then check the gates of GATES.toml on DIR/summary.csv (docs/gates.md); exit 4 if one fails")
        ->type_name("GATES.toml");
    force_ = sweep_->add_flag("--force", sweep_cmd_.options.force, "rerun the runs that an earlier sweep finished");
    sweep_->add_flag("-q,--quiet", sweep_cmd_.options.quiet, "no progress lines");
    shard_ = sweep_->add_option("--shard", shard_text_,
                                "run only shard K of N of the runs (1 <= K <= N) into DIR/runs/ and DIR/shards/K-of-N/; "
                                "shards may run at the same time, on several hosts")
                 ->type_name("K/N");
    merge_ = sweep_->add_flag("--merge", sweep_cmd_.merge,
                              "run nothing: build DIR/summary.csv and DIR/sweep.json from the shards' run folders; "
                              "exit 3 if runs are missing");
    slurm_ = sweep_->add_flag("--slurm", sweep_cmd_.slurm,
                              "submit the sweep to Slurm: a job array of N shards (--shards) and a merge job after them "
                              "(with --check, the gates); prints the job ids; submitted again, it resumes");
    shards_ = sweep_->add_option("--shards", shards_text_,
                                 "with --slurm: the number of shards, one array task each, 1 ... " + std::to_string(kMaxShards) +
                                     " (default: one per run, at most " + std::to_string(kDefaultMaxSlurmShards) + ")")
                  ->type_name("N");
    sweep_->add_option("--slurm-option", sweep_cmd_.slurm_options,
                       "with --slurm: an #SBATCH option of both jobs (--array: of the array only), e.g. "
                       "--slurm-option --partition=NAME --slurm-option --time=2:00:00 (repeatable)")
        ->type_name("OPTION")
        ->expected(1)
        ->take_all();
    sweep_->add_flag("--dry-run", sweep_cmd_.dry_run,
                     "with --slurm: print the two sbatch scripts; write and submit nothing (needs no Slurm)");

    check_ = command("check", "check the gates of GATES.toml (docs/gates.md) on the sweep table SUMMARY.csv",
                     "exit status: 0 all gates pass, 4 a gate failed, 2 bad input, 1 other error");
    check_->add_option("SUMMARY.csv", check_cmd_.summary_csv, "a sweep's summary.csv");
    check_->add_option("GATES.toml", check_cmd_.gates_toml, "the gate file");
    junit_ = check_->add_option("--junit", check_cmd_.junit, "JUnit XML report (default: gates-junit.xml next to SUMMARY.csv)")
                 ->type_name("FILE");

    stability_ = command("stability",
                         "the largest stable time step of the case's scheme on its mesh, by bisection over runs (docs/stability.md)",
                         "exit status: 0 bracket found, 5 no unstable dt up to the cap, 4 no bracket, 2 bad input, 1 other error");
    stability_->add_option("CASE.toml", stability_cmd_.case_file, "the case file");
    sets(stability_, stability_cmd_.sets, "override a case key (as for `ricochet run`; repeatable)");
    stability_threads_ = threads(stability_, stability_threads_text_, "threads of every trial run, 0 ... " + std::to_string(kMaxThreads) +
                                                 "; 0 = all cores (default: the case key `threads`, else 0)");
    stability_out_ = stability_->add_option("--out", stability_cmd_.out_dir,
                                            "write DIR/stability.json and each trial's DIR/trials/NN/summary.json, history.csv")
                         ->type_name("DIR");
    tolerance_ = stability_->add_option("--tolerance", tolerance_text_, "stop when hi/lo - 1 <= REL (default 0.01)")->type_name("REL");
    max_runs_ = stability_->add_option("--max-runs", max_runs_text_, "at most N trial runs (default 30)")->type_name("N");
    end_ = stability_->add_option("--end", end_text_, "time.end of every trial [s] (default: the case's)")->type_name("TIME");
    energy_bound_ = stability_->add_option("--energy-bound", energy_bound_text_,
                                           "a stable run keeps energy_error_max <= E (default 0.1)")
                        ->type_name("E");
    stability_->add_flag("-q,--quiet", stability_cmd_.quiet, "no per-trial lines on stderr");

    reproduce_ = command("reproduce",
                         "run studies (docs/studies.md): each study's sweeps of the tier, reusing unchanged runs, its gates "
                         "and post steps; writes DIR/<study>/study.json, then the report of the studies that changed",
                         "exit status: 0 every study passed, 4 a gate failed, 1 a sweep, run, post step or report failed, "
                         "2 bad input (nothing written)");
    reproduce_->add_option("STUDY", reproduce_cmd_.studies,
                           "a study: a folder name in --studies DIR, or a path to a folder holding study.toml "
                           "(default: every study of the tier)")
        ->expected(0, -1)
        ->take_all();
    reproduce_->add_option("--tier", reproduce_cmd_.tier, "fast or full (default full): the sweeps and post steps of that tier")
        ->type_name("TIER");
    reproduce_out_ = reproduce_->add_option("--out", reproduce_cmd_.out_dir, "output folder (default: results/<tier>)")->type_name("DIR");
    reproduce_->add_option("--studies", reproduce_cmd_.studies_dir,
                           "the folder whose subfolders are the studies (default: the source tree's cases/, or $RICOCHET_CASES)")
        ->type_name("DIR");
    reproduce_->add_flag("--force", reproduce_cmd_.force, "rerun every run and redraw every report");
    reproduce_->add_flag("-q,--quiet", reproduce_cmd_.quiet, "no run progress lines and no per-gate lines");
    reproduce_->add_flag("--no-report", reproduce_cmd_.no_report, "draw no report");

    // report and plot: every word after the command goes to the script, --help included.
    for (const Script& s : scripts()) command(s.command, s.description, s.footer)->prefix_command()->set_help_flag();

    help_ = app_.add_subcommand("help", "the complete usage")->group("")->allow_extras();  // as --help
  }

  int main(const std::vector<std::string>& args, std::ostream& out) {
    std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 takes them last first
    try {
      app_.parse(reversed);
    } catch (const CLI::CallForHelp&) {
      out << app_.help();
      return 0;
    } catch (const CLI::CallForAllHelp&) {
      out << app_.help();
      return 0;
    } catch (const CLI::CallForVersion& e) {
      out << e.what() << '\n';
      return 0;
    } catch (const CLI::ParseError& e) {
      throw InputError(message(e));
    }
    const std::vector<CLI::App*> chosen = app_.get_subcommands();
    if (chosen.empty()) {
      const std::vector<std::string> extra = app_.remaining();
      if (extra.empty()) throw InputError("missing command; allowed: " + std::string(kAllowed));
      const bool option = extra[0].size() > 1 && extra[0][0] == '-';
      throw InputError(std::string(option ? "unknown option '" : "unknown command '") + extra[0] + "'; allowed: " + kAllowed);
    }
    CLI::App& c = *chosen.front();
    if (&c == help_) {
      out << complete_usage(app_);
      return 0;
    }
    if (const Script* s = script_of(c)) run_script(s->file, c.remaining());
    if (&c == reproduce_) {
      check_options(c);
      check_out(c, reproduce_out_);
      const std::vector<std::string> after_dashes = app_.remaining();
      reproduce_cmd_.studies.insert(reproduce_cmd_.studies.end(), after_dashes.begin(), after_dashes.end());
      return run_command(reproduce_cmd_, out, std::cerr);
    }
    check_arguments(c, app_.remaining());
    check_out(c, &c == run_ ? run_out_ : &c == sweep_ ? sweep_out_ : &c == stability_ ? stability_out_ : nullptr);

    if (&c == run_) {
      if (run_threads_->count()) run_cmd_.threads = parse_threads("run", run_threads_text_);
      return run_command(run_cmd_);
    }
    if (&c == sweep_) {
      if (slurm_->count() && (merge_->count() || shard_->count()))
        throw InputError(std::string("ricochet sweep: --slurm submits the shards and the merge itself: not with ") +
                         (merge_->count() ? "--merge" : "--shard"));
      if (shards_->count())
        sweep_cmd_.shards = static_cast<int>(parse_integer("sweep", "--shards", shards_text_, 1, kMaxShards));
      if (merge_->count()) {
        if (shard_->count())
          throw InputError("ricochet sweep: --shard and --merge exclude each other: run each shard with --shard K/N, "
                           "then merge once with --merge");
        for (const CLI::Option* o : {jobs_, sweep_threads_, force_})
          if (o->count())
            throw InputError("ricochet sweep: --merge runs nothing: " + long_name(o) +
                             " is for the shards (--shard K/N), not for the merge");
      }
      if (shard_->count()) {
        sweep_cmd_.options.shard = parse_shard(shard_text_);
        if (!sweep_cmd_.gates_file.empty())
          throw InputError("ricochet sweep: --check checks the whole sweep's table: give it to --merge, not to a shard (--shard)");
      }
      if (jobs_->count()) sweep_cmd_.options.jobs = static_cast<int>(parse_integer("sweep", "--jobs", jobs_text_, 1, kMaxSweepJobs));
      if (repeat_->count()) sweep_cmd_.options.repeat = static_cast<int>(parse_integer("sweep", "--repeat", repeat_text_, 1, 1000));
      if (sweep_threads_->count()) sweep_cmd_.options.threads = parse_threads("sweep", sweep_threads_text_);
      sweep_cmd_.options.out_dir = out_dir_;
      return run_command(sweep_cmd_, out);
    }
    if (&c == check_) {
      if (junit_->count() && check_cmd_.junit.empty()) throw InputError("ricochet check: --junit needs a non-empty file name");
      return run_command(check_cmd_, out);
    }
    if (stability_threads_->count()) stability_cmd_.threads = parse_threads("stability", stability_threads_text_);
    StabilityOptions& opt = stability_cmd_.options;
    if (tolerance_->count()) opt.tolerance = parse_number("--tolerance", tolerance_text_, "a number in (0, 10]");
    if (energy_bound_->count()) opt.energy_bound = parse_number("--energy-bound", energy_bound_text_, "a number > 0");
    if (end_->count()) opt.end_time = parse_number("--end", end_text_, "a time > 0 [s]");
    if (max_runs_->count()) {
      const double n = parse_number("--max-runs", max_runs_text_, "an integer in 1 ... 10000");
      if (n != std::floor(n) || n < 1 || n > 10000)
        throw InputError("ricochet stability: --max-runs: expected an integer in 1 ... 10000; got \"" + max_runs_text_ + "\"");
      opt.max_runs = static_cast<int>(n);
    }
    return run_command(stability_cmd_);
  }

 private:
  CLI::App* command(const std::string& name, const std::string& description, const std::string& footer) {
    CLI::App* c = app_.add_subcommand(name, description);
    c->footer(footer);
    c->allow_extras();  // unknown options and extra words: reported by check_arguments, in one line
    return c;
  }

  static void sets(CLI::App* c, std::vector<std::string>& into, const std::string& help) {
    c->add_option("--set", into, help)->type_name("KEY=VALUE")->expected(1)->take_all();
  }

  // --threads N, read as text and checked by parse_threads (one error line for any bad value).
  static CLI::Option* threads(CLI::App* c, std::string& into, const std::string& help) {
    return c->add_option("--threads", into, help)->type_name("N");
  }

  // The words CLI11 left over (`after_dashes`: those after "--" that no positional took): an
  // unknown option, or more files than the command takes; then a missing file.
  // An unknown option among the words CLI11 left over: one line naming it and the allowed ones.
  static void check_options(const CLI::App& c) {
    for (const std::string& w : c.remaining())
      if (w.size() > 1 && w[0] == '-') {
        std::string allowed;
        for (const CLI::Option* o : ordered_options(c))
          if (!o->get_positional()) allowed += (allowed.empty() ? "" : ", ") + long_name(o);
        throw InputError("ricochet " + c.get_name() + ": unknown option '" + w + "'; allowed: " + allowed);
      }
  }

  static void check_arguments(const CLI::App& c, std::vector<std::string> after_dashes) {
    const std::string prefix = "ricochet " + c.get_name() + ": ";
    check_options(c);
    std::vector<std::string> words = c.remaining();
    words.insert(words.end(), after_dashes.begin(), after_dashes.end());
    std::vector<std::string> names, given;
    for (const CLI::Option* o : c.get_options([](const CLI::Option* o) { return o->get_positional(); })) {
      names.push_back(o->get_name(true, false));
      if (o->count()) given.push_back(o->as<std::string>());
    }
    if (given.size() == names.size() && words.empty()) return;
    given.insert(given.end(), words.begin(), words.end());
    if (names.size() == 1 && given.empty()) throw InputError(prefix + "missing " + names[0] + "; usage: " + synopsis(c));
    if (names.size() == 1)
      throw InputError(prefix + "more than one " + names[0] + " ('" + given[0] + "', '" + given[1] + "')");
    std::string expected;
    for (std::size_t i = 0; i < names.size(); ++i) expected += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + names[i];
    throw InputError(prefix + "expected " + expected + "; got " + std::to_string(given.size()) +
                     " file argument(s); usage: " + synopsis(c));
  }

  // A given --out must name a folder: not empty, not an existing file nor inside one.
  static void check_out(const CLI::App& c, const CLI::Option* out) {
    if (!out || !out->count()) return;
    const std::string dir = out->as<std::string>();
    if (const std::string problem = output_folder_problem(dir); !problem.empty())
      throw InputError("ricochet " + c.get_name() + ": --out " + (dir.empty() ? "''" : dir) + ": " + problem);
  }

  // A CLI11 parse error as one line naming the command: "--out needs a value" for a missing value.
  std::string message(const CLI::ParseError& e) const {
    const std::vector<CLI::App*> chosen = app_.get_subcommands();
    const std::string prefix = chosen.empty() ? "" : "ricochet " + chosen.front()->get_name() + ": ";
    std::string what = e.what();
    std::replace(what.begin(), what.end(), '\n', ' ');
    if (dynamic_cast<const CLI::ArgumentMismatch*>(&e) && what.rfind("-", 0) == 0 && what.find(" required ") != std::string::npos)
      return prefix + what.substr(0, what.find(':')) + " needs a value" +
             (what.rfind("--slurm-option", 0) == 0 ? " (an sbatch option, e.g. --slurm-option --time=2:00:00)" : "");
    return prefix + what;
  }

  CLI::App app_{std::string("ricochet ") + RICOCHET_VERSION +
                    ": a verification and benchmark harness for frictional impact simulation",
                "ricochet"};
  CLI::App *run_ = nullptr, *sweep_ = nullptr, *check_ = nullptr, *stability_ = nullptr, *help_ = nullptr;
  CLI::App* reproduce_ = nullptr;
  CLI::Option* reproduce_out_ = nullptr;
  ReproduceCommand reproduce_cmd_;
  CLI::Option *jobs_ = nullptr, *repeat_ = nullptr, *junit_ = nullptr, *force_ = nullptr, *shard_ = nullptr, *merge_ = nullptr;
  CLI::Option *slurm_ = nullptr, *shards_ = nullptr;
  CLI::Option *run_out_ = nullptr, *sweep_out_ = nullptr, *stability_out_ = nullptr;
  CLI::Option *run_threads_ = nullptr, *sweep_threads_ = nullptr, *stability_threads_ = nullptr;
  CLI::Option *tolerance_ = nullptr, *max_runs_ = nullptr, *end_ = nullptr, *energy_bound_ = nullptr;
  RunCommand run_cmd_;
  SweepCommand sweep_cmd_;
  CheckCommand check_cmd_;
  StabilityCommand stability_cmd_;
  std::string out_dir_;  // sweep --out
  std::string shard_text_;  // sweep --shard K/N
  std::string shards_text_;  // sweep --shards N
  std::string jobs_text_, repeat_text_, tolerance_text_, max_runs_text_, end_text_, energy_bound_text_;
  std::string run_threads_text_, sweep_threads_text_, stability_threads_text_;
};

}  // namespace

int ricochet_main(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  return command_status(err, [&]() -> int {
    CommandLine cli;
    return cli.main(args, out);
  });
}

int sweep_command(const std::vector<std::string>& args) {
  std::vector<std::string> a = {"sweep"};
  a.insert(a.end(), args.begin(), args.end());
  return ricochet_main(a, std::cout, std::cerr);
}

int stability_command(const std::vector<std::string>& args) {
  std::vector<std::string> a = {"stability"};
  a.insert(a.end(), args.begin(), args.end());
  return ricochet_main(a, std::cout, std::cerr);
}

int check_command(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  std::vector<std::string> a = {"check"};
  a.insert(a.end(), args.begin(), args.end());
  return ricochet_main(a, out, err);
}

}  // namespace ricochet
