// Small measures of Eigen matrices that several tests use.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace ricochet::test_support {

// The largest |entry| of any matrix or vector expression (0 for an empty one). A plain loop:
// Eigen's cwiseAbs().maxCoeff() on fixed sizes makes GCC 12 report a false -Wuninitialized inside
// its AVX-512 headers.
template <class Derived>
double max_abs(const Eigen::MatrixBase<Derived>& expr) {
  const typename Derived::PlainObject m = expr;
  double r = 0.0;
  for (Eigen::Index i = 0; i < m.size(); ++i) r = std::max(r, std::abs(m.data()[i]));
  return r;
}

}  // namespace ricochet::test_support
