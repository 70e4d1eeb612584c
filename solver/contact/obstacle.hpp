// Rigid obstacles (rigid foundations) and the one geometric query every scheme asks of them:
// the signed gap and the outward normal of a point, closest(), and the frame a step's contact
// is solved in, step_frame().
#pragma once

#include <string>
#include <vector>

#include "solver/core/types.hpp"

namespace ricochet {

// A rigid obstacle (a rigid foundation). One geometric query, closest(), serves
// every scheme: the signed gap g of a point x (g >= 0 on the allowed side, g < 0 inside the
// obstacle) and the unit outward normal n at the closest point of the obstacle's boundary,
// pointing to the allowed side; the tangent is t = (n_y, -n_x) (n rotated by -90 degrees).
// For every kind g = n . (x - q) with q the closest boundary point, so the first-order gap
// about x is g(x + du) ~ g + n . du.
//   line:     the half-plane behind the line through `point` with unit outward normal
//             `normal`: g = normal . (x - point), n = normal (the same arithmetic as
//             before circles and polylines existed);
//   circle:   centre `center`, radius `radius` > 0. inside = false: the rigid disk is the
//             obstacle (bodies stay outside, e.g. a peg): g = |x - c| - r, n = (x - c)/|x - c|.
//             inside = true: everything outside the circle is the obstacle (bodies stay inside
//             a rigid ring or bowl): g = r - |x - c|, n = -(x - c)/|x - c|. At x = c exactly the
//             radial direction is undefined and n = +y is used.
//   polyline: an open chain points[0..m] (m >= 1 segments, none of zero length). The allowed
//             side is to the left (left = true) or right of the direction of travel from
//             points[0] to points[m]; the outward normal of segment j is its direction rotated
//             by +90 degrees (left) or -90 degrees (right). The first and last segments extend
//             to infinity as rays, so the chain divides the plane in two like a line does (a
//             2-point polyline is a line); the rays must not cross the chain (not checked).
//             g is the signed distance to the nearest segment:
//               - nearest point inside segment j (or on an end ray): g = n_j . (x - p_j), n = n_j;
//               - nearest point an interior vertex v (x in the corner's wedge): |g| = |x - v|, the
//                 sign that of (x - v) . b with b the bisector of the two segment normals
//                 (positive in the wedge outside a convex corner, negative in the wedge behind
//                 a concave one), and n = sign * (x - v)/|x - v| (n = b if x = v);
//               - ties (x equidistant from several segments within 1e-12 of the chain's length
//                 scale, e.g. on the bisector of a concave corner such as the bottom of a V):
//                 g is that of the first nearest segment and n the normalized sum of the tied
//                 normals (the bisector), so a symmetric chain stays symmetric; if the tied
//                 normals cancel, n is the first one's.
//             Cost O(m) per query.
// Every scheme evaluates closest() once per candidate and step at its predicted position
// (semi-explicit: x at t+dt of the free motion; implicit: x at the predicted u of the Newton
// iterate; penalty: x at u_n) and freezes n (and t) for the step: the reactions act along that
// frame and the gap is linearized about the predicted point. For a line this is exact; for a
// circle or a polyline the linearization is first order (the boundary's curvature, or a switch
// of the nearest segment, enters at the next step), consistent with the position-level scheme.
enum class ObstacleKind { line, circle, polyline };

struct Obstacle {
  std::string name;
  Vec2 point = Vec2::Zero();    // line: a point of the line [m]
  Vec2 normal = Vec2::UnitY();  // line: unit outward normal [-]
  ObstacleKind kind = ObstacleKind::line;
  Vec2 center = Vec2::Zero();   // circle: centre [m]
  double radius = 0.0;          // circle: radius > 0 [m]
  bool inside = false;          // circle: bodies inside the circle (ring/bowl) instead of outside
  std::vector<Vec2, Eigen::aligned_allocator<Vec2>> points{};  // polyline: >= 2 vertices [m]
  bool left = true;             // polyline: allowed side left (true) or right of the chain
  Vec2 tangent() const { return {normal.y(), -normal.x()}; }  // line: t = n rotated by -90 degrees
};

// Result of closest(): signed gap [m] and unit outward normal at the closest point.
struct ObstacleContact {
  double gap = 0.0;
  Vec2 normal = Vec2::UnitY();
  Vec2 tangent() const { return {normal.y(), -normal.x()}; }
};

// Checked constructors (throw std::invalid_argument with a one-line message on bad geometry).
Obstacle make_line_obstacle(std::string name, const Vec2& point, const Vec2& normal);  // normal normalized
Obstacle make_circle_obstacle(std::string name, const Vec2& center, double radius, bool inside);
Obstacle make_polyline_obstacle(std::string name, std::vector<Vec2, Eigen::aligned_allocator<Vec2>> points,
                                bool left);
// Empty if `ob` is valid, else what is wrong (one line).
std::string obstacle_error(const Obstacle& ob);

ObstacleContact closest_circle(const Obstacle& ob, const Vec2& x);
ObstacleContact closest_polyline(const Obstacle& ob, const Vec2& x);

inline ObstacleContact closest(const Obstacle& ob, const Vec2& x) {
  switch (ob.kind) {
    case ObstacleKind::circle: return closest_circle(ob, x);
    case ObstacleKind::polyline: return closest_polyline(ob, x);
    case ObstacleKind::line: break;
  }
  return {ob.normal.dot(x - ob.point), ob.normal};
}

// The frame a step's contact with a rigid obstacle is solved in, for a node that starts the step
// at x_start and whose motion is predicted to x_pred. A line: the gap at x_pred and the line's
// normal (exact). A circle or a polyline: the normal at the midpoint x_m of the step's chord and
// the gap linearized from there, g(x_m) + n_m . (x_pred - x_m). For a node sliding fast along
// a curved obstacle, the normal at x_pred has turned by the whole step's angle against the
// node's path and the reaction pushed the node out, doing positive work; the midpoint normal
// has turned by half of it. In the Kim-Kwak problem's tripping impact this halves the normal
// reactions' work, +0.021 -> +0.010 J (docs/kim-kwak-type.md). For a convex gap function
// (outside a circle) the linearization stays below the gap, so g >= 0 still holds at the end.
inline ObstacleContact step_frame(const Obstacle& ob, const Vec2& x_start, const Vec2& x_pred) {
  if (ob.kind == ObstacleKind::line) return closest(ob, x_pred);
  const Vec2 x_mid = 0.5 * (x_start + x_pred);
  const ObstacleContact m = closest(ob, x_mid);
  return {m.gap + m.normal.dot(x_pred - x_mid), m.normal};
}

}  // namespace ricochet
