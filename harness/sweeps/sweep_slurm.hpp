// Sweeps on a Slurm cluster (docs/sweeps.md, "Running on a cluster"): `ricochet sweep FILE --slurm
// [--shards N] [--slurm-option OPT]... [--dry-run]` writes two batch scripts into DIR/slurm/ and
// submits them with Slurm's sbatch: a job array with one task per shard, task K running
// `ricochet sweep FILE --out DIR --shard K/N` (sweep_shard.hpp), and a merge job that starts when
// every task has ended, however it ended (--dependency=afterany), running
// `ricochet sweep FILE --out DIR --merge [--check GATES]`. The same command submitted again
// resumes: each shard skips the runs it finished (Resume), and the new merge job merges again.
//
// The scripts name every path in single quotes (bash) or double quotes (#SBATCH lines), run from
// the submitting command's working folder (so that the sweep file and DIR are the same paths as
// in a sweep run by hand there, and the runs' identity, overrides.json, is the same), and run the
// absolute path of this program. --dry-run prints them and writes and submits nothing; it needs
// no Slurm.
#pragma once

#include <cstddef>
#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

namespace ricochet {

struct SweepCommand;

// Slurm's default MaxArraySize is 1001 (array indices 0 ... 1000): the default number of shards,
// one per run, stays within it.
inline constexpr int kDefaultMaxSlurmShards = 1000;

// Everything the two scripts are made of, resolved (absolute program and working folder).
struct SlurmJobs {
  std::string sweep_name;              // the sweep's `name`, for the job names
  std::string sweep_file;              // as given on the command line (relative to workdir or absolute)
  std::filesystem::path out_dir;       // DIR, as the sweep resolved it (relative to workdir or absolute)
  std::filesystem::path workdir;       // absolute: the submitting command's working folder
  std::filesystem::path program;       // absolute: the ricochet program the tasks run
  int shards = 1;                      // N: array tasks 1 ... N
  int jobs = 1;                        // --jobs of each shard
  int threads = 1;                     // --threads of each shard's runs (0: all cores, no CPU count asked)
  int repeat = 1;                      // --repeat, the shards' and the merge's
  bool force = false;                  // --force, the shards'
  bool quiet = false;                  // --quiet, the shards' and the merge's
  std::string gates_file;              // --check, the merge's; empty: none
  std::vector<std::string> options;    // --slurm-option, as given: #SBATCH lines of both jobs (--array: the array's only)

  std::filesystem::path slurm_dir() const;    // DIR/slurm (absolute when DIR is not: workdir/DIR/slurm)
  std::filesystem::path array_file() const;   // DIR/slurm/array.sbatch
  std::filesystem::path merge_file() const;   // DIR/slurm/merge.sbatch
};

// The text of DIR/slurm/array.sbatch and DIR/slurm/merge.sbatch.
struct SlurmScripts {
  std::string array, merge;
};

// Throws InputError for a path the #SBATCH --output line cannot carry (a double quote, a
// backslash or a control character in the absolute DIR/slurm).
SlurmScripts slurm_scripts(const SlurmJobs& jobs);

// `text` as one bash word: in single quotes, each ' written '\''.
std::string shell_quote(const std::string& text);

// Checks one --slurm-option value: an sbatch option ("-" first), one line, at most 1000 characters.
// Throws InputError "ricochet sweep: --slurm-option 'TEXT': ...", naming what is allowed.
void check_slurm_option(const std::string& option);

// Whether an sbatch option sets the array (--array, -a): such an option goes to the array script only.
bool is_array_option(const std::string& option);

// The job ids sbatch gave the array and the merge job.
struct SlurmSubmission {
  std::string array_job, merge_job;
};

// Writes the two scripts (temporary file and rename each) and submits them: `sbatch --parsable
// ARRAY`, then `sbatch --parsable --dependency=afterany:ID MERGE`, each run as a child process
// (fork and exec of the sbatch found on PATH, no shell) from the working folder. Throws
// std::runtime_error, one line, if sbatch is not on PATH (before anything is written), if it
// fails (its exit status and the first line of its stderr), or if its answer is not a job id.
// If the merge job's submission fails, the message names the array job that was submitted.
SlurmSubmission submit_slurm(const SlurmJobs& jobs);

// The path of `name` in the folders of PATH (executable regular file), or empty.
std::filesystem::path find_on_path(const std::string& name);

// The output of a finished child process.
struct ProgramOutput {
  int status = -1;      // its exit status; 128 + N if killed by signal N
  std::string out, err; // its stdout and stderr
};

// The first line of `text` (a child's stderr), trimmed, at most 300 characters.
std::string first_line(const std::string& text);

// Runs `argv` (argv[0] a path; a relative one from `cwd`) as a child process in the folder `cwd`
// (empty: this process's), stdin from /dev/null, and collects its stdout and stderr. Throws
// std::runtime_error if it cannot be started (or `cwd` entered).
ProgramOutput run_program(const std::vector<std::string>& argv, const std::filesystem::path& cwd = {});

// The body of `ricochet sweep FILE --slurm ...`, called by run_command (sweep.hpp) once the sweep
// file, its runs and the gate file have been read and checked. Prints the job ids (or, with
// --dry-run, the scripts) on `out`; returns 0. Throws InputError for options that do not go
// with --slurm, std::runtime_error as submit_slurm.
int slurm_command(const SweepCommand& c, const std::string& sweep_name, std::size_t runs,
                  const std::filesystem::path& out_dir, std::ostream& out);

// The checks of the Slurm options of a sweep command that does not submit to Slurm: --shards,
// --slurm-option and --dry-run need --slurm. Throws InputError naming the option.
void check_no_slurm_options(const SweepCommand& c);

}  // namespace ricochet
