// Rigid obstacles (rigid foundations) in 2D and 3D and the one geometric query every scheme asks
// of them: the signed gap and the outward normal of a point, closest(), and the frame a step's
// contact is solved in, step_frame(), written once for both. The shapes are what differs: line,
// circle and polyline in 2D (Obstacle); plane, sphere, box and cylinder in 3D (Obstacle3;
// docs/three-dimensions.md, Rigid obstacles in 3D). Both have the same sign convention and
// their queries and checks the same names (closest, step_frame, obstacle_error), so that code
// templated over the dimension calls the right one.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "solver/core/types.hpp"

namespace ricochet {

// Result of closest(): signed gap [m] and unit outward normal at the closest point.
template <int D>
struct ObstacleContactT {
  double gap = 0.0;
  Eigen::Matrix<double, D, 1> normal = Eigen::Matrix<double, D, 1>::UnitY();
  // 2D: t = (n_y, -n_x), n rotated by -90 degrees.
  Vec2 tangent() const requires(D == 2) { return {normal.y(), -normal.x()}; }
};
using ObstacleContact = ObstacleContactT<2>;
using ObstacleContact3 = ObstacleContactT<3>;

// ------------------------------------------------------------------------------------------ 2D

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

// ------------------------------------------------------------------------------------------ 3D

// A rigid obstacle in 3D. One geometric query, closest(), gives the signed gap g of a point x
// (g >= 0 on the allowed side, g < 0 inside the obstacle) and the unit outward normal n at the
// closest point q of the obstacle's boundary, pointing to the allowed side, with g = n . (x - q)
// (except at the interior ties of a box or capped cylinder, below). The contact's tangent plane has
// the basis of ContactFrame<3>(n) (contact_space.hpp).
//   plane:    the half-space behind the plane through `point` with unit outward normal
//             `normal`: g = normal . (x - point), n = normal. The xy part of the dot product is
//             summed first, as the 2D line's, so a plane whose normal lies in the xy-plane gives
//             the 2D line's numbers at every z (an extruded line).
//   sphere:   centre `center`, radius `radius` > 0. inside = false: the solid ball is the obstacle
//             (bodies stay outside): g = |x - c| - r, n = (x - c)/|x - c|. inside = true: the
//             outside of the sphere is the obstacle (bodies stay inside a spherical shell or
//             bowl): g = r - |x - c|, n = -(x - c)/|x - c|. At x = c, n = +y (-y inside), as
//             the 2D circle: a sphere's section z = c_z is that circle.
//   box:      the solid box of centre `center`, unit axes the columns a_i of `axes`
//             (orthonormal) and half-extents h_i = `half_extents`(i) > 0 along them. With the
//             local coordinates y_i = a_i . (x - c), the side s_i = +1 if y_i >= 0 else -1 and the
//             face excesses e_i = |y_i| - h_i:
//               - outside (some e_i > 0): q is the clamp of y to [-h, h]; x - q has the local
//                 components d_i = s_i max(e_i, 0), so g = |d| and n = sum d_i a_i / g. One e_i > 0:
//                 a face, g = e_i and n = s_i a_i exactly; two: an edge, g = hypot(d_i, d_j); three:
//                 a corner, g = hypot(d_1, d_2, d_3); n = (x - q)/|x - q| for the last two.
//               - inside (every e_i <= 0): the nearest face, g = max_i e_i <= 0, n = s_i a_i (the
//                 face on the side of y_i; at y_i = 0 the + face). Ties (faces whose e_i is within
//                 1e-12 max_i h_i of the largest, e.g. on the diagonal plane of a corner): g is
//                 that of the first nearest face and n the normalized sum of the tied normals, so
//                 a symmetric problem stays symmetric, as the 2D polyline's ties (obstacle.hpp);
//                 there g = n . (x - q) does not hold (the tied normals are orthogonal, so they
//                 never cancel).
//             inside = true: the outside of the box is the obstacle (bodies stay inside a rigid
//             bin): g and n change sign.
//   cylinder: the solid circular cylinder of radius `radius` > 0 about the axis through `center`
//             with unit direction `axis`; infinite if `half_length` is +infinity, otherwise capped
//             by flat ends at axial distance `half_length` > 0 from `center`. With the axial
//             coordinate s = a . (x - c), the radial vector v = (x - c) - s a, rho = |v|, the radial
//             unit u = v / rho, dr = rho - r, and (capped) sigma = +1 if s >= 0 else -1 and
//             da = |s| - half_length:
//               - infinite: g = dr, n = u;
//               - capped, outside: dr > 0 and da > 0: the rim, g = hypot(dr, da) and
//                 n = (dr u + da sigma a)/g; dr > 0 only: the side, g = dr, n = u; da > 0 only: an
//                 end, g = da, n = sigma a;
//               - capped, inside (dr <= 0 and da <= 0): the nearer of the side (g = dr, n = u) and
//                 the end on the side of s (g = da, n = sigma a; the + end at s = 0); a tie within
//                 1e-12 max(r, half_length): g = max(dr, da), n = (u + sigma a)/|u + sigma a|.
//             On the axis (rho = 0) u is undefined and the fixed radial direction of
//             cylinder_fallback_radial() is used: +y made perpendicular to the axis (+z if the
//             axis is within 30 degrees of y), so that a cylinder along z is the extrusion of the
//             2D circle, which uses +y at its centre. inside = true: the outside of the cylinder
//             is the obstacle (bodies inside a rigid pipe, or a closed can): g and n change sign.
// Sphere, box and cylinder with inside = false are convex solids: their signed distance is a
// convex function of x, and n (away from ties) is its gradient or a subgradient. Cost O(1).
enum class ObstacleKind3 { plane, sphere, box, cylinder };

struct Obstacle3 {
  std::string name;
  ObstacleKind3 kind = ObstacleKind3::plane;
  Vec3 point = Vec3::Zero();         // plane: a point of the plane [m]
  Vec3 normal = Vec3::UnitY();       // plane: unit outward normal [-] (y up, as in 2D)
  Vec3 center = Vec3::Zero();        // sphere, box: centre; cylinder: a point of the axis, the middle if capped [m]
  double radius = 0.0;               // sphere, cylinder: radius > 0 [m]
  bool inside = false;               // sphere, box, cylinder: bodies inside (bowl, bin, pipe) instead of outside
  Vec3 half_extents = Vec3::Zero();  // box: half-extents > 0 along its axes [m]
  Mat3 axes = Mat3::Identity();      // box: columns the unit axes a_1, a_2, a_3 (orthonormal) [-]
  Vec3 axis = Vec3::UnitZ();         // cylinder: unit axis direction [-]
  double half_length = std::numeric_limits<double>::infinity();  // cylinder: > 0, +inf = infinite [m]
  bool capped() const { return half_length < std::numeric_limits<double>::infinity(); }
};

// Checked constructors (throw std::invalid_argument with a one-line message naming the obstacle).
// The plane's normal is normalized. The box's axes come from two directions: a_1 = axis1/|axis1|,
// a_2 the part of axis2 perpendicular to a_1, normalized (Gram-Schmidt; rejected if that part is
// below 1e-12 |axis2|, i.e. the two are parallel to round-off), a_3 = a_1 x a_2. The cylinder's
// axis is normalized; half_length = +inf (the default) is an infinite cylinder.
Obstacle3 make_plane_obstacle3(std::string name, const Vec3& point, const Vec3& normal);
Obstacle3 make_sphere_obstacle3(std::string name, const Vec3& center, double radius, bool inside);
Obstacle3 make_box_obstacle3(std::string name, const Vec3& center, const Vec3& half_extents, bool inside,
                             const Vec3& axis1 = Vec3::UnitX(), const Vec3& axis2 = Vec3::UnitY());
Obstacle3 make_cylinder_obstacle3(std::string name, const Vec3& center, const Vec3& axis, double radius,
                                  bool inside, double half_length = std::numeric_limits<double>::infinity());
// Empty if `ob` is valid, else what is wrong (one line, naming the obstacle). Unit vectors and
// the box's axes must be unit and orthogonal to 1e-12 (as the 2D line's normal).
std::string obstacle_error(const Obstacle3& ob);

// The radial direction used on a cylinder's axis: +y minus its component along the axis,
// normalized, or +z the same way if |axis_y| > sqrt(3)/2 (then +y's perpendicular part is shorter
// than 1/2 and +z's longer than sqrt(3)/2, so neither is near zero). Unit and perpendicular to
// the axis.
Vec3 cylinder_fallback_radial(const Vec3& axis);

ObstacleContact3 closest_sphere(const Obstacle3& ob, const Vec3& x);
ObstacleContact3 closest_box(const Obstacle3& ob, const Vec3& x);
ObstacleContact3 closest_cylinder(const Obstacle3& ob, const Vec3& x);

inline ObstacleContact3 closest(const Obstacle3& ob, const Vec3& x) {
  switch (ob.kind) {
    case ObstacleKind3::sphere: return closest_sphere(ob, x);
    case ObstacleKind3::box: return closest_box(ob, x);
    case ObstacleKind3::cylinder: return closest_cylinder(ob, x);
    case ObstacleKind3::plane: break;
  }
  // The xy part first, as the 2D line's Vec2 dot product; with normal_z = 0 the z term adds an
  // exact zero.
  const Vec3 d = x - ob.point;
  return {ob.normal.head<2>().dot(d.head<2>()) + ob.normal.z() * d.z(), ob.normal};
}

// The frame a step's contact with a rigid obstacle is solved in, for a node that starts the step
// at x_start and whose motion is predicted to x_pred. A line or a plane: the gap at x_pred and its
// normal (exact). Any other shape: the normal n_m at the midpoint x_m of the step's chord and the
// gap linearized from there, g(x_m) + n_m . (x_pred - x_m). For a node sliding fast along a curved
// obstacle, the normal at x_pred has turned by the whole step's angle against the node's path and
// the reaction pushed the node out, doing positive work; the midpoint normal has turned by half of
// it. In the Kim-Kwak problem's tripping impact this halves the normal reactions' work,
// +0.021 -> +0.010 J (docs/kim-kwak-type.md). A box is flat between its edges, but its normal
// turns around an edge or corner and switches between faces, as a polyline's, which uses the same
// rule. For a convex gap function (outside a circle; the convex solids of 3D, inside = false, n_m
// a subgradient) the linearization stays at or below the true gap at x_pred (ties inside a box or
// capped cylinder excepted), so g >= 0 still holds at the end.
inline bool is_flat(const Obstacle& ob) { return ob.kind == ObstacleKind::line; }
inline bool is_flat(const Obstacle3& ob) { return ob.kind == ObstacleKind3::plane; }

template <class Ob>
inline auto step_frame(const Ob& ob, const decltype(Ob::point)& x_start, const decltype(Ob::point)& x_pred)
    -> decltype(closest(ob, x_pred)) {
  if (is_flat(ob)) return closest(ob, x_pred);
  const decltype(Ob::point) x_mid = 0.5 * (x_start + x_pred);
  const auto m = closest(ob, x_mid);
  return {m.gap + m.normal.dot(x_pred - x_mid), m.normal};
}

}  // namespace ricochet
