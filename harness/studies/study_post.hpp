// A study's `[[post]]` step (docs/studies.md): its command run as a child process in the study
// folder, its output kept in <out>/<study>/post/<name>/, and the CSV it writes checked against
// its gates as `ricochet check TABLE GATES` does.
#pragma once

#include <filesystem>
#include <iosfwd>
#include <vector>

#include "harness/gates/gates.hpp"
#include "harness/outputs/json_io.hpp"
#include "harness/studies/study_placeholders.hpp"
#include "harness/studies/study_spec.hpp"

namespace ricochet {

// What a step did, as study.json records it.
struct PostOutcome {
  Json json;            // {name, command, exit, table, gates, gate_results, seconds, status, reason}
  bool failed = false;  // not started, a non-zero exit, or its table could not be read
  bool gates_failed = false;
};

// Runs the step: argv with the placeholders expanded (argv[0] without '/' is looked up on PATH),
// cwd `folder`, stdin /dev/null, stdout and stderr into `out_dir`/post/<name>/stdout.txt and
// stderr.txt. Then, with a `table`, checks its gates (one line per gate on `lines`, JUnit
// report post/<name>/gates-junit.xml). Never throws for the step's own failure: that is a
// failed outcome with a one-line reason.
PostOutcome run_post(const StudyPost& post, const Placeholders& values, const std::filesystem::path& folder,
                     const std::filesystem::path& out_dir, std::ostream& lines);

// A gate result list as study.json records it: [{name, passed, detail}].
Json gate_results_json(const std::vector<GateResult>& results);

}  // namespace ricochet
