// Accuracy against a reference run (docs/sweeps.md, "Accuracy against cost"): a run's errors
// against its reference, computed from the two runs' parsed summary.json and history.csv. Pure
// functions, no files except read_history_csv, so that each metric can be tested on synthetic
// data with a known answer.
#pragma once

#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "harness/outputs/json_io.hpp"

namespace ricochet {

struct HistoryTable {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
  int column(std::string_view name) const;  // index, or -1
};

// Reads a history.csv (docs/outputs.md) with the CSV reader of csv_reader.hpp, every cell a number.
// Throws std::runtime_error (InputError for the CSV syntax) naming the file and line.
HistoryTable read_history_csv(const std::filesystem::path& path);

struct ReferenceErrors {
  std::optional<double> probe;   // max |u_P - u_P,ref| over the samples [m]
  std::optional<double> energy;  // max |E - E_ref| / energy_scale, E = total + contact energy [-]
  std::optional<double> energy_bodies;  // the same with E = total_energy alone (springs not counted) [-]
  std::size_t samples = 0;       // run samples compared
};

// Compares `run` with `ref` at the run's sample times, the reference interpolated linearly in
// time. Samples outside the reference's time span are skipped. `probe` names the columns
// <probe>_ux, <probe>_uy; without them (in either history) `probe` stays empty. A non-finite
// difference gives +inf.
ReferenceErrors reference_errors(const HistoryTable& run, const HistoryTable& ref, const std::string& probe,
                                 double energy_scale);

// ∫ column dt over the whole history by the trapezoid rule on its rows (times from `time`);
// empty without the column, without `time` or with fewer than one row (one row: 0).
std::optional<double> trapezoid_integral(const HistoryTable& h, std::string_view column);

// One finished run's outputs, either of which may be missing (nullptr).
struct RunOutputs {
  const Json* summary = nullptr;          // its summary.json
  const HistoryTable* history = nullptr;  // its history.csv
};

// Every error metric of a run against its reference; each is empty when its inputs are
// missing (docs/sweeps.md gives each metric's definition, unit and source).
struct ReferenceMetrics {
  std::optional<double> probe;                  // error_probe_<P> [m]: history, any finished run
  std::optional<double> energy;                 // error_energy [-]: history, any finished run
  std::optional<double> energy_bodies;          // error_energy_bodies [-]: history, any finished run
  std::optional<double> penetration;            // error_penetration [m]: the run's own penetration_max; run ok
  std::optional<double> rebound_velocity;       // error_rebound_velocity [m/s]: both ok
  std::optional<double> angular_momentum;       // error_angular_momentum [kg m^2/s]: both ok
  std::optional<double> impulse_normal;         // error_impulse_normal [N s]: both ok
  std::optional<double> impulse_tangential;     // error_impulse_tangential [N s]: both ok
  std::optional<double> contact_duration;       // error_contact_duration [s]: both ok
  std::optional<double> von_mises_interior;     // error_von_mises_interior [Pa]: both ok
  std::optional<double> von_mises_interior_time;  // error_von_mises_interior_time [s]: both ok
  std::string impulse_source;   // "summary", "history", or "" when the impulses are empty
  std::size_t samples = 0;      // history samples compared (probe, energy)
};

// The run's errors against `ref`: history metrics (probe P's displacement, total energy scaled
// by the reference's initial energy) as reference_errors does; scalar metrics from the
// summaries (the impulses from the summaries when both have contact_impulse_normal and
// contact_impulse_tangential, else by the trapezoid rule on both histories' normal_force and
// tangential_force). Never throws on missing or mistyped keys: that metric is empty.
ReferenceMetrics compare_with_reference(const RunOutputs& run, const RunOutputs& ref, const std::string& probe);

// The metric names in column order, for `probe`: "probe_<probe>", "energy", "energy_bodies", "penetration",
// "rebound_velocity", "angular_momentum", "impulse_normal", "impulse_tangential",
// "contact_duration", "von_mises_interior", "von_mises_interior_time". The columns are
// "error_<name>" and "floor_<name>" (no floor for penetration: docs/sweeps.md).
std::vector<std::string> metric_names(const std::string& probe);

// The metrics as (name, value) in the order of metric_names.
std::vector<std::pair<std::string, std::optional<double>>> metric_values(const ReferenceMetrics& m,
                                                                        const std::string& probe);

// The metrics that get a floor column: every one but "penetration" (its exact value is 0).
bool has_floor(std::string_view metric);

}  // namespace ricochet
