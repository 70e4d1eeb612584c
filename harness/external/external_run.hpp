// A run whose scheme is an external code reached through an adapter (docs/peers.md): case.json
// written, the adapter run with a timeout and its CPU time measured, its result.json and
// history.csv checked and read into ricochet's summary.json and history.csv.
#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "harness/input/case_setup.hpp"
#include "harness/outputs/csv_reader.hpp"
#include "harness/outputs/json_io.hpp"

namespace ricochet {

// A run that failed: the adapter could not be started, exited non-zero, was killed or timed
// out, or left a result that does not pass the checks. what() is one line: "external scheme
// 'NAME': REASON".
struct ExternalRunFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// What the adapter process did, as measured by ricochet.
struct AdapterProcess {
  std::vector<std::string> argv;  // as run
  int exit_status = 0;            // its exit status (0 when it exited normally with 0)
  double wall_seconds = 0.0;      // start to end [s]
  double cpu_seconds = 0.0;       // user + system of the adapter and the processes it waited for [s]
  long peak_memory_bytes = 0;     // largest resident set of those processes [bytes]
};

// The adapter's command as it will be run (placeholders resolved, the shipped adapter's path),
// without the two arguments run_external appends (case.json and the work folder).
std::vector<std::string> adapter_command(const CaseSpec& spec);

// The checks of docs/peers.md ("The checks") on the adapter's files, and the summary and history
// ricochet writes from them. Throws ExternalRunFailure's reason text as std::runtime_error
// (run_external adds the scheme's name); exposed for the tests.
struct ExternalResult {
  Json summary;                             // summary.json, complete
  std::vector<std::string> columns;         // history.csv's columns, in ricochet's order
  std::vector<double> rows;                 // row-major
};
ExternalResult import_external_result(const PreparedCase& pc, const Json& case_json,
                                      const std::filesystem::path& work, const AdapterProcess& process);

// Runs the case's external scheme into `out_dir` and returns the exit status of `ricochet run`:
// 0 (ok) or 3 (diverged). Throws ExternalRunFailure for a failed run (nothing written but
// OUT/external/), InputError for an output folder that cannot be written. Progress lines on
// stderr unless quiet.
int run_external(const PreparedCase& pc, const std::filesystem::path& out_dir, bool quiet);

}  // namespace ricochet
