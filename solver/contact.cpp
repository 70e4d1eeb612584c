#include "solver/contact.hpp"

#include <algorithm>
#include <cmath>

namespace ricochet {

ContactState make_contact_state(const Model& model, const std::vector<LineObstacle>& obstacles,
                                const std::vector<std::vector<double>>& friction,
                                const std::vector<PrescribedDof>& prescribed) {
  ContactState c;
  std::vector<bool> held(model.num_nodes(), false);
  for (const auto& p : prescribed) held[p.dof / 2] = true;
  for (int b = 0; b < static_cast<int>(model.bodies.size()); ++b)
    for (int o = 0; o < static_cast<int>(obstacles.size()); ++o)
      for (int node : model.bodies[b].boundary_nodes)
        if (!held[node]) {
          c.candidates.push_back({node, o, friction[b][o]});
          c.any_friction = c.any_friction || friction[b][o] > 0.0;
        }
  const std::size_t n = c.candidates.size();
  c.reaction.assign(n, {});
  c.x_free.assign(n, {});
  c.status.assign(n, ContactStatus::open);
  c.weight.assign(n, 0.0);
  c.active.reserve(n);
  c.node_reaction.assign(model.num_nodes(), Vec2::Zero());
  return c;
}

namespace {

// Gauss-Seidel sweeps over the active contacts; each contact sees the current reactions of
// the other contacts on its node through x = x_free + w (r_own + r_others). Returns sweeps.
template <bool kFriction>
int gauss_seidel(const std::vector<LineObstacle>& obstacles, const ContactSettings& set,
                 ContactState& c) {
  for (int sweep = 1; sweep <= set.max_sweeps; ++sweep) {
    bool converged = true;
    for (int k : c.active) {
      const ContactCandidate& cc = c.candidates[k];
      const Vec2 n = obstacles[cc.obstacle].normal, t = obstacles[cc.obstacle].tangent();
      const double w = c.weight[k];
      LocalPair& r = c.reaction[k];
      const Vec2 own = r.n * n + r.t * t;
      const Vec2 other = c.node_reaction[cc.node] - own;
      const LocalPair xf{c.x_free[k].n + w * n.dot(other), c.x_free[k].t + w * t.dot(other)};
      const double rho = set.rho_factor / w;
      LocalPair next;
      if constexpr (kFriction) {
        next = bipotential_update(r, xf, w, cc.friction_coeff, rho);
      } else {
        next = {std::max(0.0, r.n - rho * (xf.n + w * r.n)), 0.0};
      }
      const double change = std::hypot(next.n - r.n, next.t - r.t);
      if (change > set.tolerance * std::hypot(next.n, next.t)) converged = false;
      c.node_reaction[cc.node] += (next.n - r.n) * n + (next.t - r.t) * t;
      r = next;
    }
    if (converged) {
      c.converged = true;
      return sweep;
    }
  }
  c.converged = false;
  return set.max_sweeps;
}

}  // namespace

void contact_phase(const Model& model, const std::vector<LineObstacle>& obstacles,
                   const ContactSettings& set, ContactState& c, State& s) {
  const double dt = s.dt;
  const bool position = set.level == ContactLevel::position;
  c.active.clear();
  // Broad phase: only boundary nodes whose free motion ends behind an obstacle at t+dt.
  for (int k = 0; k < static_cast<int>(c.candidates.size()); ++k) {
    const ContactCandidate& cc = c.candidates[k];
    const LineObstacle& ob = obstacles[cc.obstacle];
    const int i = cc.node;
    const Vec2 v_free = s.v_half.segment<2>(2 * i) + dt * s.a.segment<2>(2 * i);
    const Vec2 x_next = model.ref.col(i) + s.u.segment<2>(2 * i) + dt * v_free;
    const double gap = ob.normal.dot(x_next - ob.point);
    if (!(gap < 0.0)) {
      c.reaction[k] = {};
      c.status[k] = ContactStatus::open;
      continue;
    }
    const double m = model.mass[2 * i];
    c.x_free[k] = position ? LocalPair{gap, dt * ob.tangent().dot(v_free)}
                           : LocalPair{ob.normal.dot(v_free), ob.tangent().dot(v_free)};
    c.weight[k] = position ? dt * dt / m : dt / m;
    c.node_reaction[i].setZero();
    c.active.push_back(k);
  }
  c.active_count = static_cast<int>(c.active.size());
  c.stick_count = c.slip_count = 0;
  c.normal_force = c.tangential_force = 0.0;
  c.sweeps = 0;
  c.converged = true;
  if (c.active.empty()) return;

  // Warm start from the last step's reactions.
  for (int k : c.active) {
    const LineObstacle& ob = obstacles[c.candidates[k].obstacle];
    c.node_reaction[c.candidates[k].node] += c.reaction[k].n * ob.normal + c.reaction[k].t * ob.tangent();
  }
  c.sweeps = c.any_friction ? gauss_seidel<true>(obstacles, set, c) : gauss_seidel<false>(obstacles, set, c);
  ++c.steps_with_contact;
  c.sweeps_total += c.sweeps;
  c.sweeps_max = std::max(c.sweeps_max, c.sweeps);
  if (!c.converged) ++c.unconverged_steps;

  // U_c = dt^2 M^-1 R: the reactions enter the accelerations of step n.
  for (int k : c.active) {
    const ContactCandidate& cc = c.candidates[k];
    const LineObstacle& ob = obstacles[cc.obstacle];
    const LocalPair r = c.reaction[k];
    const Vec2 force = r.n * ob.normal + r.t * ob.tangent();
    s.a.segment<2>(2 * cc.node) += force / model.mass[2 * cc.node];
    c.normal_force += r.n;
    c.tangential_force += r.t;
    c.status[k] = classify(r, cc.friction_coeff);
    c.stick_count += c.status[k] == ContactStatus::stick;
    c.slip_count += c.status[k] == ContactStatus::slip;
  }
  // Energy bookkeeping with the final reactions. Slip work: -r_t times the slip increment
  // dt t.v_{n+1/2} of the step (>= 0 by the cone). Contact work: dt R.v_n with
  // v_n = v_{n-1/2} + dt/2 a_n, exactly the change of the half-step kinetic energy
  // 1/2 m v_{n+1/2}^2 - 1/2 m v_{n-1/2}^2 that R causes (a node stopped dead loses 1/2 m v^2).
  for (int k : c.active) {
    const ContactCandidate& cc = c.candidates[k];
    const LineObstacle& ob = obstacles[cc.obstacle];
    const Vec2 a = s.a.segment<2>(2 * cc.node);
    const Vec2 v_next = s.v_half.segment<2>(2 * cc.node) + dt * a;
    const Vec2 v_mid = s.v_half.segment<2>(2 * cc.node) + 0.5 * dt * a;
    const LocalPair r = c.reaction[k];
    c.friction_dissipation -= r.t * dt * ob.tangent().dot(v_next);
    c.contact_work += dt * (r.n * ob.normal + r.t * ob.tangent()).dot(v_mid);
  }
}

double penetration(const Model& model, const std::vector<LineObstacle>& obstacles,
                   const std::vector<ContactCandidate>& candidates, const Eigen::VectorXd& u) {
  double depth = 0.0;
  for (const ContactCandidate& cc : candidates) {
    const LineObstacle& ob = obstacles[cc.obstacle];
    const Vec2 x = model.ref.col(cc.node) + u.segment<2>(2 * cc.node);
    depth = std::max(depth, -ob.normal.dot(x - ob.point));
  }
  return depth;
}

}  // namespace ricochet
