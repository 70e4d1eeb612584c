#include "harness/sweeps/reference_errors.hpp"

#include "harness/outputs/csv_reader.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <stdexcept>

namespace ricochet {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double finite_or_inf(double d) { return std::isfinite(d) ? d : kInf; }

// The member `key` of an object; nullptr if absent or `v` is not an object.
const Json* member(const Json* v, std::string_view key) {
  if (!v || !v->is_object()) return nullptr;
  const auto it = v->find(key);
  return it == v->end() ? nullptr : &*it;
}

// The number at a path of object keys, e.g. {"final", "angular_momentum"}; empty if any key is
// missing or the value is not a number.
std::optional<double> number_at(const Json* s, std::initializer_list<std::string_view> path) {
  const Json* v = s;
  for (const std::string_view k : path) v = member(v, k);
  if (!v || !v->is_number()) return std::nullopt;
  return v->get<double>();
}

bool is_ok(const Json* s) {
  const Json* v = member(s, "status");
  return v && v->is_string() && v->get_ref<const std::string&>() == "ok";
}

// |a - b| of a scalar summary key of both runs.
std::optional<double> scalar_difference(const Json* run, const Json* ref,
                                        std::initializer_list<std::string_view> path) {
  const auto a = number_at(run, path), b = number_at(ref, path);
  if (!a || !b) return std::nullopt;
  return finite_or_inf(std::abs(*a - *b));
}

// The rigid-body velocity (final momentum) / (total mass): rebound_velocity_x/_y if present,
// else final.momentum_x/_y / total_mass.
std::optional<std::pair<double, double>> rebound_velocity(const Json* s) {
  const auto vx = number_at(s, {"rebound_velocity_x"}), vy = number_at(s, {"rebound_velocity_y"});
  if (vx && vy) return std::pair{*vx, *vy};
  const auto px = number_at(s, {"final", "momentum_x"}), py = number_at(s, {"final", "momentum_y"});
  const auto m = number_at(s, {"total_mass"});
  if (px && py && m && *m > 0.0) return std::pair{*px / *m, *py / *m};
  return std::nullopt;
}

}  // namespace

int HistoryTable::column(std::string_view name) const {
  for (std::size_t i = 0; i < columns.size(); ++i)
    if (columns[i] == name) return static_cast<int>(i);
  return -1;
}

HistoryTable read_history_csv(const std::filesystem::path& path) {
  const CsvTable t = read_csv(path);  // the project's one CSV reader (RFC 4180)
  HistoryTable h;
  h.columns = t.columns;
  h.rows.reserve(t.rows.size());
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    std::vector<double> row;
    row.reserve(t.columns.size());
    for (const std::string& cell : t.rows[r]) {
      const std::optional<double> x = parse_csv_number(cell);
      if (!x) throw std::runtime_error(path.string() + ":" + std::to_string(t.lines[r]) + ": not a number: '" + cell + "'");
      row.push_back(*x);
    }
    h.rows.push_back(std::move(row));
  }
  return h;
}

ReferenceErrors reference_errors(const HistoryTable& run, const HistoryTable& ref, const std::string& probe,
                                 double energy_scale) {
  ReferenceErrors e;
  const int t_run = run.column("time"), t_ref = ref.column("time");
  if (t_run < 0 || t_ref < 0 || ref.rows.empty()) return e;
  const int e_run = run.column("total_energy"), e_ref = ref.column("total_energy");
  // The energy held by penalty springs counts with the bodies' (the history's energy_error
  // balance does the same): without it a penalty run's total dips while its springs are loaded.
  const int c_run = run.column("contact_energy"), c_ref = ref.column("contact_energy");
  const int ux_run = run.column(probe + "_ux"), uy_run = run.column(probe + "_uy");
  const int ux_ref = ref.column(probe + "_ux"), uy_ref = ref.column(probe + "_uy");
  const bool has_probe = ux_run >= 0 && uy_run >= 0 && ux_ref >= 0 && uy_ref >= 0;
  const bool has_energy = e_run >= 0 && e_ref >= 0;

  auto at = [](const std::vector<double>& row, int c) { return row[static_cast<std::size_t>(c)]; };
  const double t0 = at(ref.rows.front(), t_ref), t1 = at(ref.rows.back(), t_ref);
  const double slack = 1e-9 * std::max(std::abs(t1 - t0), std::abs(t1));
  double probe_max = 0.0, energy_max = 0.0, bodies_max = 0.0;
  auto worse = [](double& m, double d) { m = std::max(m, finite_or_inf(d)); };
  for (const auto& row : run.rows) {
    double t = at(row, t_run);
    if (t < t0 - slack || t > t1 + slack) continue;
    t = std::clamp(t, t0, t1);
    // The reference rows j, j+1 around t (times ascending).
    const auto it = std::lower_bound(ref.rows.begin(), ref.rows.end(), t,
                                     [&](const std::vector<double>& r, double x) { return at(r, t_ref) < x; });
    std::size_t j = static_cast<std::size_t>(it - ref.rows.begin());
    auto value = [&](int c) {
      if (j < ref.rows.size() && at(ref.rows[j], t_ref) == t) return at(ref.rows[j], c);
      const auto& a = ref.rows[j - 1];
      const auto& b = ref.rows[j];
      const double w = (t - at(a, t_ref)) / (at(b, t_ref) - at(a, t_ref));
      return at(a, c) + w * (at(b, c) - at(a, c));
    };
    ++e.samples;
    if (has_probe) worse(probe_max, std::hypot(at(row, ux_run) - value(ux_ref), at(row, uy_run) - value(uy_ref)));
    if (has_energy) {
      const double e_a = at(row, e_run) + (c_run >= 0 ? at(row, c_run) : 0.0);
      const double e_b = value(e_ref) + (c_ref >= 0 ? value(c_ref) : 0.0);
      worse(energy_max, std::abs(e_a - e_b) / energy_scale);
      worse(bodies_max, std::abs(at(row, e_run) - value(e_ref)) / energy_scale);
    }
  }
  if (e.samples == 0) return e;
  if (has_probe) e.probe = probe_max;
  if (has_energy) {
    e.energy = energy_max;
    e.energy_bodies = bodies_max;
  }
  return e;
}

std::optional<double> trapezoid_integral(const HistoryTable& h, std::string_view column) {
  const int t = h.column("time"), c = h.column(column);
  if (t < 0 || c < 0 || h.rows.empty()) return std::nullopt;
  const auto ti = static_cast<std::size_t>(t), ci = static_cast<std::size_t>(c);
  double sum = 0.0;
  for (std::size_t i = 1; i < h.rows.size(); ++i)
    sum += 0.5 * (h.rows[i - 1][ci] + h.rows[i][ci]) * (h.rows[i][ti] - h.rows[i - 1][ti]);
  return sum;
}

ReferenceMetrics compare_with_reference(const RunOutputs& run, const RunOutputs& ref, const std::string& probe) {
  ReferenceMetrics m;

  // Histories: the probe displacement and the total energy over time.
  if (run.history && ref.history) {
    double scale = number_at(ref.summary, {"initial_energy"}).value_or(0.0);
    if (!(scale > 0.0)) {
      const int c = ref.history->column("total_energy");
      scale = c >= 0 && !ref.history->rows.empty() ? std::abs(ref.history->rows.front()[static_cast<std::size_t>(c)]) : 0.0;
    }
    if (!(scale > 0.0) || !std::isfinite(scale)) scale = 1.0;  // an absolute error [J]
    const ReferenceErrors e = reference_errors(*run.history, *ref.history, probe, scale);
    m.probe = e.probe;
    m.energy = e.energy;
    m.energy_bodies = e.energy_bodies;
    m.samples = e.samples;
  }

  // The run's own penetration: the exact answer is 0, so the reference is not needed.
  if (is_ok(run.summary))
    if (const auto p = number_at(run.summary, {"penetration_max"})) m.penetration = finite_or_inf(std::abs(*p));

  // Summaries of two complete runs.
  if (!is_ok(run.summary) || !is_ok(ref.summary)) return m;
  const Json* a = run.summary;
  const Json* b = ref.summary;
  if (const auto va = rebound_velocity(a), vb = rebound_velocity(b); va && vb)
    m.rebound_velocity = finite_or_inf(std::hypot(va->first - vb->first, va->second - vb->second));
  m.angular_momentum = scalar_difference(a, b, {"final", "angular_momentum"});

  const bool summary_impulses = number_at(a, {"contact_impulse_normal"}) && number_at(a, {"contact_impulse_tangential"}) &&
                                number_at(b, {"contact_impulse_normal"}) && number_at(b, {"contact_impulse_tangential"});
  if (summary_impulses) {
    m.impulse_normal = scalar_difference(a, b, {"contact_impulse_normal"});
    m.impulse_tangential = scalar_difference(a, b, {"contact_impulse_tangential"});
    m.impulse_source = "summary";
  } else if (run.history && ref.history) {
    auto diff = [&](std::string_view col) -> std::optional<double> {
      const auto x = trapezoid_integral(*run.history, col), y = trapezoid_integral(*ref.history, col);
      if (!x || !y) return std::nullopt;
      return finite_or_inf(std::abs(*x - *y));
    };
    m.impulse_normal = diff("normal_force");
    m.impulse_tangential = diff("tangential_force");
    if (m.impulse_normal || m.impulse_tangential) m.impulse_source = "history";
  }

  m.contact_duration = scalar_difference(a, b, {"contact_duration"});
  m.von_mises_interior = scalar_difference(a, b, {"von_mises_interior_max"});
  m.von_mises_interior_time = scalar_difference(a, b, {"von_mises_interior_max_time"});
  return m;
}

std::vector<std::string> metric_names(const std::string& probe) {
  return {"probe_" + probe,   "energy",          "energy_bodies",     "penetration",       "rebound_velocity",        "angular_momentum",
          "impulse_normal",   "impulse_tangential", "contact_duration", "von_mises_interior", "von_mises_interior_time"};
}

std::vector<std::pair<std::string, std::optional<double>>> metric_values(const ReferenceMetrics& m,
                                                                        const std::string& probe) {
  const std::vector<std::string> names = metric_names(probe);
  const std::optional<double> values[] = {m.probe,           m.energy,           m.energy_bodies,     m.penetration,
                                          m.rebound_velocity, m.angular_momentum, m.impulse_normal,
                                          m.impulse_tangential, m.contact_duration, m.von_mises_interior,
                                          m.von_mises_interior_time};
  std::vector<std::pair<std::string, std::optional<double>>> out;
  for (std::size_t i = 0; i < names.size(); ++i) out.emplace_back(names[i], values[i]);
  return out;
}

bool has_floor(std::string_view metric) { return metric != "penetration"; }

}  // namespace ricochet
