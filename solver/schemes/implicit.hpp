// The implicit reference scheme of the paper (FER/Impact; docs/background.md, The implicit
// theta-scheme): the first-order theta-scheme on velocities
//   M (v1 - v0) = dt [(1 - xi)(F - F_int)_0 + xi (F - F_int)_1] + dt R,
//   u1 = u0 + dt [(1 - theta) v0 + theta v1],
// solved by Newton with the consistent tangent A = M + theta xi dt^2 K_T + xi dt C assembled
// into a preallocated sparse pattern, each linear system by Jacobi-preconditioned CG or by a
// CHOLMOD Cholesky factor reused across Newton iterations and steps (modified Newton). Contact
// reactions R at t1 come from the same bi-potential update as the semi-explicit scheme, on the
// condensed problem x = x_free + W R with W = c H A^-1 H^T dt (c = dt theta at the position
// level, 1 at the velocity level), by Uzawa sweeps in which x is evaluated exactly (one solve
// of A per sweep), so the converged reactions satisfy the contact law exactly.
#pragma once

#include <string>
#include <vector>

#include "solver/contact/contact_set.hpp"
#include "solver/schemes/implicit_system.hpp"
#include "solver/schemes/run_types.hpp"

namespace ricochet {

template <class M>
class ImplicitIntegratorT {
 public:
  static constexpr int D = M::kDim;
  using Vec = VecD<D>;
  using Local = typename Space<D>::Local;
  using Stencil = typename Space<D>::Stencil;

  ImplicitIntegratorT(const M& model, const RunSettings& run, const ImplicitSettings& settings);

  // t_n -> t_{n+1}. With `with_energy` the energies of the new state are computed. Returns
  // false when Newton or a linear solve fails (failure() says why); the state is then that of
  // the failed iterate.
  bool step(bool with_energy);

  // The state at t_n for the observers: u = u_n, v_half = v_n and a = 0 (so velocity_at_step
  // gives v_n), f_int = f_int(u_n, v_n), forces = its totals.
  const State& state() const { return s_; }
  const ContactSetT<D>& contact() const { return contact_; }
  const std::vector<double>& residuals() const { return residuals_; }  // relative, last step
  const std::string& failure() const { return failure_; }
  long newton_iterations_total() const { return newton_total_; }
  long linear_iterations_total() const { return system_.cg_iterations(); }
  bool direct_solver() const { return system_.direct(); }
  long factorizations() const { return system_.factorizations(); }
  long exact_contact_solves() const { return exact_contact_solves_; }
  long shifted_iterations() const { return system_.shifted_factorizations(); }

 private:
  double residual(bool with_energy);  // G at (u1, v1) into g_, returns its relative inf-norm
  double load_average(const NodalLoad& l) const;  // (1 - xi) F(t_n) + xi F(t_n+1) [N]
  bool solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);
  bool solve_contact();  // from dv_free_, fills y_ and contact_.reaction
  bool uzawa_contact(double c);        // true if it converged
  bool exact_contact(double c);        // condensed W by column solves, Gauss-Seidel (false: a linear solve failed)
  bool column_cached(int slot, const Stencil& st, const Vec& direction) const;
  void build_impulse();
  void add_reaction(int k);                                  // candidate k's reaction into impulse_
  Local stencil_dot(int k, const Eigen::VectorXd& y) const;  // (n, t) . sum_j coef_j y_j
  void predict(bool extrapolate);           // v1 of the step's first iterate
  bool newton(double r, int& sweeps);       // the iterations to the converged v1
  void close_step(double hourglass_power0, int sweeps);  // bookkeeping; u1, v1 become the state
  bool engage_penetrating();  // engages candidates behind their obstacle at u1; true if any

  const M& model_;
  const RunSettings& run_;
  const std::vector<ObstacleOf<M>>& obstacles_;
  ImplicitSettings set_;
  State s_;
  ContactSetT<D> contact_;
  ImplicitSystem system_;  // A, its factor or CG, the refactorization rule
  // Per candidate, the local problem x = x_free + w r of the current Newton iterate (w: the
  // diagonal estimate of the local compliance).
  std::vector<Local> x_free_;
  std::vector<double> weight_;
  int contact_sweeps_ = 0;           // sweeps of the last contact solve
  bool contact_converged_ = true;    // the last contact solve met its tolerance
  // A^-1 H^T e per contact candidate k and direction d (normal, then the tangents) in column
  // dirs k + d (Dn x dirs candidates). On the direct path a column is reused while the factor,
  // the candidate's stencil and its direction are those it was computed with.
  Eigen::MatrixXd columns_;
  std::vector<long> column_factor_;      // factor_id_ of each column, -1: none
  std::vector<Vec, Eigen::aligned_allocator<Vec>> column_direction_;
  std::vector<Stencil> column_stencil_;
  std::vector<int> active_columns_;      // column of each active contact direction
  Eigen::MatrixXd w_;         // condensed compliance (m x m)
  std::vector<unsigned char> engaged_;  // per candidate: in the contact problem of this step
  Eigen::VectorXd r_vec_;     // dt R per active contact direction
  Eigen::VectorXd v_prev_, v_base_, u0_, v0_, f0_, u1_, v1_, f1_, g_, rhs_, dv_free_, y_, impulse_, prescribed_v_;
  std::vector<double> residuals_;
  std::string failure_;
  double scale_ = 0.0;  // largest momentum scale of the residual so far
  double force_roundoff_ = 0.0;  // round-off floor of the internal forces [N] (implicit.cpp)
  long newton_total_ = 0;
  long exact_contact_solves_ = 0;
  bool step_unconverged_ = false;  // a contact solve of this step reached contact.max_sweeps
};

using ImplicitIntegrator = ImplicitIntegratorT<Model<2>>;

// Instantiated for Model<2> and Model<3> (implicit.cpp).
template <class M>
RunResult run_implicit(const M& model, const RunSettings& settings, const ImplicitSettings& implicit,
                       const ProgressFn& progress = {});

}  // namespace ricochet
