// The entry functions of the fuzz targets (tests/fuzz/fuzz_*.cpp, libFuzzer) and of their
// regression replay in the normal build (tests/harness/input/test_fuzz_regressions.cpp), one per reader.
// Each takes the raw bytes of one input and returns true if the reader accepted it, false if it
// rejected it with an InputError (the one expected way to say no). Anything else that escapes
// (another exception type, a crash, a sanitizer report, a hang, running out of memory) is a
// finding; so is an accepted result that breaks the reader's documented promises, which the
// entries check and report as std::logic_error. Input formats: docs/reliability.md, Fuzzing.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "harness/gates/gates.hpp"
#include "harness/input/case_setup.hpp"
#include "harness/input/case_spec.hpp"
#include "harness/input/gmsh_reader.hpp"
#include "harness/input/input_error.hpp"
#include "harness/outputs/csv_reader.hpp"

#ifndef RICOCHET_SOURCE_DIR
#error "RICOCHET_SOURCE_DIR (the source tree) must be defined: meshes and gate includes resolve there"
#endif

namespace ricochet::fuzz {

// Where the inputs "live": a case's mesh files resolve against tests/data (which holds .msh
// files), a gate file's includes against the verification study's folder (which holds
// gates_common.toml).
// Neither file exists; only its folder matters.
inline const std::string kCaseFile = RICOCHET_SOURCE_DIR "/tests/data/fuzz-case.toml";
inline const std::string kMeshFile = "fuzz-mesh.msh";
inline const std::string kCsvFile = "fuzz-table.csv";
inline const std::string kGatesFile = RICOCHET_SOURCE_DIR "/cases/verification/fuzz-gates.toml";

inline std::string_view as_text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// An expected rejection: false, and its message on stderr if RICOCHET_FUZZ_VERBOSE is set (to
// see why a seed or a crash file is rejected: RICOCHET_FUZZ_VERBOSE=1 build-fuzz/fuzz_case FILE).
inline bool rejected(const InputError& e) {
  static const bool verbose = std::getenv("RICOCHET_FUZZ_VERBOSE") != nullptr;
  if (verbose) std::fprintf(stderr, "rejected: %s\n", e.what());
  return false;
}

[[noreturn]] inline void broken(const std::string& what) { throw std::logic_error("fuzz: " + what); }

// The case input: leading lines that start with "--set " are overrides (the rest of the line,
// without a trailing '\r', is the KEY=VALUE argument, as `ricochet run --set` gets it); the
// remaining text is the case file.
struct CaseInput {
  std::vector<std::string> overrides;
  std::string_view text;
};

inline CaseInput split_case_input(std::string_view data) {
  CaseInput in;
  constexpr std::string_view prefix = "--set ";
  while (data.substr(0, prefix.size()) == prefix) {
    const std::size_t eol = data.find('\n');
    std::string_view line = data.substr(prefix.size(), eol == std::string_view::npos ? data.npos : eol - prefix.size());
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    in.overrides.emplace_back(line);
    data = eol == std::string_view::npos ? std::string_view() : data.substr(eol + 1);
  }
  in.text = data;
  return in;
}

// The memory ceiling of a fuzzed case [GiB]: limits.max_memory, or this if lower. A real run
// may plan up to 80 % of the machine's memory (docs/reliability.md, Limits), but a model of
// millions of cells is no bug and would only be reported as out of memory (-rss_limit_mb)
// or too slow (-timeout) under the sanitizers. 0.1 GiB is about 25000 cells.
inline constexpr double kCaseMaxMemoryGib = 0.1;

// read_case_text with the overrides, then prepare_case (meshes built or read, node sets,
// model, time step, run plan) under kCaseMaxMemoryGib.
inline bool case_entry(std::string_view data) {
  const CaseInput in = split_case_input(data);
  try {
    CaseSpec spec = read_case_text(in.text, kCaseFile, in.overrides);
    spec.limits.max_memory_gib = std::min(spec.limits.max_memory_gib, kCaseMaxMemoryGib);
    const PreparedCase pc = prepare_case(spec);
    if (!(pc.settings.dt > 0.0) || !std::isfinite(pc.settings.dt)) broken("prepared step not positive and finite");
    return true;
  } catch (const InputError& e) {
    return rejected(e);
  }
}

// The promises of gmsh_reader.hpp and mesh.hpp about an accepted mesh.
inline void check_mesh(const Mesh& m) {
  const int n = m.num_nodes();
  if (m.num_cells() == 0) broken("accepted mesh without cells");
  if (!m.nodes.allFinite()) broken("accepted mesh with a non-finite coordinate");
  std::vector<char> used(static_cast<std::size_t>(n), 0);
  auto cell = [&](const int* c, int count) {
    for (int k = 0; k < count; ++k) {
      if (c[k] < 0 || c[k] >= n) broken("cell refers to node index out of range");
      used[static_cast<std::size_t>(c[k])] = 1;
    }
    if (!(signed_area(m, c, count) > 0.0)) broken("accepted cell that is not counter-clockwise");
  };
  for (const auto& q : m.quads) cell(q.data(), 4);
  for (const auto& t : m.tris) cell(t.data(), 3);
  if (std::find(used.begin(), used.end(), 0) != used.end()) broken("accepted mesh with a node used by no cell");
  for (const auto& [name, set] : m.node_sets) {
    if (name.empty()) broken("node set without a name");
    for (std::size_t k = 0; k < set.size(); ++k) {
      if (set[k] < 0 || set[k] >= n) broken("node set \"" + name + "\" refers to node index out of range");
      if (k > 0 && set[k] <= set[k - 1]) broken("node set \"" + name + "\" not sorted and unique");
    }
  }
}

inline bool gmsh_entry(std::string_view data) {
  try {
    check_mesh(parse_gmsh(std::string(data), kMeshFile));
    return true;
  } catch (const InputError& e) {
    return rejected(e);
  }
}

// parse_csv, then every cell through parse_csv_number and the lookups the gates use.
inline bool csv_entry(std::string_view data) {
  try {
    const CsvTable t = parse_csv(data, kCsvFile);
    if (t.columns.empty()) broken("accepted table without columns");
    if (t.lines.size() != t.rows.size()) broken("one line number per row");
    for (std::size_t r = 0; r < t.rows.size(); ++r) {
      if (t.rows[r].size() != t.columns.size()) broken("row with another field count than the header");
      for (std::size_t c = 0; c < t.columns.size(); ++c) {
        (void)parse_csv_number(t.rows[r][c]);
        const std::string* cell = t.find(r, t.columns[c]);
        if (!cell || &t.at(r, t.columns[c]) != cell) broken("find and at disagree");
      }
    }
    (void)t.column_list();
    return true;
  } catch (const InputError& e) {
    return rejected(e);
  }
}

// The table the gates of a gate input are evaluated on when the input brings none.
inline constexpr std::string_view kGateTable =
    "run_id,group,kind,status,reason,case,mesh,time.dt,scheme,summary.scheme,energy_error_max,"
    "penetration_max,contact_iterations.steps_with_contact,wall_seconds,final.momentum_x\n"
    "table1/0,table1,run,ok,,oblique_plate,M1,1e-05,semi_explicit,semi_explicit,0.01,0,448,1.5,0.09\n"
    "table1/1,table1,run,diverged,energy growth,oblique_plate,M2,1e-4,implicit,implicit,nan,inf,,3,\n"
    "friction/0,friction,run,ok,,bar_wall,M1,0.000001,implicit,implicit,-0.5,1e-12,800,2.5e3,-1\n"
    "friction/1,friction,run,failed,\"bad, input\",bar_wall,M1,1e-6,explicit_penalty,explicit_penalty,"
    "0,0,0,0,0\n";

// The gate input: a gate file's TOML text, optionally followed by a line "%%csv" and the CSV
// table to evaluate its gates on (else kGateTable). parse_gates, then evaluate_gates, describe
// and junit_xml: everything `ricochet check` does but writing the files.
inline bool gates_entry(std::string_view data) {
  std::string_view toml_text = data, csv_text = kGateTable;
  for (std::size_t at = 0; (at = data.find("%%csv", at)) != std::string_view::npos; at += 5) {
    if (at != 0 && data[at - 1] != '\n') continue;
    const std::size_t eol = data.find('\n', at);
    const std::string_view rest = data.substr(at + 5, eol == data.npos ? data.npos : eol - at - 5);
    if (!rest.empty() && rest != "\r") continue;
    toml_text = data.substr(0, at);
    csv_text = eol == data.npos ? std::string_view() : data.substr(eol + 1);
    break;
  }
  try {
    const GateFile gates = parse_gates(toml_text, kGatesFile);
    CsvTable table;
    try {
      table = parse_csv(csv_text, kCsvFile);
    } catch (const InputError& e) {
      rejected(e);
      return true;  // the gate file was accepted; a bad table is the CSV target's business
    }
    const std::vector<GateResult> results = evaluate_gates(table, gates);
    std::size_t expected = gates.gates.size() + (gates.require_rows ? 1 : 0);
    if (results.size() != expected) broken("one result per gate");
    for (const GateResult& r : results) (void)describe(r);
    (void)junit_xml(results, gates.name, 0.0);
    return true;
  } catch (const InputError& e) {
    return rejected(e);
  }
}

}  // namespace ricochet::fuzz
