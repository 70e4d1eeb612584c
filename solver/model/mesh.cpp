#include "solver/model/mesh.hpp"

#include <algorithm>
#include <cmath>
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

// ------------------------------------------------------------------------------------------ 3D
namespace {

// The three corners joined to hexahedron corner k by an edge, in the order whose edge vectors
// form a right-handed triple at every corner of the unit cube (determinant +1).
constexpr std::array<std::array<int, 3>, 8> kHexCornerEdges = {
    {{1, 3, 4}, {2, 0, 5}, {3, 1, 6}, {0, 2, 7}, {7, 5, 0}, {4, 6, 1}, {5, 7, 2}, {6, 4, 3}}};

double triple(const Vec3& a, const Vec3& b, const Vec3& c) { return a.dot(b.cross(c)); }

}  // namespace

double signed_volume(const Mesh3& mesh, const std::array<int, 4>& tet) {
  const Vec3 x0 = mesh.nodes.col(tet[0]);
  return triple(mesh.nodes.col(tet[1]) - x0, mesh.nodes.col(tet[2]) - x0, mesh.nodes.col(tet[3]) - x0) / 6.0;
}

double signed_volume(const Mesh3& mesh, const std::array<int, 8>& hex) {
  std::array<Vec3, 8> x;
  for (int k = 0; k < 8; ++k) x[k] = mesh.nodes.col(hex[k]);
  // The trilinear map on [0, 1]^3 (corner k at the unit cube's corner k) in monomials,
  // X = x0 + b xi + c eta + d zeta + e xi eta + f eta zeta + g xi zeta + h xi eta zeta. The
  // mixed coefficients are differences of edge vectors, exactly 0 for a box, whose volume is then
  // b . (c x d) at every Gauss point, so exactly the product of its sides as computed there.
  const Vec3 b = x[1] - x[0], c = x[3] - x[0], d = x[4] - x[0];
  const Vec3 e = (x[2] - x[3]) - b, f = (x[7] - x[4]) - c, g = (x[5] - x[4]) - b;
  const Vec3 h = ((x[6] - x[7]) - (x[5] - x[4])) - e;
  const double gauss[2] = {0.5 - 0.5 / std::sqrt(3.0), 0.5 + 0.5 / std::sqrt(3.0)};
  double sum = 0.0;
  for (const double xi : gauss)
    for (const double eta : gauss)
      for (const double zeta : gauss) {
        const Vec3 d_xi = b + eta * e + zeta * g + (eta * zeta) * h;
        const Vec3 d_eta = c + xi * e + zeta * f + (xi * zeta) * h;
        const Vec3 d_zeta = d + eta * f + xi * g + (xi * eta) * h;
        sum += triple(d_xi, d_eta, d_zeta);
      }
  return sum / 8.0;
}

double hex_corner_quality(const Mesh3& mesh, const std::array<int, 8>& hex) {
  double min_j = 1e300;
  double sum_j = 0.0;
  for (int k = 0; k < 8; ++k) {
    const Vec3 p = mesh.nodes.col(hex[k]);
    const auto& e = kHexCornerEdges[k];
    const double j = triple(mesh.nodes.col(hex[e[0]]) - p, mesh.nodes.col(hex[e[1]]) - p,
                            mesh.nodes.col(hex[e[2]]) - p);
    min_j = std::min(min_j, j);
    sum_j += j;
  }
  const double mean = sum_j / 8.0;
  return mean > 0.0 ? min_j / mean : -1.0;
}

std::vector<BoundaryFace> boundary_faces(const Mesh3& mesh) {
  struct Key {
    std::array<int, 4> sorted;  // a triangle's three nodes after a -1, so never a quadrilateral's
    int index;                  // the face's place in cell order
  };
  std::vector<BoundaryFace> all;
  std::vector<Key> keys;
  all.reserve(6 * mesh.hexes.size() + 4 * mesh.tets.size());
  keys.reserve(all.capacity());
  int cell = 0;
  for (const auto& h : mesh.hexes) {
    const double volume = signed_volume(mesh, h);
    for (int f = 0; f < 6; ++f) {
      BoundaryFace face{{}, 4, cell, f, volume};
      for (int k = 0; k < 4; ++k) face.nodes[k] = h[kHexFaces[f][k]];
      Key key{face.nodes, static_cast<int>(all.size())};
      std::sort(key.sorted.begin(), key.sorted.end());
      keys.push_back(key);
      all.push_back(face);
    }
    ++cell;
  }
  for (const auto& t : mesh.tets) {
    const double volume = signed_volume(mesh, t);
    for (int f = 0; f < 4; ++f) {
      BoundaryFace face{{t[kTetFaces[f][0]], t[kTetFaces[f][1]], t[kTetFaces[f][2]], -1}, 3, cell, f, volume};
      Key key{face.nodes, static_cast<int>(all.size())};
      std::sort(key.sorted.begin(), key.sorted.end());  // the -1 goes first
      keys.push_back(key);
      all.push_back(face);
    }
    ++cell;
  }
  std::sort(keys.begin(), keys.end(),
            [](const Key& x, const Key& y) { return std::tie(x.sorted, x.index) < std::tie(y.sorted, y.index); });
  std::vector<char> once(all.size(), 0);
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i;
    while (j < keys.size() && keys[j].sorted == keys[i].sorted) ++j;
    if (j - i == 1) once[static_cast<std::size_t>(keys[i].index)] = 1;
    i = j;
  }
  std::vector<BoundaryFace> faces;
  for (std::size_t f = 0; f < all.size(); ++f)
    if (once[f]) faces.push_back(all[f]);
  return faces;
}

Vec3 face_area_vector(const Mesh3& mesh, const BoundaryFace& face) {
  const auto x = [&](int k) -> Vec3 { return mesh.nodes.col(face.nodes[k]); };
  if (face.corners == 3) return 0.5 * (x(1) - x(0)).cross(x(2) - x(0));
  return 0.5 * (x(2) - x(0)).cross(x(3) - x(1));
}

std::vector<int> face_nodes(const std::vector<BoundaryFace>& faces) {
  std::vector<int> nodes;
  for (const BoundaryFace& f : faces)
    for (int k = 0; k < f.corners; ++k) nodes.push_back(f.nodes[k]);
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  return nodes;
}

}  // namespace ricochet
