// The bodies of `ricochet run`, `ricochet report` and `ricochet plot` (the command line itself is
// harness/cli/cli.hpp; the other commands' bodies are in sweep.hpp, gates.hpp and stability.hpp).
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace ricochet {

// `ricochet run CASE.toml [--set KEY=VALUE]... [--threads N] [--out DIR] [--quiet]`.
struct RunCommand {
  std::string case_file;
  std::vector<std::string> sets;  // --set KEY=VALUE, in order
  std::optional<int> threads;     // --threads N: replaces the case key `threads` (after --set)
  std::string out_dir;            // empty: results/<case name>
  bool quiet = false;             // no progress and no summary line
};

// Runs the case and writes its outputs (docs/outputs.md), with a progress line on stderr for
// runs longer than a couple of seconds and a one-line summary on stdout (unless quiet).
// Returns 0 (ok) or 3 (diverged, outputs written); throws InputError for bad input (checked
// before the run, an output folder that is, or is inside, a file included) and std::runtime_error
// if the outputs cannot be written (then none of them is left: write_run_outputs).
int run_command(const RunCommand& c);

// `ricochet report` and `ricochet plot`: replaces this process with the report script `script`
// (reports/make_report.py, reports/plot_run.py) run by Debian's Python with `args` as given
// (RICOCHET_PYTHON and RICOCHET_REPORTS override the interpreter and the scripts' folder); the
// script's exit status is the command's: 0 written, 2 bad input. Throws InputError if the
// script is missing, std::runtime_error if the interpreter cannot be started.
// The path of report script `script`: in $RICOCHET_REPORTS if set, else the source tree's reports/.
std::string report_script_path(const std::string& script);

[[noreturn]] void run_script(const std::string& script, const std::vector<std::string>& args);

}  // namespace ricochet
