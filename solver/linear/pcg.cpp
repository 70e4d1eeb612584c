#include "solver/linear/pcg.hpp"

#include <cmath>

namespace ricochet {

void Pcg::resize(int n) {
  r_.resize(n);
  z_.resize(n);
  p_.resize(n);
  q_.resize(n);
}

PcgResult Pcg::solve(const SparseMatrixR& A, const Eigen::VectorXd& inv_diag, const Eigen::VectorXd& b,
                     Eigen::VectorXd& x, double tol, int max_iterations) {
  PcgResult res;
  const double b_norm = b.norm();
  if (b_norm == 0.0) {
    x.setZero();
    res.converged = true;
    return res;
  }
  r_.noalias() = A * x;
  r_ = b - r_;
  double r_norm = r_.norm();
  z_ = inv_diag.cwiseProduct(r_);
  p_ = z_;
  double rz = r_.dot(z_);
  while (r_norm > tol * b_norm && res.iterations < max_iterations) {
    q_.noalias() = A * p_;
    const double pq = p_.dot(q_);
    if (!(pq > 0.0)) break;  // not positive definite along p: report not converged
    const double alpha = rz / pq;
    x += alpha * p_;
    r_ -= alpha * q_;
    r_norm = r_.norm();
    z_ = inv_diag.cwiseProduct(r_);
    const double rz_next = r_.dot(z_);
    p_ = z_ + (rz_next / rz) * p_;
    rz = rz_next;
    ++res.iterations;
  }
  res.relative_residual = r_norm / b_norm;
  res.converged = r_norm <= tol * b_norm;
  return res;
}

}  // namespace ricochet
