#include "harness/sweeps/sweep_slurm.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <ostream>
#include <stdexcept>
#include <system_error>

#include "harness/input/input_error.hpp"
#include "harness/outputs/atomic_file.hpp"
#include "harness/sweeps/sweep.hpp"

namespace ricochet {
namespace {

namespace fs = std::filesystem;

std::string errno_text(int e) { return std::generic_category().message(e); }

// A log file in an #SBATCH line: the folder `dir` and the file name `pattern` (with Slurm's file
// name patterns: %a the array index, %A the array's job id, %j the job id) in double quotes
// (sbatch's own reading of the line takes them off), each % of the folder doubled. sbatch cannot
// carry a double quote or a line break there, and a backslash turns the patterns off: such a
// folder is refused.
std::string sbatch_log(const fs::path& dir, const std::string& pattern) {
  const std::string s = dir.string();
  for (const char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (ch == '"' || ch == '\\' || c < 0x20 || c == 0x7f)
      throw InputError("ricochet sweep: --slurm: the job logs' folder '" + one_line(s) +
                       "' holds a double quote, a backslash or a control character, which an #SBATCH line cannot "
                       "carry; give --out a folder without them");
  }
  std::string out = "\"";
  for (const char ch : s) out += ch == '%' ? std::string("%%") : std::string(1, ch);
  return out + "/" + pattern + "\"";
}

// sbatch --parsable prints "JOBID" or "JOBID;CLUSTER": the job id, or empty if it is not one.
std::string job_id(const std::string& answer) {
  std::string id = first_line(answer);
  id = id.substr(0, id.find(';'));
  if (id.empty() || id.size() > 20 || id.find_first_not_of("0123456789") != std::string::npos) return {};
  return id;
}

// The scripts' heading comments: what they run, and how `--slurm` submits them.
std::string array_comment(const SlurmJobs& j) {
  return "# Shard K of " + std::to_string(j.shards) + " of the sweep " + j.sweep_name +
         ", K = the array task id (docs/sweeps.md, \"Running on a\n"
         "# cluster\"). Written and submitted by `ricochet sweep --slurm` (sbatch --parsable " +
         j.array_file().filename().string() +
         ");\n"
         "# submitted again, each shard runs only the runs it has not finished.\n";
}

std::string merge_comment(const SlurmJobs& j) {
  return "# The merge of the " + std::to_string(j.shards) + " shards of the sweep " + j.sweep_name +
         (j.gates_file.empty() ? std::string() : ", then its gates") +
         " (docs/sweeps.md, \"Running on a\n"
         "# cluster\"). Written and submitted by `ricochet sweep --slurm` after the array job\n"
         "# (sbatch --parsable --dependency=afterany:ARRAY_JOB_ID " +
         j.merge_file().filename().string() +
         "): it starts once every\n"
         "# shard has ended, however it ended.\n";
}

// The #SBATCH lines both scripts share at their end: the --slurm-option values, in order (a
// later line overrides an earlier one, ours included). An --array option goes to the array only.
std::string user_lines(const SlurmJobs& j, bool array) {
  std::string s;
  for (const std::string& o : j.options)
    if (array || !is_array_option(o)) s += "#SBATCH " + o + "\n";
  return s;
}

}  // namespace

fs::path SlurmJobs::slurm_dir() const { return (out_dir.is_absolute() ? out_dir : workdir / out_dir).lexically_normal() / "slurm"; }
fs::path SlurmJobs::array_file() const { return slurm_dir() / "array.sbatch"; }
fs::path SlurmJobs::merge_file() const { return slurm_dir() / "merge.sbatch"; }

std::string shell_quote(const std::string& text) {
  std::string s = "'";
  for (const char c : text) s += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return s + "'";
}

void check_slurm_option(const std::string& option) {
  std::string why;
  if (option.empty() || option[0] != '-' || option == "-" || option == "--")
    why = "expected an sbatch option, starting with '-'";
  else if (option.size() > 1000)
    why = "longer than 1000 characters";
  for (const char ch : option) {
    const auto c = static_cast<unsigned char>(ch);
    if (why.empty() && (c < 0x20 || c == 0x7f)) why = "holds a line break or another control character";
  }
  if (!why.empty())
    throw InputError("ricochet sweep: --slurm-option '" + one_line(option) + "': " + why +
                     "; one #SBATCH option per --slurm-option, e.g. --partition=NAME, --time=2:00:00, --account=NAME");
}

bool is_array_option(const std::string& option) {
  if (option.rfind("--", 0) == 0) {
    const std::string name = option.substr(2, option.find_first_of("= \t") - 2);
    return name == "array";
  }
  return option.size() >= 2 && option[0] == '-' && option[1] == 'a';
}

SlurmScripts slurm_scripts(const SlurmJobs& j) {
  const std::string program = shell_quote(j.program.string());
  const std::string file = shell_quote(j.sweep_file);
  const std::string out = shell_quote(j.out_dir.string());
  const std::string logs = j.slurm_dir().string();
  const std::string n = std::to_string(j.shards);
  const std::string cd = "cd " + shell_quote(j.workdir.string()) + "\n";

  SlurmScripts s;
  std::string& a = s.array;
  a = "#!/bin/bash\n";
  a += array_comment(j);
  a += "#SBATCH --job-name=ricochet-" + j.sweep_name + "\n";
  a += "#SBATCH --array=1-" + n + "\n";
  a += "#SBATCH --ntasks=1\n";
  // One CPU per thread of each of the shard's --jobs runs; with --threads 0 (every core of
  // whatever node) there is no count to ask for: the --slurm-option values decide.
  if (j.threads > 0) a += "#SBATCH --cpus-per-task=" + std::to_string(j.jobs * j.threads) + "\n";
  a += "#SBATCH --output=" + sbatch_log(j.slurm_dir(), "shard-%a-%A.out") + "\n";
  a += "#SBATCH --open-mode=append\n";  // a task that Slurm requeues (preemption) adds to its log
  a += user_lines(j, true);
  a += "set -eu\n";
  a += cd;
  a += "exec " + program + " sweep " + file + " --out " + out + " --shard \"${SLURM_ARRAY_TASK_ID}/" + n + "\"";
  if (j.jobs != 1) a += " --jobs " + std::to_string(j.jobs);
  a += " --threads " + std::to_string(j.threads);
  if (j.repeat != 1) a += " --repeat " + std::to_string(j.repeat);
  if (j.force) a += " --force";
  if (j.quiet) a += " --quiet";
  a += "\n";

  std::string& m = s.merge;
  m = "#!/bin/bash\n";
  m += merge_comment(j);
  m += "#SBATCH --job-name=ricochet-" + j.sweep_name + "-merge\n";
  m += "#SBATCH --ntasks=1\n";
  m += "#SBATCH --cpus-per-task=1\n";
  m += "#SBATCH --output=" + sbatch_log(j.slurm_dir(), "merge-%j.out") + "\n";
  m += "#SBATCH --open-mode=append\n";
  m += user_lines(j, false);
  m += "set -eu\n";
  m += cd;
  m += "exec " + program + " sweep " + file + " --out " + out + " --merge";
  if (j.repeat != 1) m += " --repeat " + std::to_string(j.repeat);
  if (!j.gates_file.empty()) m += " --check " + shell_quote(j.gates_file);
  if (j.quiet) m += " --quiet";
  m += "\n";
  return s;
}

fs::path find_on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t end = std::min(dirs.find(':', start), dirs.size());
    const std::string dir = end == start ? "." : dirs.substr(start, end - start);  // an empty entry: the working folder
    const fs::path p = fs::path(dir) / name;
    struct stat st {};
    if (stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode) && access(p.c_str(), X_OK) == 0) return p;
    start = end + 1;
  }
  return {};
}

std::string first_line(const std::string& text) {
  std::size_t start = text.find_first_not_of(" \t\r\n");
  if (start == std::string::npos) return {};
  std::string line = text.substr(start, text.find('\n', start) - start);
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
  return line.size() > 300 ? line.substr(0, 300) + "..." : line;
}

ProgramOutput run_program(const std::vector<std::string>& argv_in, const fs::path& cwd) {
  std::vector<std::string> args = argv_in;
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const std::string cwd_text = cwd.string();
  const char* dir = cwd_text.empty() ? nullptr : cwd_text.c_str();
  int out[2], err[2], report[2];
  if (pipe2(out, O_CLOEXEC) != 0) throw std::runtime_error("pipe: " + errno_text(errno));
  if (pipe2(err, O_CLOEXEC) != 0) {
    const int e = errno;
    close(out[0]), close(out[1]);
    throw std::runtime_error("pipe: " + errno_text(e));
  }
  if (pipe2(report, O_CLOEXEC) != 0) {
    const int e = errno;
    close(out[0]), close(out[1]), close(err[0]), close(err[1]);
    throw std::runtime_error("pipe: " + errno_text(e));
  }
  const pid_t pid = fork();
  if (pid == 0) {
    // The child: async-signal-safe calls only, until exec.
    const int in = open("/dev/null", O_RDONLY);
    if (in >= 0 && dup2(in, 0) >= 0 && dup2(out[1], 1) >= 0 && dup2(err[1], 2) >= 0 && (!dir || chdir(dir) == 0))
      execv(argv[0], argv.data());
    const int e = errno;
    if (write(report[1], &e, sizeof e) < 0) _exit(127);
    _exit(127);
  }
  const int fork_errno = errno;
  close(out[1]), close(err[1]), close(report[1]);
  if (pid < 0) {
    close(out[0]), close(err[0]), close(report[0]);
    throw std::runtime_error("cannot start '" + args[0] + "': fork: " + errno_text(fork_errno));
  }
  ProgramOutput r;
  // Both pipes at once, so that a child that fills one while we read the other cannot block.
  pollfd fds[2] = {{out[0], POLLIN, 0}, {err[0], POLLIN, 0}};
  std::string* into[2] = {&r.out, &r.err};
  int open_fds = 2;
  char buf[4096];
  while (open_fds > 0) {
    if (poll(fds, 2, -1) < 0) {
      if (errno == EINTR) continue;
      break;
    }
    for (int i = 0; i < 2; ++i) {
      if (fds[i].fd < 0 || !(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      const ssize_t got = read(fds[i].fd, buf, sizeof buf);
      if (got > 0) {
        into[i]->append(buf, static_cast<std::size_t>(got));
      } else if (got == 0 || errno != EINTR) {
        close(fds[i].fd);
        fds[i].fd = -1;
        --open_fds;
      }
    }
  }
  for (const pollfd& f : fds)
    if (f.fd >= 0) close(f.fd);
  int exec_errno = 0;
  ssize_t got = 0;
  do got = read(report[0], &exec_errno, sizeof exec_errno);
  while (got < 0 && errno == EINTR);
  close(report[0]);
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (got == static_cast<ssize_t>(sizeof exec_errno))
    throw std::runtime_error("cannot start '" + args[0] + "': " + errno_text(exec_errno));
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : WIFSIGNALED(status) ? 128 + WTERMSIG(status) : -1;
  return r;
}

SlurmSubmission submit_slurm(const SlurmJobs& jobs) {
  const fs::path sbatch = find_on_path("sbatch");
  if (sbatch.empty())
    throw std::runtime_error("--slurm: sbatch not found on PATH (Slurm's client commands); nothing written or submitted "
                             "(--dry-run prints the scripts without it)");
  const SlurmScripts s = slurm_scripts(jobs);
  write_file_atomic(jobs.array_file(), s.array);
  write_file_atomic(jobs.merge_file(), s.merge);

  auto submit = [&](std::vector<std::string> args, const fs::path& script, const std::string& already) {
    args.insert(args.begin(), {sbatch.string(), "--parsable"});
    args.push_back(script.string());
    const ProgramOutput r = run_program(args);
    const std::string id = job_id(r.out);
    if (r.status == 0 && !id.empty()) return id;
    std::string why = r.status != 0 ? "exit " + std::to_string(r.status) : "no job id in its answer '" + first_line(r.out) + "'";
    if (const std::string line = first_line(r.err); !line.empty()) why += ": " + line;
    throw std::runtime_error("--slurm: sbatch " + script.string() + " failed (" + why + ")" + already);
  };
  SlurmSubmission sub;
  sub.array_job = submit({}, jobs.array_file(), "; nothing submitted");
  sub.merge_job = submit({"--dependency=afterany:" + sub.array_job}, jobs.merge_file(),
                         "; the array job " + sub.array_job + " was submitted: cancel it (scancel " + sub.array_job +
                             ") or merge by hand once it has ended (ricochet sweep ... --merge)");
  return sub;
}

void check_no_slurm_options(const SweepCommand& c) {
  const char* given = c.shards ? "--shards" : !c.slurm_options.empty() ? "--slurm-option" : c.dry_run ? "--dry-run" : nullptr;
  if (given)
    throw InputError(std::string("ricochet sweep: ") + given + " goes with --slurm (it submits the sweep to Slurm as a job array)");
}

int slurm_command(const SweepCommand& c, const std::string& sweep_name, std::size_t runs, const fs::path& out_dir,
                  std::ostream& out) {
  const std::string p = "ricochet sweep: ";
  if (c.merge || c.options.shard)
    throw InputError(p + "--slurm submits the shards and the merge itself: not with " + (c.merge ? "--merge" : "--shard"));
  for (const std::string& o : c.slurm_options) check_slurm_option(o);

  SlurmJobs j;
  j.sweep_name = sweep_name;
  j.sweep_file = c.file;
  j.out_dir = out_dir;
  std::error_code ec;
  j.workdir = fs::current_path(ec);
  if (ec) throw std::runtime_error("--slurm: the working folder: " + ec.message());
  j.program = c.options.executable.empty() ? fs::read_symlink("/proc/self/exe") : c.options.executable;
  j.program = fs::absolute(j.program);
  j.shards = c.shards ? *c.shards : static_cast<int>(std::min<std::size_t>(runs, kDefaultMaxSlurmShards));
  j.shards = std::max(j.shards, 1);
  j.jobs = c.options.jobs;
  j.threads = c.options.threads.value_or(1);
  j.repeat = c.options.repeat;
  j.force = c.options.force;
  j.quiet = c.options.quiet;
  j.gates_file = c.gates_file;
  j.options = c.slurm_options;

  if (c.dry_run) {
    const SlurmScripts s = slurm_scripts(j);
    out << "# ---- " << j.array_file().string() << ": submitted as `sbatch --parsable " << shell_quote(j.array_file().string())
        << "`\n"
        << s.array << "# ---- " << j.merge_file().string()
        << ": submitted as `sbatch --parsable --dependency=afterany:ARRAY_JOB_ID " << shell_quote(j.merge_file().string())
        << "`\n"
        << s.merge;
    return 0;
  }
  const SlurmSubmission sub = submit_slurm(j);
  out << "slurm array job " << sub.array_job << ": " << j.shards << " shard" << (j.shards == 1 ? "" : "s") << " of sweep "
      << sweep_name << " (" << runs << " runs) -> " << out_dir.string() << " (" << j.array_file().string() << ")\n"
      << "slurm merge job " << sub.merge_job << ": after job " << sub.array_job << " has ended (afterany)"
      << (c.gates_file.empty() ? "" : ", then the gates of " + c.gates_file) << " (" << j.merge_file().string() << ")\n";
  return 0;
}

}  // namespace ricochet
