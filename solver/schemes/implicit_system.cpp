#include "solver/schemes/implicit_system.hpp"

#include <algorithm>
#include <cmath>

namespace ricochet {

ImplicitSystem::ImplicitSystem(SystemMatrix matrix, const Eigen::VectorXd& mass,
                               const std::vector<PrescribedDof>& prescribed, const ImplicitSettings& settings,
                               double contraction)
    : mass_(mass), set_(settings), system_(std::move(matrix)) {
  const int n = static_cast<int>(mass.size());
  pcg_.resize(n);
  inv_diag_.setZero(n);
  column_b_.setZero(n);
  column_x_.setZero(n);
  fixed_.assign(n, 0);
  for (const auto& p : prescribed) fixed_[p.dof] = 1;
  inv_mass_ = mass.cwiseInverse();
  for (const auto& p : prescribed) inv_mass_[p.dof] = 1.0;
  const SparseMatrixR& A = system_.matrix;
  for (int i = 0; i < n; ++i)
    for (int k = A.outerIndexPtr()[i]; k < A.outerIndexPtr()[i + 1]; ++k) {
      const int j = A.innerIndexPtr()[k];
      if (!fixed_[i] && !fixed_[j]) continue;
      (i == j ? constrained_diagonal_ : constrained_entries_).push_back(k);
    }
  // "auto" is the mass iteration where it contracts fast (docs/implicit.md, "The mass
  // iteration"), with the direct solver, analysed now so that no step allocates, for the steps
  // it leaves unconverged; elsewhere the direct solver: on the oblique plate it was faster than
  // PCG at every step measured, 0.05 to 15 x the critical step (docs/implicit.md, The linear
  // solver: measured).
  const LinearSolverKind kind = set_.linear_solver;
  mass_run_ = kind == LinearSolverKind::mass ||
          (kind == LinearSolverKind::automatic && contraction <= set_.mass_contraction);
  mass_fallback_ = mass_run_ && kind == LinearSolverKind::automatic;
  mass_now_ = mass_run_;
  if (kind == LinearSolverKind::direct || kind == LinearSolverKind::automatic) use_direct();
}

double mass_contraction_estimate(double theta, double xi, double dt, double dt_crit) {
  if (!(dt_crit > 0.0)) return 1e300;
  const double omega_dt = 2.0 * dt / dt_crit;
  return theta * xi * omega_dt * omega_dt;
}

void ImplicitSystem::use_direct() {
  direct_ = true;
  factor_.analyze(system_.matrix, CholmodFactor::Method::automatic);
  // Single-precision solves when the case asks for them (docs/implicit.md, "Single-precision
  // solves"): half the double solves' time on the oblique plate's M2x2, none on M2x4 or the 3D
  // M2x2 in whole runs, slower on M2; not the default, and momentum is kept only to the Newton
  // tolerance with them.
  factor_.use_single(set_.factor_precision == FactorPrecision::single);
  // Automatic: no cap of its own (the step's max_newton_iterations); the contraction, line-search
  // and run-out rules of end_iteration() decide.
  refactor_iterations_ = set_.refactor_iterations > 0 ? set_.refactor_iterations : set_.max_newton_iterations;
  a_values_.assign(system_.matrix.valuePtr(), system_.matrix.valuePtr() + system_.matrix.nonZeros());
  refactor_next_ = true;
}

bool ImplicitSystem::prepare() {
  double* values = system_.matrix.valuePtr();
  for (int k : constrained_entries_) values[k] = 0.0;
  for (int k : constrained_diagonal_) values[k] = 1.0;
  for (int i = 0; i < static_cast<int>(inv_diag_.size()); ++i) inv_diag_[i] = 1.0 / values[system_.diagonal_slots[i]];
  if (!direct_) return true;
  if (!factorize()) return false;
  refactor_next_ = false;
  return true;
}

// Factorizes A. If A is indefinite (the tangent of a far-off iterate under strong compression,
// e.g. St Venant-Kirchhoff's negative geometric stiffness), shifts it by lambda M with lambda =
// 1, 4, 16, ... until it is positive definite: the iteration matrix changes, the converged
// solution G = 0 does not (a damped Newton iteration). The contact problem needs W positive
// definite.
bool ImplicitSystem::factorize() {
  const int n = static_cast<int>(inv_diag_.size());
  double* a = a_values_.data();
  std::copy(system_.matrix.valuePtr(), system_.matrix.valuePtr() + system_.matrix.nonZeros(), a);
  ++factor_id_;
  ++factorizations_;
  iterations_on_factor_ = 0;
  for (int attempt = 0; attempt < 12; ++attempt) {
    if (factor_.factorize(a)) {
      if (attempt > 0) {
        ++shifted_;
        for (int i = 0; i < n; ++i) inv_diag_[i] = 1.0 / a[system_.diagonal_slots[i]];
      }
      return true;
    }
    const double add = attempt == 0 ? 1.0 : 3.0 * std::pow(4.0, attempt - 1);  // lambda 1, 4, 16, ...
    for (int i = 0; i < n; ++i)
      if (!fixed_[i]) a[system_.diagonal_slots[i]] += add * mass_[i];
  }
  failure_ = "Cholesky factorization: matrix not positive definite even when shifted by 4^11 M";
  return false;
}

bool ImplicitSystem::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  if (mass_now_) {
    x = b.cwiseProduct(inv_mass_);
    return true;
  }
  if (direct_) {
    factor_.solve(b, x);
    return true;
  }
  const PcgResult r = pcg_.solve(system_.matrix, inv_diag_, b, x, set_.linear_tolerance, set_.max_linear_iterations);
  cg_iterations_ += r.iterations;
  if (r.converged) return true;
  // CG met an indefinite matrix (a far-off iterate) or stalled: continue the run with the
  // shifted Cholesky factorization, which handles both.
  if (set_.linear_solver == LinearSolverKind::pcg) {
    failure_ = "linear solve did not converge (relative residual " + std::to_string(r.relative_residual) + ")";
    return false;
  }
  use_direct();
  if (!factorize()) return false;
  refactor_next_ = false;
  factor_.solve(b, x);
  return true;
}

bool ImplicitSystem::solve_block(const double* b, double* x, int ncol) {
  const Eigen::Index n = inv_diag_.size();
  if (mass_now_) {
    for (int k = 0; k < ncol; ++k)
      Eigen::Map<Eigen::VectorXd>(x + k * n, n) = Eigen::Map<const Eigen::VectorXd>(b + k * n, n).cwiseProduct(inv_mass_);
    return true;
  }
  if (direct_) {
    factor_.solve_block(b, x, ncol);
    return true;
  }
  for (int k = 0; k < ncol; ++k) {
    column_b_ = Eigen::Map<const Eigen::VectorXd>(b + k * n, n);
    column_x_.setZero();
    if (!solve(column_b_, column_x_)) return false;
    Eigen::Map<Eigen::VectorXd>(x + k * n, n) = column_x_;
  }
  return true;
}

void ImplicitSystem::end_iteration(double r, double r_before, double alpha, int iteration) {
  if (mass_now_) {
    // The factor takes over a step the mass iteration has not finished (automatic only): after
    // mass_iterations, or at once when an iteration after the first did not contract or needed a
    // line search (the first may engage new contacts and grow the residual).
    if (mass_fallback_ && r > set_.newton_tolerance &&
        (step_mass_iterations_ >= set_.mass_iterations || alpha < 1.0 || (iteration > 1 && !(r < r_before))))
      mass_now_ = false;
    return;
  }
  // Counting converged steps too refactorized M2 at 1e-5 100 times instead of 35 (docs/implicit.md).
  if (!direct_ || r <= set_.newton_tolerance) return;
  if (!(r <= set_.refactor_contraction * r_before) || alpha < 1.0 || iterations_on_factor_ >= refactor_iterations_) {
    refactor_next_ = true;
    return;
  }
  if (set_.refactor_iterations > 0) return;  // a cap the case set: the rule above alone
  const double rate = r / r_before;
  if (!(rate > 0.0 && rate < 1.0)) return;
  const double remaining = std::log(set_.newton_tolerance / r) / std::log(rate);
  if (iteration + remaining > set_.max_newton_iterations - 2) refactor_next_ = true;
}

}  // namespace ricochet
