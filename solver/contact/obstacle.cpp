#include "solver/contact/obstacle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Geometry>  // cross()

namespace ricochet {

namespace {

// The obstacle if it is valid, else std::invalid_argument with obstacle_error's line.
template <class Ob>
Ob checked(Ob ob) {
  if (const std::string e = obstacle_error(ob); !e.empty()) throw std::invalid_argument(e);
  return ob;
}

}  // namespace

Obstacle make_line_obstacle(std::string name, const Vec2& point, const Vec2& normal) {
  const Vec2 n = normal.norm() > 0.0 ? Vec2(normal.normalized()) : normal;
  return checked(Obstacle{.name = std::move(name), .point = point, .normal = n, .kind = ObstacleKind::line});
}

Obstacle make_circle_obstacle(std::string name, const Vec2& center, double radius, bool inside) {
  return checked(Obstacle{
      .name = std::move(name), .kind = ObstacleKind::circle, .center = center, .radius = radius, .inside = inside});
}

Obstacle make_polyline_obstacle(std::string name, std::vector<Vec2, Eigen::aligned_allocator<Vec2>> points,
                                bool left) {
  return checked(
      Obstacle{.name = std::move(name), .kind = ObstacleKind::polyline, .points = std::move(points), .left = left});
}

std::string obstacle_error(const Obstacle& ob) {
  const std::string who = "obstacle \"" + ob.name + "\": ";
  switch (ob.kind) {
    case ObstacleKind::line:
      if (!ob.point.allFinite()) return who + "point must be finite";
      if (!ob.normal.allFinite() || !(std::abs(ob.normal.norm() - 1.0) <= 1e-12))
        return who + "normal must be a finite unit vector";
      return {};
    case ObstacleKind::circle:
      if (!ob.center.allFinite()) return who + "center must be finite";
      if (!(ob.radius > 0.0) || !std::isfinite(ob.radius)) return who + "radius must be finite and > 0";
      return {};
    case ObstacleKind::polyline:
      if (ob.points.size() < 2) return who + "a polyline needs at least 2 points";
      for (std::size_t j = 0; j < ob.points.size(); ++j) {
        if (!ob.points[j].allFinite()) return who + "point " + std::to_string(j) + " is not finite";
        if (j > 0 && !((ob.points[j] - ob.points[j - 1]).norm() > 0.0))
          return who + "segment " + std::to_string(j - 1) + " (points " + std::to_string(j - 1) + " and " +
                 std::to_string(j) + ") has zero length";
      }
      return {};
  }
  return who + "unknown kind";
}

namespace {

// A circle (2D) or a sphere (3D) of centre c and radius r: g = |x - c| - r and n = (x - c)/|x - c|
// outside (inside = false), both negated inside; n = +y at x = c.
template <int D>
ObstacleContactT<D> closest_round(const Eigen::Matrix<double, D, 1>& c, double r, bool inside,
                                  const Eigen::Matrix<double, D, 1>& x) {
  using Vec = Eigen::Matrix<double, D, 1>;
  const Vec v = x - c;
  const double d = v.norm();
  const double sign = inside ? -1.0 : 1.0;
  const Vec radial = d > 0.0 ? Vec(v / d) : Vec(Vec::UnitY());
  return {sign * (d - r), sign * radial};
}

}  // namespace

ObstacleContact closest_circle(const Obstacle& ob, const Vec2& x) {
  return closest_round<2>(ob.center, ob.radius, ob.inside, x);
}

ObstacleContact closest_polyline(const Obstacle& ob, const Vec2& x) {
  const auto& p = ob.points;
  const int segments = static_cast<int>(p.size()) - 1;
  const double side = ob.left ? 1.0 : -1.0;
  auto seg_normal = [&](int j) -> Vec2 {
    const Vec2 e = (p[j + 1] - p[j]).normalized();
    return side * Vec2(-e.y(), e.x());  // left: direction rotated by +90 degrees
  };
  // Nearest feature: per segment, the projection parameter clamped to [0, 1] (not clamped at
  // the free ends of the end segments, which extend as rays).
  double best = std::numeric_limits<double>::infinity();
  double scale = 0.0;
  for (int j = 0; j < segments; ++j) scale = std::max(scale, (p[j + 1] - p[j]).norm());
  // First pass: nearest distance.
  auto feature = [&](int j, int& vertex) -> double {
    const Vec2 e = p[j + 1] - p[j];
    const double s = (x - p[j]).dot(e) / e.squaredNorm();
    vertex = -1;
    if (s <= 0.0 && j > 0) vertex = j;
    else if (s >= 1.0 && j < segments - 1) vertex = j + 1;
    if (vertex >= 0) return (x - p[vertex]).norm();
    return std::abs(seg_normal(j).dot(x - p[j]));
  };
  int first = -1, first_vertex = -1;
  for (int j = 0; j < segments; ++j) {
    int v;
    const double d = feature(j, v);
    if (d < best) {
      best = d;
      first = j;
      first_vertex = v;
    }
  }
  // Signed gap and normal of one feature.
  auto signed_feature = [&](int j, int vertex) -> ObstacleContact {
    if (vertex < 0) {
      const Vec2 n = seg_normal(j);
      return {n.dot(x - p[j]), n};
    }
    const Vec2 r = x - p[vertex];
    const Vec2 b = (seg_normal(vertex - 1) + seg_normal(vertex)).normalized();
    const double d = r.norm();
    if (!(d > 0.0)) return {0.0, b};
    const double sgn = r.dot(b) >= 0.0 ? 1.0 : -1.0;
    return {sgn * d, sgn * r / d};
  };
  ObstacleContact out = signed_feature(first, first_vertex);
  // Ties: the other features within 1e-12 of the length scale add their normals.
  const double tie = 1e-12 * std::max(scale, best);
  Vec2 sum = out.normal;
  int tied = 0;
  for (int j = first + 1; j < segments; ++j) {
    int v;
    const double d = feature(j, v);
    if (!(d - best <= tie)) continue;
    if (v >= 0 && v == first_vertex) continue;  // the same vertex seen from its other segment
    sum += signed_feature(j, v).normal;
    ++tied;
  }
  if (tied > 0 && sum.norm() > 1e-12) out.normal = sum.normalized();
  return out;
}

// ------------------------------------------------------------------------------------------ 3D

namespace {

std::string who(const std::string& name) { return "obstacle \"" + name + "\": "; }

// A direction given to a constructor: finite and non-zero, normalized afterwards.
void check_direction(const std::string& name, const char* what, const Vec3& v) {
  if (!v.allFinite() || !(v.norm() > 0.0))
    throw std::invalid_argument(who(name) + what + " must be finite and non-zero");
}

bool unit(const Vec3& v) { return v.allFinite() && std::abs(v.norm() - 1.0) <= 1e-12; }

}  // namespace

Obstacle3 make_plane_obstacle3(std::string name, const Vec3& point, const Vec3& normal) {
  check_direction(name, "normal", normal);
  return checked(
      Obstacle3{.name = std::move(name), .kind = ObstacleKind3::plane, .point = point, .normal = normal.normalized()});
}

Obstacle3 make_sphere_obstacle3(std::string name, const Vec3& center, double radius, bool inside) {
  return checked(Obstacle3{
      .name = std::move(name), .kind = ObstacleKind3::sphere, .center = center, .radius = radius, .inside = inside});
}

Obstacle3 make_box_obstacle3(std::string name, const Vec3& center, const Vec3& half_extents, bool inside,
                             const Vec3& axis1, const Vec3& axis2) {
  check_direction(name, "axis1", axis1);
  check_direction(name, "axis2", axis2);
  const Vec3 a1 = axis1.normalized();
  const Vec3 v = axis2 - a1.dot(axis2) * a1;  // Gram-Schmidt
  if (!(v.norm() > 1e-12 * axis2.norm())) throw std::invalid_argument(who(name) + "axis2 is parallel to axis1");
  const Vec3 a2 = v.normalized();
  Mat3 axes;
  axes << a1, a2, a1.cross(a2);
  return checked(Obstacle3{.name = std::move(name), .kind = ObstacleKind3::box, .center = center,
                           .inside = inside, .half_extents = half_extents, .axes = axes});
}

Obstacle3 make_cylinder_obstacle3(std::string name, const Vec3& center, const Vec3& axis, double radius,
                                  bool inside, double half_length) {
  check_direction(name, "axis", axis);
  return checked(Obstacle3{.name = std::move(name), .kind = ObstacleKind3::cylinder, .center = center,
                           .radius = radius, .inside = inside, .axis = axis.normalized(), .half_length = half_length});
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
  return closest_round<3>(ob.center, ob.radius, ob.inside, x);
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
