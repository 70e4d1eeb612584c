#include "solver/contact/bipotential_contact.hpp"

#include <algorithm>
#include <cmath>

namespace ricochet {

template <class M>
BipotentialContactT<M::kDim> make_bipotential_contact(const M& model, const std::vector<ObstacleOf<M>>& obstacles,
                                                      const std::vector<std::vector<double>>& friction,
                                                      const std::vector<PrescribedDof>& prescribed,
                                                      const std::vector<BodyPair>& pairs) {
  BipotentialContactT<M::kDim> b;
  b.set = make_contact_set(model, obstacles, friction, prescribed, pairs);
  const std::size_t n = b.set.candidates.size();
  b.x_free.assign(n, {});
  b.weight.assign(n, 0.0);
  b.node_reaction.assign(model.num_nodes(), VecD<M::kDim>::Zero());
  b.node_mark.assign(model.num_nodes(), 0u);
  b.reaction_global.assign(n, VecD<M::kDim>::Zero());
  b.frame_kept.assign(n, 0);
  return b;
}

namespace {

// Gauss-Seidel sweeps over the active contacts; each contact sees the current reactions of
// the other contacts on its node through x = x_free + w (r_own + r_others). Returns the sweeps
// taken and sets `converged`.
template <bool kFriction, int D>
int gauss_seidel(const ContactSettings& set, BipotentialContactT<D>& b, bool& converged_out) {
  using Vec = VecD<D>;
  using Local = typename Space<D>::Local;
  ContactSetT<D>& c = b.set;
  for (int sweep = 1; sweep <= set.max_sweeps; ++sweep) {
    bool converged = true;
    for (int k : c.active) {
      const ContactCandidate& cc = c.candidates[k];
      const auto& st = c.stencil[k];
      const ContactFrame<D> f(c.normal[k]);
      const double w = b.weight[k];
      Local& r = c.reaction[k];
      const Vec own = f.global(r);
      // x = x_free + sum_j coef_j w_j (reactions on node j other than this contact's own).
      Local xf = b.x_free[k];
      for (int j = 0; j < st.count; ++j) {
        const Local other = f.local(b.node_reaction[st.node[j]] - st.coef[j] * own);
        xf.n += st.factor[j] * other.n;
        xf.t += st.factor[j] * other.t;
      }
      const double rho = set.rho_factor / w;
      Local next;
      if constexpr (kFriction) {
        next = bipotential_update(r, xf, w, cc.friction_coeff, rho);
      } else {
        next.n = std::max(0.0, r.n - rho * (xf.n + w * r.n));
      }
      const double change = local_distance(next, r);
      if (change > set.tolerance * local_norm(next)) converged = false;
      const Vec delta = f.global(Local{next.n - r.n, next.t - r.t});
      for (int j = 0; j < st.count; ++j) b.node_reaction[st.node[j]] += st.coef[j] * delta;
      r = next;
    }
    if (converged) {
      converged_out = true;
      return sweep;
    }
  }
  converged_out = false;
  return set.max_sweeps;
}

}  // namespace

template <class M>
void add_reaction_accelerations(const M& model, const BipotentialContactT<M::kDim>& b, State& s) {
  constexpr int D = M::kDim;
  const ContactSetT<D>& c = b.set;
  for (int k : c.active) {
    const auto& st = c.stencil[k];
    const VecD<D> force = ContactFrame<D>(c.normal[k]).global(c.reaction[k]);
    for (int j = 0; j < st.count; ++j)
      s.a.segment<D>(D * st.node[j]) += st.coef[j] * force / model.mass[D * st.node[j]];
  }
}

namespace {

// One frame update (ContactSettings::frame_updates) of the active contacts, position level: the
// positions at t+dt that the current reactions give, x = predicted + dt dt_n R / m; at them each
// active contact's frame, gap and stencil again (the tracked face or segment may change; a node
// that no longer faces its master keeps the last frame); its reaction carried over in global
// axes; and the local problem re-linearized there: x_free = (g - n . sum_j factor_j R_j,
// dt t . v_rel,free), so that x_free + the current reactions' share is the gap at those
// positions. A rigid plane's frame does not change; a curved obstacle's or a master body's
// does, by the square of the step's correction.
// Out of line: the frozen-frame step (frame_updates = 0) compiles as it did without it, so
// its floating-point contractions and results stay those of the paper's scheme bit for bit.
template <class M, class Predicted, class VFree>
[[gnu::noinline]] void update_frames(const M& model, const std::vector<ObstacleOf<M>>& obstacles, BipotentialContactT<M::kDim>& b,
                   const State& s, const Predicted& predicted, const VFree& v_free) {
  constexpr int D = M::kDim;
  using Vec = VecD<D>;
  using Local = typename Space<D>::Local;
  ContactSetT<D>& c = b.set;
  const double dt = s.dt, dt_n = velocity_step(s);
  // The nodes whose node_reaction is current: those of the active contacts' stencils.
  const unsigned mark = ++b.mark;
  for (int k : c.active)
    for (int j = 0; j < c.stencil[k].count; ++j) b.node_mark[c.stencil[k].node[j]] = mark;
  auto corrected = [&](int j) -> Vec {
    const Vec x = predicted(j);
    return b.node_mark[j] == mark ? Vec(x + (dt * dt_n / model.mass[D * j]) * b.node_reaction[j]) : x;
  };
  for (int k : c.active) {
    b.reaction_global[k] = ContactFrame<D>(c.normal[k]).global(c.reaction[k]);
    typename Space<D>::ObstacleContact oc;
    const int tracked = c.segment[k];
    b.frame_kept[k] = !candidate_frame(model, obstacles, c, k, s.u, s.v_half, corrected, oc);
    if (b.frame_kept[k]) {
      c.segment[k] = tracked;  // its stencil, normal and x_free stay those of the step
      continue;
    }
    c.normal[k] = oc.normal;
    b.x_free[k].n = oc.gap;
  }
  // The reactions on the new stencils.
  const unsigned next = ++b.mark;
  for (int k : c.active)
    for (int j = 0; j < c.stencil[k].count; ++j) {
      b.node_reaction[c.stencil[k].node[j]].setZero();
      b.node_mark[c.stencil[k].node[j]] = next;
    }
  for (int k : c.active) {
    const auto& st = c.stencil[k];
    const Vec r = b.reaction_global[k];
    c.reaction[k] = ContactFrame<D>(c.normal[k]).local(r);
    for (int j = 0; j < st.count; ++j) b.node_reaction[st.node[j]] += st.coef[j] * r;
  }
  for (int k : c.active) {
    if (b.frame_kept[k]) continue;
    auto& st = c.stencil[k];
    const ContactFrame<D> f(c.normal[k]);
    Vec v_rel = Vec::Zero(), shift = Vec::Zero();
    double w = 0.0;
    for (int j = 0; j < st.count; ++j) {
      const int node = st.node[j];
      v_rel += st.coef[j] * v_free(node);
      const double wj = dt * dt_n / model.mass[D * node];
      st.factor[j] = st.coef[j] * wj;
      w += st.coef[j] * st.factor[j];
      shift += st.factor[j] * b.node_reaction[node];
    }
    b.x_free[k] = Local{b.x_free[k].n - f.local(shift).n, dt * f.tangential(v_rel)};
    b.weight[k] = w;
  }
}

}  // namespace

template <class M>
void contact_phase(const M& model, const std::vector<ObstacleOf<M>>& obstacles, const ContactSettings& set,
                   BipotentialContactT<M::kDim>& b, State& s) {
  constexpr int D = M::kDim;
  using Vec = VecD<D>;
  using Local = typename Space<D>::Local;
  ContactSetT<D>& c = b.set;
  // dt = dt_{n+1/2} (t_n to t_n+1) and dt_n = (dt_{n-1/2} + dt_{n+1/2}) / 2, over which a_n acts
  // on the velocity (central_difference.hpp); both are dt for a fixed step. A reaction r on a
  // node of mass m moves v_{n+1/2} by dt_n r / m and x_{n+1} by dt dt_n r / m: the local
  // compliance is w = dt dt_n / m at position level, dt_n / m at velocity level
  // (docs/background.md, Variable time step).
  const double dt = s.dt, dt_n = velocity_step(s);
  const bool position = set.level == ContactLevel::position;
  // Free motion to t+dt: v_{n+1/2} without contact and the predicted position.
  auto v_free = [&](int j) -> Vec { return s.v_half.segment<D>(D * j) + dt_n * s.a.segment<D>(D * j); };
  auto predicted = [&](int j) -> Vec { return model.ref.col(j) + s.u.segment<D>(D * j) + dt * v_free(j); };
  update_boxes(c, predicted);
  begin_step(c);
  // Broad phase: only boundary nodes whose free motion ends behind an obstacle (or inside a
  // master body) at t+dt. Gap and frame at the predicted position, frozen for the step.
  for (int k = 0; k < static_cast<int>(c.candidates.size()); ++k) {
    typename Space<D>::ObstacleContact oc;
    if (!candidate_frame(model, obstacles, c, k, s.u, s.v_half, predicted, oc) || !(oc.gap < 0.0)) {
      c.reaction[k] = {};
      record(c, k, ContactStatus::open);
      continue;
    }
    auto& st = c.stencil[k];
    c.normal[k] = oc.normal;
    const ContactFrame<D> f(oc.normal);
    // Relative free velocity and compliance of the stencil: w = sum_j coef_j^2 w_j.
    Vec v_rel = Vec::Zero();
    double w = 0.0;
    for (int j = 0; j < st.count; ++j) {
      const int node = st.node[j];
      v_rel += st.coef[j] * v_free(node);
      const double wj = position ? dt * dt_n / model.mass[D * node] : dt_n / model.mass[D * node];
      st.factor[j] = st.coef[j] * wj;
      w += st.coef[j] * st.factor[j];
      b.node_reaction[node].setZero();
    }
    b.x_free[k] = position ? Local{oc.gap, dt * f.tangential(v_rel)} : f.local(v_rel);
    b.weight[k] = w;
    c.active.push_back(k);
  }
  if (c.active.empty()) {
    finish_step(c, 0, true);
    return;
  }

  // Warm start from the last step's reactions.
  for (int k : c.active) {
    const auto& st = c.stencil[k];
    const Vec r = ContactFrame<D>(c.normal[k]).global(c.reaction[k]);
    for (int j = 0; j < st.count; ++j) b.node_reaction[st.node[j]] += st.coef[j] * r;
  }
  bool converged = true;
  int sweeps = c.any_friction ? gauss_seidel<true>(set, b, converged) : gauss_seidel<false>(set, b, converged);
  if (position)
    for (int pass = 0; pass < set.frame_updates; ++pass) {
      bool pass_converged = true;
      update_frames(model, obstacles, b, s, predicted, v_free);
      sweeps += c.any_friction ? gauss_seidel<true>(set, b, pass_converged) : gauss_seidel<false>(set, b, pass_converged);
      converged = converged && pass_converged;
    }

  // U_c = dt^2 M^-1 R: the reactions enter the accelerations of step n.
  add_reaction_accelerations(model, b, s);
  for (int k : c.active) record(c, k, classify(c.reaction[k], c.candidates[k].friction_coeff));
  // Work with the final reactions: dt_n R.v with v = v_{n-1/2} + dt_n/2 a_n (v_n for a fixed
  // step), exactly the change of the half-step kinetic energy 1/2 m v_{n+1/2}^2 - 1/2 m v_{n-1/2}^2
  // that R causes (a node stopped dead loses 1/2 m v^2); slip work -r_t times the slip increment
  // dt t.v_{n+1/2} of the step (>= 0 by the cone). Between bodies both are sums over the stencil.
  auto v_mid = [&](int j) -> Vec { return s.v_half.segment<D>(D * j) + 0.5 * dt_n * s.a.segment<D>(D * j); };
  auto v_next = [&](int j) -> Vec { return s.v_half.segment<D>(D * j) + dt_n * s.a.segment<D>(D * j); };
  for (int k : c.active) record_work(c, k, dt_n, v_mid, true, v_next, dt);
  finish_step(c, sweeps, converged);
}

// The instantiations: one per model type.
#define RICOCHET_BIPOTENTIAL_FOR(M)                                                                          \
  template BipotentialContactT<M::kDim> make_bipotential_contact<M>(                                         \
      const M&, const std::vector<ObstacleOf<M>>&, const std::vector<std::vector<double>>&,                  \
      const std::vector<PrescribedDof>&, const std::vector<BodyPair>&);                                      \
  template void contact_phase<M>(const M&, const std::vector<ObstacleOf<M>>&, const ContactSettings&,        \
                                 BipotentialContactT<M::kDim>&, State&);                                     \
  template void add_reaction_accelerations<M>(const M&, const BipotentialContactT<M::kDim>&, State&);
RICOCHET_BIPOTENTIAL_FOR(Model<2>)
RICOCHET_BIPOTENTIAL_FOR(Model<3>)
#undef RICOCHET_BIPOTENTIAL_FOR

}  // namespace ricochet
