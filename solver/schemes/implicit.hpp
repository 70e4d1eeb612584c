// The implicit reference scheme of the paper (FER/Impact; docs/background.md, The implicit
// theta-scheme): the first-order theta-scheme on velocities
//   M (v1 - v0) = dt [(1 - xi)(F - F_int)_0 + xi (F - F_int)_1] + dt R,
//   u1 = u0 + dt [(1 - theta) v0 + theta v1],
// solved by Newton with the consistent tangent A = M + theta xi dt^2 K_T + xi dt C assembled
// into a preallocated sparse pattern, each linear system by Jacobi-preconditioned CG or by a
// CHOLMOD Cholesky factor reused across Newton iterations and steps (modified Newton). Contact
// reactions R at t1 come from the same bi-potential update as the semi-explicit scheme, on the
// condensed problem x = x_free + W R with W = c H A^-1 H^T dt (c = dt theta at the position
// level, 1 at the velocity level; solver/contact/condensed_contact.hpp), so the converged
// reactions satisfy the contact law exactly. The scheme is in three parts: this integrator
// (predict -> Newton -> close the step), the linear system (implicit_system.hpp) and the
// condensed contact problem.
#pragma once

#include <string>
#include <vector>

#include "solver/contact/condensed_contact.hpp"
#include "solver/contact/contact_set.hpp"
#include "solver/linear/anderson.hpp"
#include "solver/schemes/implicit_system.hpp"
#include "solver/schemes/run_types.hpp"

namespace ricochet {

// Wall time of the scheme's phases [s] (RunImplicit's *_seconds).
struct ImplicitPhases {
  double assembly = 0.0, factorization = 0.0, solve = 0.0, contact = 0.0, residual = 0.0;
};

template <class M>
class ImplicitIntegratorT {
 public:
  static constexpr int D = M::kDim;
  using Vec = VecD<D>;
  using Local = typename Space<D>::Local;
  using Stencil = typename Space<D>::Stencil;

  ImplicitIntegratorT(const M& model, const RunSettings& run, const ImplicitSettings& settings);

  // t_n -> t_{n+1}. With `with_energy` the energies of the new state are computed, with
  // `stress` (RunMonitor::stress_tracking(n + 1)) its stress peaks into state().forces, and
  // what the tracking samples. Both come from the force pass of the Newton iterate that
  // converges when the step predicts which one that is (from the last step's count of
  // iterations), otherwise from one pass more.
  // Returns false when Newton or a linear solve fails (failure() says why); the state is then
  // that of the failed iterate.
  bool step(bool with_energy, const StressTracking* stress = nullptr);

  // The state at t_n for the observers: u = u_n, v_half = v_n and a = 0 (so velocity_at_step
  // gives v_n), f_int = f_int(u_n, v_n), forces = its totals.
  const State& state() const { return s_; }
  const ContactSetT<D>& contact() const { return contact_; }
  const std::vector<double>& residuals() const { return residuals_; }  // relative, last step
  const std::string& failure() const { return failure_; }
  long newton_iterations_total() const { return newton_total_; }
  long linear_iterations_total() const { return system_.cg_iterations(); }
  bool direct_solver() const { return system_.has_factor(); }  // a factor is (or may be) used
  bool supernodal() const { return system_.supernodal(); }     // that factor is supernodal
  bool single_solves() const { return system_.single_solves(); }  // ... solved in single precision
  bool mass_solver() const { return system_.mass_run(); }  // steps start with the mass iteration
  long mass_iterations() const { return system_.mass_iterations(); }
  long factorizations() const { return system_.factorizations(); }
  int refactor_iterations() const { return system_.has_factor() ? system_.refactor_iterations() : 0; }
  const ImplicitPhases& phases() const { return phases_; }
  long exact_contact_solves() const { return condensed_.exact_solves(); }
  long shifted_iterations() const { return system_.shifted_factorizations(); }

 private:
  // G at (u1, v1) into g_, returns its relative inf-norm. From the step's evaluation
  // fuse_from_ on, the force pass also gives what step() was asked for (fused_*).
  double residual();
  double load_average(const NodalLoad& l) const;  // (1 - xi) F(t_n) + xi F(t_n+1) [N]
  bool solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);
  bool solve_contact();  // from dv_free_: the reactions into contact_, their response into condensed_
  // The step's first iterate v1: extrapolated from the last steps' velocities, v0, or the one
  // that keeps u1 = u0 (implicit.cpp).
  enum class Predictor { extrapolate, constant, hold };
  void predict(Predictor kind);
  bool newton(double r, int& sweeps);       // the iterations to the converged v1
  void close_step(double hourglass_power0, int sweeps);  // bookkeeping; u1, v1 become the state
  bool engage_penetrating();  // engages candidates behind their obstacle at u1; true if any

  const M& model_;
  const RunSettings& run_;
  const std::vector<ObstacleOf<M>>& obstacles_;
  ImplicitSettings set_;
  State s_;
  ContactSetT<D> contact_;
  ImplicitSystem system_;        // A, its factor or CG, the refactorization rule
  CondensedContact<D> condensed_;  // R on x = x_free + W R; H^T R and its response A^-1 dt H^T R
  AndersonMixer anderson_;  // accelerates the mass iteration (ImplicitSettings::mass_anderson_depth)
  std::vector<unsigned char> engaged_;  // per candidate: in the contact problem of this step
  Eigen::VectorXd v_prev2_, v_prev_, v_base_, u0_, v0_, f0_, u1_, v1_, f1_, g_, rhs_, dv_free_, prescribed_v_;
  Eigen::VectorXd y_frame_;  // the response whose shift the contact frames take (solve_contact)
  int iteration_ = 0;         // the Newton iteration solve_contact() runs in
  std::vector<double> residuals_;
  std::string failure_;
  double scale_ = 0.0;  // largest momentum scale of the residual so far
  double step_scale_ = 0.0;  // the step's constant terms of the momentum scale (M v0, dt f0, dt f_ext)
  // The force pass that gives the step's energies and stresses (step()): the step's residual
  // evaluations are counted from 0 (the predictor's); from evaluation fuse_from_ (the index of
  // the last step's converged one) on, a pass computes what fused_energy_ and fused_stress_ ask.
  int evaluation_ = 0, fuse_from_ = 1;
  bool fused_energy_ = false;
  const StressTracking* fused_stress_ = nullptr;  // &fused_tracking_ or null
  StressTracking fused_tracking_;  // the step's tracking, sampled_max redirected to fused_sampled_
  VonMises2 fused_sampled_{0.0, 0.0, 0.0};  // what the iterates' passes fold in, not used
  bool last_energy_ = false, last_stress_ = false;  // what the last evaluation's pass computed
  double force_roundoff_ = 0.0;  // round-off floor of the internal forces [N] (implicit.cpp)
  long newton_total_ = 0;
  ImplicitPhases phases_;
  bool step_unconverged_ = false;  // a contact solve of this step reached contact.max_sweeps
};

using ImplicitIntegrator = ImplicitIntegratorT<Model<2>>;

// Instantiated for Model<2> and Model<3> (implicit.cpp).
template <class M>
RunResult run_implicit(const M& model, const RunSettings& settings, const ImplicitSettings& implicit,
                       const ProgressFn& progress = {});

}  // namespace ricochet
