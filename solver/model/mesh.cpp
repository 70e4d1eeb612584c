#include "solver/model/mesh.hpp"

#include <algorithm>
#include <tuple>

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

std::vector<BoundaryEdge> boundary_edges(const Mesh& mesh) {
  struct Directed {
    int lo, hi, index;  // the undirected key, and the edge's place in cell order
  };
  std::vector<BoundaryEdge> all;
  std::vector<Directed> keys;
  auto add_cell = [&](const int* c, int count) {
    const double area = signed_area(mesh, c, count);
    for (int k = 0; k < count; ++k) {
      const int a = c[k], b = c[(k + 1) % count];
      keys.push_back({std::min(a, b), std::max(a, b), static_cast<int>(all.size())});
      all.push_back({a, b, area});
    }
  };
  for (const auto& q : mesh.quads) add_cell(q.data(), 4);
  for (const auto& t : mesh.tris) add_cell(t.data(), 3);
  std::sort(keys.begin(), keys.end(),
            [](const Directed& x, const Directed& y) { return std::tie(x.lo, x.hi, x.index) < std::tie(y.lo, y.hi, y.index); });
  std::vector<char> once(all.size(), 0);
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i;
    while (j < keys.size() && keys[j].lo == keys[i].lo && keys[j].hi == keys[i].hi) ++j;
    if (j - i == 1) once[keys[i].index] = 1;
    i = j;
  }
  std::vector<BoundaryEdge> edges;
  for (std::size_t e = 0; e < all.size(); ++e)
    if (once[e]) edges.push_back(all[e]);
  return edges;
}

std::vector<int> edge_nodes(const std::vector<BoundaryEdge>& edges) {
  std::vector<int> nodes;
  for (const BoundaryEdge& e : edges) {
    nodes.push_back(e.a);
    nodes.push_back(e.b);
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  return nodes;
}

}  // namespace ricochet
