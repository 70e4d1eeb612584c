#include "harness/cli/commands.hpp"

#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "harness/external/external_run.hpp"
#include "harness/input/case_setup.hpp"
#include "harness/input/input_error.hpp"
#include "harness/outputs/run_outputs.hpp"
#include "harness/studies/study_placeholders.hpp"

namespace ricochet {
namespace {

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

}  // namespace

int run_command(const RunCommand& c) {
  CaseSpec spec = read_case(c.case_file, c.sets);
  if (c.threads) spec.threads = *c.threads;
  const std::string out_dir = c.out_dir.empty() ? "results/" + spec.name : c.out_dir;
  // A folder that cannot be one is found before the run, not after it.
  if (const std::string problem = output_folder_problem(out_dir); !problem.empty())
    throw InputError("ricochet run: " + std::string(c.out_dir.empty() ? "output folder " : "--out ") + out_dir + ": " + problem);
  const PreparedCase pc = prepare_case(spec);
  if (spec.scheme == Scheme::external) return run_external(pc, out_dir, c.quiet);

  ProgressLine progress(!c.quiet);
  const RunResult r = run_case(pc, [&progress](long s, long n, double t) { progress(s, n, t); });
  progress.done();
  write_run_outputs(out_dir, pc, r);
  if (!c.quiet) std::printf("%s\n", one_line_summary(pc, r, out_dir).c_str());
  return r.status == RunStatus::ok ? 0 : 3;
}

std::string report_script_path(const std::string& script) {
  const char* dir = std::getenv("RICOCHET_REPORTS");
  return std::string(dir && *dir ? dir : RICOCHET_REPORTS_DIR) + "/" + script;
}

void run_script(const std::string& script, const std::vector<std::string>& args) {
  const std::string interpreter = report_python();
  const std::string path = report_script_path(script);
  if (access(path.c_str(), R_OK) != 0)
    throw InputError("report script '" + path + "' not found; set RICOCHET_REPORTS to the reports/ folder");
  std::vector<std::string> argv_s = {interpreter, path};
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::fflush(stdout);
  execv(interpreter.c_str(), argv.data());
  throw std::runtime_error("cannot run " + interpreter + ": " + std::strerror(errno));
}

}  // namespace ricochet
