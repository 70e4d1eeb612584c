// The `ricochet` command line.
//   ricochet run CASE.toml [--set KEY=VALUE]... [--out DIR] [--quiet]
// Exit status: 0 run finished ok; 3 run diverged (a result, written like any other);
// 2 bad input (one line on stderr naming file, key and what is allowed; nothing written);
// 1 anything else (e.g. an output file could not be written).
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <iostream>
#include <string>
#include <unistd.h>
#include <vector>

#include "harness/case_setup.hpp"
#include "harness/gates.hpp"
#include "harness/stability.hpp"
#include "harness/sweep.hpp"
#include "harness/input_error.hpp"
#include "harness/run_outputs.hpp"

namespace {

constexpr const char* kRunUsage =
    "usage: ricochet run CASE.toml [--set KEY=VALUE]... [--out DIR] [--quiet]\n"
    "  run a case (docs/case-format.md); writes DIR/summary.json, DIR/history.csv, DIR/fields/*.vtu\n"
    "  --set KEY=VALUE  override a case key, e.g. --set time.dt=1e-6 --set mesh=M2 (repeatable)\n"
    "  --out DIR        output folder (default: results/<case name>)\n"
    "  --quiet, -q      no progress and no summary line\n"
    "  --help, -h       this text\n"
    "  exit status: 0 ok, 3 diverged (outputs written), 2 bad input (nothing written), 1 other error\n";

constexpr const char* kUsage =
    "usage: ricochet run CASE.toml [--set KEY=VALUE]... [--out DIR] [--quiet]\n"
    "       ricochet sweep SWEEP.toml [--out DIR] [--jobs N] [--repeat K] [--check GATES.toml] [--force] [--quiet]\n"
    "       ricochet check SUMMARY.csv GATES.toml [--junit FILE]\n"
    "       ricochet stability CASE.toml [--set KEY=VALUE]... [--out DIR] [--tolerance REL] [--max-runs N]\n"
    "                          [--end TIME] [--energy-bound E] [--quiet]\n"
    "       ricochet report DIR [--out OUT] [options of reports/make_report.py]\n"
    "       ricochet plot RUN_DIR [--out PNG]\n"
    "       ricochet --version | --help\n"
    "  run       run a case; writes DIR/summary.json, DIR/history.csv, DIR/fields/*.vtu\n"
    "  --set     override a case key, e.g. --set time.dt=1e-6 --set mesh=M2\n"
    "  --out     output folder (default: results/<case name>)\n"
    "  --quiet   no progress and no summary line\n"
    "  sweep     run a sweep of cases (docs/sweeps.md); writes DIR/summary.csv and DIR/runs/\n"
    "  check     evaluate gate files on a sweep's summary.csv (docs/gates.md); exit 4 if a gate fails\n"
    "  stability the largest stable time step by bisection (docs/stability.md)\n"
    "  report    the HTML report of any sweep folder (docs/report.md): DIR/report/index.html\n"
    "  plot      one PNG of a run's history (docs/report.md): RUN_DIR/history.png\n"
    "  ricochet COMMAND --help gives each command's options.\n";

// `ricochet report` and `ricochet plot`: the report scripts, run by Debian's Python with the
// arguments as given (RICOCHET_PYTHON and RICOCHET_REPORTS override the interpreter and the
// scripts' folder). Their exit status is the command's: 0 written, 2 bad input.
int python_command(const char* script, const std::vector<std::string>& args) {
  const char* python = std::getenv("RICOCHET_PYTHON");
  const char* dir = std::getenv("RICOCHET_REPORTS");
  const std::string interpreter = python && *python ? python : "/usr/bin/python3";
  const std::string path = std::string(dir && *dir ? dir : RICOCHET_REPORTS_DIR) + "/" + script;
  if (access(path.c_str(), R_OK) != 0)
    throw ricochet::InputError("report script '" + path + "' not found; set RICOCHET_REPORTS to the reports/ folder");
  std::vector<std::string> argv_s = {interpreter, path};
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::fflush(stdout);
  execv(interpreter.c_str(), argv.data());
  throw std::runtime_error("cannot run " + interpreter + ": " + std::strerror(errno));
}

// Progress on stderr for runs longer than a couple of seconds: in place on a terminal,
// one line every 10 s otherwise (CI logs).
class ProgressLine {
 public:
  explicit ProgressLine(bool enabled) : enabled_(enabled), tty_(isatty(STDERR_FILENO)) {}
  void operator()(long step, long planned, double time) {
    if (!enabled_) return;
    const double elapsed = seconds_since(start_);
    if (elapsed < 2.0 || seconds_since(last_) < (tty_ ? 0.5 : 10.0)) return;
    last_ = clock::now();
    const double frac = planned > 0 ? static_cast<double>(step) / planned : 1.0;
    std::fprintf(stderr, "%s  t = %.4g s  step %ld/%ld (%.0f%%)  elapsed %.1f s  left ~%.1f s%s",
                 tty_ ? "\r" : "", time, step, planned, 100.0 * frac, elapsed,
                 frac > 0 ? elapsed * (1.0 - frac) / frac : 0.0, tty_ ? "   " : "\n");
    shown_ = true;
  }
  void done() {
    if (shown_ && tty_) std::fprintf(stderr, "\n");
  }

 private:
  using clock = std::chrono::steady_clock;
  static double seconds_since(clock::time_point t) {
    return std::chrono::duration<double>(clock::now() - t).count();
  }
  bool enabled_, tty_, shown_ = false;
  clock::time_point start_ = clock::now(), last_ = clock::now();
};

int run_command(const std::vector<std::string>& args) {
  std::string case_file, out_dir;
  std::vector<std::string> sets;
  bool quiet = false;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    auto value = [&](const char* flag) -> std::string {
      if (i + 1 >= args.size()) throw ricochet::InputError(std::string("ricochet run: ") + flag + " needs a value");
      return args[++i];
    };
    if (a == "--set") sets.push_back(value("--set"));
    else if (a.rfind("--set=", 0) == 0) sets.push_back(a.substr(6));
    else if (a == "--out") out_dir = value("--out");
    else if (a.rfind("--out=", 0) == 0) out_dir = a.substr(6);
    else if (a == "--quiet" || a == "-q") quiet = true;
    else if (a == "--help" || a == "-h") {
      std::fputs(kRunUsage, stdout);
      return 0;
    }
    else if (!a.empty() && a[0] == '-') throw ricochet::InputError("ricochet run: unknown option '" + a + "'; allowed: --set, --out, --quiet, --help");
    else if (case_file.empty()) case_file = a;
    else throw ricochet::InputError("ricochet run: more than one case file ('" + case_file + "', '" + a + "')");
  }
  if (case_file.empty()) throw ricochet::InputError("ricochet run: missing CASE.toml; usage: ricochet run CASE.toml [--set KEY=VALUE]... [--out DIR] [--quiet] (--help for more)");

  const ricochet::CaseSpec spec = ricochet::read_case(case_file, sets);
  const ricochet::PreparedCase pc = ricochet::prepare_case(spec);
  if (out_dir.empty()) out_dir = "results/" + spec.name;

  ProgressLine progress(!quiet);
  const ricochet::RunResult r =
      ricochet::run_case(pc, [&progress](long s, long n, double t) { progress(s, n, t); });
  progress.done();
  ricochet::write_run_outputs(out_dir, pc, r);
  if (!quiet) std::printf("%s\n", ricochet::one_line_summary(pc, r, out_dir).c_str());
  return r.status == ricochet::RunStatus::ok ? 0 : 3;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  return ricochet::command_status(std::cerr, [&]() -> int {
    if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
      std::fputs(kUsage, args.empty() ? stderr : stdout);
      return args.empty() ? 2 : 0;
    }
    if (args[0] == "--version") {
      std::printf("ricochet %s\n", RICOCHET_VERSION);
      return 0;
    }
    if (args[0] == "run") return run_command({args.begin() + 1, args.end()});
    if (args[0] == "sweep") return ricochet::sweep_command({args.begin() + 1, args.end()});
    if (args[0] == "check") return ricochet::check_command({args.begin() + 1, args.end()});
    if (args[0] == "stability") return ricochet::stability_command({args.begin() + 1, args.end()});
    if (args[0] == "report") return python_command("make_report.py", {args.begin() + 1, args.end()});
    if (args[0] == "plot") return python_command("plot_run.py", {args.begin() + 1, args.end()});
    throw ricochet::InputError("ricochet: unknown command '" + args[0] +
                               "'; allowed: run, sweep, check, stability, report, plot, --version, --help");
  });
}
