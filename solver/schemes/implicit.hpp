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
#include "solver/linear/cholmod_factor.hpp"
#include "solver/linear/pcg.hpp"
#include "solver/schemes/run_types.hpp"
#include "solver/forces/tangent.hpp"

namespace ricochet {

enum class LinearSolverKind {
  automatic,  // see below
  pcg,        // Jacobi-preconditioned CG, full Newton (A assembled every iteration)
  direct,     // CHOLMOD supernodal Cholesky (solver/linear/cholmod_factor.hpp; symbolic analysis
              // once per run), modified Newton: the factor is reused while Newton contracts fast
};
// automatic: direct (faster than pcg at every step measured, docs/implicit.md). With pcg, a
// solve that fails (indefinite matrix of a far-off iterate) switches the run to direct.

struct ImplicitSettings {
  double theta = 0.5;               // [0.5, 1]; 0.5 = trapezoidal displacement update
  double xi = 0.5;                  // [0.5, 1]; 0.5 = trapezoidal force average
  double newton_tolerance = 1e-10;  // |G|_inf <= tol * momentum scale (or dt * the internal forces' round-off)
  int max_newton_iterations = 25;
  double linear_tolerance = 1e-12;  // relative CG residual
  int max_linear_iterations = 10000;
  LinearSolverKind linear_solver = LinearSolverKind::automatic;
  int uzawa_sweeps = 30;  // Uzawa sweeps before switching to the exact condensed W (pcg only)
  // Refactorization rule of the direct solver's modified Newton (docs/implicit.md). The factor
  // of A is kept across Newton iterations and steps; the next iteration refactorizes when the
  // last one, not yet converged, contracted the residual by less than this factor
  // (r_k+1 > refactor_contraction r_k), needed a line search, or was the
  // refactor_iterations-th of this step on the same factor. refactor_contraction = 0
  // refactorizes every iteration (full Newton); refactor_iterations = 1 every iteration but the
  // first of each step.
  double refactor_contraction = 0.5;  // [0, 1)
  int refactor_iterations = 6;        // >= 1
};

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
  long linear_iterations_total() const { return linear_total_; }
  bool direct_solver() const { return direct_; }
  long factorizations() const { return factorizations_; }
  long exact_contact_solves() const { return exact_contact_solves_; }
  long shifted_iterations() const { return shifted_iterations_; }

 private:
  double residual(bool with_energy);  // G at (u1, v1) into g_, returns its relative inf-norm
  double load_average(const NodalLoad& l) const;  // (1 - xi) F(t_n) + xi F(t_n+1) [N]
  bool solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);
  bool solve_contact();  // from dv_free_, fills y_ and contact_.reaction
  bool uzawa_contact(double c);        // true if it converged
  bool exact_contact(double c);        // condensed W by column solves, Gauss-Seidel (false: a linear solve failed)
  bool factorize();
  void use_direct();
  bool column_cached(int slot, const Stencil& st, const Vec& direction) const;
  void build_impulse();
  void add_reaction(int k);                                  // candidate k's reaction into impulse_
  Local stencil_dot(int k, const Eigen::VectorXd& y) const;  // (n, t) . sum_j coef_j y_j
  void predict(bool extrapolate);           // v1 of the step's first iterate
  bool newton(double r, int& sweeps);       // the iterations to the converged v1
  void close_step(double hourglass_power0, int sweeps);  // bookkeeping; u1, v1 become the state
  bool engage_penetrating();  // engages candidates behind their obstacle at u1; true if any
  void constrain_matrix();

  const M& model_;
  const RunSettings& run_;
  const std::vector<ObstacleOf<M>>& obstacles_;
  ImplicitSettings set_;
  State s_;
  ContactSetT<D> contact_;
  // Per candidate, the local problem x = x_free + w r of the current Newton iterate (w: the
  // diagonal estimate of the local compliance).
  std::vector<Local> x_free_;
  std::vector<double> weight_;
  int contact_sweeps_ = 0;           // sweeps of the last contact solve
  bool contact_converged_ = true;    // the last contact solve met its tolerance
  SystemMatrix system_;
  Pcg pcg_;
  bool direct_ = false;
  CholmodFactor factor_;
  long factor_id_ = 0;         // increases with every factorization: the version of the factor
  bool refactor_next_ = true;  // the next Newton iteration assembles and factorizes A
  int iterations_on_factor_ = 0;  // Newton iterations of this step on the current factor
  long factorizations_ = 0;
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
  std::vector<double> a_values_;  // the values of A as factorized (with the shift, if any)
  Eigen::VectorXd inv_diag_;
  std::vector<unsigned char> fixed_;  // per DOF: prescribed
  std::vector<int> constrained_entries_;  // value positions of prescribed rows and columns
  std::vector<int> constrained_diagonal_;
  Eigen::VectorXd v_prev_, v_base_, u0_, v0_, f0_, u1_, v1_, f1_, g_, rhs_, dv_free_, y_, impulse_, prescribed_v_;
  std::vector<double> residuals_;
  std::string failure_;
  double scale_ = 0.0;  // largest momentum scale of the residual so far
  double force_roundoff_ = 0.0;  // round-off floor of the internal forces [N] (implicit.cpp)
  long newton_total_ = 0, linear_total_ = 0;
  long exact_contact_solves_ = 0;
  long shifted_iterations_ = 0;
  bool step_unconverged_ = false;  // a contact solve of this step reached contact.max_sweeps
};

using ImplicitIntegrator = ImplicitIntegratorT<Model>;

// Instantiated for Model and Model3 (implicit.cpp).
template <class M>
RunResult run_implicit(const M& model, const RunSettings& settings, const ImplicitSettings& implicit,
                       const ProgressFn& progress = {});

}  // namespace ricochet
