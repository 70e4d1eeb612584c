// Gates: pass/fail checks on a sweep table (DIR/summary.csv of `ricochet sweep`), read from a
// TOML gate file (format: docs/gates.md), reported one line per gate and as JUnit XML.
//   ricochet check SUMMARY.csv GATES.toml [--junit FILE]
// Exit status: 0 every gate passed; 4 a gate failed; 2 bad input (one line on stderr naming the
// file and the line or key; nothing written); 1 anything else (e.g. the JUnit file could not be
// written).
#pragma once

#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "harness/outputs/csv_reader.hpp"

namespace ricochet {

// One value a selector accepts. A value that reads as a number (a TOML number, or a TOML string
// that parse_csv_number accepts) matches a cell whose number is equal to 12 significant digits
// (1e-6 matches "1e-06" and "0.000001"); otherwise the cell text must be equal.
struct MatchValue {
  std::string text;             // as written in the gate file (numbers in shortest form)
  std::optional<double> number;  // set when the value reads as a number
};

// column = value, or column = [v1, v2, ...] (any of them).
struct SelectorTerm {
  std::string column;
  std::vector<MatchValue> any_of;
};

// A row is selected when every term matches (an empty selector selects every row).
using Selector = std::vector<SelectorTerm>;

enum class GateKind { max, min, near, ratio, count, pattern };

struct PatternCell {
  Selector where;
  std::string expect;
};

struct Gate {
  std::string name;
  GateKind kind = GateKind::max;
  std::string location;  // "FILE:LINE" of the gate's table, for messages
  std::string column;    // max, min, near, ratio: the value; pattern: the compared column
  Selector where;        // max, min, near, count
  bool allow_empty = false;  // max, min, near: an empty selection passes
  // max, min
  double limit = 0.0;
  bool strict = false;
  // near
  double reference = 0.0;
  std::optional<double> tolerance, rel_tolerance;
  // ratio
  Selector numerator, denominator;
  std::optional<double> floor, ceiling;
  // count
  std::optional<long> min_rows, max_rows;
  // pattern
  std::vector<PatternCell> cells;
};

struct GateFile {
  std::string file;                 // as given
  std::string name;                 // JUnit suite name: `name` key, else the file's stem
  std::optional<long> require_rows;  // the table must have at least this many rows
  std::vector<Gate> gates;
};

struct GateResult {
  std::string name;
  bool passed = false;
  std::vector<std::string> failures;  // one per failing row or cell, each naming the run and margin
  std::vector<std::string> notes;     // e.g. the worst row of a passing gate and its margin
  int checked_rows = 0;               // rows (or cells) the gate looked at
};

// Reads and validates a gate file. InputError "FILE:LINE: KEY: what is wrong; allowed: ..." for
// TOML syntax errors, unknown kinds or keys, missing keys, and wrong types or ranges.
GateFile read_gates(const std::filesystem::path& path);
// Same, from TOML text; `file` names it in messages.
GateFile parse_gates(std::string_view toml_text, const std::string& file);

// Evaluates every gate on the table; if require_rows is set, a first result named
// "require_rows" checks the row count. Never throws for problems of the table: a missing
// column, an empty or non-numeric cell, or a selector that matches the wrong number of rows
// fails the gate with a message.
std::vector<GateResult> evaluate_gates(const CsvTable& table, const GateFile& gates);

// One line per gate: "PASS NAME (N rows)[; note...]" or "FAIL NAME: failure; failure; ...".
std::string describe(const GateResult& result);

// JUnit XML: one <testsuite name=SUITE> with one <testcase> per gate; a failing gate gets a
// <failure message="FIRST FAILURE" type="gate"> whose text lists every failure, one per line;
// notes go to <system-out>. Text is XML-escaped; control characters that XML 1.0 forbids are
// written as '?'. `elapsed_seconds` is the suite's time attribute.
std::string junit_xml(const std::vector<GateResult>& results, const std::string& suite,
                      double elapsed_seconds);

// Evaluates the gates, prints describe() of each result and a final line
// "gates: P passed, F failed" on `out`, writes the JUnit XML atomically to `junit_path`.
// Returns 0 if every gate passed, 4 otherwise. Throws std::runtime_error if the JUnit file
// cannot be written. For `ricochet sweep --check GATES.toml`: call read_gates() before the
// sweep runs (bad gate file = exit 2 before any work), then read_csv() the summary and this.
int run_gates(const CsvTable& table, const GateFile& gates, const std::filesystem::path& junit_path,
              std::ostream& out);

// run_gates, returning the results instead of the status (`ricochet reproduce` records them).
std::vector<GateResult> check_gates(const CsvTable& table, const GateFile& gates, const std::filesystem::path& junit_path,
                                    std::ostream& out);

// What describe() says after the gate's name: "N rows[; note...]" for a passing gate, its
// failures joined by "; " for a failing one.
std::string gate_detail(const GateResult& result);

// `ricochet check SUMMARY.csv GATES.toml [--junit FILE]`.
struct CheckCommand {
  std::string summary_csv, gates_toml;
  std::string junit;  // empty: gates-junit.xml next to SUMMARY.csv
};

// Reads both files, then run_gates with the lines on `out`. Returns 0 all gates passed, 4 a gate
// failed. Throws InputError for bad input (nothing written), std::runtime_error when the JUnit
// file cannot be written.
int run_command(const CheckCommand& c, std::ostream& out);

inline constexpr int kGateFailedExit = 4;

}  // namespace ricochet
