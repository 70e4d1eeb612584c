#include "solver/contact/obstacle.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace ricochet {

Obstacle make_line_obstacle(std::string name, const Vec2& point, const Vec2& normal) {
  Obstacle ob;
  ob.name = std::move(name);
  ob.kind = ObstacleKind::line;
  ob.point = point;
  ob.normal = normal.norm() > 0.0 ? Vec2(normal.normalized()) : normal;
  if (const std::string e = obstacle_error(ob); !e.empty()) throw std::invalid_argument(e);
  return ob;
}

Obstacle make_circle_obstacle(std::string name, const Vec2& center, double radius, bool inside) {
  Obstacle ob;
  ob.name = std::move(name);
  ob.kind = ObstacleKind::circle;
  ob.center = center;
  ob.radius = radius;
  ob.inside = inside;
  if (const std::string e = obstacle_error(ob); !e.empty()) throw std::invalid_argument(e);
  return ob;
}

Obstacle make_polyline_obstacle(std::string name, std::vector<Vec2, Eigen::aligned_allocator<Vec2>> points,
                                bool left) {
  Obstacle ob;
  ob.name = std::move(name);
  ob.kind = ObstacleKind::polyline;
  ob.points = std::move(points);
  ob.left = left;
  if (const std::string e = obstacle_error(ob); !e.empty()) throw std::invalid_argument(e);
  return ob;
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

ObstacleContact closest_circle(const Obstacle& ob, const Vec2& x) {
  const Vec2 r = x - ob.center;
  const double d = r.norm();
  const double sign = ob.inside ? -1.0 : 1.0;
  const Vec2 radial = d > 0.0 ? Vec2(r / d) : Vec2(Vec2::UnitY());
  return {sign * (d - ob.radius), sign * radial};
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

}  // namespace ricochet
