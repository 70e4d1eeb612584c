#include "solver/mesh.hpp"

#include <algorithm>

namespace ricochet {

double signed_area(const Mesh& mesh, const int* corners, int count) {
  double twice = 0.0;
  for (int k = 0; k < count; ++k) {
    const auto a = mesh.nodes.col(corners[k]);
    const auto b = mesh.nodes.col(corners[(k + 1) % count]);
    twice += a.x() * b.y() - b.x() * a.y();
  }
  return 0.5 * twice;
}

double q4_corner_quality(const Mesh& mesh, const std::array<int, 4>& q) {
  // Corner Jacobian of the bilinear map = cross product of the two edges leaving the corner.
  double min_j = 1e300;
  double sum_j = 0.0;
  for (int k = 0; k < 4; ++k) {
    const Vec2 p = mesh.nodes.col(q[k]);
    const Vec2 e1 = mesh.nodes.col(q[(k + 1) % 4]) - p;
    const Vec2 e2 = mesh.nodes.col(q[(k + 3) % 4]) - p;
    const double j = e1.x() * e2.y() - e1.y() * e2.x();
    min_j = std::min(min_j, j);
    sum_j += j;
  }
  const double mean = sum_j / 4.0;
  return mean > 0.0 ? min_j / mean : -1.0;
}

}  // namespace ricochet
