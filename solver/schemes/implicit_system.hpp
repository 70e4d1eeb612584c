// The implicit scheme's linear system (docs/implicit.md, The linear solver): the iteration matrix
// A = M + theta xi dt^2 K_T + xi dt C in its preallocated pattern (forces/tangent.hpp), its
// prescribed rows and columns, and how A x = b is solved:
//   - direct: CHOLMOD's Cholesky factor (solver/linear/cholmod_factor.hpp), shifted by lambda M
//     when A is indefinite, and kept over Newton iterations and steps (modified Newton) until the
//     refactorization rule asks for a new one (ImplicitSettings::refactor_contraction);
//   - pcg: Jacobi-preconditioned CG with A assembled every iteration (full Newton), and the
//     direct path as the fallback of a solve that fails (unless pcg was asked for by name);
//   - mass: the lumped mass M stands for A (no assembly, no factor: x = M^-1 b), a fixed-point
//     iteration that contracts by about theta xi (dt omega_max)^2 per iteration, cheap where the
//     step is far below the explicit limit and A is nearly M. Chosen by `auto` from the step's
//     conditioning, with the factor as the fallback of a step it does not finish.
// A Newton iteration calls needs_matrix(); if true, it assembles into matrix() and calls
// prepare(); then count_iteration(), solves, and after its update end_iteration().
#pragma once

#include <string>
#include <vector>

#include "solver/core/loads.hpp"
#include "solver/forces/tangent.hpp"
#include "solver/linear/cholmod_factor.hpp"
#include "solver/linear/pcg.hpp"

namespace ricochet {

enum class LinearSolverKind {
  automatic,  // see below
  pcg,        // Jacobi-preconditioned CG, full Newton (A assembled every iteration)
  direct,     // CHOLMOD supernodal Cholesky (solver/linear/cholmod_factor.hpp; symbolic analysis
              // once per run), modified Newton: the factor is reused while Newton contracts fast
  mass,       // the lumped mass matrix as the iteration matrix: v1 <- v1 - M^-1 G (no assembly,
              // no solve), up to max_newton_iterations
};
// automatic: mass where the estimated contraction per iteration, mass_contraction_estimate(),
// is at most ImplicitSettings::mass_contraction, with the factor taking over a step that
// mass_iterations leave unconverged; direct otherwise (faster than pcg at every step measured,
// docs/implicit.md). With pcg, a solve that fails (indefinite matrix of a far-off iterate)
// switches the run to direct.

// The precision of the direct solver's solves (docs/implicit.md, "Single-precision solves"); the
// factorization is always double.
enum class FactorPrecision {
  double_,  // CHOLMOD's solves with its double factor
  single,   // solves with a single-precision copy of L (solver/linear/single_factor.hpp): half
            // the solve time where the float copy fits the cache and the double factor does not
            // (M2x2); momentum kept to the Newton tolerance rather than to round-off
};

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
  // first of each step; refactor_iterations = 0 (automatic) sets no cap of its own and adds the
  // run-out rule of end_iteration() (docs/implicit.md, "Modified Newton").
  double refactor_contraction = 0.5;  // [0, 1)
  int refactor_iterations = 0;        // >= 0; 0: automatic
  // The mass iteration of `automatic` (docs/implicit.md, "The mass iteration"): used when the
  // estimated contraction per iteration is at most mass_contraction; a step still unconverged
  // after mass_iterations of them goes on with the factor.
  double mass_contraction = 0.6;  // [0, 1)
  int mass_iterations = 15;       // >= 1
  int mass_anderson_depth = 2;     // 0 .. AndersonMixer::kMaxDepth; 0: the plain iteration
  FactorPrecision factor_precision = FactorPrecision::double_;
};

// The mass iteration's estimated contraction per Newton iteration at step dt on a model whose
// critical step is dt_crit (the cells' L_e / c_p): the spectral radius of theta xi dt^2 M^-1 K,
// theta xi (dt omega_max)^2 with omega_max = 2 / dt_crit.
double mass_contraction_estimate(double theta, double xi, double dt, double dt_crit);

class ImplicitSystem {
 public:
  // `mass`: the lumped masses per DOF (the shift's lambda M, the mass iteration's matrix), kept
  // by reference. `contraction`: mass_contraction_estimate() of the run, for `automatic`.
  ImplicitSystem(SystemMatrix matrix, const Eigen::VectorXd& mass, const std::vector<PrescribedDof>& prescribed,
                 const ImplicitSettings& settings, double contraction);

  // The matrix to assemble A into (values only: the pattern is fixed).
  SystemMatrix& matrix() { return system_; }
  // True when this Newton iteration must assemble A: always with CG, with the factor when the
  // rule asked for a new one (or refactor_contraction = 0: full Newton).
  // The mass iteration needs none.
  bool needs_matrix() const {
    return !mass_now_ && (!direct_ || refactor_next_ || set_.refactor_contraction <= 0.0);
  }
  // After an assembly: prescribed rows and columns become the identity's (their increment is
  // zero), the Jacobi diagonal is taken, and on the direct path A is factorized. False (failure()
  // says why) when A is not positive definite even shifted.
  bool prepare();
  // x = A^-1 b, by the factor or by CG from x. False (failure()) when CG fails and pcg was asked
  // for by name, or the fallback's factorization fails.
  bool solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);
  // X = A^-1 B for the ncol (1 to CholmodFactor::kMaxBlock) columns of B (n x ncol,
  // column-major): one sweep over the factor for all of them, or one CG solve each (from zero).
  // False as solve().
  bool solve_block(const double* b, double* x, int ncol);
  // The bookkeeping of the refactorization rule: a step starts with no iteration on the factor
  // (and with the mass iteration, where the run uses it),
  void begin_step() {
    iterations_on_factor_ = 0;
    mass_now_ = mass_run_;
    step_mass_iterations_ = 0;
  }
  // each Newton iteration counts one,
  void count_iteration() {
    if (mass_now_) {
      ++step_mass_iterations_;
      ++mass_iterations_;
    } else {
      ++iterations_on_factor_;
    }
  }
  // and an iteration that left the residual r (from r_before; line-search factor alpha) above the
  // tolerance asks for a new factor when it contracted too little, needed a line search, or was
  // the refactor_iterations-th on this factor. Automatic (refactor_iterations = 0: no cap but
  // max_newton_iterations) it also asks for one when the iterations still needed at the rate just seen, log(tol / r) /
  // log(r / r_before), would take the step (`iteration` Newton iterations so far) to within two
  // of max_newton_iterations. A step that converges keeps the factor. On the mass iteration of
  // `automatic`, the step goes on with the factor once mass_iterations have not converged it.
  void end_iteration(double r, double r_before, double alpha, int iteration);

  bool direct() const { return direct_ && !mass_now_; }  // this iteration solves with the factor
  bool has_factor() const { return direct_; }             // the direct solver is set up (analysed)
  bool supernodal() const { return direct_ && factor_.supernodal(); }  // its factor's method
  bool single_solves() const { return direct_ && factor_.single(); }   // ... and its solves' precision
  bool mass_iteration() const { return mass_now_; }      // this iteration solves with M
  bool mass_run() const { return mass_run_; }                // the run starts its steps with M
  // The identity of the matrix the solves use, for the contact problem's kept columns: 0 for
  // M, the factor's (1, 2, ..., one per factorization), -1 for CG (no fixed matrix).
  long matrix_id() const { return mass_now_ ? 0 : direct_ ? factor_id_ : -1; }
  long factor_id() const { return factor_id_; }  // increases with every factorization
  int refactor_iterations() const { return refactor_iterations_; }  // in effect (0 resolved)
  double factor_nonzeros() const { return direct_ ? factor_.factor_nonzeros() : 0.0; }  // entries of L
  // 1 / diag(A) as solved (1 / M on the mass iteration)
  const Eigen::VectorXd& inverse_diagonal() const { return mass_now_ ? inv_mass_ : inv_diag_; }
  long factorizations() const { return factorizations_; }
  long mass_iterations() const { return mass_iterations_; }  // Newton iterations solved with M
  long shifted_factorizations() const { return shifted_; }  // factorizations that needed a shift
  long cg_iterations() const { return cg_iterations_; }
  const std::string& failure() const { return failure_; }

 private:
  void use_direct();
  bool factorize();

  const Eigen::VectorXd& mass_;
  ImplicitSettings set_;
  SystemMatrix system_;
  Pcg pcg_;
  bool direct_ = false;
  CholmodFactor factor_;
  long factor_id_ = 0;
  bool refactor_next_ = true;     // the next Newton iteration assembles and factorizes A
  int iterations_on_factor_ = 0;  // Newton iterations of this step on the current factor
  int refactor_iterations_ = 0;   // set_.refactor_iterations, or max_newton_iterations (automatic)
  bool mass_run_ = false;         // the run's steps start with the mass iteration
  bool mass_fallback_ = false;    // ... and go on with the factor after mass_iterations (auto)
  bool mass_now_ = false;         // this step is on the mass iteration
  int step_mass_iterations_ = 0;
  long mass_iterations_ = 0;
  Eigen::VectorXd inv_mass_;      // 1 / M per DOF (1 at prescribed DOFs: their rows are I's)
  long factorizations_ = 0;
  long shifted_ = 0;
  long cg_iterations_ = 0;
  std::vector<double> a_values_;  // the values of A as factorized (with the shift, if any)
  Eigen::VectorXd inv_diag_;
  Eigen::VectorXd column_b_, column_x_;  // one column of solve_block on the CG path
  std::vector<unsigned char> fixed_;       // per DOF: prescribed
  std::vector<int> constrained_entries_;   // value positions of prescribed rows and columns
  std::vector<int> constrained_diagonal_;
  std::string failure_;
};

}  // namespace ricochet
