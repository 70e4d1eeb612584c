#include "solver/schemes/implicit.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "solver/schemes/central_difference.hpp"
#include "solver/schemes/run_monitor.hpp"
#include "solver/schemes/relaxation.hpp"
#include "solver/schemes/threads.hpp"

namespace ricochet {
namespace {

// The thickness of a body in internal_force_roundoff whose largest cell size is `size` [m]:
// the body's thickness in 2D, the cell size in 3D.
inline double roundoff_thickness(const BodyInfo<2>& b, double) { return b.thickness; }
inline double roundoff_thickness(const BodyInfo<3>&, double size) { return size; }

// The round-off floor of the internal nodal forces [N]: a cell's stress carries an error of
// about eps (lambda + 2 mu) from the cancellation in E = (F^T F - I)/2 near F = I, and its
// nodal forces about that times its size and thickness; 16 such errors, of the stiffest cell.
// (lambda + 2 mu) = rho c_p^2 and the cell size L_e = c_p cell_dt (model.hpp). In 3D the
// thickness is the cell size too: the error scales with the cell's face area L_e^2.
template <class M>
double internal_force_roundoff(const M& model) {
  double f = 0.0;
  for (const auto& b : model.bodies) {
    const double rho = material_density(b.material), c = material_wave_speed(b.material);
    double size = 0.0;
    for (int k = b.first_cell; k < b.first_cell + b.num_cells; ++k) size = std::max(size, c * model.cell_dt[k]);
    f = std::max(f,
                 16.0 * std::numeric_limits<double>::epsilon() * rho * c * c * size * roundoff_thickness(b, size));
  }
  return f;
}

// The diagonal of A at a node, for the local compliance estimate: the mean over its DOFs.
inline double node_diagonal(const Eigen::VectorXd& inv_diag, int node, std::integral_constant<int, 2>) {
  return 0.5 / inv_diag[2 * node] + 0.5 / inv_diag[2 * node + 1];
}
inline double node_diagonal(const Eigen::VectorXd& inv_diag, int node, std::integral_constant<int, 3>) {
  return (1.0 / inv_diag[3 * node] + 1.0 / inv_diag[3 * node + 1] + 1.0 / inv_diag[3 * node + 2]) / 3.0;
}

// Adds the wall time of its scope to a phase's seconds (ImplicitPhases).
class PhaseTimer {
 public:
  explicit PhaseTimer(double& seconds) : seconds_(seconds), start_(std::chrono::steady_clock::now()) {}
  ~PhaseTimer() { seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }
  PhaseTimer(const PhaseTimer&) = delete;
  PhaseTimer& operator=(const PhaseTimer&) = delete;

 private:
  double& seconds_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace

template <class M>
ImplicitIntegratorT<M>::ImplicitIntegratorT(const M& model, const RunSettings& run, const ImplicitSettings& settings)
    : model_(model),
      run_(run),
      obstacles_(obstacles_of(run, model)),
      set_(settings),
      system_(make_system_matrix(model), model.mass, run.prescribed, settings,
              mass_contraction_estimate(settings.theta, settings.xi, run.dt, model.critical_dt)) {
  s_ = initial_state(model, run.prescribed, run.dt, run.initial_displacement, run.loads);
  contact_ = make_contact_set(model, obstacles_, run.friction, run.prescribed, run.body_pairs);
  // The contact problem keeps as many response columns as the factor has nonzeros per row (at
  // least twice A's), so that they take no more memory than the factor.
  const int n = model.num_dofs();
  const double per_row = std::max(system_.factor_nonzeros(), 2.0 * system_.matrix().matrix.nonZeros()) / n;
  condensed_.reserve(contact_, n, static_cast<int>(per_row));
  engaged_.assign(contact_.candidates.size(), 0);
  if (system_.mass_run()) anderson_.reserve(n, settings.mass_anderson_depth);
  force_roundoff_ = internal_force_roundoff(model);
  for (Eigen::VectorXd* v : {&v_prev2_, &v_prev_, &v_base_, &u0_, &v0_, &f0_, &u1_, &v1_, &f1_, &g_, &rhs_, &dv_free_,
                             &prescribed_v_, &y_frame_})
    v->setZero(n);
  s_.a.setZero();
  s_.forces = internal_forces(model, s_.u.data(), s_.v_half.data(), s_.f_int.data(), true);
  residuals_.reserve(set_.max_newton_iterations + 1);
}

template <class M>
double ImplicitIntegratorT<M>::load_average(const NodalLoad& l) const {
  return (1.0 - set_.xi) * l.force_at(s_.time) + set_.xi * l.force_at(s_.time + s_.dt);
}

template <class M>
bool ImplicitIntegratorT<M>::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  PhaseTimer timer(phases_.solve);
  if (system_.solve(b, x)) return true;
  failure_ = system_.failure();
  return false;
}

template <class M>
double ImplicitIntegratorT<M>::residual() {
  PhaseTimer timer(phases_.residual);
  const double dt = s_.dt, th = set_.theta, xi = set_.xi;
  u1_ = u0_ + dt * ((1.0 - th) * v0_ + th * v1_);
  const bool fused = evaluation_++ >= fuse_from_;
  last_energy_ = fused && fused_energy_;
  last_stress_ = fused && fused_stress_ != nullptr;
  s_.forces = internal_forces(model_, u1_.data(), v1_.data(), f1_.data(), last_energy_,
                              last_stress_ ? fused_stress_ : nullptr);
  // G and the largest entries of M v1, f1 and the impulse in one pass over the DOFs, without
  // reading the vectors again for each norm.
  const Eigen::VectorXd& impulse = condensed_.impulse();
  const double *m = model_.mass.data(), *v1 = v1_.data(), *v0 = v0_.data(), *f1 = f1_.data(), *f0 = f0_.data(),
               *fe = s_.f_ext.data(), *imp = impulse.data();
  double* g = g_.data();
  // Four entries at a time (Eigen's packets, as the expression was evaluated).
  using A4 = Eigen::Array4d;
  A4 mv4 = A4::Zero(), f4 = A4::Zero(), imp4 = A4::Zero(), g4 = A4::Zero(), probe4 = A4::Zero();
  const long n = g_.size(), n4 = n - n % 4;
  const double c0 = 1.0 - xi;
  for (long i = 0; i < n4; i += 4) {
    const A4 mi = A4::Map(m + i), v1i = A4::Map(v1 + i), f1i = A4::Map(f1 + i), impi = A4::Map(imp + i);
    const A4 gi = mi * (v1i - A4::Map(v0 + i)) + dt * (xi * f1i + c0 * A4::Map(f0 + i) - A4::Map(fe + i)) - dt * impi;
    A4::Map(g + i) = gi;
    mv4 = mv4.max((mi * v1i).abs());
    f4 = f4.max(f1i.abs());
    imp4 = imp4.max(impi.abs());
    g4 = g4.max(gi.abs());
    probe4 += 0.0 * gi;  // NaN if an entry is not finite (max() could drop a NaN)
  }
  double mv_max = mv4.maxCoeff(), f_max = f4.maxCoeff(), imp_max = imp4.maxCoeff(), g_max = g4.maxCoeff();
  double nan_probe = probe4.sum();
  // The last n % 4 entries by the vector expression itself, whose arithmetic there is Eigen's
  // scalar path's (a loop written out here may contract differently into fused multiply-adds).
  if (const long r = n - n4; r > 0) {
    g_.tail(r) = model_.mass.tail(r).cwiseProduct(v1_.tail(r) - v0_.tail(r)) +
                 dt * (xi * f1_.tail(r) + (1.0 - xi) * f0_.tail(r) - s_.f_ext.tail(r)) - dt * impulse.tail(r);
    for (long i = n4; i < n; ++i) {
      mv_max = std::max(mv_max, std::abs(m[i] * v1[i]));
      f_max = std::max(f_max, std::abs(f1[i]));
      imp_max = std::max(imp_max, std::abs(imp[i]));
      g_max = std::max(g_max, std::abs(g[i]));
      nan_probe += 0.0 * g[i];
    }
  }
  // Nodal loads, xi-averaged like the other forces: dt [(1 - xi) F(t_n) + xi F(t_n+1)].
  for (const LoadedDof& l : s_.loads) g_[l.load.dof] -= dt * load_average(l.load);
  for (const auto& p : run_.prescribed) {
    prescribed_v_[p.dof] = g_[p.dof];  // the unconstrained residual: dt times the reaction
    g_[p.dof] = 0.0;
  }
  if (!s_.loads.empty() || !run_.prescribed.empty()) g_max = g_.lpNorm<Eigen::Infinity>();
  // The momentum scale of the residual: the largest seen in the run, so the round-off floor of G
  // (e.g. the cancellation in E = (F^T F - I)/2) stays relative to the problem's scale when the
  // motion decays.
  // A body at rest has no momentum, and its internal forces balance gravity and the contact
  // reactions: then the floor is the internal forces' own round-off (internal_force_roundoff),
  // which the tolerance must not ask G to go below. The step's constant terms are step_scale_.
  scale_ = std::max({scale_, step_scale_, mv_max, dt * f_max, dt * imp_max});
  return (g_max + nan_probe) / scale_;
}

template <class M>
bool ImplicitIntegratorT<M>::solve_contact() {
  const double dt = s_.dt, th = set_.theta;
  const bool position = run_.contact.level == ContactLevel::position;
  const double c = position ? dt * th : 1.0;  // x = x_free + c H y
  ContactSetT<D>& cs = contact_;
  cs.active.clear();
  auto u_pred = [&](int j) -> Vec {
    return u1_.template segment<D>(D * j) + dt * th * dv_free_.template segment<D>(D * j);
  };
  // With frame updates ([contact] frame_updates) the frames are taken where the last iteration's
  // reactions left the nodes, x_pred + c y (y the response to them), and each gap is carried
  // back to the free prediction linearly, so that x = x_free + c H y stays the gap where the
  // frame is taken; at convergence that is where the nodes end. Without, at x_pred (the paper's).
  // The first frame_updates + 1 iterations of a step take the frames where the last one's
  // reactions left the nodes; later ones keep that shift (y_frame_), so that the frames move
  // only with the iterate, as without updates: re-taking them in every iteration let a node of
  // the ball on a block's fine mesh switch between faces, and Newton stalled at 4e-6 (step 31).
  const bool shifted = position && run_.contact.frame_updates > 0;
  if (shifted && iteration_ <= run_.contact.frame_updates) y_frame_ = condensed_.response();
  const Eigen::VectorXd& y = y_frame_;  // the response to the reactions the frames follow
  auto x_pred = [&](int j) -> Vec {
    if (!shifted) return model_.ref.col(j) + u_pred(j);
    return model_.ref.col(j) + u_pred(j) + c * y.template segment<D>(D * j);
  };
  update_boxes(cs, x_pred);
  for (int k = 0; k < static_cast<int>(cs.candidates.size()); ++k) {
    // Gap and frame at the predicted position (see closest() in obstacle.hpp); the reactions of
    // this iterate act along this frame. Between bodies the segment is chosen from the start of
    // the step (u0, v0).
    typename Space<D>::ObstacleContact oc;
    if (!candidate_frame(model_, obstacles_, cs, k, u0_, v0_, x_pred, oc)) {
      cs.reaction[k] = {};
      continue;
    }
    const Stencil& st = cs.stencil[k];
    double gap = oc.gap;
    if (shifted) {
      Vec shift = Vec::Zero();
      for (int j = 0; j < st.count; ++j) shift += st.coef[j] * y.template segment<D>(D * st.node[j]);
      gap -= c * oc.normal.dot(shift);
    }
    // Within a step the engaged set only grows, so Newton cannot cycle between active sets; an
    // engaged contact that separates simply gets R = 0 from the contact law.
    if (gap < 0.0) engaged_[k] = 1;
    if (!engaged_[k]) {
      cs.reaction[k] = {};
      continue;
    }
    cs.normal[k] = oc.normal;
    const ContactFrame<D> frame(oc.normal);
    Vec du = Vec::Zero(), v_rel = Vec::Zero();
    double compliance = 0.0;  // sum_j coef_j^2 / a_jj: exact when A is diagonal
    for (int j = 0; j < st.count; ++j) {
      const int node = st.node[j];
      du += st.coef[j] * (u_pred(node) - u0_.template segment<D>(D * node));
      v_rel += st.coef[j] * (v1_.template segment<D>(D * node) + dv_free_.template segment<D>(D * node));
      const double a_jj = node_diagonal(system_.inverse_diagonal(), node, std::integral_constant<int, D>{});
      compliance += st.coef[j] * st.coef[j] / a_jj;
    }
    condensed_.set_local(k, position ? Local{gap, frame.tangential(du)} : frame.local(v_rel), c * dt * compliance);
    cs.active.push_back(k);
  }
  if (cs.active.empty()) {
    condensed_.clear();
    return true;
  }
  // Uzawa with CG (ImplicitSettings::uzawa_sweeps), the exact W with the factor or when Uzawa
  // does not converge. As in the semi-explicit scheme, Gauss-Seidel that reaches
  // contact.max_sweeps leaves its last iterate: the step goes on and is counted in
  // unconverged_steps. Only a failed linear solve stops the run.
  auto solve_a = [this](const Eigen::VectorXd& b, Eigen::VectorXd& x) { return solve(b, x); };
  auto solve_block = [this](const double* b, double* x, int ncol) {
    PhaseTimer timer(phases_.solve);
    if (system_.solve_block(b, x, ncol)) return true;
    failure_ = system_.failure();
    return false;
  };
  const double tol = run_.contact.tolerance;
  if (system_.matrix_id() < 0 && condensed_.uzawa(cs, c, dt, set_.uzawa_sweeps, tol, solve_a)) return true;
  if (!condensed_.exact(cs, c, dt, run_.contact.max_sweeps, tol, solve_a, solve_block, system_.matrix_id(),
                        system_.mass_iteration() ? &system_.inverse_diagonal() : nullptr))
    return false;
  if (!condensed_.converged()) step_unconverged_ = true;
  return true;
}

template <class M>
bool ImplicitIntegratorT<M>::engage_penetrating() {
  CandidateDepth<M> depth_of(model_, obstacles_, contact_.surfaces, u1_);
  bool any = false;
  for (std::size_t k = 0; k < contact_.candidates.size(); ++k) {
    if (engaged_[k] != 0 || depth_of(contact_.candidates[k]) <= 0.0) continue;
    engaged_[k] = 1;
    any = true;
  }
  return any;
}

template <class M>
bool ImplicitIntegratorT<M>::step(bool with_energy, const StressTracking* stress) {
  u0_ = s_.u;
  v0_ = s_.v_half;
  f0_ = s_.f_int;
  const double hourglass_power0 = s_.forces.hourglass_power;
  step_scale_ = std::max({model_.mass.cwiseProduct(v0_).template lpNorm<Eigen::Infinity>(),
                          s_.dt * f0_.lpNorm<Eigen::Infinity>(), s_.dt * s_.f_ext.lpNorm<Eigen::Infinity>(),
                          s_.dt * force_roundoff_ / set_.newton_tolerance, 1e-300});
  // A history sample's maxima fold in every pass they are given: the Newton iterates' passes
  // take the tracking with sampled_max pointing nowhere, and the converged pass's own maxima
  // (ForceTotals::sampled) go to the sample below. A snapshot's cell values are overwritten by
  // each pass, so the converged one's stay.
  evaluation_ = 0;
  fused_energy_ = with_energy;
  fused_stress_ = nullptr;
  if (stress) {
    fused_tracking_ = *stress;
    fused_tracking_.sampled_max = stress->sampled_max ? &fused_sampled_ : nullptr;
    fused_stress_ = &fused_tracking_;
  }
  predict(s_.step > 0 && s_.dt <= model_.critical_dt ? Predictor::extrapolate : Predictor::constant);
  // The last step's reactions in the frame (and on the stencil) they were solved in.
  condensed_.impulse_of_all(contact_);
  for (std::size_t k = 0; k < contact_.candidates.size(); ++k) engaged_[k] = contact_.reaction[k].n > 0.0;
  residuals_.clear();
  step_unconverged_ = false;
  system_.begin_step();
  anderson_.reset();
  double r = residual();
  // A predictor that inverts an element (or gives a non-finite residual) is replaced: the
  // extrapolated one by v1 = v0, and v1 = v0 by the iterate that stays at u0 (valid, since u0
  // is the last converged state). Above the explicit limit the trapezoidal rule alternates the
  // unresolved modes' velocities, so v1 = v0 moves their nodes the wrong way by dt |v0|: on the
  // oblique plate's M2x2 at 1e-4 s that inverted an element at step 21 and Newton, whose line
  // search cannot leave an inverted state, stopped.
  auto invalid = [&] { return !std::isfinite(r) || !(s_.forces.min_jacobian > 0.0); };
  if (s_.step > 0 && invalid() && s_.dt <= model_.critical_dt) {
    predict(Predictor::constant);
    r = residual();
  }
  if (invalid()) {
    predict(Predictor::hold);
    r = residual();
  }
  int sweeps = 0;
  if (!newton(r, sweeps)) return false;
  // The converged iterate's pass gave the energies and stresses if the step predicted it was
  // the one; otherwise one more pass (the same forces, f1 is rewritten with the same values).
  fuse_from_ = evaluation_ - 1;
  if ((with_energy && !last_energy_) || (stress != nullptr && !last_stress_)) {
    PhaseTimer timer(phases_.residual);
    s_.forces = internal_forces(model_, u1_.data(), v1_.data(), f1_.data(), with_energy, stress);
  } else if (stress != nullptr && stress->sampled_max != nullptr) {
    max_into(*stress->sampled_max, s_.forces.sampled);
  }
  close_step(hourglass_power0, sweeps);
  return true;
}

// Predictor: where the step resolves the dynamics (dt <= critical_dt), quadratic extrapolation of
// the velocity, v1 = 3 v0 - 3 v_{-1} + v_{-2} (linear, 2 v0 - v_{-1}, at the second step; on the
// oblique plate's M2 at 1e-6 s it starts Newton 8x closer than the linear one); otherwise (and at
// the first step) v1 = v0; `hold` keeps u1 = u0 (the fallbacks of step()). A contact that ended
// the last step with a reaction is predicted to stay closed: its slave node's normal velocity is set so that the stencil's gap does not change over the step (position
// level: n . sum_j coef_j ((1 - theta) v0_j + theta v1_j) = 0) or its normal relative velocity
// is zero (velocity level). The trapezoidal rule alternates a closed contact's normal velocity
// (v1_n = -v0_n on a fixed obstacle), which extrapolation predicts with the wrong sign: on the
// oblique plate at 1e-6 s that left 7e-4 of the residual after the first iteration of every
// contact step (docs/implicit.md, "Predictor"). Prescribed DOFs take their velocity, or the one
// that reaches their displacement at t_n+1.
template <class M>
void ImplicitIntegratorT<M>::predict(Predictor kind) {
  const double dt = s_.dt, th = set_.theta;
  const double t1 = s_.time + dt;
  if (kind == Predictor::extrapolate && s_.step > 1)
    v1_ = 3.0 * (v0_ - v_prev_) + v_prev2_;
  else if (kind == Predictor::extrapolate)
    v1_ = 2.0 * v0_ - v_prev_;
  else if (kind == Predictor::constant)
    v1_ = v0_;
  else
    v1_ = (-(1.0 - th) / th) * v0_;  // u1 = u0 + dt ((1 - theta) v0 + theta v1) = u0
  const bool position = run_.contact.level == ContactLevel::position;
  const ContactSetT<D>& cs = contact_;
  for (std::size_t k = 0; k < cs.candidates.size(); ++k) {
    if (!(cs.reaction[k].n > 0.0)) continue;
    const Stencil& st = cs.stencil[k];
    const Vec n = cs.normal[k];
    double rate = 0.0;  // d gap / dt over the step, or the normal relative velocity at t_n+1
    for (int j = 0; j < st.count; ++j) {
      const int node = st.node[j];
      const Vec v1 = v1_.template segment<D>(D * node);
      rate += st.coef[j] * n.dot(position ? Vec((1.0 - th) * v0_.template segment<D>(D * node) + th * v1) : v1);
    }
    const double slave_share = st.coef[0] * (position ? th : 1.0);
    v1_.template segment<D>(D * st.node[0]) -= (rate / slave_share) * n;
  }
  for (const auto& p : run_.prescribed)
    v1_[p.dof] = p.kind == PrescribedDof::Kind::velocity
                     ? p.value
                     : (p.displacement_at(t1) - u0_[p.dof] - dt * (1.0 - th) * v0_[p.dof]) / (dt * th);
}

// Newton's iterations from the predictor (relative residual r) until the residual meets the
// tolerance with the contact law imposed; sweeps: the most contact sweeps of an iteration. False
// (failure_ set) when it does not converge or a solve fails.
template <class M>
bool ImplicitIntegratorT<M>::newton(double r, int& sweeps) {
  const double dt = s_.dt, th = set_.theta, xi = set_.xi;
  for (int it = 0;; ++it) {
    if (!std::isfinite(r)) {
      failure_ = "non-finite Newton residual at iteration " + std::to_string(it);
      return false;
    }
    residuals_.push_back(r);
    // With contact candidates at least one iteration runs: the contact law is only imposed
    // inside an iteration, and a free iterate can have a zero residual (a rigid translation).
    // Converged also requires that no contact candidate outside the engaged set penetrates at u1:
    // the reactions of engaged contacts can push a neighbouring node into the obstacle.
    // With contact frame updates ([contact] frame_updates) a step with active contacts runs that
    // many iterations more: each takes the frames again where the last one left the nodes.
    if (r <= set_.newton_tolerance && (it > 0 || contact_.candidates.empty()) &&
        (contact_.active.empty() || it > run_.contact.frame_updates) && !engage_penetrating())
      break;
    if (it == set_.max_newton_iterations) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "Newton did not converge in %d iterations (relative residual %.3g)", it, r);
      failure_ = buf;
      return false;
    }
    ++newton_total_;
    // The direct path reuses the factor of an earlier iterate (modified Newton) unless the rule
    // below asked for a new one; PCG needs the current A every iteration.
    if (system_.needs_matrix()) {
      {
        PhaseTimer timer(phases_.assembly);
        assemble_system(model_, u1_.data(), v1_.data(), 1.0, th * xi * dt * dt, xi * dt, system_.matrix(),
                        f1_.data(), false);
      }
      PhaseTimer timer(phases_.factorization);
      if (!system_.prepare()) {
        failure_ = system_.failure();
        return false;
      }
    }
    system_.count_iteration();
    const double r_before = r;
    // The update for the residual without the contact reactions. The mass iteration's solve is
    // one multiplication by 1 / M, done in the same pass (the same numbers as system_.solve()).
    if (system_.mass_iteration()) {
      PhaseTimer timer(phases_.solve);
      dv_free_ = (-(g_ + dt * condensed_.impulse())).cwiseProduct(system_.inverse_diagonal());
    } else {
      rhs_ = -(g_ + dt * condensed_.impulse());
      dv_free_.setZero();
      if (!solve(rhs_, dv_free_)) return false;
    }
    if (!contact_.candidates.empty()) {
      // The contact problem's own time: its wall time less that of the solves it makes.
      const double solve_before = phases_.solve;
      bool solved;
      {
        PhaseTimer timer(phases_.contact);
        iteration_ = it;
        solved = solve_contact();
      }
      phases_.contact -= phases_.solve - solve_before;
      if (!solved) return false;
      sweeps = std::max(sweeps, condensed_.sweeps());
      condensed_.add_response(dv_free_);
    }
    // The mass iteration's update, accelerated (AndersonMixer); a history from the factor's
    // iterations or a line search would mix two maps.
    if (system_.mass_iteration()) anderson_.mix(v1_, dv_free_);
    // Backtracking: the full Newton update unless it inverts an element or is not finite
    // (large steps on coarse stiff problems); then halve it, up to 10 times.
    v_base_.swap(v1_);  // v1_ is set from it below
    double alpha = 1.0;
    for (int ls = 0;; ++ls) {
      v1_ = v_base_ + alpha * dv_free_;
      r = residual();
      if ((std::isfinite(r) && s_.forces.min_jacobian > 0.0) || ls == 10) break;
      alpha *= 0.5;
    }
    if (alpha < 1.0) anderson_.reset();
    system_.end_iteration(r, r_before, alpha, it + 1);  // the refactorization rule (implicit_system.hpp)
  }
  return true;
}

// The converged step's bookkeeping, and u1, v1 become the state at t_n+1.
template <class M>
void ImplicitIntegratorT<M>::close_step(double hourglass_power0, int sweeps) {
  const double dt = s_.dt, xi = set_.xi;
  // Bookkeeping of the converged step: reactions at prescribed DOFs (R = G_unconstrained/dt),
  // contact work R.du and slip work, viscous hourglass work (same xi-average as the forces).
  for (const auto& p : run_.prescribed)
    s_.reaction_work += prescribed_v_[p.dof] / dt * (u1_[p.dof] - u0_[p.dof]);
  // The loads' work with the force the step applied: [(1 - xi) F_n + xi F_n+1] . (u1 - u0).
  for (const LoadedDof& l : s_.loads) s_.load_work += load_average(l.load) * (u1_[l.load.dof] - u0_[l.load.dof]);
  s_.hourglass_dissipation += dt * (xi * s_.forces.hourglass_power + (1.0 - xi) * hourglass_power0);
  // The step's contact results, from the converged reactions: the contacts with r_n > 0, their
  // statuses and forces, and their work and slip work on the step's displacement.
  ContactSetT<D>& cs = contact_;
  begin_step(cs);
  for (int k = 0; k < static_cast<int>(cs.candidates.size()); ++k) {
    const Local r = cs.reaction[k];
    if (!(r.n > 0.0)) {
      record(cs, k, ContactStatus::open);
      continue;
    }
    cs.active.push_back(k);
    record(cs, k, classify(r, cs.candidates[k].friction_coeff));
  }
  auto du = [&](int j) -> Vec { return u1_.template segment<D>(D * j) - u0_.template segment<D>(D * j); };
  for (int k : cs.active) record_work(cs, k, 1.0, du, true, du);
  finish_step(cs, sweeps, !step_unconverged_);
  // Swaps, not copies: v0_, u1_, v1_ and f1_ are set again before the next step reads them.
  v_prev2_.swap(v_prev_);
  v_prev_.swap(v0_);
  s_.u.swap(u1_);
  s_.v_half.swap(v1_);
  s_.f_int.swap(f1_);
  ++s_.step;
  s_.time = static_cast<double>(s_.step) * dt;
}

template <class M>
RunResult run_implicit(const M& model, const RunSettings& settings, const ImplicitSettings& implicit,
                       const ProgressFn& progress) {
  if (settings.dt_update_interval != 0)
    throw std::invalid_argument("implicit scheme: the step is fixed (dt_update_interval must be 0)");
  // The whole run, the integrator's set-up included, uses the run's thread count.
  ThreadScope threads(settings.threads, settings.adapt_threads);
  RunResult result;
  result.timing.threads = threads.threads();
  result.timing.threads_min = threads.threads_min();
  // A quasi-static start (relaxation.hpp): relaxed with the semi-explicit loop and the same
  // bi-potential contact law, the run starts from the relaxed displacement.
  result.relaxed = settings.relaxation.enabled;
  RunSettings relaxed;
  bool relaxed_ok = true;
  if (result.relaxed) {
    relaxed = settings;
    relaxed_ok = relax_displacement(model, settings, relaxed.initial_displacement, result.relaxation);
  }
  const RunSettings& run = result.relaxed ? relaxed : settings;
  ImplicitIntegratorT<M> integrator(model, run, implicit);
  const State& s = integrator.state();
  const double kinetic0 = 0.5 * s.v_half.cwiseAbs2().dot(model.mass);
  const bool with_contact = !integrator.contact().candidates.empty();
  RunMonitorT<M> monitor(model, run, result, integrator.contact());
  const long planned = monitor.planned_steps();
  Eigen::VectorXd stress_forces(model.num_dofs());  // the stress pass's nodal forces, not used
  if (!relaxed_ok) {
    monitor.diverge(s, "relaxation: " + result.relaxation.reason);
    monitor.finish(s);
    result.implicit.direct_solver = integrator.direct_solver();
    return result;
  }
  // The initial state's stresses from a pass of their own; every later state's from the force
  // pass of the Newton iterate that converged to it (ImplicitIntegratorT::step), or one more.
  if (const StressTracking* st = monitor.stress_tracking(0))
    monitor.track_stress(s, internal_forces(model, s.u.data(), s.v_half.data(), stress_forces.data(), false, st).stress);
  for (;;) {
    threads.adapt();
    const long n = s.step;
    if (monitor.is_monitor_step(n)) {
      if (!monitor.observe(s, kinetic0)) break;
      if (progress) progress(n, planned, s.time);
    }
    if (n == planned) break;
    const StressTracking* st = monitor.stress_tracking(n + 1);
    if (!integrator.step(monitor.is_monitor_step(n + 1), st)) {
      monitor.diverge(s, integrator.failure());
      break;
    }
    if (st) monitor.track_stress(s, s.forces.stress);
    if (with_contact) monitor.contact_step(s.time - s.dt, s.dt);  // the step just taken: [t_n, t_n+1]
    if (!(s.forces.min_jacobian > 0.0)) {
      monitor.diverge(s, "inverted element (det F = " + std::to_string(s.forces.min_jacobian) + ")");
      break;
    }
  }
  monitor.finish(s);
  result.timing.threads_min = threads.threads_min();
  result.implicit.newton_iterations = integrator.newton_iterations_total();
  result.implicit.linear_iterations = integrator.linear_iterations_total();
  result.implicit.direct_solver = integrator.direct_solver();
  result.implicit.supernodal = integrator.supernodal();
  result.implicit.single_solves = integrator.single_solves();
  result.implicit.mass_solver = integrator.mass_solver();
  result.implicit.mass_iterations = integrator.mass_iterations();
  result.implicit.factorizations = integrator.factorizations();
  result.implicit.refactor_iterations = integrator.refactor_iterations();
  const ImplicitPhases& ph = integrator.phases();
  result.implicit.assembly_seconds = ph.assembly;
  result.implicit.factorization_seconds = ph.factorization;
  result.implicit.solve_seconds = ph.solve;
  result.implicit.contact_seconds = ph.contact;
  result.implicit.residual_seconds = ph.residual;
  return result;
}

template class ImplicitIntegratorT<Model<2>>;
template class ImplicitIntegratorT<Model<3>>;
template RunResult run_implicit<Model<2>>(const Model<2>&, const RunSettings&, const ImplicitSettings&, const ProgressFn&);
template RunResult run_implicit<Model<3>>(const Model<3>&, const RunSettings&, const ImplicitSettings&, const ProgressFn&);

}  // namespace ricochet
