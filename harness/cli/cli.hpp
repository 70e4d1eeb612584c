// The `ricochet` command line (CLI11): the commands run, sweep, check, stability, report and
// plot, and --version and --help. `ricochet --help` gives the complete usage, every command with
// its options; `ricochet COMMAND --help` one command's (for report and plot, their script's own
// help). The commands' bodies are run_command() in commands.hpp, sweep.hpp, gates.hpp and
// stability.hpp; report and plot hand their arguments to the report scripts as given.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

namespace ricochet {

// The program: `args` are the words after the program's name. Parses them, runs the command and
// returns its exit status, all inside command_status (input_error.hpp): bad usage (an unknown
// command or option, a missing or extra argument, a value out of range) is one line
// "ricochet: ..." on `err` and status 2, like any bad input. Help and the version go to `out`
// with status 0.
int ricochet_main(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

// One command as the program runs it: ricochet_main({COMMAND, args...}) on std::cout and
// std::cerr (check: on `out` and `err`).
int sweep_command(const std::vector<std::string>& args);
int stability_command(const std::vector<std::string>& args);
int check_command(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

}  // namespace ricochet
