// What a run writes (docs/outputs.md): DIR/summary.json, DIR/history.csv and, when field
// times are asked for, DIR/fields/<case>_<step>.vtu with DIR/fields/fields.pvd. Each file is
// written atomically; summary.json is written last, so its presence marks a finished run.
#pragma once

#include <filesystem>
#include <string>

#include "harness/input/case_setup.hpp"
#include "harness/outputs/json_io.hpp"

namespace ricochet {

// What every written result starts with: program version, case, case file, overrides,
// scheme, mesh(es) and element formulation(s) (bodies joined by "+").
Json case_identity(const PreparedCase& pc);
// The bodies' mesh names (or element formulations) joined by "+": "M1" for one body.
std::string joined_bodies(const CaseSpec& c, bool element);
Json run_summary(const PreparedCase& pc, const RunResult& r);

// {compiler, build_type} of this program, and the current UTC time (ISO 8601): what every
// written result records about how it was obtained.
Json build_info();
std::string utc_now();
void write_run_outputs(const std::filesystem::path& dir, const PreparedCase& pc, const RunResult& r);
std::string one_line_summary(const PreparedCase& pc, const RunResult& r, const std::string& dir);

}  // namespace ricochet
