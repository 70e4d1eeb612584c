// One study of `ricochet reproduce` (harness/studies/reproduce.hpp): its tier's sweeps run in
// this process by the sweep machinery (run_sweep, resuming), their gates checked, then its post
// steps, and <out>/<study>/study.json written (docs/studies.md, Outputs).
#pragma once

#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "harness/gates/gates.hpp"
#include "harness/outputs/json_io.hpp"
#include "harness/studies/study_spec.hpp"
#include "harness/sweeps/sweep_spec.hpp"

namespace ricochet {

// A sweep entry with its sweep file and gate file read and its runs expanded and checked.
struct PreparedSweep {
  StudySweep entry;  // a copy: the prepared study may move
  SweepSpec spec;
  std::vector<SweepRun> runs;
  std::optional<GateFile> gates;
};

// A study ready to run in one tier: everything it reads is read and valid.
struct PreparedStudy {
  StudySpec spec;
  std::string tier;
  std::vector<PreparedSweep> sweeps;
};

// Reads the tier's sweep files (read_sweep, expand, check_runs) and gate files (the post steps'
// too). Throws InputError, naming the file, for bad input; nothing is written.
PreparedStudy prepare_study(StudySpec spec, const std::string& tier);

struct StudyRunOptions {
  std::filesystem::path out;  // <out>/<study>, absolute
  bool force = false;         // rerun every run
  bool quiet = false;         // no progress lines, no per-gate lines
};

// What study.json says, and what the report's stamp is made from.
struct StudyOutcome {
  Json json;
  std::string status;  // "passed", "gates failed", "failed" or "skipped"
};

// What the study's [requires] names and this machine lacks: "program ccx", "Python module
// getfem"; empty when it has everything.
std::vector<std::string> missing_requirements(const StudySpec& spec);

// The outcome of a study not run for what it lacks: study.json with status "skipped" and the
// reason, and one line.
StudyOutcome skip_study(const PreparedStudy& study, const StudyRunOptions& opt, const std::vector<std::string>& missing,
                        std::ostream& lines);

// Runs the study: each sweep into <out>/<name> with the entry's repeat, jobs and threads, its
// gates checked on its summary.csv (JUnit report <out>/<name>/gates-junit.xml); then, unless a
// sweep could not run, each post step. A sweep that cannot run (another sweep in its folder, a
// folder that cannot be written), a sweep with failed runs, and a failing post step make the
// study "failed" with a one-line reason each; a failing gate makes it "gates failed". Writes
// <out>/study.json (a temporary file and a rename). Progress lines on `lines` (stdout), the
// sweeps' run lines on `log` (stderr). Throws only if study.json cannot be written.
StudyOutcome run_study(const PreparedStudy& study, const StudyRunOptions& options, std::ostream& lines, std::ostream& log);

}  // namespace ricochet
