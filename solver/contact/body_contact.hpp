// Contact between deformable bodies: node to segment (docs/contact-between-bodies.md).
//
// A pair (slave, master) keeps the boundary nodes of the slave body outside the master body,
// whose boundary is a closed chain of straight segments (the cell edges used by one cell only,
// oriented with the body on their left, so the outward normal of a -> b is (e_y, -e_x)/|e|).
// A one-way pair checks the slave's nodes only; a symmetric contact is two pairs, (A, B) and
// (B, A) ("two-pass"). Self-contact is not treated.
//
// One contact is a slave node s facing a point p = (1 - xi) x_a + xi x_b of a master segment
// (a, b): gap g = n . (x_s - p), slip increment t . (dx_s - (1 - xi) dx_a - xi dx_b), with
// (n, t = (n_y, -n_x)) the segment's outward normal and tangent. Its reaction r = r_n n + r_t t
// acts on s and, with the opposite sign, on a and b with weights 1 - xi and xi: the stencil
// (s, a, b) with coefficients (1, -(1 - xi), -xi). The coefficients sum to zero, so contact
// forces between bodies never change the total momentum. As for rigid obstacles, the segment,
// xi and the frame are chosen at the predicted position of the step and frozen for it.
//
// Segment choice (large sliding, passing from one segment to the next):
//   1. the segment tracked from the last step is kept while the predicted projection of s on it
//      lies within it (xi in [-eps, 1 + eps], eps = 1e-6); if xi < 0 (> 1) the previous (next)
//      segment of the chain is tried;
//   2. otherwise, among all master segments onto which s projects at the START of the step (the
//      node is outside the master there), the nearest (smallest |g|); ties within 1e-9 of the
//      longest segment are broken in favour of the segment s is approaching fastest (most
//      negative n . (v_s - v_p)). This resolves a slave node sitting exactly on a master corner
//      (two identical bars meeting end to end) to the face it moves into, not the side face;
//   3. a node whose predicted position is not inside the master's bounding box (grown by its
//      longest segment) has no segment: nothing is done for it.
// Vertex contact: a node that projects onto neither of two neighbouring segments (. -> v) and
// (v -> .) lies in the wedge of their common vertex v: outside the master at a convex corner,
// inside it at a concave one (where a node pressed into a dent of a deformed surface ends up).
// Its contact is with the point v, gap n . (x_s - x_v), with n taken at the start of the step:
// at a convex corner the direction from v to the node (the bisector if the node is on v), at
// a concave corner the bisector of the two faces' normals. In step 1 this is the walk's result
// when the projection leaves a segment and misses its neighbour on the other side; in step 2
// the vertices whose wedge holds the node at the start of the step compete with the segments
// by distance |x_s - x_v|. The contact is reported as the segment with xi clamped to the
// vertex's end, so its stencil is (s, v) with coefficients (1, -1).
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "solver/model/model.hpp"

namespace ricochet {

struct BodyPair {
  int slave = 0;          // body whose boundary nodes are checked
  int master = 1;         // body whose boundary segments they are checked against
  double friction = 0.0;  // mu of the pair [-]
  std::string name;       // its interface (contact_set.hpp); pairs of one name are one interface
};

struct SurfaceSegment {
  int a = 0, b = 0;         // global node indices, master body on the left of a -> b
  int prev = -1, next = -1; // neighbouring segments of the chain (prev ends at a, next starts at b)
};

// The boundary of one body: oriented segments and their nodes.
struct Surface {
  int body = 0;
  std::vector<SurfaceSegment> segments;
  std::vector<int> nodes;   // the boundary nodes (for the bounding box)
  double max_length = 0.0;  // longest reference segment [m]
};

// The boundary of `body` as oriented segments: its boundary edges (BodyInfo<2>::boundary_edges), in
// their order (throws std::logic_error for a body without any).
Surface make_surface(const Model<2>& model, int body);

// Which nodes and coefficients a contact's relative motion is made of (1 node for a rigid
// obstacle, 3 for node to segment), and the factors coef_j w_j with w_j = dt^2/m_j (position
// level) or dt/m_j (velocity level) of the step.
// N nodes at most: 3 in 2D (node to segment), 5 in 3D (node to a quadrilateral face).
template <int N>
struct StencilN {
  int count = 1;
  std::array<int, N> node{};
  std::array<double, N> coef{1.0};  // {1, 0, ...}
  std::array<double, N> factor{};
};
using Stencil = StencilN<3>;

struct SegmentProjection {
  double xi = 0.0;   // unclamped parameter of the projection along a -> b [-]
  double gap = 0.0;  // n . (x - p(xi)) [m]
  Vec2 normal = Vec2::UnitY();
};

inline SegmentProjection project_on_segment(const Vec2& xa, const Vec2& xb, const Vec2& x) {
  const Vec2 e = xb - xa;
  const double l2 = e.squaredNorm();
  SegmentProjection p;
  p.xi = l2 > 0.0 ? (x - xa).dot(e) / l2 : 0.0;
  const double l = std::sqrt(l2);
  p.normal = l > 0.0 ? Vec2(e.y() / l, -e.x() / l) : Vec2(Vec2::UnitY());
  p.gap = p.normal.dot(x - xa);
  return p;
}

constexpr double kSegmentEps = 1e-6;  // relative tolerance on xi at segment ends

// The result of the segment choice: segment -1 when the node has none.
struct NodeSegment {
  int segment = -1;
  double xi = 0.0;  // clamped to [0, 1]; 0 or 1 for a vertex contact
  double gap = 0.0; // at the evaluation positions [m]
  Vec2 normal = Vec2::UnitY();
  bool vertex = false;  // contact with the segment's end point xi (vertex contact)
};

// The segment choice above. `start(j)` and `eval(j)` give node j's position at the start of the
// step and where the gap is evaluated (the predicted position); `vel(j)` its velocity (ties only).
template <class Start, class Eval, class Vel>
NodeSegment find_segment(const Surface& surf, int node, int tracked, const Start& start, const Eval& eval,
                         const Vel& vel) {
  const Vec2 x = eval(node), x0 = start(node);
  auto at_eval = [&](int seg) {
    const SurfaceSegment& sg = surf.segments[seg];
    return project_on_segment(eval(sg.a), eval(sg.b), x);
  };
  auto accept = [&](int seg, const SegmentProjection& p) {
    return NodeSegment{seg, std::clamp(p.xi, 0.0, 1.0), p.gap, p.normal, false};
  };
  auto inside = [](double xi) { return xi >= -kSegmentEps && xi <= 1.0 + kSegmentEps; };
  // Contact with the vertex shared by `seg` and `other`, the one after it in the chain when
  // `after` (v = b of seg), else the one before it (v = a of seg). The frame is taken at the
  // start of the step.
  auto vertex = [&](int seg, int other, bool after) {
    const SurfaceSegment& sg = surf.segments[seg];
    const SurfaceSegment& so = surf.segments[other];
    const int v = after ? sg.b : sg.a;
    const Vec2 xv = start(v);
    const Vec2 n_seg = project_on_segment(start(sg.a), start(sg.b), x0).normal;
    const Vec2 n_other = project_on_segment(start(so.a), start(so.b), x0).normal;
    // In chain order the incoming segment ends at v and the outgoing one starts there; the body
    // is on the left, so a left turn (positive cross product) is a convex corner.
    const Vec2 e_in = after ? Vec2(start(sg.b) - start(sg.a)) : Vec2(start(so.b) - start(so.a));
    const Vec2 e_out = after ? Vec2(start(so.b) - start(so.a)) : Vec2(start(sg.b) - start(sg.a));
    const bool convex = e_in.x() * e_out.y() - e_in.y() * e_out.x() > 0.0;
    Vec2 n = n_seg + n_other;  // the bisector of the two faces' normals
    n = n.norm() > 1e-12 ? Vec2(n.normalized()) : n_seg;
    // Outside a convex corner (its wedge holds exterior points) the distance to the vertex is
    // the gap, along the direction from the vertex to the node. Inside a concave corner (its
    // wedge holds interior points) the node is pushed out along the bisector.
    const Vec2 d = x0 - xv;
    if (convex && d.norm() > 1e-12 * surf.max_length) n = d.normalized();
    return NodeSegment{seg, after ? 1.0 : 0.0, n.dot(x - eval(v)), n, true};
  };
  // Evaluate `seg`, or its neighbour on the side the projection leaves it, or their vertex
  // when the projection misses both.
  auto walk = [&](int seg) -> NodeSegment {
    const SegmentProjection p = at_eval(seg);
    if (inside(p.xi)) return accept(seg, p);
    const bool after = p.xi > 1.0;
    const int other = after ? surf.segments[seg].next : surf.segments[seg].prev;
    if (other < 0) return {};
    const SegmentProjection q = at_eval(other);
    if (inside(q.xi)) return accept(other, q);
    // Beyond the shared vertex on both: the node is in the vertex's wedge.
    if (after ? q.xi < 0.0 : q.xi > 1.0) return vertex(seg, other, after);
    return {};
  };
  if (tracked >= 0) {
    const NodeSegment r = walk(tracked);
    if (r.segment >= 0) return r;
  }
  const Vec2 v0 = vel(node);
  const double tie = 1e-9 * surf.max_length;
  int best = -1;
  double best_dist = std::numeric_limits<double>::infinity(), best_approach = 0.0;
  bool best_vertex = false;
  for (int seg = 0; seg < static_cast<int>(surf.segments.size()); ++seg) {
    const SurfaceSegment& sg = surf.segments[seg];
    const SegmentProjection p = project_on_segment(start(sg.a), start(sg.b), x0);
    if (!inside(p.xi)) {
      // The vertex a of seg, if the node is in its wedge (beyond the end of the previous
      // segment too). Each vertex is seen once, from the segment that starts at it.
      if (p.xi > 0.0 || sg.prev < 0) continue;
      const SurfaceSegment& sp = surf.segments[sg.prev];
      if (project_on_segment(start(sp.a), start(sp.b), x0).xi <= 1.0 + kSegmentEps) continue;
      const double dist = (x0 - start(sg.a)).norm();
      if (dist < best_dist - tie) {
        best = seg;
        best_dist = dist;
        best_vertex = true;
      }
      continue;
    }
    const double dist = std::abs(p.gap);
    if (dist > best_dist + tie) continue;
    const double xi = std::clamp(p.xi, 0.0, 1.0);
    const double approach = p.normal.dot(v0 - (1.0 - xi) * vel(sg.a) - xi * vel(sg.b));
    if (dist < best_dist - tie || best_vertex || approach < best_approach) {
      best = seg;
      best_dist = std::min(dist, best_dist);
      best_approach = approach;
      best_vertex = false;
    }
  }
  if (best < 0 || best_dist > surf.max_length) return {};
  if (best_vertex) return vertex(best, surf.segments[best].prev, false);
  return walk(best);
}

// Axis-aligned bounding box of a surface at positions pos(j), grown by `margin`, in dimension D.
// A point with a NaN coordinate is in no box.
template <int D>
struct BoxD {
  using Vec = Eigen::Matrix<double, D, 1>;
  Vec lo = Vec::Zero(), hi = Vec::Zero();
  bool contains(const Vec& x) const {
    for (int i = 0; i < D; ++i)
      if (!(x[i] >= lo[i] && x[i] <= hi[i])) return false;
    return true;
  }
};
using Box2 = BoxD<2>;
// Any surface type with the list of its nodes (`nodes`): Surface, Surface3 (body_contact3.hpp).
template <class S, class Pos>
auto surface_box(const S& surf, const Pos& pos, double margin) {
  using Vec = std::decay_t<decltype(pos(0))>;
  BoxD<Vec::RowsAtCompileTime> b{Vec::Constant(std::numeric_limits<double>::infinity()),
                                 Vec::Constant(-std::numeric_limits<double>::infinity())};
  for (int j : surf.nodes) {
    const Vec x = pos(j);
    b.lo = b.lo.cwiseMin(x);
    b.hi = b.hi.cwiseMax(x);
  }
  b.lo.array() -= margin;
  b.hi.array() += margin;
  return b;
}

// Depth of point x inside the master body bounded by `surf` at displacements u: the distance to
// the nearest segment if x is inside (even-odd crossing rule), else 0 [m].
double depth_inside(const Model<2>& model, const Surface& surf, const Eigen::VectorXd& u, const Vec2& x);
// The signed distance of x to the master body bounded by `surf` at displacements u: the distance
// to the nearest segment, negative if x is inside (even-odd crossing rule) [m].
double signed_distance(const Model<2>& model, const Surface& surf, const Eigen::VectorXd& u, const Vec2& x);

}  // namespace ricochet
