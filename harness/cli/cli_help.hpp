// The help of the `ricochet` command line (harness/cli/cli.hpp), made from its CLI11 options: each
// command's usage line and option list, and the complete usage of `ricochet --help`. report and
// plot take their scripts' arguments, which CLI11 does not see; they are listed here.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace ricochet {

// A report script's argument as the complete usage shows it.
struct ScriptArg {
  std::string names;  // "DIR", "--out", "-h, --help"
  std::string value;  // "OUT", "PATH ..."; empty for a positional or a switch
  std::string help;
};

// A command that runs a report script with its arguments as given.
struct Script {
  std::string command, file, description, footer;
  std::vector<ScriptArg> args;  // as reports/<file> --help lists them (CliTest checks that)
};

// report (reports/make_report.py) and plot (reports/plot_run.py).
const std::vector<Script>& scripts();
// The script that command `app` runs; nullptr for the others.
const Script* script_of(const CLI::App& app);

// A command's options in the order of its usage: positionals, the others, --help last.
std::vector<const CLI::Option*> ordered_options(const CLI::App& app);
// "--jobs" ("-j" for an option without a long name).
std::string long_name(const CLI::Option* o);
// "ricochet run CASE.toml [--set KEY=VALUE]... [--out DIR] [--quiet]".
std::string synopsis(const CLI::App& command);
// `ricochet --help`: every command's usage, then each command with its options.
std::string complete_usage(const CLI::App& root);
// The formatter of the app and its commands: `COMMAND --help` is the command's usage line, its
// description, one line per option and its exit statuses; `--help` the complete usage.
std::shared_ptr<CLI::Formatter> help_formatter();

}  // namespace ricochet
