// Anderson acceleration of a fixed-point iteration x <- x + f(x) (Walker & Ni 2011, "Anderson
// acceleration for fixed-point iterations", SIAM J. Numer. Anal. 49(4), the "type II" form with
// depth m): the next iterate is x_k + f_k - (dX + dF) gamma, where dX and dF hold the last m
// differences of the iterates and of their updates and gamma minimizes |f_k - dF gamma|_2. On a
// linear contraction it is a GMRES-like Krylov method; the implicit scheme uses it on the mass
// iteration (docs/implicit.md, "The mass iteration"). Sized once (reserve); nothing allocates
// in mix().
#pragma once

#include <Eigen/Dense>

namespace ricochet {

class AndersonMixer {
 public:
  static constexpr int kMaxDepth = 4;

  // For vectors of size n and a history of `depth` (0 .. kMaxDepth; 0: no acceleration).
  void reserve(int n, int depth) {
    depth_ = depth < 0 ? 0 : depth > kMaxDepth ? kMaxDepth : depth;
    dx_.setZero(n, depth_);
    df_.setZero(n, depth_);
    x_prev_.setZero(n);
    f_prev_.setZero(n);
    reset();
  }
  // Forget the history (a new step, or an iteration the accelerated map does not describe).
  void reset() {
    count_ = 0;
    next_ = 0;
    has_prev_ = false;
  }

  // Iterate x with the plain update f: replaces f by the accelerated update, so that the next
  // iterate is x + f.
  void mix(const Eigen::VectorXd& x, Eigen::VectorXd& f) {
    if (depth_ == 0) return;
    if (has_prev_) {
      // The new differences, and their products with the kept ones (gram_): the older
      // columns' products do not change, so each iteration computes count_ + 1 of them. The
      // differences and the copies of x and f are one pass each.
      const int k = next_;
      difference_and_copy(x, x_prev_, dx_.col(k).data());
      difference_and_copy(f, f_prev_, df_.col(k).data());
      next_ = (next_ + 1) % depth_;
      if (count_ < depth_) ++count_;
      for (int j = 0; j < count_; ++j) gram_(k, j) = gram_(j, k) = df_.col(j).dot(df_.col(k));
      norm2_[k] = df_.col(k).squaredNorm();
    } else {
      x_prev_ = x;
      f_prev_ = f;
    }
    has_prev_ = true;
    if (count_ == 0) return;
    // gamma from the normal equations dF^T dF gamma = dF^T f, scaled to a unit diagonal and
    // slightly regularized: the columns become nearly parallel as the iteration converges.
    Small a(count_, count_);
    SmallVec rhs(count_), scale(count_);
    for (int i = 0; i < count_; ++i) {
      const double d = norm2_[i];
      if (!(d > 0.0)) {  // a repeated update: nothing to extrapolate from
        reset();
        return;
      }
      scale[i] = 1.0 / std::sqrt(d);
    }
    for (int i = 0; i < count_; ++i) {
      for (int j = 0; j <= i; ++j) a(i, j) = a(j, i) = scale[i] * scale[j] * gram_(i, j);
      a(i, i) += 1e-12;
      rhs[i] = scale[i] * df_.col(i).dot(f);
    }
    const SmallVec gamma = a.ldlt().solve(rhs).cwiseProduct(scale);
    if (!gamma.allFinite()) {
      reset();
      return;
    }
    // f - gamma_0 (dx_0 + df_0) - gamma_1 (dx_1 + df_1) - ..., left to right as one term a
    // pass would, two terms a pass.
    int i = 0;
    for (; i + 2 <= count_; i += 2)
      f = (f - gamma[i] * (dx_.col(i) + df_.col(i))) - gamma[i + 1] * (dx_.col(i + 1) + df_.col(i + 1));
    if (i < count_) f -= gamma[i] * (dx_.col(i) + df_.col(i));
  }

 private:
  // out = a - prev, then prev = a, in one pass.
  static void difference_and_copy(const Eigen::VectorXd& a, Eigen::VectorXd& prev, double* out) {
    const long n = a.size();
    const double* pa = a.data();
    double* pp = prev.data();
    for (long i = 0; i < n; ++i) {
      out[i] = pa[i] - pp[i];
      pp[i] = pa[i];
    }
  }

  using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxDepth, kMaxDepth>;
  using SmallVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxDepth, 1>;
  int depth_ = 0;
  int count_ = 0;  // differences kept
  int next_ = 0;   // the column the next difference goes to
  bool has_prev_ = false;
  Eigen::MatrixXd dx_, df_;
  Eigen::Matrix<double, kMaxDepth, kMaxDepth> gram_;  // gram_(i, j) = dF_i . dF_j of the kept columns
  Eigen::Matrix<double, kMaxDepth, 1> norm2_;         // |dF_i|^2
  Eigen::VectorXd x_prev_, f_prev_;
};

}  // namespace ricochet
