// Deformation gradients at which the 2D material and tangent checks are made.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <random>
#include <vector>

#include "solver/core/types.hpp"

namespace ricochet::test_support {

// The counterclockwise rotation by `angle` [rad].
inline Mat2 rotation(double angle) {
  Mat2 r;
  r << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
  return r;
}

// Random well-conditioned deformation gradients: F = R(theta) Q diag(l1, l2) Q^T with
// stretches in [0.75, 1.35] (so det F lies in 0.56..1.82, inside 0.5..2) and |theta| <= 0.6 rad.
inline std::vector<Mat2> random_deformations(int count, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> stretch(0.75, 1.35);
  std::uniform_real_distribution<double> angle(-0.6, 0.6);
  std::uniform_real_distribution<double> axis(0.0, 3.14159);
  std::vector<Mat2> out;
  while (static_cast<int>(out.size()) < count) {
    const Mat2 q = rotation(axis(gen));
    const Mat2 u = q * Eigen::Vector2d(stretch(gen), stretch(gen)).asDiagonal() * q.transpose();
    const Mat2 f = rotation(angle(gen)) * u;
    const double j = f.determinant();
    if (j >= 0.5 && j <= 2.0) out.push_back(f);
  }
  return out;
}

}  // namespace ricochet::test_support
