// A sweep file (docs/sweeps.md): base cases plus lists of case-key values to cross, read and
// validated, and its expansion into the list of runs. Each run is a base case (the sweep's, or
// its group's own) with a list of `--set KEY=VALUE` overrides.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <toml++/toml.h>

namespace ricochet {

// One case-key value of a sweep file.
struct SweepValue {
  std::string key;      // canonical dotted case key, array elements as [N], e.g. "obstacles[0].friction"
  std::string toml;     // the value as TOML text, e.g. "1e-5", "\"M1\"", "[0.0, -9.81]"
  std::string display;  // the value for tables and run ids: strings without quotes, e.g. "M1"
  std::string where;    // "FILE:LINE: KEY" of the value in the sweep file, for messages

  std::string set_arg() const { return key + "=" + toml; }  // the --set argument
};

struct SweepAxis {
  std::string key;                 // canonical case key
  std::vector<SweepValue> values;  // in the order written; at least one
};

// The search options of a stability group (`kind = "stability"`): the options of `ricochet
// stability` (harness/stability/stability.hpp), each as the sweep file gives it, in the order of
// the command's help; only the ones given are passed on, so the command's defaults apply.
struct SweepStabilityOption {
  std::string key;   // sweep-file key: tolerance, max_runs, energy_bound, end
  std::string flag;  // the command's option: --tolerance, --max-runs, --energy-bound, --end
  std::string text;  // the value as passed on, e.g. "0.05", "12"
};

struct SweepGroup {
  std::string name;
  std::string description;
  std::filesystem::path base;         // the group's own base case, resolved; empty = the sweep's
  std::vector<SweepValue> set;        // group overrides
  std::vector<SweepAxis> cross;       // crossed in the order written (first = outermost)
  std::vector<SweepValue> reference;  // the group's own reference runs; empty = none
  bool reference_opt_out = false;     // `reference = false`: not compared with the sweep's [reference]
  std::string error_probe = "P";      // probe whose displacement error is measured (own reference)
  // `kind = "stability"`: each combination is a stability search (`ricochet stability`), not a
  // run; such a group has no reference and is never compared with the sweep's [reference].
  bool stability = false;
  std::vector<SweepStabilityOption> stability_options;  // the search options given, in order
  std::string where;                  // "FILE:LINE: group[N]"
};

// The sweep's shared reference, the top-level [reference] table: one run (and an optional
// check run) that every group without its own `reference` is compared with.
struct SweepReference {
  bool present = false;
  std::string name = "shared";        // run ids reference/<name> and reference/<name>-check
  std::filesystem::path base;         // its own base case, resolved; empty = the sweep's
  std::vector<SweepValue> set;        // its overrides, after the sweep's `set`; at least one
  std::vector<SweepValue> check;      // the check run's overrides on top; empty = no check run
  std::string error_probe = "P";      // probe whose displacement error is measured
  std::string where;                  // "FILE:LINE: reference"

  std::string id() const { return "reference/" + name; }
  std::string check_id() const { return id() + "-check"; }
};

struct SweepSpec {
  std::string file;             // the sweep file, as given
  std::string name;             // default: the file's stem
  std::string description;
  std::filesystem::path base;   // the base case file, resolved against the sweep file's folder;
                                // empty if every group names its own
  std::vector<SweepValue> set;  // overrides for every run, the shared reference's included
  SweepReference reference;     // the top-level [reference], if `present`
  std::vector<SweepGroup> groups;
};

// One run of an expanded sweep.
struct SweepRun {
  std::string id;      // "<group>/<NNN>-<slug>", "<group>/reference[-<slug>]", or the shared
                       // reference's "reference/<name>" and "reference/<name>-check"
  std::string group;   // the group's name; "reference" for the shared reference's runs
  std::filesystem::path base;  // the run's base case: its group's own, else the sweep's
  bool is_reference = false;
  std::vector<SweepValue> overrides;  // merged: sweep set, group set, crossed values (then reference values)
  std::vector<std::string> swept;     // keys of `overrides` that come from `cross` (or `reference`)
  std::string reference_id;           // id of the run's reference run; empty if none
  std::string reference_kind;         // "shared" (the sweep's [reference]) or "group"; empty if none
  std::string error_probe;            // probe name for the reference errors (groups with a reference)
  bool stability = false;             // a stability search (`ricochet stability`), not a run
  std::vector<SweepStabilityOption> stability_options;  // its search options (its group's)

  std::vector<std::string> set_args() const;  // "key=value" for read_case / ricochet run --set
  std::filesystem::path folder() const;       // "runs/<id>", relative to the sweep's output folder
};

// Reads and validates a sweep file (not the cases: see check_runs in sweep.hpp). The top-level
// `base` may be left out when every group names its own. Throws InputError with a one-line
// message "FILE:LINE: KEY: what is wrong; allowed: ...".
SweepSpec read_sweep(const std::string& file);

// The runs of a sweep, each on its group's base case (else the sweep's): first the shared
// reference run and its check run (on the reference's base, else the sweep's), then for each
// group in order, its reference runs (one per distinct combination of the crossed keys that
// `reference` does not set, in first-seen order), then the cartesian product of its `cross`
// lists (the first key varies slowest). The runs of groups without their own reference (and not opted out)
// are compared with the shared reference; the check run is compared with the reference. Throws
// InputError if the sweep has more than 100000 runs, or if a group (or the shared reference)
// has no base case (only for a spec that read_sweep did not make).
std::vector<SweepRun> expand(const SweepSpec& spec);

// --- pieces, exposed for tests ----------------------------------------------------------------

// A name that may name a folder: letters, digits, '_', '-', '.', not '.' or '-' first, at most 64
// characters (sweeps, groups, a study's sweeps).
bool valid_name(const std::string& s);

// A TOML value as TOML text that parses back to the same value: strings quoted and escaped,
// floats in shortest round-trip form with a short exponent ("1e-5", "0.25", "2.0"), arrays as
// "[a, b]", tables as "{ k = v }". Throws InputError for date/time values.
std::string toml_text(const toml::node& value);

// The display form of a value: like toml_text, except that a top-level string is unquoted.
std::string display_text(const toml::node& value);

// A key with array indices written as [N]: "bodies.0.element" -> "bodies[0].element".
std::string canonical_key(const std::string& key);

// Run-id slug of key=value pairs joined by '_', every character outside [A-Za-z0-9._=-]
// replaced ('[' by '.', ']' dropped, others by '_'), capped at 120 characters.
std::string slug(const std::vector<SweepValue>& values);

}  // namespace ricochet
