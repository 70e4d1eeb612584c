// When a study's report page is drawn again (docs/studies.md, What reruns): only when what it is
// drawn from changed. Its stamp, <out>/<study>/report/.stamp, holds a hash of that; the report is
// skipped while the stamp equals the study's current one.
#pragma once

#include <filesystem>
#include <string>

#include "harness/outputs/json_io.hpp"
#include "harness/studies/study_spec.hpp"

namespace ricochet {

// FNV-1a (16 hex digits) over the study's study.toml text, its plug-in's text ([report]
// plugin), and for each sweep of `study_json` (study.json's `sweeps`, in order) its name, the
// text of its summary.csv and its gate results, then each post step's name, exit and gate
// results, and the study's status.
std::string report_stamp(const StudySpec& spec, const Json& study_json);

// The stamp of the report last drawn in `out` (<out>/report/.stamp); empty if none.
std::string read_report_stamp(const std::filesystem::path& out);

// Records `stamp` as the one of the report just drawn (a temporary file and a rename).
void write_report_stamp(const std::filesystem::path& out, const std::string& stamp);

}  // namespace ricochet
