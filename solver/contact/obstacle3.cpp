#include "solver/contact/obstacle3.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Geometry>  // cross()

namespace ricochet {

namespace {

std::string who(const std::string& name) { return "obstacle \"" + name + "\": "; }

void check(const Obstacle3& ob) {
  if (const std::string e = obstacle_error(ob); !e.empty()) throw std::invalid_argument(e);
}

// A direction given to a constructor: finite and non-zero, normalized afterwards.
void check_direction(const std::string& name, const char* what, const Vec3& v) {
  if (!v.allFinite() || !(v.norm() > 0.0))
    throw std::invalid_argument(who(name) + what + " must be finite and non-zero");
}

bool unit(const Vec3& v) { return v.allFinite() && std::abs(v.norm() - 1.0) <= 1e-12; }

}  // namespace

Obstacle3 make_plane_obstacle3(std::string name, const Vec3& point, const Vec3& normal) {
  check_direction(name, "normal", normal);
  Obstacle3 ob;
  ob.name = std::move(name);
  ob.kind = ObstacleKind3::plane;
  ob.point = point;
  ob.normal = normal.normalized();
  check(ob);
  return ob;
}

Obstacle3 make_sphere_obstacle3(std::string name, const Vec3& center, double radius, bool inside) {
  Obstacle3 ob;
  ob.name = std::move(name);
  ob.kind = ObstacleKind3::sphere;
  ob.center = center;
  ob.radius = radius;
  ob.inside = inside;
  check(ob);
  return ob;
}

Obstacle3 make_box_obstacle3(std::string name, const Vec3& center, const Vec3& half_extents, bool inside,
                             const Vec3& axis1, const Vec3& axis2) {
  check_direction(name, "axis1", axis1);
  check_direction(name, "axis2", axis2);
  const Vec3 a1 = axis1.normalized();
  const Vec3 v = axis2 - a1.dot(axis2) * a1;  // Gram-Schmidt
  if (!(v.norm() > 1e-12 * axis2.norm())) throw std::invalid_argument(who(name) + "axis2 is parallel to axis1");
  const Vec3 a2 = v.normalized();
  Obstacle3 ob;
  ob.name = std::move(name);
  ob.kind = ObstacleKind3::box;
  ob.center = center;
  ob.half_extents = half_extents;
  ob.inside = inside;
  ob.axes.col(0) = a1;
  ob.axes.col(1) = a2;
  ob.axes.col(2) = a1.cross(a2);
  check(ob);
  return ob;
}

Obstacle3 make_cylinder_obstacle3(std::string name, const Vec3& center, const Vec3& axis, double radius,
                                  bool inside, double half_length) {
  check_direction(name, "axis", axis);
  Obstacle3 ob;
  ob.name = std::move(name);
  ob.kind = ObstacleKind3::cylinder;
  ob.center = center;
  ob.axis = axis.normalized();
  ob.radius = radius;
  ob.inside = inside;
  ob.half_length = half_length;
  check(ob);
  return ob;
}

std::string obstacle_error(const Obstacle3& ob) {
  const std::string w = who(ob.name);
  auto radius_error = [&]() -> std::string {
    if (!(ob.radius > 0.0) || !std::isfinite(ob.radius)) return w + "radius must be finite and > 0";
    return {};
  };
  switch (ob.kind) {
    case ObstacleKind3::plane:
      if (!ob.point.allFinite()) return w + "point must be finite";
      if (!unit(ob.normal)) return w + "normal must be a finite unit vector";
      if (ob.inside) return w + "inside applies to a sphere, box or cylinder (turn the plane's normal instead)";
      return {};
    case ObstacleKind3::sphere:
      if (!ob.center.allFinite()) return w + "center must be finite";
      return radius_error();
    case ObstacleKind3::box: {
      if (!ob.center.allFinite()) return w + "center must be finite";
      if (!ob.half_extents.allFinite() || !(ob.half_extents.minCoeff() > 0.0))
        return w + "half_extents must be finite and > 0";
      if (!ob.axes.allFinite()) return w + "axes must be finite";
      const Mat3 gram = ob.axes.transpose() * ob.axes;
      if (!((gram - Mat3::Identity()).cwiseAbs().maxCoeff() <= 1e-12))
        return w + "axes must be orthonormal (the columns unit and orthogonal to 1e-12)";
      return {};
    }
    case ObstacleKind3::cylinder:
      if (!ob.center.allFinite()) return w + "center must be finite";
      if (!unit(ob.axis)) return w + "axis must be a finite unit vector";
      if (const std::string e = radius_error(); !e.empty()) return e;
      if (!(ob.half_length > 0.0)) return w + "half_length must be > 0 (+infinity for an infinite cylinder)";
      return {};
  }
  return w + "unknown kind";
}

Vec3 cylinder_fallback_radial(const Vec3& axis) {
  const Vec3 up = std::abs(axis.y()) > 0.8660254037844386 ? Vec3(Vec3::UnitZ()) : Vec3(Vec3::UnitY());
  return (up - axis.dot(up) * axis).normalized();
}

ObstacleContact3 closest_sphere(const Obstacle3& ob, const Vec3& x) {
  const Vec3 r = x - ob.center;
  const double d = r.norm();
  const double sign = ob.inside ? -1.0 : 1.0;
  const Vec3 radial = d > 0.0 ? Vec3(r / d) : Vec3(Vec3::UnitY());
  return {sign * (d - ob.radius), sign * radial};
}

ObstacleContact3 closest_box(const Obstacle3& ob, const Vec3& x) {
  const Vec3 d = x - ob.center;
  const double flip = ob.inside ? -1.0 : 1.0;
  double side[3], excess[3];  // s_i, e_i = |y_i| - h_i [m]
  int out[3], outside = 0;    // the axes with e_i > 0
  for (int i = 0; i < 3; ++i) {
    const double y = ob.axes.col(i).dot(d);
    side[i] = y >= 0.0 ? 1.0 : -1.0;
    excess[i] = std::abs(y) - ob.half_extents[i];
    if (excess[i] > 0.0) out[outside++] = i;
  }
  if (outside == 1) {  // a face: exactly its plane's gap and normal
    const int i = out[0];
    return {flip * excess[i], Vec3(flip * side[i] * ob.axes.col(i))};
  }
  if (outside > 1) {  // an edge or a corner: x - q = sum d_i a_i over the axes outside
    Vec3 dq = Vec3::Zero();
    for (int k = 0; k < outside; ++k) dq += (side[out[k]] * excess[out[k]]) * ob.axes.col(out[k]);
    const double g = outside == 2 ? std::hypot(excess[out[0]], excess[out[1]])
                                  : std::hypot(excess[0], excess[1], excess[2]);
    return {flip * g, Vec3((flip / g) * dq)};
  }
  // Inside: the nearest face; ties within 1e-12 of the box's size add their normals.
  int first = 0;
  for (int i = 1; i < 3; ++i)
    if (excess[i] > excess[first]) first = i;
  const double tie = 1e-12 * ob.half_extents.maxCoeff();
  Vec3 n = side[first] * ob.axes.col(first);
  int tied = 0;
  for (int i = 0; i < 3; ++i) {
    if (i == first || !(excess[first] - excess[i] <= tie)) continue;
    n += side[i] * ob.axes.col(i);
    ++tied;
  }
  if (tied > 0) n.normalize();
  return {flip * excess[first], Vec3(flip * n)};
}

ObstacleContact3 closest_cylinder(const Obstacle3& ob, const Vec3& x) {
  const Vec3 d = x - ob.center;
  const double flip = ob.inside ? -1.0 : 1.0;
  const double s = ob.axis.dot(d);  // axial coordinate [m]
  const Vec3 v = d - s * ob.axis;   // radial vector [m]
  const double rho = v.norm();
  const Vec3 u = rho > 0.0 ? Vec3(v / rho) : cylinder_fallback_radial(ob.axis);
  const double dr = rho - ob.radius;
  if (!ob.capped()) return {flip * dr, Vec3(flip * u)};
  const double sigma = s >= 0.0 ? 1.0 : -1.0;
  const double da = std::abs(s) - ob.half_length;
  if (dr > 0.0 && da > 0.0) {  // the rim
    const double g = std::hypot(dr, da);
    return {flip * g, Vec3((flip / g) * (dr * u + (da * sigma) * ob.axis))};
  }
  if (dr > 0.0) return {flip * dr, Vec3(flip * u)};                   // the side
  if (da > 0.0) return {flip * da, Vec3((flip * sigma) * ob.axis)};  // an end
  // Inside: the nearer of the side and the end; a tie adds their normals.
  const double tie = 1e-12 * std::max(ob.radius, ob.half_length);
  if (std::abs(dr - da) <= tie)
    return {flip * std::max(dr, da), Vec3(flip * (u + sigma * ob.axis).normalized())};
  if (dr >= da) return {flip * dr, Vec3(flip * u)};
  return {flip * da, Vec3((flip * sigma) * ob.axis)};
}

}  // namespace ricochet
