#include "solver/schemes/time_step.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "solver/contact/penalty_contact.hpp"

namespace ricochet {

double critical_time_step(const Model& model, const RunSettings& settings, double* penalty_critical) {
  const bool contact = !settings.obstacles.empty() || !settings.body_pairs.empty();
  if (settings.contact_method != RunSettings::ContactMethod::penalty || !contact) return model.critical_dt;
  const PenaltyContact springs = make_penalty_contact(model, settings.obstacles, settings.friction,
                                                      settings.prescribed, settings.penalty, settings.body_pairs);
  if (penalty_critical) *penalty_critical = penalty_critical_dt(model, springs);
  return penalty_combined_critical_dt(model, springs);
}

namespace {

// Steps from t to end at dt, as the fixed-step loop counts them: ceil((end - t) / dt).
long steps_to(double t, double end, double dt) {
  return static_cast<long>(std::ceil((end - t) / dt - 1e-9));
}

// A step of end - t <= this x dt is no step: t has reached end.
constexpr double kEndTolerance = 1e-9;

}  // namespace

StepControl::StepControl(const Model& model, const RunSettings& settings, double spring_critical_dt)
    : model_(model),
      interval_(settings.dt_update_interval),
      safety_(settings.dt_safety),
      end_(settings.end_time),
      dt0_(settings.dt),
      floor_(settings.dt_min_ratio * settings.dt),
      spring_dt_(spring_critical_dt),
      dt_min_(settings.dt_update_interval > 0 ? std::numeric_limits<double>::infinity() : settings.dt),
      dt_max_(settings.dt_update_interval > 0 ? 0.0 : settings.dt) {
  if (interval_ < 0) throw std::invalid_argument("run: dt_update_interval must be >= 0");
  if (interval_ > 0 && !(safety_ > 0.0 && settings.dt_min_ratio > 0.0 && settings.dt_min_ratio <= 1.0))
    throw std::invalid_argument("run: a variable step needs dt_safety > 0 and dt_min_ratio in (0, 1]");
  planned_ = steps_to(0.0, end_, dt0_);
  for (const auto& b : model.q4_hourglass) wave_speed_[0].push_back(material_wave_speed(b.material));
  for (const auto& b : model.q4_full) wave_speed_[1].push_back(material_wave_speed(b.material));
  for (const auto& b : model.t3) wave_speed_[2].push_back(material_wave_speed(b.material));
  failure_.reserve(512);
}

double StepControl::critical(const Eigen::VectorXd& u, int* cell) const {
  double dt_e = std::numeric_limits<double>::infinity();
  int worst = -1;
  auto corner = [&](int node) -> Vec2 { return model_.ref.col(node) + u.segment<2>(2 * node); };
  // The blocks in every force pass's order (kBlockKinds); within a block the cells in order.
  auto quads = [&](const auto& blocks, const std::vector<double>& speed) {
    for (std::size_t b = 0; b < blocks.size(); ++b)
      for (std::size_t e = 0; e < blocks[b].conn.size(); ++e) {
        const auto& c = blocks[b].conn[e];
        Eigen::Matrix<double, 2, 4> x;
        for (int i = 0; i < 4; ++i) x.col(i) = corner(c[i]);
        const double dt = q4_characteristic_length(x) / speed[b];
        if (!(dt >= dt_e)) dt_e = dt, worst = blocks[b].first_cell + static_cast<int>(e);
      }
  };
  quads(model_.q4_hourglass, wave_speed_[0]);
  quads(model_.q4_full, wave_speed_[1]);
  for (std::size_t b = 0; b < model_.t3.size(); ++b)
    for (std::size_t e = 0; e < model_.t3[b].conn.size(); ++e) {
      const auto& c = model_.t3[b].conn[e];
      Eigen::Matrix<double, 2, 3> x;
      for (int i = 0; i < 3; ++i) x.col(i) = corner(c[i]);
      const double dt = t3_characteristic_length(x) / wave_speed_[2][b];
      if (!(dt >= dt_e)) dt_e = dt, worst = model_.t3[b].first_cell + static_cast<int>(e);
    }
  if (cell) *cell = worst;
  if (!(dt_e > 0.0)) return 0.0;  // an inverted cell (or NaN coordinates)
  return combined_critical_dt(dt_e, spring_dt_);
}

bool StepControl::begin_step(State& s) {
  if (landed_ || end_ - s.time <= kEndTolerance * s.dt) {
    s.time = end_;
    return false;
  }
  if (interval_ > 0 && s.step % interval_ == 0) {
    int cell = -1;
    const double dt = safety_ * critical(s.u, &cell);
    ++updates_;
    if (dt >= floor_) {
      set_step(s, dt);
      dt_min_ = std::min(dt_min_, dt);
      dt_max_ = std::max(dt_max_, dt);
      planned_ = s.step + steps_to(s.time, end_, dt);
    } else if (failure_.empty()) {
      // The cell that sets the step: its body and its index within the body.
      int body = 0;
      while (body + 1 < static_cast<int>(model_.bodies.size()) && model_.bodies[body + 1].first_cell <= cell) ++body;
      const BodyInfo* b = model_.bodies.empty() ? nullptr : &model_.bodies[body];
      char buf[400];
      std::snprintf(buf, sizeof buf,
                    "time step floor: the recomputed step %.4g s is below %.4g s, time.dt_min_ratio = %g x the "
                    "initial step %.4g s (body \"%s\" element %d %s)",
                    dt, floor_, floor_ / dt0_, dt0_, b ? b->name.c_str() : "", b ? cell - b->first_cell : cell,
                    dt > 0.0 ? "sets it" : "is inverted");
      failure_ = buf;
    }
  }
  // A step that would pass end_time is shortened to end on it.
  if (s.time + s.dt >= end_) {
    set_step(s, end_ - s.time);
    planned_ = s.step + 1;
    landed_ = true;
  }
  return true;
}

void StepControl::report(RunResult& r) const {
  r.dt_update_interval = interval_;
  r.dt_min = dt_min_ <= dt_max_ ? dt_min_ : dt0_;
  r.dt_max = dt_min_ <= dt_max_ ? dt_max_ : dt0_;
  r.dt_updates = updates_;
  r.dt_floor = interval_ > 0 ? floor_ : 0.0;
}

}  // namespace ricochet
