// What a run writes (docs/outputs.md): DIR/summary.json, DIR/history.csv and, when field
// times are asked for, DIR/fields/<case>_<step>.vtu with DIR/fields/fields.pvd. All or nothing:
// every file is written into a staging folder DIR/.staging-<pid>/ and then renamed into place,
// summary.json last, so its presence marks a finished run and a complete set.
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
// plane's name in summary.json and case.json: "stress" or "strain".
const char* plane_name(PlaneMode p);
// summary.json's dimension, plane, friction_coeff, obstacles, contact_pairs (in that order).
void add_case_shape(Json& j, const PreparedCase& pc);
// summary.json's nodes and elements.
void add_model_size(Json& j, const PreparedCase& pc);
// summary.json's `probes`: each probe's name, body, node and reference position.
Json probes_json(const PreparedCase& pc);

// {compiler, build_type} of this program, and the current UTC time (ISO 8601): what every
// written result records about how it was obtained.
Json build_info();
std::string utc_now();
// Writes the outputs of a run into `dir` (created if missing): first removes the earlier
// summary.json, history.csv and fields/ (and staging folders left by killed runs), then writes
// the new ones into DIR/.staging-<pid>/ and renames them into place, summary.json last. On any
// failure the staging folder and whatever was already moved are removed, so `dir` holds none
// of the outputs, and std::runtime_error is thrown with one line naming the file as it would be
// in `dir` and the OS error, e.g. "cannot write 'out/fields/plate_00000050.vtu': File too large".
void write_run_outputs(const std::filesystem::path& dir, const PreparedCase& pc, const RunResult& r);

// Why `dir` cannot be an output folder, found without writing anything: it is empty, or it or
// one of its parents is an existing file ("'a/b' is a file, not a folder"); empty if neither.
std::string output_folder_problem(const std::filesystem::path& dir);
std::string one_line_summary(const PreparedCase& pc, const RunResult& r, const std::string& dir);

}  // namespace ricochet
