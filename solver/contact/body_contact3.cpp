#include "solver/contact/body_contact3.hpp"

#include <map>
#include <stdexcept>
#include <utility>

namespace ricochet {

Surface3 make_surface3(const Model<3>& model, int body) {
  Surface3 s;
  s.body = body;
  // Boundary faces run counter-clockwise seen from outside (mesh.hpp; build_model checks
  // positive volumes), so x_xi x x_eta is outward.
  for (const BoundaryFace& bf : model.bodies[body].boundary_faces) {
    SurfaceFace f;
    f.count = bf.corners;
    for (int k = 0; k < f.count; ++k) f.node[k] = bf.nodes[k];
    s.faces.push_back(f);
  }
  if (s.faces.empty()) throw std::logic_error("body " + model.bodies[body].name + " has no boundary face");
  // Each edge by its sorted node pair: the faces that have it, and whether they run it forwards.
  struct Use {
    int face, edge;
    bool forwards;  // node[edge] is the pair's smaller node
  };
  std::map<std::pair<int, int>, std::vector<Use>> edges;
  for (int fi = 0; fi < static_cast<int>(s.faces.size()); ++fi) {
    const SurfaceFace& f = s.faces[fi];
    for (int k = 0; k < f.count; ++k) {
      const int a = f.node[k], b = f.node[(k + 1) % f.count];
      edges[{std::min(a, b), std::max(a, b)}].push_back({fi, k, a < b});
      s.max_length = std::max(s.max_length, (model.ref.col(b) - model.ref.col(a)).norm());
    }
  }
  // Neighbours: an edge of exactly two faces that run it in opposite directions (a consistently
  // oriented surface). An edge of one face (an open surface) or of more than two (bodies meeting
  // along an edge) links nothing: the walk stops there and the search of find_face takes over.
  for (const auto& [key, uses] : edges) {
    if (uses.size() != 2 || uses[0].forwards == uses[1].forwards) continue;
    s.faces[uses[0].face].neighbour[uses[0].edge] = uses[1].face;
    s.faces[uses[0].face].neighbour_edge[uses[0].edge] = uses[1].edge;
    s.faces[uses[1].face].neighbour[uses[1].edge] = uses[0].face;
    s.faces[uses[1].face].neighbour_edge[uses[1].edge] = uses[0].edge;
  }
  // The nodes, sorted, and the faces at each.
  for (const SurfaceFace& f : s.faces)
    for (int k = 0; k < f.count; ++k) s.nodes.push_back(f.node[k]);
  std::sort(s.nodes.begin(), s.nodes.end());
  s.nodes.erase(std::unique(s.nodes.begin(), s.nodes.end()), s.nodes.end());
  s.vertex_faces_begin.assign(s.nodes.size() + 1, 0);
  for (SurfaceFace& f : s.faces)
    for (int k = 0; k < f.count; ++k) {
      f.vertex[k] = static_cast<int>(std::lower_bound(s.nodes.begin(), s.nodes.end(), f.node[k]) - s.nodes.begin());
      ++s.vertex_faces_begin[f.vertex[k] + 1];
    }
  for (std::size_t i = 0; i < s.nodes.size(); ++i) s.vertex_faces_begin[i + 1] += s.vertex_faces_begin[i];
  s.vertex_faces.resize(s.vertex_faces_begin.back());
  std::vector<int> next(s.vertex_faces_begin.begin(), s.vertex_faces_begin.end() - 1);
  for (int fi = 0; fi < static_cast<int>(s.faces.size()); ++fi)
    for (int k = 0; k < s.faces[fi].count; ++k) s.vertex_faces[next[s.faces[fi].vertex[k]]++] = fi;
  return s;
}

double signed_distance(const Model<3>& model, const Surface3& surf, const Eigen::VectorXd& u, const Vec3& x) {
  auto pos = [&](int j) -> Vec3 { return model.ref.col(j) + u.segment<3>(3 * j); };
  return surface_signed_distance(surf, pos, x);
}

double depth_inside(const Model<3>& model, const Surface3& surf, const Eigen::VectorXd& u, const Vec3& x) {
  const double d = signed_distance(model, surf, u, x);
  return d < 0.0 ? -d : 0.0;
}

}  // namespace ricochet
