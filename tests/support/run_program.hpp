// Running programs from the tests: a shell command whose output is collected, the `ricochet`
// program of this build (RICOCHET_BINARY, defined by tests/CMakeLists.txt), and a program started
// in the background with its output to a file.
#pragma once

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace ricochet::test_support {

struct ProgramOutcome {
  int status = -1;      // the exit status; -1 if the command did not exit (a signal ended it)
  int wait_status = 0;  // as pclose() returned it
  std::string output;   // its standard output (with " 2>&1" in the command, its errors too)
};

// Runs `command` through /bin/sh and waits for it.
inline ProgramOutcome run_shell(const std::string& command) {
  ProgramOutcome o;
  FILE* p = popen(command.c_str(), "r");
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), p)) o.output += buf.data();
  o.wait_status = pclose(p);
  o.status = WIFEXITED(o.wait_status) ? WEXITSTATUS(o.wait_status) : -1;
  return o;
}

// `ricochet ARGS` through /bin/sh, after the shell commands `prefix` (e.g. "cd DIR &&"), its
// standard output and errors together.
inline ProgramOutcome run_ricochet(const std::string& args, const std::string& prefix = "") {
  return run_shell(prefix + " " + std::string(RICOCHET_BINARY) + " " + args + " 2>&1");
}

// Starts `args` (args[0] the program) without waiting, standard input from /dev/null, standard
// output and errors to `log`; std::runtime_error if it cannot be started.
inline pid_t start_process(const std::vector<std::string>& args, const std::filesystem::path& log) {
  std::vector<std::string> a = args;
  std::vector<char*> argv;
  for (auto& x : a) argv.push_back(x.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&fa, 1, 2);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) throw std::runtime_error("cannot start " + args[0]);
  return pid;
}

// Waits for a started process: its exit status, -1 if it did not exit.
inline int wait_exit(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace ricochet::test_support
