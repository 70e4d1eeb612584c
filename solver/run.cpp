#include "solver/run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <stdexcept>

#include "solver/observers.hpp"

namespace ricochet {

std::vector<std::string> history_columns(const std::vector<Probe>& probes) {
  std::vector<std::string> c = {"time",          "kinetic_energy",  "strain_energy",
                                "hourglass_energy", "external_work", "friction_dissipation",
                                "total_energy",  "energy_error",    "momentum_x",
                                "momentum_y",    "von_mises_max",   "penetration_max",
                                "contact_nodes", "normal_force",    "tangential_force",
                                "contact_work",  "contact_stick",   "contact_slip",
                                "contact_iterations"};
  for (const auto& p : probes)
    for (const char* s : {"_ux", "_uy", "_vx", "_vy"}) c.push_back(p.name + s);
  return c;
}

std::size_t History::column(const std::string& name) const {
  const auto it = std::find(columns.begin(), columns.end(), name);
  if (it == columns.end()) throw std::out_of_range("no history column '" + name + "'");
  return static_cast<std::size_t>(it - columns.begin());
}

namespace {

// Steps at which the history is sampled: k * interval rounded to the nearest step, and the last.
std::vector<long> sample_steps(const RunSettings& s, long planned) {
  std::vector<long> steps;
  if (s.sample_interval <= 0.0) {
    for (long n = 0; n <= planned; ++n) steps.push_back(n);
    return steps;
  }
  for (long k = 0;; ++k) {
    const long n = std::lround(static_cast<double>(k) * s.sample_interval / s.dt);
    if (n > planned) break;
    if (steps.empty() || n > steps.back()) steps.push_back(n);
  }
  if (steps.back() != planned) steps.push_back(planned);
  return steps;
}

// A snapshot or history-row recorder, fed at sample steps only.
struct Recorder {
  const Model& model;
  const RunSettings& settings;
  RunResult& result;
  std::vector<double> cell_vm;

  double record(const State& s, const Energies& e, double error, const ContactState& c,
                double depth) {
    cell_von_mises(model, s.u.data(), cell_vm.data());
    const double vm = cell_vm.empty() ? 0.0 : *std::max_element(cell_vm.begin(), cell_vm.end());
    const Vec2 p = linear_momentum(model, s);
    auto& v = result.history.values;
    v.insert(v.end(), {s.time, e.kinetic, e.strain, e.hourglass, e.external_work,
                       e.friction_dissipation, e.total(), error, p.x(), p.y(), vm, depth,
                       static_cast<double>(c.active_count), c.normal_force, c.tangential_force,
                       c.contact_work, static_cast<double>(c.stick_count),
                       static_cast<double>(c.slip_count), static_cast<double>(c.sweeps)});
    for (const auto& pr : settings.probes) {
      const int d = 2 * pr.node;
      v.insert(v.end(), {s.u[d], s.u[d + 1], velocity_at_step(s, d), velocity_at_step(s, d + 1)});
    }
    return vm;
  }

  void snapshot(const State& s) {
    FieldSnapshot f;
    f.step = s.step;
    f.time = s.time;
    f.u = s.u;
    f.v.resize(s.u.size());
    for (int d = 0; d < f.v.size(); ++d) f.v[d] = velocity_at_step(s, d);
    f.von_mises.resize(cell_vm.size());
    cell_von_mises(model, s.u.data(), f.von_mises.data());
    result.fields.push_back(std::move(f));
  }
};

}  // namespace

RunResult run_explicit(const Model& model, const RunSettings& settings, const ProgressFn& progress) {
  if (!(settings.dt > 0.0) || !(settings.end_time >= 0.0))
    throw std::invalid_argument("run_explicit: dt must be > 0 and end_time >= 0");
  RunResult result;
  result.dt = settings.dt;
  const long planned = static_cast<long>(std::ceil(settings.end_time / settings.dt - 1e-9));
  result.planned_steps = planned;

  const std::vector<long> samples = sample_steps(settings, planned);
  std::vector<long> field_steps;
  for (double t : settings.field_times)
    field_steps.push_back(std::clamp(std::lround(t / settings.dt), 0L, planned));
  std::sort(field_steps.begin(), field_steps.end());
  field_steps.erase(std::unique(field_steps.begin(), field_steps.end()), field_steps.end());

  result.history.columns = history_columns(settings.probes);
  result.history.values.reserve(samples.size() * result.history.columns.size());
  result.fields.reserve(field_steps.size());
  Recorder rec{model, settings, result, std::vector<double>(model.num_cells())};

  State s = initial_state(model, settings.prescribed, settings.dt, settings.initial_displacement);
  ContactState contact = make_contact_state(model, settings.obstacles, settings.friction, settings.prescribed);
  const bool with_contact = !contact.candidates.empty();
  result.contact_candidates = static_cast<int>(contact.candidates.size());
  const Eigen::VectorXd u0 = s.u;
  // E_0 from the initial conditions themselves: the reconstructed v_0 of step 0 already holds
  // half of any contact impulse of the first step.
  const double kinetic0 = 0.5 * s.v_half.cwiseAbs2().dot(model.mass);
  double reference_energy = 0.0;
  std::size_t next_sample = 0, next_field = 0;
  const long monitor_every = std::max(1, settings.monitor_every);

  const auto wall0 = std::chrono::steady_clock::now();
  const std::clock_t cpu0 = std::clock();
  for (;;) {
    const long n = s.step;
    const bool sample = next_sample < samples.size() && samples[next_sample] == n;
    const bool field = next_field < field_steps.size() && field_steps[next_field] == n;
    const bool monitor = sample || field || n % monitor_every == 0 || n == planned;
    evaluate(model, settings.prescribed, s, monitor);
    if (with_contact) contact_phase(model, settings.obstacles, settings.contact, contact, s);

    auto diverge = [&](std::string why) {
      result.status = RunStatus::diverged;
      result.reason = std::move(why);
      result.diverged_step = n;
      result.diverged_time = s.time;
    };
    if (!(s.forces.min_jacobian > 0.0)) {
      diverge("inverted element (det F = " + std::to_string(s.forces.min_jacobian) + ")");
      break;
    }
    if (monitor) {
      Energies e = observe_energies(model, s, u0);
      e.friction_dissipation = contact.friction_dissipation;
      if (n == 0) result.initial_energy = kinetic0 + e.strain + e.hourglass;
      reference_energy = std::max({reference_energy, result.initial_energy, std::abs(e.external_work)});
      if (!std::isfinite(e.total()) || !std::isfinite(e.external_work)) {
        diverge("non-finite state");
        break;
      }
      if (reference_energy > 0.0 && e.total() > settings.energy_growth_limit * reference_energy) {
        diverge("energy growth: total energy " + std::to_string(e.total()) + " J exceeds " +
                std::to_string(settings.energy_growth_limit) + " x reference " +
                std::to_string(reference_energy) + " J");
        break;
      }
      const double error = energy_error(e, result.initial_energy, reference_energy);
      if (sample) {
        const double depth = with_contact ? penetration(model, settings.obstacles, contact, s.u) : 0.0;
        result.penetration_max = std::max(result.penetration_max, depth);
        const double vm = rec.record(s, e, error, contact, depth);
        result.energy_error_max = std::max(result.energy_error_max, error);
        if (vm > result.von_mises_max) {
          result.von_mises_max = vm;
          result.von_mises_max_time = s.time;
        }
        ++next_sample;
      }
      if (field) {
        rec.snapshot(s);
        ++next_field;
      }
      if (progress) progress(n, planned, s.time);
    }
    if (n == planned) break;
    update(s);
  }
  const auto wall1 = std::chrono::steady_clock::now();
  result.wall_seconds = std::chrono::duration<double>(wall1 - wall0).count();
  result.cpu_seconds = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
  result.steps = s.step;
  result.friction_dissipation = contact.friction_dissipation;
  result.contact_work = contact.contact_work;
  result.contact_steps = contact.steps_with_contact;
  result.contact_sweeps_max = contact.sweeps_max;
  result.contact_unconverged_steps = contact.unconverged_steps;
  if (contact.steps_with_contact > 0)
    result.contact_sweeps_mean = static_cast<double>(contact.sweeps_total) / contact.steps_with_contact;
  result.end_time = s.time;
  if (result.wall_seconds > 0.0)
    result.element_steps_per_second =
        static_cast<double>(model.num_cells()) * static_cast<double>(s.step) / result.wall_seconds;
  return result;
}

}  // namespace ricochet
