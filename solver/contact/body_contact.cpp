#include "solver/contact/body_contact.hpp"

#include <algorithm>
#include <map>
#include <stdexcept>

namespace ricochet {

Surface make_surface(const Model<2>& model, int body) {
  Surface s;
  s.body = body;
  // Boundary edges run as their cell does (counter-clockwise, build_model checks positive
  // areas), so each has the body on its left.
  for (const BoundaryEdge& e : model.bodies[body].boundary_edges) s.segments.push_back({e.a, e.b, -1, -1});
  if (s.segments.empty()) throw std::logic_error("body " + model.bodies[body].name + " has no boundary segment");
  std::map<int, int> starting, ending;  // node -> segment starting / ending there
  for (int k = 0; k < static_cast<int>(s.segments.size()); ++k) {
    starting[s.segments[k].a] = k;
    ending[s.segments[k].b] = k;
    s.max_length = std::max(s.max_length, (model.ref.col(s.segments[k].b) - model.ref.col(s.segments[k].a)).norm());
  }
  for (SurfaceSegment& sg : s.segments) {
    if (const auto it = ending.find(sg.a); it != ending.end()) sg.prev = it->second;
    if (const auto it = starting.find(sg.b); it != starting.end()) sg.next = it->second;
  }
  for (const auto& [node, seg] : starting) s.nodes.push_back(node);
  return s;
}

double depth_inside(const Model<2>& model, const Surface& surf, const Eigen::VectorXd& u, const Vec2& x) {
  const double d = signed_distance(model, surf, u, x);
  return d < 0.0 ? -d : 0.0;
}

double signed_distance(const Model<2>& model, const Surface& surf, const Eigen::VectorXd& u, const Vec2& x) {
  bool in = false;
  double dist = std::numeric_limits<double>::infinity();
  for (const SurfaceSegment& sg : surf.segments) {
    const Vec2 a = model.ref.col(sg.a) + u.segment<2>(2 * sg.a);
    const Vec2 b = model.ref.col(sg.b) + u.segment<2>(2 * sg.b);
    if ((a.y() > x.y()) != (b.y() > x.y()) && x.x() < a.x() + (x.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y()))
      in = !in;
    const Vec2 e = b - a;
    const double l2 = e.squaredNorm();
    const double xi = l2 > 0.0 ? std::clamp((x - a).dot(e) / l2, 0.0, 1.0) : 0.0;
    dist = std::min(dist, (x - a - xi * e).norm());
  }
  return in ? -dist : dist;
}

}  // namespace ricochet
