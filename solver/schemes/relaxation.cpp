#include "solver/schemes/relaxation.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>

#include "solver/schemes/central_difference.hpp"

namespace ricochet {
namespace {

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", x);
  return buf;
}

// The run's prescribed DOFs held at their t = 0 displacement.
std::vector<PrescribedDof> held_dofs(const std::vector<PrescribedDof>& prescribed, const Eigen::VectorXd& u) {
  std::vector<PrescribedDof> held;
  for (const PrescribedDof& p : prescribed) held.push_back({p.dof, PrescribedDof::Kind::displacement, u[p.dof], 0.0});
  return held;
}

// The run's loads, constant at their t = 0 value (the zero ones dropped).
std::vector<NodalLoad> loads_at_start(const std::vector<NodalLoad>& loads) {
  std::vector<NodalLoad> out;
  for (const NodalLoad& l : loads)
    if (const double f = l.force_at(0.0); f != 0.0) out.push_back({l.dof, f, 0.0, 0.0});
  return out;
}

// Largest node displacement between two displacement vectors of D DOFs per node [m].
template <int D>
double largest_move(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  double d = 0.0;
  for (Eigen::Index i = 0; i + D - 1 < a.size(); i += D)
    d = std::max(d, (a.segment<D>(i) - b.segment<D>(i)).squaredNorm());
  return std::sqrt(d);
}

// Runs a relaxation to its end; the report with its wall time and settlement.
template <class M>
bool run_relaxation(RelaxationT<M>& r, const Eigen::VectorXd& u_start, RelaxationReport& report) {
  using Status = typename RelaxationT<M>::Status;
  const auto t0 = std::chrono::steady_clock::now();
  Status status;
  do status = r.step();
  while (status == Status::running);
  report = r.report();
  report.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  report.settlement = largest_move<M::kDim>(r.state().u, u_start);
  return status == Status::converged;
}

}  // namespace

template <class M>
double relaxation_step(const M& model, const RunSettings& settings, bool implicit) {
  if (settings.relaxation.dt > 0.0) return settings.relaxation.dt;
  return kRelaxationStepFactor * (implicit ? 0.9 * model.critical_dt : settings.dt);
}

template <class M>
RelaxationT<M>::RelaxationT(const M& model, const RunSettings& settings, double dt, const Eigen::VectorXd& u_start,
                            RelaxationContactT<M::kDim> contact)
    : model_(model), settings_(settings), contact_(contact) {
  held_ = held_dofs(settings.prescribed, u_start);
  fixed_.assign(model.num_dofs(), 0);
  for (const PrescribedDof& p : held_) fixed_[p.dof] = 1;
  const std::vector<NodalLoad> loads = loads_at_start(settings.loads);
  s_ = initial_state(model, held_, dt, u_start, loads);
  s_.v_half.setZero();
  Eigen::VectorXd f = s_.f_ext;
  for (const NodalLoad& l : loads) f[l.dof] += l.value;
  load_norm_ = f.norm();
  report_.dt = dt;
}

template <class M>
void RelaxationT<M>::contact() {
  if (contact_.bipotential)
    contact_phase(model_, obstacles_of(settings_, model_), settings_.contact, *contact_.bipotential, s_);
  else if (contact_.penalty)
    penalty_phase(model_, obstacles_of(settings_, model_), *contact_.penalty, s_);
}

template <class M>
typename RelaxationT<M>::Status RelaxationT<M>::step() {
  evaluate(model_, held_, s_, false);
  contact();
  if (!(s_.forces.min_jacobian > 0.0)) {
    report_.reason = "inverted element (det F = " + number(s_.forces.min_jacobian) + ") at relaxation step " +
                     std::to_string(report_.steps);
    return Status::failed;
  }
  // The residual M a_n = f_ext + F - f_int + R over the free DOFs, against the loads.
  double r2 = 0.0, f2 = 0.0;
  const int n = model_.num_dofs();
  for (int d = 0; d < n; ++d) {
    if (fixed_[d]) continue;
    const double r = model_.mass[d] * s_.a[d];
    r2 += r * r;
  }
  double scale = load_norm_;
  if (!(scale > 0.0)) {
    for (int d = 0; d < n; ++d) f2 += s_.f_int[d] * s_.f_int[d];
    scale = std::sqrt(f2);
  }
  const double residual = scale > 0.0 ? std::sqrt(r2) / scale : (r2 > 0.0 ? INFINITY : 0.0);
  report_.residual = residual;
  report_.kinetic_ratio = kinetic_peak_ > 0.0 ? kinetic_last_ / kinetic_peak_ : 0.0;
  if (!std::isfinite(residual)) {
    report_.reason = "non-finite force residual at relaxation step " + std::to_string(report_.steps);
    return Status::failed;
  }
  const double tol = settings_.relaxation.tolerance;
  if (residual <= tol && kinetic_last_ <= tol * tol * kinetic_peak_) {
    report_.converged = true;
    return Status::converged;
  }
  if (report_.steps >= settings_.relaxation.max_steps) {
    report_.reason = "did not converge in " + std::to_string(report_.steps) + " steps (force residual " +
                     number(residual) + ", kinetic energy ratio " + number(report_.kinetic_ratio) +
                     "; tolerance " + number(tol) + ", relaxation.max_steps " +
                     std::to_string(settings_.relaxation.max_steps) + ")";
    return Status::failed;
  }
  update(s_);
  ++report_.steps;
  // Kinetic damping (Cundall 1976): past a peak of the kinetic energy, every velocity is zeroed
  // and u goes back to the step's midpoint, which never adds energy (kRelaxationStepFactor).
  double kinetic = 0.0;
  for (int d = 0; d < n; ++d) kinetic += model_.mass[d] * s_.v_half[d] * s_.v_half[d];
  kinetic *= 0.5;
  kinetic_peak_ = std::max(kinetic_peak_, kinetic);
  if (kinetic < kinetic_last_) {
    s_.u.noalias() -= (0.5 * s_.dt) * s_.v_half;
    s_.v_half.setZero();
    ++report_.velocity_resets;
    kinetic_last_ = 0.0;
  } else {
    kinetic_last_ = kinetic;
  }
  return Status::running;
}

template <class M>
bool relax_explicit_start(const M& model, const RunSettings& settings, RelaxationContactT<M::kDim> contact, State& s,
                          RelaxationReport& report) {
  constexpr int D = M::kDim;
  const Eigen::VectorXd u_start = s.u;
  bool converged;
  {
    RelaxationT<M> r(model, settings, relaxation_step(model, settings, false), u_start, contact);
    converged = run_relaxation(r, u_start, report);
    s = initial_state(model, settings.prescribed, settings.dt, r.state().u, settings.loads);
  }
  for (ContactSetT<D>* c : {contact.bipotential ? &contact.bipotential->set : nullptr,
                            contact.penalty ? &contact.penalty->set : nullptr}) {
    if (!c) continue;
    // The first step reconstructs v_{-1/2} = v_0 - dt/2 a_0 from the free acceleration
    // (evaluate()), which does not see the contact forces that hold the relaxed state: v_0 is
    // handed over less dt/2 M^-1 R of the relaxation's last step, so that v_{-1/2} = v_0 -
    // dt/2 M^-1 (f_ext - f_int + R), ~v_0 at equilibrium. Otherwise the loaded penalty springs
    // would kick the contact nodes by dt/2 M^-1 R at the first step.
    for (int k : c->active) {
      const VecD<D> force = ContactFrame<D>(c->normal[k]).global(c->reaction[k]);
      const auto& st = c->stencil[k];
      for (int j = 0; j < st.count; ++j)
        s.v_half.segment<D>(D * st.node[j]) -= 0.5 * s.dt * st.coef[j] * force * model.inv_mass[D * st.node[j]];
    }
    // The contacts keep their state; what they measured belongs to the relaxation.
    c->total = ContactTotals{};
    c->last = ContactStep{};
  }
  return converged;
}

template <class M>
bool relax_displacement(const M& model, const RunSettings& settings, Eigen::VectorXd& u,
                        RelaxationReport& report) {
  constexpr int D = M::kDim;
  const double dt = relaxation_step(model, settings, true);
  const Eigen::VectorXd u_start = initial_state(model, settings.prescribed, dt, settings.initial_displacement).u;
  BipotentialContactT<D> bipotential;
  RelaxationContactT<D> contact;
  const auto& obstacles = obstacles_of(settings, model);
  if (!obstacles.empty() || !settings.body_pairs.empty()) {
    bipotential = make_bipotential_contact(model, obstacles, settings.friction, settings.prescribed,
                                           settings.body_pairs);
    if (!bipotential.set.candidates.empty()) contact.bipotential = &bipotential;
  }
  RelaxationT<M> r(model, settings, dt, u_start, contact);
  const bool converged = run_relaxation(r, u_start, report);
  u = r.state().u;
  return converged;
}

// The instantiations: one per model type.
template double relaxation_step<Model<2>>(const Model<2>&, const RunSettings&, bool);
template class RelaxationT<Model<2>>;
template bool relax_explicit_start<Model<2>>(const Model<2>&, const RunSettings&, RelaxationContactT<2>, State&,
                                          RelaxationReport&);
template bool relax_displacement<Model<2>>(const Model<2>&, const RunSettings&, Eigen::VectorXd&, RelaxationReport&);
template double relaxation_step<Model<3>>(const Model<3>&, const RunSettings&, bool);
template class RelaxationT<Model<3>>;
template bool relax_explicit_start<Model<3>>(const Model<3>&, const RunSettings&, RelaxationContactT<3>, State&,
                                           RelaxationReport&);
template bool relax_displacement<Model<3>>(const Model<3>&, const RunSettings&, Eigen::VectorXd&, RelaxationReport&);

}  // namespace ricochet
