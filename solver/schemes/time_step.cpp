#include "solver/schemes/time_step.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <tuple>
#include <type_traits>
#include <utility>

#include "solver/contact/penalty_contact.hpp"

namespace ricochet {

template <class M>
double critical_time_step(const M& model, const RunSettings& settings, double* penalty_critical) {
  const auto& obstacles = obstacles_of(settings, model);
  const bool contact = !obstacles.empty() || !settings.body_pairs.empty();
  if (settings.contact_method != RunSettings::ContactMethod::penalty || !contact) return model.critical_dt;
  const PenaltyContactT<M::kDim> springs = make_penalty_contact(model, obstacles, settings.friction,
                                                                settings.prescribed, settings.penalty, settings.body_pairs);
  if (penalty_critical) *penalty_critical = penalty_critical_dt(model, springs);
  return penalty_combined_critical_dt(model, springs);
}

namespace {

// Steps from t to end at dt, as the fixed-step loop counts them: ceil((end - t) / dt), at
// most 2^53 (an estimate for progress output; the conversion cannot overflow).
long steps_to(double t, double end, double dt) {
  const double n = std::ceil((end - t) / dt - 1e-9);
  return n < 9007199254740992.0 ? static_cast<long>(n) : 9007199254740992L;
}

// A step of end - t <= this x dt is no step: t has reached end.
constexpr double kEndTolerance = 1e-9;

}  // namespace

template <class M>
StepControlT<M>::StepControlT(const M& model, const RunSettings& settings, double spring_critical_dt)
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
  if constexpr (M::kDim == 2) {
    for (const auto& b : model.q4_hourglass) wave_speed_[0].push_back(material_wave_speed(b.material));
    for (const auto& b : model.q4_full) wave_speed_[1].push_back(material_wave_speed(b.material));
    for (const auto& b : model.t3) wave_speed_[2].push_back(material_wave_speed(b.material));
  } else {
    for (const auto& b : model.hex8_hourglass) wave_speed_[0].push_back(material_wave_speed(b.material));
    for (const auto& b : model.hex8_full) wave_speed_[1].push_back(material_wave_speed(b.material));
    for (const auto& b : model.tet4) wave_speed_[2].push_back(material_wave_speed(b.material));
  }
  for (int k = 0; k < 3; ++k)
    for (double c : wave_speed_[k]) inv_c2_[k].push_back(1.0 / (c * c));
  position_.assign(model.num_dofs(), 0.0);
  failure_.reserve(512);
}

namespace {

// The smallest (L_e / c_p)^2 over cells, or a cell with non-positive area (inverted), as
// (value, global cell); the first such cell in cell order on ties, whatever the order the cells
// are visited in. Also the smallest value of the other cells (runner_up), which tells whether
// another cell is within rounding of it.
struct Smallest {
  double value = std::numeric_limits<double>::infinity();  // [s^2]; -1: an inverted cell
  int cell = -1;
  double runner_up = std::numeric_limits<double>::infinity();
  void take(double v, int c) {
    if (v < value || (v == value && c < cell)) {
      runner_up = std::min(runner_up, value);
      value = v, cell = c;
    } else {
      runner_up = std::min(runner_up, v);
    }
  }
  void merge(const Smallest& o) {
    take(o.value, o.cell);
    runner_up = std::min(runner_up, o.runner_up);
  }
};

// The squared form and the exact step round differently (a few eps each; more where a cell's
// area cancels), so cells whose squared forms are within this relative margin of the smallest
// may hold the smallest exact step.
constexpr double kTieMargin = 1e-12;

// Squared characteristic lengths L_e^2 [m^2] of a block's cells e0 <= e < e1 with current node positions x
// (2n, interleaved), the squares of q4_characteristic_length / t3_characteristic_length
// (model.hpp) without their square roots, times 1 / c_p^2; -1 for a non-positive area:
//   Q4: L_e^2 = (2A)^2 / (2 (d13^2 + d24^2)),
//   T3: L_e^2 = (2/3) (2A)^2 / eig_max(sum_k e_k e_k^T).
template <class Geom>
void smallest_in(const ElementBlock<4, Geom>& b, int e0, int e1, double inv_c2, const double* __restrict x,
                 Smallest& best) {
  for (int e = e0; e < e1; ++e) {
    const std::array<int, 4>& c = b.conn[e];
    const double ax = x[2 * c[2]] - x[2 * c[0]], ay = x[2 * c[2] + 1] - x[2 * c[0] + 1];
    const double bx = x[2 * c[3]] - x[2 * c[1]], by = x[2 * c[3] + 1] - x[2 * c[1] + 1];
    const double twice_area = ax * by - bx * ay;
    const double d = ax * ax + ay * ay + bx * bx + by * by;
    const double q = twice_area * twice_area / (2.0 * d) * inv_c2;
    best.take(twice_area > 0.0 ? q : -1.0, b.first_cell + e);
  }
}

void smallest_in(const T3Block& b, int e0, int e1, double inv_c2, const double* __restrict x, Smallest& best) {
  for (int e = e0; e < e1; ++e) {
    const std::array<int, 3>& c = b.conn[e];
    const double e1x = x[2 * c[1]] - x[2 * c[0]], e1y = x[2 * c[1] + 1] - x[2 * c[0] + 1];
    const double e2x = x[2 * c[2]] - x[2 * c[0]], e2y = x[2 * c[2] + 1] - x[2 * c[0] + 1];
    const double e3x = e2x - e1x, e3y = e2y - e1y;
    const double twice_area = e1x * e2y - e1y * e2x;
    const double s00 = e1x * e1x + e2x * e2x + e3x * e3x, s11 = e1y * e1y + e2y * e2y + e3y * e3y;
    const double s01 = e1x * e1y + e2x * e2y + e3x * e3y;
    const double half_diff = 0.5 * (s00 - s11);
    const double s_max = 0.5 * (s00 + s11) + std::sqrt(half_diff * half_diff + s01 * s01);
    const double q = (2.0 / 3.0) * twice_area * twice_area / s_max * inv_c2;
    best.take(twice_area > 0.0 ? q : -1.0, b.first_cell + e);
  }
}

}  // namespace

// The 2D model's cells. (Each model type has its own: the squared forms are the cell types'.)
template <>
double StepControlT<Model<2>>::critical(const Eigen::VectorXd& u, int* cell, bool parallel) const {
  // The smallest cell in squared form over every block (no square root per quad), then its
  // step from the same functions as model.critical_dt, so that the undeformed configuration
  // gives model.critical_dt bit for bit. On the run's threads when asked: each takes a share
  // of every block, and the smallest (value, cell) is the same whatever the share.
  double* x = position_.data();
  const double* X = model_.ref.data();
  const long dofs = static_cast<long>(position_.size());
  Smallest best;
  // Part `part` of `parts` of every block, after that part of the positions X + u.
  auto part_of = [&](int part, int parts, Smallest& mine) {
    auto share = [part, parts](std::size_t n) {
      return std::make_pair(static_cast<int>(n * part / parts), static_cast<int>(n * (part + 1) / parts));
    };
    for (std::size_t b = 0; b < model_.q4_hourglass.size(); ++b) {
      const auto [e0, e1] = share(model_.q4_hourglass[b].conn.size());
      smallest_in(model_.q4_hourglass[b], e0, e1, inv_c2_[0][b], x, mine);
    }
    for (std::size_t b = 0; b < model_.q4_full.size(); ++b) {
      const auto [e0, e1] = share(model_.q4_full[b].conn.size());
      smallest_in(model_.q4_full[b], e0, e1, inv_c2_[1][b], x, mine);
    }
    for (std::size_t b = 0; b < model_.t3.size(); ++b) {
      const auto [e0, e1] = share(model_.t3[b].conn.size());
      smallest_in(model_.t3[b], e0, e1, inv_c2_[2][b], x, mine);
    }
  };
  if (parallel && omp_get_max_threads() > 1) {
#pragma omp parallel
    {
      const int part = omp_get_thread_num(), parts = omp_get_num_threads();
      for (long i = dofs * part / parts; i < dofs * (part + 1) / parts; ++i) x[i] = X[i] + u[i];
#pragma omp barrier
      Smallest mine;
      part_of(part, parts, mine);
#pragma omp critical(ricochet_step_control)
      best.merge(mine);
    }
  } else {
    for (long i = 0; i < dofs; ++i) x[i] = X[i] + u[i];
    part_of(0, 1, best);
  }
  if (best.cell < 0 || !(best.value > 0.0)) {  // an inverted cell (or NaN coordinates)
    if (cell) *cell = best.cell;
    return 0.0;
  }
  // The exact step of that cell.
  auto corner = [&](int node) -> Vec2 { return model_.ref.col(node) + u.segment<2>(2 * node); };
  auto exact_step = [&](const auto& block, int e, double speed) {
    const auto& c = block.conn[e];
    if constexpr (std::tuple_size_v<std::decay_t<decltype(c)>> == 4) {
      Eigen::Matrix<double, 2, 4> x;
      for (int i = 0; i < 4; ++i) x.col(i) = corner(c[i]);
      return q4_characteristic_length(x) / speed;
    } else {
      Eigen::Matrix<double, 2, 3> x;
      for (int i = 0; i < 3; ++i) x.col(i) = corner(c[i]);
      return t3_characteristic_length(x) / speed;
    }
  };
  double dt_e = 0.0;
  int dt_cell = best.cell;
  auto exact = [&](const auto& blocks, const std::vector<double>& speed) {
    for (std::size_t b = 0; b < blocks.size(); ++b) {
      const int e = best.cell - blocks[b].first_cell;
      if (e < 0 || e >= static_cast<int>(blocks[b].conn.size())) continue;
      dt_e = exact_step(blocks[b], e, speed[b]);
    }
  };
  exact(model_.q4_hourglass, wave_speed_[0]);
  exact(model_.q4_full, wave_speed_[1]);
  exact(model_.t3, wave_speed_[2]);
  if (best.runner_up <= best.value * (1.0 + kTieMargin)) {
    // Other cells within rounding of the smallest (a regular mesh, undeformed or deformed
    // uniformly): the least exact step among them, the first in cell order on ties, as
    // model.critical_dt takes min of cell_dt. Else the cell that the squared forms rank first
    // need not have the least step (by an ulp or two), and the undeformed configuration
    // would not give model.critical_dt bit for bit. One more pass, on one thread.
    const double margin = best.value * (1.0 + kTieMargin);
    auto least = [&](const auto& blocks, const std::vector<double>& speed, const std::vector<double>& inv_c2) {
      for (std::size_t b = 0; b < blocks.size(); ++b) {
        const int first = blocks[b].first_cell;
        Smallest near;
        for (int e = 0; e < static_cast<int>(blocks[b].conn.size()); ++e) {
          near = Smallest{};
          smallest_in(blocks[b], e, e + 1, inv_c2[b], x, near);
          if (!(near.value <= margin)) continue;
          const double d = exact_step(blocks[b], e, speed[b]);
          if (d < dt_e || (d == dt_e && first + e < dt_cell)) dt_e = d, dt_cell = first + e;
        }
      }
    };
    least(model_.q4_hourglass, wave_speed_[0], inv_c2_[0]);
    least(model_.q4_full, wave_speed_[1], inv_c2_[1]);
    least(model_.t3, wave_speed_[2], inv_c2_[2]);
  }
  if (cell) *cell = dt_cell;
  if (!(dt_e > 0.0)) return 0.0;
  return combined_critical_dt(dt_e, spring_dt_);
}

// The 3D model's cells: the step L_e / c_p of every cell from the functions of
// model.critical_dt (hex8_characteristic_length, tet4_characteristic_length, element3d.hpp) on
// the corners X + u, so that the undeformed configuration gives model.critical_dt bit for bit;
// the least, the first in cell order on ties (Smallest). No squared pre-pass as in 2D: a
// hexahedron's length needs its masses and gradients, so it is computed once per cell. Only
// every dt_update_interval steps.
template <>
double StepControlT<Model<3>>::critical(const Eigen::VectorXd& u, int* cell, bool parallel) const {
  Smallest best;
  auto part_of = [&](int part, int parts, Smallest& mine) {
    auto blocks = [&](const auto& list, const std::vector<double>& speed) {
      for (std::size_t b = 0; b < list.size(); ++b) {
        const auto& block = list[b];
        constexpr int N = std::decay_t<decltype(block)>::kNodes;
        const std::size_t n = block.conn.size();
        for (std::size_t e = n * part / parts; e < n * (part + 1) / parts; ++e) {
          Nodes3<N> x;
          for (int a = 0; a < N; ++a) x.col(a) = model_.ref.col(block.conn[e][a]) + u.segment<3>(3 * block.conn[e][a]);
          double length;
          if constexpr (N == 8)
            length = hex8_characteristic_length(x);
          else
            length = tet4_characteristic_length(x);
          mine.take(length > 0.0 ? length / speed[b] : -1.0, block.first_cell + static_cast<int>(e));
        }
      }
    };
    blocks(model_.hex8_hourglass, wave_speed_[0]);
    blocks(model_.hex8_full, wave_speed_[1]);
    blocks(model_.tet4, wave_speed_[2]);
  };
  if (parallel && omp_get_max_threads() > 1) {
#pragma omp parallel
    {
      Smallest mine;
      part_of(omp_get_thread_num(), omp_get_num_threads(), mine);
#pragma omp critical(ricochet_step_control)
      best.merge(mine);
    }
  } else {
    part_of(0, 1, best);
  }
  if (cell) *cell = best.cell;
  if (best.cell < 0 || !(best.value > 0.0)) return 0.0;  // an inverted cell (or NaN coordinates)
  return combined_critical_dt(best.value, spring_dt_);
}

template <class M>
bool StepControlT<M>::begin_step(State& s) {
  if (landed_ || end_ - s.time <= kEndTolerance * s.dt) {
    s.time = end_;
    return false;
  }
  if (interval_ > 0 && s.step % interval_ == 0) {
    int cell = -1;
    // On the run's threads where the force pass uses them (central_difference.cpp).
    const double dt = safety_ * critical(s.u, &cell, s.force_scratch.chunks.size() >= kForceParallelChunks);
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
      const auto* b = model_.bodies.empty() ? nullptr : &model_.bodies[body];
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

template <class M>
void StepControlT<M>::report(RunResult& r) const {
  r.dt_update_interval = interval_;
  r.dt_min = dt_min_ <= dt_max_ ? dt_min_ : dt0_;
  r.dt_max = dt_min_ <= dt_max_ ? dt_max_ : dt0_;
  r.dt_updates = updates_;
  r.dt_floor = interval_ > 0 ? floor_ : 0.0;
}

// The instantiations: one per model type.
template double critical_time_step<Model<2>>(const Model<2>&, const RunSettings&, double*);
template class StepControlT<Model<2>>;
template double critical_time_step<Model<3>>(const Model<3>&, const RunSettings&, double*);
template class StepControlT<Model<3>>;

}  // namespace ricochet
