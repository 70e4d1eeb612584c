// Rigid obstacles in 3D (issue 18; docs/three-dimensions.md, Rigid obstacles in 3D): the 3D
// counterpart of obstacle.hpp, with the same query, the same sign convention and the same step
// frame, under the same names (closest, step_frame, obstacle_error) so that code templated over
// the dimension calls the right one. Nothing of 2D changes. No scheme uses it yet.
#pragma once

#include <limits>
#include <string>

#include "solver/contact/coulomb3d.hpp"  // Frame3d, contact_frame_3d
#include "solver/core/types.hpp"

namespace ricochet {

// A rigid obstacle in 3D. One geometric query, closest(), gives the signed gap g of a point x
// (g >= 0 on the allowed side, g < 0 inside the obstacle) and the unit outward normal n at the
// closest point q of the obstacle's boundary, pointing to the allowed side, with g = n . (x - q)
// (except at the interior ties of a box or capped cylinder, below). The contact's tangent plane has
// the basis of contact_frame_3d(n) (coulomb3d.hpp).
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

// Result of closest(): signed gap [m] and unit outward normal at the closest point.
struct ObstacleContact3 {
  double gap = 0.0;
  Vec3 normal = Vec3::UnitY();
  Frame3d frame() const { return contact_frame_3d(normal); }  // (t1, t2, n), coulomb3d.hpp
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
// at x_start and whose motion is predicted to x_pred: the 2D rule of step_frame (obstacle.hpp).
// A plane: the gap at x_pred and the plane's normal (exact). A sphere, box or cylinder: the
// normal n_m at the midpoint x_m of the step's chord and the gap linearized from there,
// g(x_m) + n_m . (x_pred - x_m): a node sliding fast along a curved surface then meets a normal
// turned by half the step's angle rather than the whole (docs/kim-kwak-type.md: in 2D this halves
// the normal reactions' spurious work). The box is flat between its edges, but its normal turns
// around an edge or corner and switches between faces, as the 2D polyline's, which uses the same
// rule. For the convex solids (inside = false) the signed distance is convex and n_m a
// subgradient of it, so the linearized gap stays at or below the true gap at x_pred (ties inside
// a box or capped cylinder excepted): g >= 0 still holds at the end.
inline ObstacleContact3 step_frame(const Obstacle3& ob, const Vec3& x_start, const Vec3& x_pred) {
  if (ob.kind == ObstacleKind3::plane) return closest(ob, x_pred);
  const Vec3 x_mid = 0.5 * (x_start + x_pred);
  const ObstacleContact3 m = closest(ob, x_mid);
  return {m.gap + m.normal.dot(x_pred - x_mid), m.normal};
}

}  // namespace ricochet
