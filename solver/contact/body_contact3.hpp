// Contact between deformable bodies in 3D: node to face, the geometry (docs/three-dimensions.md,
// Contact between bodies in 3D: node to face). The 3D counterpart of body_contact.hpp's node to
// segment: the master's surface, the projection of a point onto a face, the face choice for a
// slave node and the depth of a point inside the master. The contact set (contact_set.hpp) uses it
// for the body pairs of a Model<3>, in all three schemes.
//
// The master's surface is its boundary faces (BodyInfo<3>::boundary_faces): quadrilaterals of
// hexahedra and triangles of tetrahedra, their corners counter-clockwise seen from outside the
// body (mesh.hpp), so the right-hand rule gives the outward normal. Each face is parametrized on
// [0, 1]^2 (quadrilateral, bilinear) or on the unit triangle xi, eta >= 0, xi + eta <= 1:
//   quadrilateral  x(xi, eta) = sum_a N_a x_a, N = ((1-xi)(1-eta), xi(1-eta), xi eta, (1-xi) eta)
//                  (corner 0 at (0, 0), 1 at (1, 0), 2 at (1, 1), 3 at (0, 1));
//   triangle       N = (1 - xi - eta, xi, eta)  (barycentric).
// In both, x_xi x x_eta is the outward normal. Edge k runs from corner k to corner k + 1 (mod the
// corner count).
//
// One contact is a slave node s facing the point p = sum_a N_a x_a of a master face: gap
// g = n . (x_s - p) with n the face's outward unit normal at p, the stencil (s, face corners) with
// coefficients (1, -N_0, ..., -N_3), which sum to zero (the contact forces between two bodies
// cancel, momentum is conserved). Edge and vertex contacts have the stencils (s, a, b) with
// (1, -(1 - t), -t) and (s, v) with (1, -1). As in 2D the face, the parametric coordinates and the
// frame are chosen once per step and frozen for it.
//
// Face choice (find_face), the rules of find_segment one dimension up:
//   1. the face tracked from the last step is kept while the predicted projection of s lies in it
//      (parametric coordinates within kFaceEps = 1e-6 of the face); otherwise the neighbours
//      across the edges the projection leaves by are tried, the farthest-left edge first, then
//      the faces at those edges' corners (a node that crossed near a vertex, e.g. diagonally
//      over a quadrilateral's corner), the nearest that holds the projection; then the edge or
//      vertex of the tracked face nearest to the node, if the node is in its region (below);
//   2. otherwise, at the START of the step, the nearest face (smallest |g|) among those the node
//      projects into; ties within 1e-9 of the longest face edge go to the face the node approaches
//      fastest (most negative n . (v_s - sum_a N_a v_a)). An edge or vertex competes by its distance
//      |x_s - q| when the node lies in its region (below) and is nearer by more than the tie;
//   3. nothing beyond the longest face edge (and nothing when the walk of 1 fails and the search
//      of 2 finds nothing): face -1.
// Edge and vertex contact: a node that projects into no face near it lies in the region of an
// edge or a vertex: the nearest point q of the faces' boundaries is on that edge or vertex, and
// none of the faces around it holds the node's projection or a nearer boundary point. Outside
// the master (at a convex edge or vertex) the normal is the direction from q to the node; on q or
// inside (a concave edge or vertex, where a node pressed into a dent ends up) it is the
// pseudo-normal of q: the sum of the two faces' unit normals at an edge, the angle-weighted sum of
// the corner normals at a vertex (normalized). Outside vs inside is the sign of (x - q) . pseudo-
// normal. The frame is taken at the positions the region was found at: the predicted ones when
// the walk of rule 1 ends there, the start of the step in rule 2. The gap is n . (x_s - q) at the
// predicted positions, q moving with the edge's (vertex's) nodes.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Geometry>  // cross()

#include "solver/contact/body_contact.hpp"  // StencilN, BoxD, surface_box
#include "solver/model/model.hpp"

namespace ricochet {

constexpr double kFaceEps = 1e-6;                 // tolerance on (xi, eta) at a face's edges
constexpr int kProjectionMaxIterations = 30;      // Newton iterations of the quadrilateral projection
constexpr double kProjectionTolerance = 1e-12;    // Newton stops when |d(xi, eta)|_inf <= this

// A face of the master's surface. The neighbour across edge k has that edge in the opposite
// direction (a consistently oriented surface); -1 where the edge borders no face or more than two.
struct SurfaceFace {
  std::array<int, 4> node{-1, -1, -1, -1};           // global node indices, counter-clockwise seen
                                                      // from outside; node[3] = -1 for a triangle
  int count = 4;                                      // corners: 4 or 3
  std::array<int, 4> neighbour{-1, -1, -1, -1};      // face across edge k (node[k] -> node[k + 1])
  std::array<int, 4> neighbour_edge{-1, -1, -1, -1};  // that edge's index in the neighbour
  std::array<int, 4> vertex{-1, -1, -1, -1};         // corner k's index in Surface3::nodes
};

// The boundary of one 3D body as faces. `nodes` and `max_length` are what the dimension-generic
// contact code reads (update_boxes, surface_box).
struct Surface3 {
  int body = 0;
  std::vector<SurfaceFace> faces;
  std::vector<int> nodes;               // the boundary nodes, sorted (for the bounding box)
  std::vector<int> vertex_faces_begin;  // faces at nodes[i]: vertex_faces[begin[i] .. begin[i + 1])
  std::vector<int> vertex_faces;
  double max_length = 0.0;              // longest reference face edge [m]
};

// The boundary of `body` as faces, in the order of BodyInfo<3>::boundary_faces, with their
// neighbours (throws std::logic_error for a body without any).
Surface3 make_surface3(const Model<3>& model, int body);

// The projection of a point x onto a face: (xi, eta) unclamped (outside the face when the nearest
// point of the face's extension is), the point p there, the outward unit normal n at p, the gap
// n . (x - p), and the weights N_a(xi, eta) of the corners (weight[3] = 0 for a triangle), which
// sum to one and give p = sum_a N_a x_a.
struct FaceProjection {
  double xi = 0.0, eta = 0.0;
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitY();
  double gap = 0.0;  // [m]
  std::array<double, 4> weight{};
  int iterations = 0;     // Newton iterations (quadrilateral), 0 for a triangle
  bool converged = true;  // false: the iteration cap was hit or the face is degenerate there
};

inline std::array<double, 4> face_weights(int count, double xi, double eta) {
  if (count == 3) return {1.0 - xi - eta, xi, eta, 0.0};
  return {(1.0 - xi) * (1.0 - eta), xi * (1.0 - eta), xi * eta, (1.0 - xi) * eta};
}

// Triangle (x0, x1, x2): exact. With e1 = x1 - x0, e2 = x2 - x0, m = e1 x e2 and d = x - x0,
// xi = (d x e2) . m / |m|^2, eta = (e1 x d) . m / |m|^2 (the components of d along e1 and e2 after
// removing its part along m), n = m / |m|, g = n . d.
inline FaceProjection project_on_triangle(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x) {
  const Vec3 e1 = x1 - x0, e2 = x2 - x0, d = x - x0;
  const Vec3 m = e1.cross(e2);
  const double m2 = m.squaredNorm();
  FaceProjection p;
  if (!(m2 > 0.0)) {  // a degenerate triangle: no normal
    p.point = x0;
    p.weight = {1.0, 0.0, 0.0, 0.0};
    p.converged = false;
    return p;
  }
  p.xi = d.cross(e2).dot(m) / m2;
  p.eta = e1.cross(d).dot(m) / m2;
  p.normal = m / std::sqrt(m2);
  p.weight = face_weights(3, p.xi, p.eta);
  p.point = x0 + p.xi * e1 + p.eta * e2;
  p.gap = p.normal.dot(d);
  return p;
}

// Bilinear quadrilateral (x0, x1, x2, x3) on [0, 1]^2: x(xi, eta) = x0 + xi a + eta b + xi eta c,
// a = x1 - x0, b = x3 - x0, c = x2 - x3 - x1 + x0 (c = 0 for a parallelogram). The projection is
// the nearest stationary point of f = |x(xi, eta) - x|^2 / 2 from the centre (0.5, 0.5), by
// Newton's method on grad f = (r . x_xi, r . x_eta) = 0 with r = x(xi, eta) - x and the Hessian
//   H = [x_xi . x_xi,  x_xi . x_eta + r . c;  x_xi . x_eta + r . c,  x_eta . x_eta].
// Safeguards for warped faces and far points: where H is not positive definite (det H <= 1e-12
// H_11 H_22) the step uses the metric alone (Gauss-Newton: r . c dropped), which is positive
// definite for a non-degenerate face, so every step is a descent direction; a step is at most 1
// in each coordinate; and a step longer than 1e-8 is halved until f does not increase. It stops
// when the step is at most kProjectionTolerance (converged) or after kProjectionMaxIterations.
// The normal is x_xi x x_eta normalized (the mean normal (x2 - x0) x (x3 - x1) where that vanishes).
inline FaceProjection project_on_quad(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3, const Vec3& x) {
  const Vec3 a = x1 - x0, b = x3 - x0, c = (x2 - x3) - a, d = x - x0;
  auto residual = [&](double s, double t) -> Vec3 { return s * a + t * b + (s * t) * c - d; };
  double s = 0.5, t = 0.5;
  Vec3 r = residual(s, t);
  double f = 0.5 * r.squaredNorm();
  FaceProjection p;
  p.converged = false;
  for (int it = 1; it <= kProjectionMaxIterations; ++it) {
    p.iterations = it;
    const Vec3 ts = a + t * c, tt = b + s * c;
    const double gs = r.dot(ts), gt = r.dot(tt);
    const double hss = ts.squaredNorm(), htt = tt.squaredNorm(), hst = ts.dot(tt);
    double h12 = hst + r.dot(c);
    double det = hss * htt - h12 * h12;
    if (!(det > 1e-12 * hss * htt)) {
      h12 = hst;
      det = hss * htt - hst * hst;
    }
    if (!(det > 0.0)) break;  // degenerate here: x_xi parallel to x_eta
    double ds = -(htt * gs - h12 * gt) / det, dt = -(hss * gt - h12 * gs) / det;
    const double len = std::max(std::abs(ds), std::abs(dt));
    if (!(len <= 1.0)) {
      if (!std::isfinite(len)) break;
      ds /= len;
      dt /= len;
    }
    double lambda = 1.0;
    Vec3 r_new = residual(s + ds, t + dt);
    double f_new = 0.5 * r_new.squaredNorm();
    for (int h = 0; h < 60 && f_new > f && lambda * std::min(len, 1.0) > 1e-8; ++h) {
      lambda *= 0.5;
      r_new = residual(s + lambda * ds, t + lambda * dt);
      f_new = 0.5 * r_new.squaredNorm();
    }
    s += lambda * ds;
    t += lambda * dt;
    r = r_new;
    f = f_new;
    if (lambda * std::min(len, 1.0) <= kProjectionTolerance) {
      p.converged = true;
      break;
    }
  }
  p.xi = s;
  p.eta = t;
  const Vec3 m = (a + t * c).cross(b + s * c);
  const double mn = m.norm();
  const Vec3 mean = (x2 - x0).cross(x3 - x1);
  p.normal = mn > 1e-14 * (a.squaredNorm() + b.squaredNorm()) ? Vec3(m / mn) : Vec3(mean.normalized());
  p.weight = face_weights(4, s, t);
  p.point = p.weight[0] * x0 + p.weight[1] * x1 + p.weight[2] * x2 + p.weight[3] * x3;
  p.gap = p.normal.dot(x - p.point);
  return p;
}

// The projection of x onto face f at positions pos(j).
template <class Pos>
FaceProjection project_on_face(const SurfaceFace& f, const Pos& pos, const Vec3& x) {
  if (f.count == 3) return project_on_triangle(pos(f.node[0]), pos(f.node[1]), pos(f.node[2]), x);
  return project_on_quad(pos(f.node[0]), pos(f.node[1]), pos(f.node[2]), pos(f.node[3]), x);
}

// (xi, eta) within `eps` of the face (quadrilateral [0, 1]^2, triangle xi, eta >= 0, xi + eta <= 1).
inline bool inside_face(int count, double xi, double eta, double eps = kFaceEps) {
  if (count == 3) return xi >= -eps && eta >= -eps && xi + eta <= 1.0 + eps;
  return xi >= -eps && xi <= 1.0 + eps && eta >= -eps && eta <= 1.0 + eps;
}

// How far (xi, eta) lies beyond edge k, in parametric units (> 0 outside that edge's line).
inline double edge_excess(int count, int k, double xi, double eta) {
  if (count == 3) return k == 0 ? -eta : k == 1 ? xi + eta - 1.0 : -xi;
  return k == 0 ? -eta : k == 1 ? xi - 1.0 : k == 2 ? eta - 1.0 : -xi;
}

// The parametric coordinates of the point at fraction t along edge k (from corner k).
inline std::array<double, 2> edge_coordinates(int count, int k, double t) {
  if (count == 3) {
    if (k == 0) return {t, 0.0};
    if (k == 1) return {1.0 - t, t};
    return {0.0, 1.0 - t};
  }
  if (k == 0) return {t, 0.0};
  if (k == 1) return {1.0, t};
  if (k == 2) return {1.0 - t, 1.0};
  return {0.0, 1.0 - t};
}

// (xi, eta) moved onto the face: clamped to [0, 1]^2, or for a triangle to xi, eta >= 0 and then
// scaled onto xi + eta <= 1 (for points within kFaceEps of a face, where the two hardly differ).
inline std::array<double, 2> clamp_to_face(int count, double xi, double eta) {
  if (count == 4) return {std::clamp(xi, 0.0, 1.0), std::clamp(eta, 0.0, 1.0)};
  xi = std::max(xi, 0.0);
  eta = std::max(eta, 0.0);
  const double sum = xi + eta;
  if (sum > 1.0) return {xi / sum, eta / sum};
  return {xi, eta};
}

// The outward unit normal of face f at (xi, eta), positions pos(j).
template <class Pos>
Vec3 face_normal(const SurfaceFace& f, const Pos& pos, double xi, double eta) {
  const Vec3 x0 = pos(f.node[0]), x1 = pos(f.node[1]), x2 = pos(f.node[2]);
  if (f.count == 3) return (x1 - x0).cross(x2 - x0).normalized();
  const Vec3 x3 = pos(f.node[3]);
  const Vec3 a = x1 - x0, b = x3 - x0, c = (x2 - x3) - a;
  const Vec3 m = (a + eta * c).cross(b + xi * c);
  const double mn = m.norm();
  if (mn > 1e-14 * (a.squaredNorm() + b.squaredNorm())) return m / mn;
  return (x2 - x0).cross(x3 - x1).normalized();
}

// A point of a face's boundary: on edge `edge` at fraction t from its first corner; a vertex when
// t is 0 or 1.
struct BoundaryPoint {
  int face = -1;
  int edge = 0;
  double t = 0.0;
  double distance = std::numeric_limits<double>::infinity();  // from the point it was found for [m]
  bool vertex() const { return t == 0.0 || t == 1.0; }
};

// The point of face fi's boundary (its straight edges) nearest to x, at positions pos(j). The
// first edge wins a tie.
template <class Pos>
BoundaryPoint nearest_boundary_point(const Surface3& surf, int fi, const Pos& pos, const Vec3& x) {
  const SurfaceFace& f = surf.faces[fi];
  BoundaryPoint best;
  best.face = fi;
  for (int k = 0; k < f.count; ++k) {
    const Vec3 xa = pos(f.node[k]), e = pos(f.node[(k + 1) % f.count]) - xa;
    const double l2 = e.squaredNorm();
    const double t = l2 > 0.0 ? std::clamp((x - xa).dot(e) / l2, 0.0, 1.0) : 0.0;
    const double dist = (x - xa - t * e).norm();
    if (dist < best.distance) {
      best.edge = k;
      best.t = t;
      best.distance = dist;
    }
  }
  return best;
}

// The position of boundary point q at positions pos(j).
template <class Pos>
Vec3 boundary_point_position(const Surface3& surf, const BoundaryPoint& q, const Pos& pos) {
  const SurfaceFace& f = surf.faces[q.face];
  return (1.0 - q.t) * pos(f.node[q.edge]) + q.t * pos(f.node[(q.edge + 1) % f.count]);
}

// The corner of q's face that q is on (q a vertex).
inline int boundary_point_corner(const Surface3& surf, const BoundaryPoint& q) {
  return q.t == 0.0 ? q.edge : (q.edge + 1) % surf.faces[q.face].count;
}

// The pseudo-normal at boundary point q, positions pos(j), normalized: on an edge the sum of the
// unit normals of its two faces there; at a vertex the sum over the faces around it of their unit
// normal at that corner, (x_next - x_v) x (x_prev - x_v) normalized, weighted by the corner's angle
// (the angle-weighted pseudo-normal of Baerentzen and Aanaes 2005). For a point x whose nearest
// point of a closed surface is q, (x - q) . pseudo-normal > 0 outside and < 0 inside.
template <class Pos>
Vec3 pseudo_normal(const Surface3& surf, const BoundaryPoint& q, const Pos& pos) {
  const SurfaceFace& f = surf.faces[q.face];
  Vec3 sum = Vec3::Zero();
  if (!q.vertex()) {
    const std::array<double, 2> c = edge_coordinates(f.count, q.edge, q.t);
    sum = face_normal(f, pos, c[0], c[1]);
    const int g = f.neighbour[q.edge];
    if (g >= 0) {
      const SurfaceFace& fg = surf.faces[g];
      const std::array<double, 2> cg = edge_coordinates(fg.count, f.neighbour_edge[q.edge], 1.0 - q.t);
      sum += face_normal(fg, pos, cg[0], cg[1]);
    }
  } else {
    const int v = f.vertex[boundary_point_corner(surf, q)];
    for (int i = surf.vertex_faces_begin[v]; i < surf.vertex_faces_begin[v + 1]; ++i) {
      const SurfaceFace& h = surf.faces[surf.vertex_faces[i]];
      int k = 0;
      while (k < h.count && h.vertex[k] != v) ++k;
      const Vec3 xv = pos(h.node[k]);
      const Vec3 e1 = pos(h.node[(k + 1) % h.count]) - xv, e2 = pos(h.node[(k + h.count - 1) % h.count]) - xv;
      const Vec3 m = e1.cross(e2);
      const double mn = m.norm();
      if (mn > 0.0) sum += std::atan2(mn, e1.dot(e2)) * (m / mn);
    }
  }
  const double sn = sum.norm();
  if (sn > 0.0) return sum / sn;
  const std::array<double, 2> c = edge_coordinates(f.count, q.edge, q.t);
  return face_normal(f, pos, c[0], c[1]);
}

// Whether x lies in the region of boundary point q (found at distance q.distance on q's face,
// whose projection does not hold x): neither the other face of q's edge nor any face at q's
// vertex holds x's projection (within kFaceEps) or a boundary point nearer than q by more than
// `tie`.
template <class Pos>
bool in_region(const Surface3& surf, const BoundaryPoint& q, const Pos& pos, const Vec3& x, double tie) {
  auto clear = [&](int h) {
    const FaceProjection p = project_on_face(surf.faces[h], pos, x);
    if (inside_face(surf.faces[h].count, p.xi, p.eta)) return false;
    return nearest_boundary_point(surf, h, pos, x).distance >= q.distance - tie;
  };
  const SurfaceFace& f = surf.faces[q.face];
  if (!q.vertex()) return f.neighbour[q.edge] < 0 || clear(f.neighbour[q.edge]);
  const int v = f.vertex[boundary_point_corner(surf, q)];
  for (int i = surf.vertex_faces_begin[v]; i < surf.vertex_faces_begin[v + 1]; ++i)
    if (surf.vertex_faces[i] != q.face && !clear(surf.vertex_faces[i])) return false;
  return true;
}

enum class FaceContactKind { face, edge, vertex };

// The result of the face choice: face -1 when the node has none.
struct NodeFace {
  int face = -1;               // the face, or the face whose edge or corner the contact is with
  double xi = 0.0, eta = 0.0;  // on the face (clamped onto it); on its boundary for an edge or vertex
  double gap = 0.0;            // at the evaluation positions [m]
  Vec3 normal = Vec3::UnitY();
  FaceContactKind kind = FaceContactKind::face;
  // (s, corners) with (1, -N_a); (s, a, b) with (1, -(1 - t), -t) on an edge; (s, v) with (1, -1)
  // at a vertex. The factors are left to the scheme.
  StencilN<5> stencil;
};

// Face contact of node `node` with face fi, from its projection p at the evaluation positions.
inline NodeFace face_contact(const Surface3& surf, int node, int fi, const FaceProjection& p) {
  const SurfaceFace& f = surf.faces[fi];
  NodeFace r;
  r.face = fi;
  const std::array<double, 2> c = clamp_to_face(f.count, p.xi, p.eta);
  r.xi = c[0];
  r.eta = c[1];
  r.gap = p.gap;
  r.normal = p.normal;
  const std::array<double, 4> w = face_weights(f.count, r.xi, r.eta);
  r.stencil.count = 1 + f.count;
  r.stencil.node[0] = node;
  r.stencil.coef[0] = 1.0;
  for (int a = 0; a < f.count; ++a) {
    r.stencil.node[1 + a] = f.node[a];
    r.stencil.coef[1 + a] = -w[a];
  }
  return r;
}

// Edge or vertex contact of node `node` with boundary point q, its frame (the side, the normal)
// from positions frame(j), its gap at eval(j).
template <class Frame, class Eval>
NodeFace boundary_contact(const Surface3& surf, int node, const BoundaryPoint& q, const Frame& frame,
                          const Eval& eval) {
  const SurfaceFace& f = surf.faces[q.face];
  const Vec3 d = frame(node) - boundary_point_position(surf, q, frame);
  const Vec3 pn = pseudo_normal(surf, q, frame);
  const double dn = d.norm();
  // Outside (a convex edge or vertex): the direction from q to the node; on q or inside (a
  // concave one): the pseudo-normal.
  const Vec3 n = d.dot(pn) > 0.0 && dn > 1e-12 * surf.max_length ? Vec3(d / dn) : pn;
  NodeFace r;
  r.face = q.face;
  const std::array<double, 2> c = edge_coordinates(f.count, q.edge, q.t);
  r.xi = c[0];
  r.eta = c[1];
  r.normal = n;
  r.gap = n.dot(eval(node) - boundary_point_position(surf, q, eval));
  r.stencil.node[0] = node;
  r.stencil.coef[0] = 1.0;
  if (q.vertex()) {
    r.kind = FaceContactKind::vertex;
    r.stencil.count = 2;
    r.stencil.node[1] = f.node[boundary_point_corner(surf, q)];
    r.stencil.coef[1] = -1.0;
  } else {
    r.kind = FaceContactKind::edge;
    r.stencil.count = 3;
    r.stencil.node[1] = f.node[q.edge];
    r.stencil.node[2] = f.node[(q.edge + 1) % f.count];
    r.stencil.coef[1] = -(1.0 - q.t);
    r.stencil.coef[2] = -q.t;
  }
  return r;
}

// The face choice above. `start(j)` and `eval(j)` give node j's position at the start of the step
// and where the gap is evaluated (the predicted position); `vel(j)` its velocity (ties only).
template <class Start, class Eval, class Vel>
NodeFace find_face(const Surface3& surf, int node, int tracked, const Start& start, const Eval& eval,
                   const Vel& vel) {
  const Vec3 x = eval(node), x0 = start(node);
  const double tie = 1e-9 * surf.max_length;
  // Face fi at the evaluation positions, or its neighbour across an edge the projection leaves
  // by (the farthest first), or the edge or vertex of fi nearest to the node if the node is in
  // its region.
  auto walk = [&](int fi) -> NodeFace {
    const SurfaceFace& f = surf.faces[fi];
    const FaceProjection p = project_on_face(f, eval, x);
    if (inside_face(f.count, p.xi, p.eta)) return face_contact(surf, node, fi, p);
    std::array<int, 4> order{};
    std::array<double, 4> excess{};
    int m = 0;
    for (int k = 0; k < f.count; ++k) {
      const double e = edge_excess(f.count, k, p.xi, p.eta);
      if (!(e > kFaceEps)) continue;
      int i = m++;
      for (; i > 0 && excess[i - 1] < e; --i) {
        order[i] = order[i - 1];
        excess[i] = excess[i - 1];
      }
      order[i] = k;
      excess[i] = e;
    }
    for (int i = 0; i < m; ++i) {
      const int g = f.neighbour[order[i]];
      if (g < 0) continue;
      const FaceProjection q = project_on_face(surf.faces[g], eval, x);
      if (inside_face(surf.faces[g].count, q.xi, q.eta)) return face_contact(surf, node, g, q);
    }
    // A node that crossed near a vertex (diagonally over a quadrilateral's corner, or around a
    // fan of triangles) is in a face at an end of a violated edge that is no edge neighbour: the
    // nearest (smallest |g|) of those faces that holds the projection.
    int near_face = -1;
    FaceProjection near_p;
    for (int i = 0; i < m; ++i)
      for (const int corner : {order[i], (order[i] + 1) % f.count}) {
        const int v = f.vertex[corner];
        for (int j = surf.vertex_faces_begin[v]; j < surf.vertex_faces_begin[v + 1]; ++j) {
          const int h = surf.vertex_faces[j];
          if (h == fi) continue;
          const FaceProjection q = project_on_face(surf.faces[h], eval, x);
          if (inside_face(surf.faces[h].count, q.xi, q.eta) && (near_face < 0 || std::abs(q.gap) < std::abs(near_p.gap))) {
            near_face = h;
            near_p = q;
          }
        }
      }
    if (near_face >= 0) return face_contact(surf, node, near_face, near_p);
    const BoundaryPoint q = nearest_boundary_point(surf, fi, eval, x);
    if (in_region(surf, q, eval, x, tie)) return boundary_contact(surf, node, q, eval, eval);
    return {};
  };
  if (tracked >= 0) {
    const NodeFace r = walk(tracked);
    if (r.face >= 0) return r;
  }
  const Vec3 v0 = vel(node);
  int best = -1;
  double best_dist = std::numeric_limits<double>::infinity(), best_approach = 0.0;
  BoundaryPoint best_point;  // best_point.face >= 0: the best is an edge or vertex
  for (int fi = 0; fi < static_cast<int>(surf.faces.size()); ++fi) {
    const SurfaceFace& f = surf.faces[fi];
    // Every point of a face is a convex combination of its corners: it is no nearer to the node
    // than |x0 - x_corner0| - max_k |x_k - x_corner0|.
    const Vec3 c0 = start(f.node[0]);
    double reach = 0.0;
    for (int k = 1; k < f.count; ++k) reach = std::max(reach, (start(f.node[k]) - c0).norm());
    const double lower = (x0 - c0).norm() - reach;
    if (lower > best_dist + tie || lower > surf.max_length) continue;
    const FaceProjection p = project_on_face(f, start, x0);
    if (!inside_face(f.count, p.xi, p.eta)) {
      const BoundaryPoint q = nearest_boundary_point(surf, fi, start, x0);
      if (q.distance < best_dist - tie && in_region(surf, q, start, x0, tie)) {
        best = fi;
        best_dist = q.distance;
        best_point = q;
      }
      continue;
    }
    const double dist = std::abs(p.gap);
    if (dist > best_dist + tie) continue;
    const std::array<double, 2> c = clamp_to_face(f.count, p.xi, p.eta);
    const std::array<double, 4> w = face_weights(f.count, c[0], c[1]);
    Vec3 vp = Vec3::Zero();
    for (int a = 0; a < f.count; ++a) vp += w[a] * vel(f.node[a]);
    const double approach = p.normal.dot(v0 - vp);
    if (dist < best_dist - tie || best_point.face >= 0 || approach < best_approach) {
      best = fi;
      best_dist = std::min(dist, best_dist);
      best_approach = approach;
      best_point = BoundaryPoint{};
    }
  }
  if (best < 0 || best_dist > surf.max_length) return {};
  if (best_point.face >= 0) return boundary_contact(surf, node, best_point, start, eval);
  return walk(best);
}

// The signed distance of x to the body bounded by `surf` at positions pos(j): the distance to
// the nearest point q of its faces (the face's projection where it lies in the face, else the
// nearest point of its edges), negative inside, the side by the sign of (x - q) . n with n the
// face normal at q, or the pseudo-normal (pseudo_normal()) when q is on an edge or a vertex [m].
template <class Pos>
double surface_signed_distance(const Surface3& surf, const Pos& pos, const Vec3& x) {
  double best = std::numeric_limits<double>::infinity();
  double side = 1.0;
  for (int fi = 0; fi < static_cast<int>(surf.faces.size()); ++fi) {
    const SurfaceFace& f = surf.faces[fi];
    const Vec3 c0 = pos(f.node[0]);
    double reach = 0.0;
    for (int k = 1; k < f.count; ++k) reach = std::max(reach, (pos(f.node[k]) - c0).norm());
    if ((x - c0).norm() - reach >= best) continue;
    const FaceProjection p = project_on_face(f, pos, x);
    if (inside_face(f.count, p.xi, p.eta, 0.0)) {
      const double dist = (x - p.point).norm();
      if (dist < best) {
        best = dist;
        side = p.normal.dot(x - p.point);
      }
      continue;
    }
    const BoundaryPoint q = nearest_boundary_point(surf, fi, pos, x);
    if (q.distance < best) {
      best = q.distance;
      side = pseudo_normal(surf, q, pos).dot(x - boundary_point_position(surf, q, pos));
    }
  }
  return side < 0.0 ? -best : best;
}

// The signed distance of x to the master body bounded by `surf` at displacements u (3 DOFs a
// node): surface_signed_distance at X + u [m].
double signed_distance(const Model<3>& model, const Surface3& surf, const Eigen::VectorXd& u, const Vec3& x);
// Depth of x inside that body: minus the signed distance if x is inside, else 0 [m].
double depth_inside(const Model<3>& model, const Surface3& surf, const Eigen::VectorXd& u, const Vec3& x);

}  // namespace ricochet
