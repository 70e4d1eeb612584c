// Jacobi-preconditioned conjugate gradients on a sparse symmetric positive definite matrix,
// with preallocated work vectors (no allocation per solve). Chosen for the implicit scheme's
// velocity system A = M + theta xi dt^2 K_T (+ xi dt C): at the small steps of the paper's
// Table 1 it is mass-dominated, so a few matrix-vector products solve it (docs/implicit.md).
#pragma once

#include <Eigen/Sparse>

namespace ricochet {

using SparseMatrixR = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

struct PcgResult {
  int iterations = 0;
  double relative_residual = 0.0;  // |b - A x| / |b|
  bool converged = false;
};

class Pcg {
 public:
  void resize(int n);
  // Solves A x = b from the initial guess in x, preconditioned by 1/diag(A) (inv_diag given).
  // Stops when |b - A x| <= tol |b| or after max_iterations.
  PcgResult solve(const SparseMatrixR& A, const Eigen::VectorXd& inv_diag, const Eigen::VectorXd& b,
                  Eigen::VectorXd& x, double tol, int max_iterations);

 private:
  Eigen::VectorXd r_, z_, p_, q_;
};

}  // namespace ricochet
