#include "solver/schemes/run_monitor.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <sys/resource.h>

#include "solver/forces/internal_forces.hpp"
#include "solver/observers/observers.hpp"

namespace ricochet {

namespace {

// The largest step count a run may plan: beyond it a step index would not be exact as a
// double (times t_n = n dt) and the count could overflow the conversion to long.
constexpr double kMaxPlannedSteps = 9007199254740992.0;  // 2^53

// z angular momentum of all nodes about their common centre of mass at t_n [kg m^2/s]:
// L = sum m_i (x_i - x_c) x (v_i - v_c), x = X + u, v = v_n. Taken about the current centre of
// mass so that it is the spin alone (no orbital part from the translation), and computed in
// two passes (centre first) rather than as sum m x x v - M x_c x v_c, which would cancel
// digits for a body far from the origin. O(nodes), run at sample steps only.
// In 3D the vector L, the same sum with the cross product.
template <class M>
typename MonitorSpace<M::kDim>::Angular angular_momentum(const M& model, const State& s) {
  constexpr int D = M::kDim;
  using Vec = VecD<D>;
  using Angular = typename MonitorSpace<D>::Angular;
  auto position = [&](int i) -> Vec { return model.ref.col(i) + s.u.segment<D>(D * i); };
  auto velocity = [&](int i) -> Vec {
    Vec v;
    for (int k = 0; k < D; ++k) v[k] = velocity_at_step(s, D * i + k);
    return v;
  };
  double mass = 0.0;
  Vec mx = Vec::Zero(), mv = Vec::Zero();
  for (int i = 0; i < model.num_nodes(); ++i) {
    const double m = model.mass[D * i];
    mass += m;
    mx += m * position(i);
    mv += m * velocity(i);
  }
  Angular L = MonitorSpace<D>::zero_angular();
  if (!(mass > 0.0)) return L;
  const Vec xc = mx / mass, vc = mv / mass;
  for (int i = 0; i < model.num_nodes(); ++i) {
    const Vec r = position(i) - xc;
    const Vec w = velocity(i) - vc;
    if constexpr (D == 2)
      L += model.mass[D * i] * (r.x() * w.y() - r.y() * w.x());
    else
      L += model.mass[D * i] * r.cross(w);
  }
  return L;
}


// Cells with a node on a contact boundary: the candidate nodes, and the boundary nodes of the
// master bodies of body pairs.
template <class M>
std::vector<std::uint8_t> contact_boundary_cells(const M& model, const RunSettings& settings,
                                                 const std::vector<ContactCandidate>& candidates) {
  std::vector<std::uint8_t> node(model.num_nodes(), 0), cell(model.num_cells(), 0);
  for (const ContactCandidate& c : candidates) node[c.node] = 1;
  for (const BodyPair& bp : settings.body_pairs)
    if (bp.master >= 0 && bp.master < static_cast<int>(model.bodies.size()))
      for (int n : model.bodies[bp.master].boundary_nodes) node[n] = 1;
  auto mark = [&](const auto& block) {
    for (std::size_t e = 0; e < block.conn.size(); ++e)
      for (int n : block.conn[e])
        if (node[n]) cell[block.first_cell + e] = 1;
  };
  for_each_cell_block(model, mark);
  return cell;
}

// Body, element within the body and current centroid of a global cell.
template <class M>
void locate_cell(const M& model, const State& s, int cell, StressPeak& p) {
  constexpr int D = M::kDim;
  p.cell = cell;
  bool found = false;
  for_each_cell_block(model, [&](const auto& block) {
    const int k = cell - block.first_cell;
    if (found || k < 0 || k >= static_cast<int>(block.conn.size())) return;
    VecD<D> c = VecD<D>::Zero();
    for (int n : block.conn[k]) c += model.ref.col(n) + s.u.segment<D>(D * n);
    c /= static_cast<double>(block.conn[k].size());
    p.x = c.x();
    p.y = c.y();
    if constexpr (D == 3) p.z = c.z();
    p.body = block.body;
    p.element = cell - model.bodies[block.body].first_cell;
    found = true;
  });
}

// What a history row is made of at a sample step.
template <int D>
struct HistoryInputs {
  const State& s;
  const Energies& e;
  const ContactStep& c;     // the contact set's last step
  const ContactTotals& ct;  // and its run totals
  double energy_error = 0.0;      // [-]
  VecD<D> momentum = VecD<D>::Zero();  // [kg m/s]
  double von_mises = 0.0;         // [Pa]
  double penetration = 0.0;       // [m]
  typename MonitorSpace<D>::Angular angular_momentum = MonitorSpace<D>::zero_angular();  // [kg m^2/s]
};

// The history's columns before the probes', in order, each with its value: the one definition
// of a history row (docs/outputs.md, history.csv). fn(name, value) is called per column; with
// x null only the names are wanted (the values are 0). In 3D the momentum has a z column and the
// angular momentum three (about x, y, z) where 2D has its z component alone.
template <int D, class Fn>
void history_fields(const HistoryInputs<D>* x, Fn&& fn) {
  auto of = [x](auto get) { return x ? get(*x) : 0.0; };
  using X = HistoryInputs<D>;
  fn("time", of([](const X& h) { return h.s.time; }));
  fn("dt", of([](const X& h) { return h.s.dt; }));
  fn("kinetic_energy", of([](const X& h) { return h.e.kinetic; }));
  fn("strain_energy", of([](const X& h) { return h.e.strain; }));
  fn("hourglass_energy", of([](const X& h) { return h.e.hourglass; }));
  fn("external_work", of([](const X& h) { return h.e.external_work; }));
  fn("friction_dissipation", of([](const X& h) { return h.e.friction_dissipation; }));
  fn("total_energy", of([](const X& h) { return h.e.total(); }));
  fn("energy_error", of([](const X& h) { return h.energy_error; }));
  fn("momentum_x", of([](const X& h) { return h.momentum.x(); }));
  fn("momentum_y", of([](const X& h) { return h.momentum.y(); }));
  if constexpr (D == 3) fn("momentum_z", of([](const X& h) { return h.momentum.z(); }));
  fn("von_mises_max", of([](const X& h) { return h.von_mises; }));
  fn("penetration_max", of([](const X& h) { return h.penetration; }));
  fn("contact_nodes", of([](const X& h) { return static_cast<double>(h.c.active); }));
  fn("normal_force", of([](const X& h) { return h.c.normal_force; }));
  fn("tangential_force", of([](const X& h) { return h.c.tangential_force; }));
  fn("contact_work", of([](const X& h) { return h.ct.contact_work; }));
  fn("contact_stick", of([](const X& h) { return static_cast<double>(h.c.stick); }));
  fn("contact_slip", of([](const X& h) { return static_cast<double>(h.c.slip); }));
  fn("contact_iterations", of([](const X& h) { return static_cast<double>(h.c.iterations); }));
  fn("contact_energy", of([](const X& h) { return h.c.stored_energy; }));
  if constexpr (D == 2) {
    fn("angular_momentum", of([](const X& h) { return h.angular_momentum; }));
  } else {
    fn("angular_momentum_x", of([](const X& h) { return h.angular_momentum.x(); }));
    fn("angular_momentum_y", of([](const X& h) { return h.angular_momentum.y(); }));
    fn("angular_momentum_z", of([](const X& h) { return h.angular_momentum.z(); }));
  }
  fn("contact_work_normal", of([](const X& h) { return h.ct.contact_work_normal; }));
  fn("contact_status_changes", of([](const X& h) { return static_cast<double>(h.c.status_changes); }));
}

// Per interface (contact_interface_names()), after the columns above: <name> + each suffix.
constexpr const char* kInterfaceColumns[] = {"_normal_force", "_tangential_force", "_contact_nodes",
                                             "_contact_work", "_friction_dissipation"};

}  // namespace

std::size_t History::column(const std::string& name) const {
  const auto it = std::find(columns.begin(), columns.end(), name);
  if (it == columns.end()) throw std::out_of_range("no history column '" + name + "'");
  return static_cast<std::size_t>(it - columns.begin());
}

std::vector<std::string> history_columns(const std::vector<Probe>& probes, const std::vector<std::string>& interfaces,
                                         int dimension) {
  std::vector<std::string> c;
  auto name = [&c](const char* n, double) { c.emplace_back(n); };
  if (dimension == 3)
    history_fields<3>(nullptr, name);
  else
    history_fields<2>(nullptr, name);
  for (const std::string& i : interfaces)
    for (const char* s : kInterfaceColumns) c.push_back(i + s);
  for (const auto& p : probes) {
    if (dimension == 3)
      for (const char* s : {"_ux", "_uy", "_uz", "_vx", "_vy", "_vz"}) c.push_back(p.name + s);
    else
      for (const char* s : {"_ux", "_uy", "_vx", "_vy"}) c.push_back(p.name + s);
  }
  return c;
}

template <class M>
RunMonitorT<M>::RunMonitorT(const M& model, const RunSettings& settings, RunResult& result,
                            const ContactSetT<M::kDim>& contact)
    : model_(model), settings_(settings), result_(result), contact_(contact) {
  if (!(settings.dt > 0.0) || !(settings.end_time >= 0.0))
    throw std::invalid_argument("run: dt must be > 0 and end_time >= 0");
  result.dt = settings.dt;
  const double planned = std::ceil(settings.end_time / settings.dt - 1e-9);
  if (!(planned <= kMaxPlannedSteps))  // the harness checks its own, lower ceiling first
    throw std::invalid_argument("run: end_time / dt = " + std::to_string(planned) + " steps, more than 2^53");
  planned_ = static_cast<long>(planned);
  result.planned_steps = planned_;
  result.history.columns =
      history_columns(settings.probes,
                      contact.candidates.empty()
                          ? std::vector<std::string>{}
                          : contact_interface_names(obstacles_of(settings, model), settings.body_pairs),
                      M::kDim);
  variable_ = settings.dt_update_interval > 0;
  if (!variable_) {
    // Samples: step round(k x interval / dt) for k = 0, 1, ... up to the planned step, and the
    // planned step; every step when the interval is at most one step (then those roundings
    // cover every step). Made one at a time (next_sample()), not listed: a list would be as
    // long as the run.
    every_step_ = !(settings.sample_interval > settings.dt);
    next_sample_step_ = 0;
    for (double t : settings.field_times) {
      const double x = t / settings.dt;  // times after the end are skipped
      if (x >= 0.0 && std::round(x) <= planned) field_steps_.push_back(std::lround(x));
    }
    std::sort(field_steps_.begin(), field_steps_.end());
    field_steps_.erase(std::unique(field_steps_.begin(), field_steps_.end()), field_steps_.end());
    const double rows = every_step_ ? planned + 1.0
                                    : std::min(planned + 1.0, std::floor(settings.end_time / settings.sample_interval) + 2.0);
    result.history.values.reserve(static_cast<std::size_t>(std::min(rows, 1e7)) * result.history.columns.size());
    result.fields.reserve(field_steps_.size());
    if (!field_steps_.empty()) field_cells_.assign(model.num_cells(), 0.0);
  } else {
    // By time (plan_step). Rows: one per sample time and the last state; sampling every step
    // (interval 0), twice the steps at the first step, beyond which the rows grow
    // geometrically (the step floor bounds their number: time.dt_min_ratio).
    for (double t : settings.field_times)
      if (t >= 0.0 && t <= settings.end_time * (1.0 + 1e-9)) field_times_.push_back(t);
    std::sort(field_times_.begin(), field_times_.end());
    field_times_.erase(std::unique(field_times_.begin(), field_times_.end()), field_times_.end());
    const double rows = settings.sample_interval > 0.0 ? std::floor(settings.end_time / settings.sample_interval) + 2.0
                                                       : 2.0 * static_cast<double>(planned_) + 2.0;
    result.history.values.reserve(static_cast<std::size_t>(std::min(rows, 1e7)) * result.history.columns.size());
    result.fields.reserve(field_times_.size() + 1);
    if (!field_times_.empty()) field_cells_.assign(model.num_cells(), 0.0);
  }
  monitor_every_ = std::max(1, settings.monitor_every);
  contact_cell_ = contact_boundary_cells(model, settings, contact.candidates);
  tracking_.contact_cell = contact_cell_.data();
  tracking_.measure = settings.stress_measure;
  result.stress.measure = settings.stress_measure;
  result.total_mass = model.mass.sum() / M::kDim;
  result.contact.candidates = static_cast<int>(contact.candidates.size());
  // The rest window of `drift`: up to the first time a nodal load changes.
  result.rest_until = settings.end_time;
  for (const NodalLoad& l : settings.loads)
    if (!l.constant()) result.rest_until = std::min(result.rest_until, l.start);
  wall0_ = std::chrono::steady_clock::now();
  cpu0_ = std::clock();
}

template <class M>
bool RunMonitorT<M>::sample_at(long n) const {
  if (variable_) return n == planned_step_ && planned_sample_;
  return next_sample_step_ == n;
}

template <class M>
void RunMonitorT<M>::next_sample() {
  const long n = next_sample_step_;
  if (n >= planned_) {
    next_sample_step_ = -1;  // the planned step was the last
  } else if (every_step_) {
    next_sample_step_ = n + 1;
  } else {
    // interval > dt: consecutive k are more than a step apart before rounding, so the next k
    // is the next sample, unless round-off in k x interval / dt (interval within a few ulps of
    // dt) rounds it onto this one: then the one after (a loop of at most two turns). A sample
    // beyond the end is the planned step.
    double x = 0.0;
    do {
      ++sample_k_;
      x = static_cast<double>(sample_k_) * settings_.sample_interval / settings_.dt;
    } while (std::round(x) <= static_cast<double>(n));
    next_sample_step_ = std::round(x) > static_cast<double>(planned_) ? planned_ : std::lround(x);
  }
}

template <class M>
bool RunMonitorT<M>::field_at(long n) const {
  if (variable_) return n == planned_step_ && planned_field_;
  return next_field_ < field_steps_.size() && field_steps_[next_field_] == n;
}

template <class M>
bool RunMonitorT<M>::is_last_step(long n) const { return variable_ ? n == planned_step_ && planned_last_ : n == planned_; }

template <class M>
void RunMonitorT<M>::plan_step(const State& s, bool last) {
  planned_step_ = s.step;
  planned_last_ = last;
  // Times before the midpoint of the step from t_n (all that are left at the last state) go to
  // t_n; the next ones are then after it.
  const double mid = s.time + 0.5 * s.dt;
  const double every = settings_.sample_interval;
  if (every > 0.0) {
    planned_sample_ = last || static_cast<double>(next_sample_k_) * every < mid;
    if (planned_sample_ && !last) {
      next_sample_k_ = std::max(next_sample_k_ + 1, static_cast<long>(std::ceil(mid / every)));
      while (static_cast<double>(next_sample_k_) * every < mid) ++next_sample_k_;
    }
  } else {
    planned_sample_ = true;  // every step
  }
  planned_field_ = false;
  while (next_field_ < field_times_.size() && (last || field_times_[next_field_] < mid)) {
    planned_field_ = true;
    ++next_field_;
  }
}

template <class M>
const StressTracking* RunMonitorT<M>::stress_tracking(long n) {
  const bool sample = sample_at(n);
  const bool field = field_at(n);
  if (!sample && !field && !settings_.stress_every_step) return nullptr;
  const double peak = result_.stress.interior_peak.value;
  // A field snapshot between samples without per-step tracking ranks nothing: von_mises_max
  // then stays a maximum over the samples (RunSettings::stress_every_step).
  tracking_.threshold = sample                        ? 0.0
                        : settings_.stress_every_step ? peak * peak
                                                      : std::numeric_limits<double>::max();
  sampled_vm2_ = VonMises2{0.0, 0.0, 0.0};
  tracking_.sampled_max = sample ? &sampled_vm2_ : nullptr;
  tracking_.cell_von_mises = field ? field_cells_.data() : nullptr;
  tracked_step_ = n;
  return &tracking_;
}

template <class M>
void RunMonitorT<M>::track_stress(const State& s, const StressPeaks& peaks) {
  if (s.step != tracked_step_) throw std::logic_error("RunMonitor: track_stress for another step than stress_tracking's");
  sampled_step_ = tracking_.samples() ? s.step : -1;
  if (!tracking_.sampled_max && !settings_.stress_every_step) return;  // a field snapshot's pass alone
  last_peaks_ = peaks;
  const double all = std::sqrt(peaks.all), interior = std::sqrt(peaks.interior);
  if (peaks.all_cell >= 0 && all > result_.stress.peak.value) {
    StressPeak& p = result_.stress.peak;
    p.value = all;
    p.time = s.time;
    locate_cell(model_, s, peaks.all_cell, p);
    result_.stress.von_mises_max = p.value;
    result_.stress.von_mises_max_time = p.time;
  }
  if (peaks.interior_cell >= 0 && interior > result_.stress.interior_peak.value) {
    StressPeak& p = result_.stress.interior_peak;
    p.value = interior;
    p.time = s.time;
    locate_cell(model_, s, peaks.interior_cell, p);
  }
}

template <class M>
void RunMonitorT<M>::contact_step(double t_begin, double dt, double impulse_dt) {
  const ContactStep& c = contact_.last;
  result_.contact.impulse_normal += c.normal_force * impulse_dt;
  result_.contact.impulse_tangential += c.tangential_force * impulse_dt;
  if (c.active > 0) {
    if (result_.contact.first_time < 0.0) result_.contact.first_time = t_begin;
    result_.contact.last_time = t_begin + dt;
    result_.contact.time += dt;
  }
}

template <class M>
bool RunMonitorT<M>::is_monitor_step(long n) const {
  return sample_at(n) || field_at(n) || n % monitor_every_ == 0 || is_last_step(n);
}

template <class M>
void RunMonitorT<M>::diverge(const State& s, std::string reason) {
  result_.status = RunStatus::diverged;
  result_.reason = std::move(reason);
  result_.diverged_step = s.step;
  result_.diverged_time = s.time;
  // The state it diverged in, as one more field snapshot (written like the others), so that it
  // can be inspected; unless this step already has one, or the state or its von Mises values
  // are not finite (the VTU files hold finite values only: docs/outputs.md; the tensors and
  // contact data have their non-finite values written as 0, snapshot()).
  if (result_.fields.empty() || result_.fields.back().step != s.step) {
    FieldSnapshot f = snapshot(s);
    if (!f.u.allFinite() || !f.v.allFinite()) return;
    f.von_mises.assign(model_.num_cells(), 0.0);
    cell_von_mises(model_, s.u.data(), settings_.stress_measure, f.von_mises.data());
    if (std::all_of(f.von_mises.begin(), f.von_mises.end(), [](double x) { return std::isfinite(x); }))
      result_.fields.push_back(std::move(f));
  }
}

template <class M>
FieldSnapshot RunMonitorT<M>::snapshot(const State& s) const {
  FieldSnapshot f;
  f.step = s.step;
  f.time = s.time;
  f.u = s.u;
  f.v.resize(s.u.size());
  for (int d = 0; d < f.v.size(); ++d) f.v[d] = velocity_at_step(s, d);
  if (!f.u.allFinite() || !f.v.allFinite()) return f;  // diverge() keeps no snapshot of it
  f.cauchy.resize(6 * static_cast<std::size_t>(model_.num_cells()));
  f.green_lagrange.resize(f.cauchy.size());
  cell_tensors(model_, s.u.data(), f.cauchy.data(), f.green_lagrange.data());
  contact_fields(s, f);
  // A value that is not finite, which only a state outside the laws' range gives (an inverted
  // cell, a plane-stress St Venant-Kirchhoff cell stretched beyond a real thickness stretch,
  // F33^2 < 0) or a diverged step's contact solve, is written as 0 (docs/outputs.md).
  for (auto* a : {&f.cauchy, &f.green_lagrange, &f.contact_force, &f.contact_gap})
    for (double& x : *a)
      if (!std::isfinite(x)) x = 0.0;
  return f;
}

template <class M>
void RunMonitorT<M>::contact_fields(const State& s, FieldSnapshot& f) const {
  const std::size_t n = static_cast<std::size_t>(model_.num_nodes());
  f.contact_force.resize(M::kDim * n);
  f.contact_gap.resize(n);
  f.contact_status.resize(n);
  node_contact_fields(model_, obstacles_of(settings_, model_), contact_, s.u, f.contact_force.data(),
                      f.contact_gap.data(), f.contact_status.data());
}

template <class M>
bool RunMonitorT<M>::observe(const State& s, double kinetic0) {
  constexpr int D = M::kDim;
  const long n = s.step;
  if (n == 0) u0_ = s.u;
  track_displacement(s);
  const ContactStep& c = contact_.last;
  Energies e = observe_energies(model_, s, u0_);
  e.friction_dissipation = contact_.total.friction_dissipation;
  if (n == 0) result_.initial_energy = kinetic0 + e.strain + e.hourglass + c.stored_energy;
  reference_energy_ = std::max({reference_energy_, result_.initial_energy, std::abs(e.external_work)});
  const double total = e.total() + c.stored_energy;
  if (!std::isfinite(total) || !std::isfinite(e.external_work)) {
    diverge(s, "non-finite state");
    return false;
  }
  // Growth is judged against the energy put in, E_0 + |W_ext| (a body released under gravity
  // legitimately reaches E_0 + W_ext, which can be twice max(E_0, |W_ext|)).
  input_energy_ = std::max(input_energy_, result_.initial_energy + std::abs(e.external_work));
  if (input_energy_ > 0.0 && total > settings_.energy_growth_limit * input_energy_) {
    diverge(s, "energy growth: total energy " + std::to_string(total) + " J exceeds " +
                   std::to_string(settings_.energy_growth_limit) + " x the energy put in " +
                   std::to_string(input_energy_) + " J");
    return false;
  }
  // The balance counts the stored contact (penalty) energy with the bodies' energies.
  Energies balance = e;
  balance.strain += c.stored_energy;
  const double error = energy_error(balance, result_.initial_energy, reference_energy_);

  if (sample_at(n)) {
    if (sampled_step_ != n) throw std::logic_error("RunMonitor: a history sample without its stress pass");
    const double vm = std::sqrt(last_peaks_.all);
    VonMises2 sampled = sampled_vm2_;  // of this step's force (or stress) pass
    for (double& x : sampled) x = std::sqrt(x);
    max_into(result_.stress.sampled_max, sampled);
    const double depth = penetration(model_, obstacles_of(settings_, model_), contact_, s.u);
    auto& v = result_.history.values;
    const HistoryInputs<D> row{s,  e,  c, contact_.total, error, linear_momentum(model_, s),
                               vm, depth, angular_momentum(model_, s)};
    history_fields(&row, [&v](const char*, double value) { v.push_back(value); });
    if (!contact_.candidates.empty())
      for (std::size_t i = 0; i < contact_.interface_last.size(); ++i) {
        const InterfaceStep& is = contact_.interface_last[i];
        const InterfaceTotals& it = contact_.interface_total[i];
        v.insert(v.end(), {is.normal_force, is.tangential_force, static_cast<double>(is.active),
                           it.contact_work, it.friction_dissipation});
      }
    for (const auto& pr : settings_.probes) {
      const int d = D * pr.node;
      for (int k = 0; k < D; ++k) v.push_back(s.u[d + k]);
      for (int k = 0; k < D; ++k) v.push_back(velocity_at_step(s, d + k));
    }
    result_.energy_error_max = std::max(result_.energy_error_max, error);
    result_.penetration_max = std::max(result_.penetration_max, depth);
    if (variable_) planned_sample_ = false;
    else next_sample();
  }
  if (field_at(n)) {
    if (sampled_step_ != n) throw std::logic_error("RunMonitor: a field snapshot without its stress pass");
    FieldSnapshot f = snapshot(s);
    f.von_mises = field_cells_;  // of this step's force (or stress) pass
    result_.fields.push_back(std::move(f));
    if (variable_) planned_field_ = false;
    else ++next_field_;
  }
  return true;
}

template <class M>
void RunMonitorT<M>::track_displacement(const State& s) {
  constexpr int D = M::kDim;
  double largest = 0.0;
  int node = -1;
  for (int i = 0; i < model_.num_nodes(); ++i) {
    const double d = (s.u.segment<D>(D * i) - u0_.segment<D>(D * i)).squaredNorm();
    if (d > largest) largest = d, node = i;
  }
  largest = std::sqrt(largest);
  result_.displacement_max = std::max(result_.displacement_max, largest);
  if (s.time <= result_.rest_until && largest > result_.drift_max) {
    result_.drift_max = largest;
    result_.drift_node = node;
  }
}

template <class M>
void RunMonitorT<M>::finish(const State& s) {
  result_.timing.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  result_.timing.cpu_seconds = static_cast<double>(std::clock() - cpu0_) / CLOCKS_PER_SEC;
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) == 0) result_.timing.peak_memory_bytes = 1024.0 * static_cast<double>(usage.ru_maxrss);
  result_.steps = s.step;
  result_.end_time = s.time;
  if (result_.timing.wall_seconds > 0.0)
    result_.timing.element_steps_per_second =
        static_cast<double>(model_.num_cells()) * static_cast<double>(s.step) / result_.timing.wall_seconds;
  const ContactTotals& c = contact_.total;
  result_.friction_dissipation = c.friction_dissipation;
  result_.contact_work = c.contact_work;
  result_.contact.steps = c.steps_with_contact;
  result_.contact.sweeps_max = c.iterations_max;
  result_.contact.unconverged_steps = c.unconverged_steps;
  result_.contact.status_changes = c.status_changes;
  result_.contact.status_change_steps = c.steps_with_status_changes;
  if (c.steps_with_contact > 0)
    result_.contact.sweeps_mean = static_cast<double>(c.iterations_total) / c.steps_with_contact;
}

template class RunMonitorT<Model<2>>;
template class RunMonitorT<Model<3>>;

}  // namespace ricochet
