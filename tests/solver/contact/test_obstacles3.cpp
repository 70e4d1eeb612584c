// Rigid obstacles in 3D (solver/contact/obstacle.hpp; docs/three-dimensions.md, Rigid obstacles
// in 3D): the gap and normal of each kind (plane, sphere, box, cylinder) against independent
// computations on random points: the distance by a brute-force minimization over the obstacle's
// boundary, the closest point and normal by an explicit enumeration of the boundary's faces, the
// side by a membership test; the plane against the 2D line (obstacle.hpp) bit for bit; the
// degenerate points and ties; the step frame (exact for a plane, the chord's midpoint for the
// others, below the gap outside the convex solids and above it inside bowls, bins and pipes);
// the constructors' checks; the overloads of the local law for the 3D pair (coulomb.hpp); no heap
// allocation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include <Eigen/Geometry>  // cross()

#include "solver/contact/coulomb.hpp"
#include "solver/contact/contact_space.hpp"
#include "solver/contact/obstacle.hpp"
#include "solver/contact/obstacle.hpp"

#include "tests/support/alloc_counter.hpp"

namespace ricochet {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A unit vector perpendicular to a (the coordinate axis least aligned with a, made perpendicular),
// and the third of a right-handed triple: the test's own basis of the plane normal to a.
void basis_of(const Vec3& a, Vec3& e1, Vec3& e2) {
  Eigen::Index k = 0;
  a.cwiseAbs().minCoeff(&k);
  const Vec3 c = Vec3::Unit(k);
  e1 = (c - a.dot(c) * a).normalized();
  e2 = a.cross(e1);
}

// The smallest distance from x to the surface patch q(u, v), (u, v) in [u0, u1] x [v0, v1], by
// brute force: the squared distance on a 64 x 64 grid, then 56 times a 9 x 9 grid over +-2 cells
// of the best point so far (the cell halves each time: after 56 rounds it is 2^-62 of the patch,
// below round-off). A periodic parameter
// (an angle) is not clamped to its interval there, so that a minimum near its ends is reached
// from either side. The squared distance is smooth and, on every patch used here, has one
// minimum the 64 x 64 grid brackets; the value found is the minimum to a few eps of the patch's
// size (a point sqrt(eps) off the minimizer changes it by eps only).
template <class Q>
double brute_force_distance(const Vec3& x, const Q& q, double u0, double u1, double v0, double v1,
                            bool u_periodic, bool v_periodic) {
  auto f = [&](double u, double v) { return (x - q(u, v)).squaredNorm(); };
  constexpr int kStart = 64, kZoom = 8;
  double bu = u0, bv = v0, best = f(u0, v0);
  for (int i = 0; i <= kStart; ++i)
    for (int j = 0; j <= kStart; ++j) {
      const double u = u0 + (u1 - u0) * i / kStart, v = v0 + (v1 - v0) * j / kStart;
      if (const double d = f(u, v); d < best) best = d, bu = u, bv = v;
    }
  double hu = (u1 - u0) / kStart, hv = (v1 - v0) / kStart;
  for (int round = 0; round < 56; ++round) {
    const double lu = u_periodic ? bu - 2 * hu : std::max(u0, bu - 2 * hu);
    const double uu = u_periodic ? bu + 2 * hu : std::min(u1, bu + 2 * hu);
    const double lv = v_periodic ? bv - 2 * hv : std::max(v0, bv - 2 * hv);
    const double uv = v_periodic ? bv + 2 * hv : std::min(v1, bv + 2 * hv);
    for (int i = 0; i <= kZoom; ++i)
      for (int j = 0; j <= kZoom; ++j) {
        const double u = lu + (uu - lu) * i / kZoom, v = lv + (uv - lv) * j / kZoom;
        if (const double d = f(u, v); d < best) best = d, bu = u, bv = v;
      }
    hu = (uu - lu) / kZoom;
    hv = (uv - lv) / kZoom;
  }
  return std::sqrt(best);
}

// What the tests know about a point, computed without obstacle.cpp: the distance to the
// boundary by brute force, the closest point q and the outward normal (of the solid) by an
// enumeration of the boundary's faces, whether x is inside the solid, and the length scale of
// the comparison (|x - c| + the obstacle's size).
struct Reference {
  double distance = kNaN;  // brute force (when asked for: it is the costly part)
  Vec3 q = Vec3::Zero();  // enumeration
  Vec3 normal = Vec3::Zero();
  bool in_solid = false;
  double scale = 0.0;
  double enumerated = 0.0;  // |x - q| of the enumeration
};

// Sphere: the surface in spherical angles about the test's own basis; the closest point is on
// the ray from the centre (the sphere's one face).
Reference sphere_reference(const Obstacle3& ob, const Vec3& x, bool brute) {
  Reference r;
  const Vec3 c = ob.center;
  Vec3 e1, e2;
  basis_of(Vec3::UnitZ(), e1, e2);
  auto q = [&](double th, double ph) {
    return Vec3(c + ob.radius * (std::sin(th) * (std::cos(ph) * e1 + std::sin(ph) * e2) +
                                 std::cos(th) * Vec3::UnitZ()));
  };
  if (brute)
    r.distance = brute_force_distance(x, q, 0.0, std::numbers::pi, -std::numbers::pi, std::numbers::pi, false, true);
  r.normal = (x - c).normalized();
  r.q = c + ob.radius * r.normal;
  r.in_solid = (x - c).norm() < ob.radius;
  r.scale = (x - c).norm() + ob.radius;
  r.enumerated = (x - r.q).norm();
  return r;
}

// Box: six face rectangles, each q(u, v) = c + s h_i a_i + u a_j + v a_k. Enumeration: the
// nearest point of each rectangle (the in-plane coordinates clamped), the nearest of the six.
Reference box_reference(const Obstacle3& ob, const Vec3& x, bool brute) {
  Reference r;
  const Vec3 c = ob.center, h = ob.half_extents;
  if (brute) r.distance = kInf;
  r.enumerated = kInf;
  r.in_solid = true;
  int face_axis = 0;
  double face_side = 1.0;
  for (int i = 0; i < 3; ++i) {
    const Vec3 ai = ob.axes.col(i);
    if (!(std::abs(ai.dot(x - c)) < h[i])) r.in_solid = false;
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    const Vec3 aj = ob.axes.col(j), ak = ob.axes.col(k);
    for (double s : {-1.0, 1.0}) {
      const Vec3 o = c + s * h[i] * ai;
      auto q = [&](double u, double v) { return Vec3(o + u * aj + v * ak); };
      if (brute) r.distance = std::min(r.distance, brute_force_distance(x, q, -h[j], h[j], -h[k], h[k], false, false));
      const Vec3 qe = q(std::clamp(aj.dot(x - o), -h[j], h[j]), std::clamp(ak.dot(x - o), -h[k], h[k]));
      if (const double d = (x - qe).norm(); d < r.enumerated) {
        r.enumerated = d, r.q = qe, face_axis = i, face_side = s;
      }
    }
  }
  // Outside: along x - q. Inside: x - q is along the face normal, pointing in; outward is the face's.
  r.normal = r.in_solid ? Vec3(face_side * ob.axes.col(face_axis)) : Vec3((x - r.q) / r.enumerated);
  r.scale = (x - c).norm() + h.maxCoeff();
  return r;
}

// Cylinder: the side q(phi, s) = c + s a + r (cos phi e1 + sin phi e2), s over [-L, L] (or a
// window about x's s wide enough for any nearer point when infinite), and the two end disks
// q(rho, phi) = c +- L a + rho (cos phi e1 + sin phi e2). Enumeration: the nearest point of the
// side (s clamped, the radial direction of x) and of each disk (rho clamped to r).
Reference cylinder_reference(const Obstacle3& ob, const Vec3& x, bool brute) {
  Reference r;
  const Vec3 c = ob.center, a = ob.axis;
  const double R = ob.radius, L = ob.half_length;
  const bool capped = std::isfinite(L);
  Vec3 e1, e2;
  basis_of(a, e1, e2);
  const Vec3 dx = x - c;
  const double sx = a.dot(dx);
  const Vec3 radial = (dx - sx * a).normalized();
  auto around = [&](double ph) { return Vec3(std::cos(ph) * e1 + std::sin(ph) * e2); };
  auto side = [&](double ph, double s) { return Vec3(c + s * a + R * around(ph)); };
  const double window = dx.norm() + R;
  const double s0 = capped ? -L : sx - window, s1 = capped ? L : sx + window;
  if (brute) r.distance = brute_force_distance(x, side, -std::numbers::pi, std::numbers::pi, s0, s1, true, false);
  r.q = c + std::clamp(sx, s0, s1) * a + R * radial;
  r.enumerated = (x - r.q).norm();
  bool on_side = true;
  double end_sign = 1.0;
  if (capped) {
    for (double s : {-1.0, 1.0}) {
      auto disk = [&](double rho, double ph) { return Vec3(c + s * L * a + rho * around(ph)); };
      if (brute)
        r.distance = std::min(r.distance,
                              brute_force_distance(x, disk, 0.0, R, -std::numbers::pi, std::numbers::pi, false, true));
      const Vec3 o = c + s * L * a;
      const Vec3 in_plane = (x - o) - a.dot(x - o) * a;
      const Vec3 qe = o + std::min(in_plane.norm(), R) * radial;
      if (const double d = (x - qe).norm(); d < r.enumerated) r.enumerated = d, r.q = qe, on_side = false, end_sign = s;
    }
  }
  r.in_solid = (dx - sx * a).norm() < R && (!capped || std::abs(sx) < L);
  r.normal = !r.in_solid ? Vec3((x - r.q) / r.enumerated) : on_side ? radial : Vec3(end_sign * a);
  r.scale = dx.norm() + (capped ? std::max(R, L) : R);
  return r;
}

Reference reference(const Obstacle3& ob, const Vec3& x, bool brute) {
  switch (ob.kind) {
    case ObstacleKind3::sphere: return sphere_reference(ob, x, brute);
    case ObstacleKind3::box: return box_reference(ob, x, brute);
    case ObstacleKind3::cylinder: return cylinder_reference(ob, x, brute);
    case ObstacleKind3::plane: break;
  }
  ADD_FAILURE() << "no reference for a plane";
  return {};
}

// The boundary's implicit equation at q: 0 on the boundary, the signed excess otherwise [m].
double boundary_residual(const Obstacle3& ob, const Vec3& q) {
  const Vec3 d = q - ob.center;
  switch (ob.kind) {
    case ObstacleKind3::sphere: return d.norm() - ob.radius;
    case ObstacleKind3::box: return ((ob.axes.transpose() * d).cwiseAbs() - ob.half_extents).maxCoeff();
    case ObstacleKind3::cylinder: {
      const double s = ob.axis.dot(d), dr = (d - s * ob.axis).norm() - ob.radius;
      return ob.capped() ? std::max(dr, std::abs(s) - ob.half_length) : dr;
    }
    case ObstacleKind3::plane: break;
  }
  return ob.normal.dot(q - ob.point);
}

Vec3 random_unit(std::mt19937_64& gen) {
  std::normal_distribution<double> gauss;
  for (;;) {
    const Vec3 v(gauss(gen), gauss(gen), gauss(gen));
    if (v.norm() > 1e-3) return v.normalized();
  }
}

// Random obstacles of each curved kind: centres in [-2, 2]^3, sizes in [0.3, 2], random
// orientations; boxes and capped cylinders of every aspect, and infinite cylinders.
std::vector<Obstacle3> random_obstacles(std::mt19937_64& gen, bool inside) {
  std::uniform_real_distribution<double> pos(-2.0, 2.0), size(0.3, 2.0);
  std::vector<Obstacle3> obs;
  for (int k = 0; k < 6; ++k) {
    const Vec3 c(pos(gen), pos(gen), pos(gen));
    obs.push_back(make_sphere_obstacle3("sphere" + std::to_string(k), c, size(gen), inside));
    obs.push_back(make_box_obstacle3("box" + std::to_string(k), c, Vec3(size(gen), size(gen), size(gen)), inside,
                                     random_unit(gen), random_unit(gen)));
    obs.push_back(make_cylinder_obstacle3("can" + std::to_string(k), c, random_unit(gen), size(gen), inside,
                                          size(gen)));
    obs.push_back(make_cylinder_obstacle3("pipe" + std::to_string(k), c, random_unit(gen), size(gen), inside));
  }
  obs.push_back(make_box_obstacle3("aligned", Vec3(0.1, -0.2, 0.3), Vec3(0.5, 1.0, 2.0), inside));
  obs.push_back(make_cylinder_obstacle3("z", Vec3(0.1, -0.2, 0.3), Vec3::UnitZ(), 0.7, inside, 0.4));
  return obs;
}

// Points about an obstacle: uniform in a cube of twice its extent about its centre, and points
// pushed off its boundary along the normal by 1e-3 to 1 of its size (both sides), so that every
// region (faces, edges, corners, rims, ends, inside) is visited.
std::vector<Vec3> points_about(const Obstacle3& ob, std::mt19937_64& gen, int count) {
  const double size = ob.kind == ObstacleKind3::box ? ob.half_extents.maxCoeff()
                      : ob.kind == ObstacleKind3::cylinder && ob.capped() ? std::max(ob.radius, ob.half_length)
                                                                          : ob.radius;
  std::uniform_real_distribution<double> cube(-2.0 * size, 2.0 * size), expo(-3.0, 0.0), sign(-1.0, 1.0);
  std::vector<Vec3> xs;
  for (int k = 0; k < count; ++k) {
    const Vec3 x = ob.center + Vec3(cube(gen), cube(gen), cube(gen));
    xs.push_back(x);
    if (k % 2 == 0) {  // near the boundary, from the closest point of x
      const ObstacleContact3 c = closest(ob, x);
      const Vec3 q = x - c.gap * c.normal;
      xs.push_back(q + (sign(gen) < 0 ? -1.0 : 1.0) * std::pow(10.0, expo(gen)) * size * c.normal);
    }
  }
  return xs;
}

const char* kind_name(ObstacleKind3 k) {
  return k == ObstacleKind3::plane    ? "plane"
         : k == ObstacleKind3::sphere ? "sphere"
         : k == ObstacleKind3::box    ? "box"
                                      : "cylinder";
}

// ---------------------------------------------------------------------------------------------
// The plane

TEST(Obstacles3, PlaneGapIsTheSignedDistance) {
  // Planes through three random points P0, P1, P2, their normal given unnormalized as
  // (P1 - P0) x (P2 - P0). The gap of a random x against the triple product
  // det[P1 - P0, P2 - P0, x - P0] / |(P1 - P0) x (P2 - P0)| (the height of the parallelepiped);
  // q = x - g n in the plane: its height above P0 against the plane's other two points, i.e. the
  // same triple product at q, zero. Tolerances 1e-12 of the scale |x - P0| + |P1 - P0| + |P2 - P0|:
  // both sides are a few rounded operations on numbers of that size (~1e-15), while a wrong sign
  // or an unnormalized normal is off by O(1).
  std::mt19937_64 gen(31);
  std::uniform_real_distribution<double> pos(-3.0, 3.0);
  double worst = 0.0;
  for (int k = 0; k < 2000; ++k) {
    const Vec3 p0(pos(gen), pos(gen), pos(gen)), p1(pos(gen), pos(gen), pos(gen)), p2(pos(gen), pos(gen), pos(gen));
    const Vec3 cross = (p1 - p0).cross(p2 - p0);
    if (cross.norm() < 1e-2) continue;
    const Obstacle3 ob = make_plane_obstacle3("p", p0, cross);
    const Vec3 x(pos(gen), pos(gen), pos(gen));
    const ObstacleContact3 c = closest(ob, x);
    const double scale = (x - p0).norm() + (p1 - p0).norm() + (p2 - p0).norm();
    Mat3 m;
    m << p1 - p0, p2 - p0, x - p0;
    const double height = m.determinant() / cross.norm();
    EXPECT_NEAR(c.gap, height, 1e-12 * scale) << k;
    const Vec3 q = x - c.gap * c.normal;
    m.col(2) = q - p0;
    EXPECT_NEAR(m.determinant() / cross.norm(), 0.0, 1e-12 * scale) << k;
    EXPECT_NEAR(c.normal.norm(), 1.0, 4 * kEps);
    EXPECT_EQ(c.normal, ob.normal);
    worst = std::max(worst, std::abs(c.gap - height) / scale);
  }
  std::printf("[obstacles3] plane: gap against the triple product, max %.2e of the scale\n", worst);
}

TEST(Obstacles3, PlaneIsThe2dLineForANormalInTheXyPlane) {
  // A plane whose normal lies in the xy-plane, against the 2D line with the same point and normal:
  // the normalized normal, the gap and the step frame bit for bit, at z = 0 and at any z (the z
  // term of the gap is an exact zero: the 3D plane is the extruded line). The same arithmetic: the
  // normal's squared norm adds +0, the gap sums its xy part first, as the 2D dot product.
  std::mt19937_64 gen(32);
  std::uniform_real_distribution<double> pos(-3.0, 3.0);
  long compared = 0;
  for (int k = 0; k < 5000; ++k) {
    const Vec2 p(pos(gen), pos(gen)), n(pos(gen), pos(gen));
    if (n.norm() < 1e-3) continue;
    const Obstacle line = make_line_obstacle("l", p, n);
    const Obstacle3 plane = make_plane_obstacle3("l", Vec3(p.x(), p.y(), pos(gen)), Vec3(n.x(), n.y(), 0.0));
    ASSERT_EQ(plane.normal.x(), line.normal.x()) << k;
    ASSERT_EQ(plane.normal.y(), line.normal.y()) << k;
    ASSERT_EQ(plane.normal.z(), 0.0) << k;
    const Vec2 x(pos(gen), pos(gen)), xp(pos(gen), pos(gen));
    for (double z : {0.0, pos(gen)}) {
      const ObstacleContact c2 = closest(line, x);
      const ObstacleContact3 c3 = closest(plane, Vec3(x.x(), x.y(), z));
      EXPECT_EQ(c3.gap, c2.gap) << k;
      EXPECT_EQ(c3.normal, Vec3(c2.normal.x(), c2.normal.y(), 0.0)) << k;
      const ObstacleContact f2 = step_frame(line, x, xp);
      const ObstacleContact3 f3 = step_frame(plane, Vec3(x.x(), x.y(), z), Vec3(xp.x(), xp.y(), -z));
      EXPECT_EQ(f3.gap, f2.gap) << k;
      EXPECT_EQ(f3.normal, Vec3(f2.normal.x(), f2.normal.y(), 0.0)) << k;
      ++compared;
    }
  }
  EXPECT_GT(compared, 9000);
}

// ---------------------------------------------------------------------------------------------
// Sphere, box, cylinder: against brute force and enumeration

TEST(Obstacles3, CurvedKindsAgainstBruteForceAndEnumeration) {
  // For each random obstacle (6 spheres, 6 boxes, 6 capped and 6 infinite cylinders, plus an
  // axis-aligned box and a z cylinder) and each of ~300 points about it:
  // - |g| against the brute-force distance to the boundary (every third point: the brute force
  //   is 10^4 evaluations a face, the cost of the test), to 1e-12 of the scale |x - c| + size
  //   (the brute force finds the minimum to a few eps of the size; the solver's g is a few rounded
  //   operations; a wrong region, sign or formula is off by far more);
  // - sign(g) against membership: g < 0 exactly when x is in the solid (points within 1e-9 of the
  //   scale of the boundary, where the rounding of either side may decide, are left out of this
  //   one check);
  // - |g| against the enumeration's |x - q| to 1e-12 of the scale (the same reason);
  // - n against the enumeration's outward normal (x - q)/|x - q| outside, the nearest face's
  //   normal inside, to 1e-12, for points farther than 1e-3 of the scale from the boundary
  //   (closer, (x - q)/|x - q| itself loses digits: eps scale / |x - q|) and not on a tie (the two
  //   nearest faces within 1e-9 of the scale; ties are tested on their own below);
  // - q = x - g n on the boundary (its implicit equation to 1e-12 of the scale) and |n| = 1 to
  //   4 eps.
  std::mt19937_64 gen(33);
  struct Worst {
    double bf = 0, en = 0, n = 0, q = 0, unit = 0;
    long points = 0, brute = 0, normals = 0, in_solid = 0;
  } worst[4];
  for (const Obstacle3& ob : random_obstacles(gen, false)) {
    Worst& w = worst[static_cast<int>(ob.kind)];
    long index = 0;
    for (const Vec3& x : points_about(ob, gen, 200)) {
      const bool brute = index++ % 3 == 0;
      const ObstacleContact3 c = closest(ob, x);
      const Reference r = reference(ob, x, brute);
      const std::string where = ob.name + " x = (" + std::to_string(x.x()) + ", " + std::to_string(x.y()) + ", " +
                                std::to_string(x.z()) + ")";
      if (brute) {
        EXPECT_NEAR(std::abs(c.gap), r.distance, 1e-12 * r.scale) << where;
        w.bf = std::max(w.bf, std::abs(std::abs(c.gap) - r.distance) / r.scale);
        ++w.brute;
      }
      EXPECT_NEAR(std::abs(c.gap), r.enumerated, 1e-12 * r.scale) << where;
      if (r.enumerated > 1e-9 * r.scale) {
        EXPECT_EQ(c.gap < 0.0, r.in_solid) << where << " gap " << c.gap;
      }
      EXPECT_NEAR(c.normal.norm(), 1.0, 4 * kEps) << where;
      const Vec3 q = x - c.gap * c.normal;
      EXPECT_NEAR(boundary_residual(ob, q), 0.0, 1e-12 * r.scale) << where;
      // A tie: the second-nearest face of the solid within 1e-9 of the scale (inside only).
      bool tie = false;
      if (r.in_solid) {
        if (ob.kind == ObstacleKind3::box) {
          const Vec3 e = (ob.axes.transpose() * (x - ob.center)).cwiseAbs() - ob.half_extents;
          Vec3 sorted = e;
          std::sort(sorted.data(), sorted.data() + 3);
          tie = sorted[2] - sorted[1] <= 1e-9 * r.scale;
        } else if (ob.kind == ObstacleKind3::cylinder && ob.capped()) {
          const double s = ob.axis.dot(x - ob.center);
          const double dr = (x - ob.center - s * ob.axis).norm() - ob.radius, da = std::abs(s) - ob.half_length;
          tie = std::abs(dr - da) <= 1e-9 * r.scale;
        }
      }
      if (r.enumerated > 1e-3 * r.scale && !tie) {
        EXPECT_LE((c.normal - r.normal).norm(), 1e-12) << where;
        w.n = std::max(w.n, (c.normal - r.normal).norm());
        ++w.normals;
      }
      w.en = std::max(w.en, std::abs(std::abs(c.gap) - r.enumerated) / r.scale);
      w.unit = std::max(w.unit, std::abs(c.normal.norm() - 1.0) / kEps);
      w.in_solid += r.in_solid;
      ++w.points;
    }
  }
  for (int k = 1; k < 4; ++k) {
    const Worst& w = worst[k];
    std::printf("[obstacles3] %s: %ld points (%ld in the solid), |g| - brute force (%ld points) max %.2e, "
                "- enumeration max %.2e of the scale; %ld normals, max deviation %.2e; ||n| - 1| max %.1f eps\n",
                kind_name(static_cast<ObstacleKind3>(k)), w.points, w.in_solid, w.brute, w.bf, w.en, w.normals, w.n,
                w.unit);
    EXPECT_GT(w.points, 1000);
    EXPECT_GT(w.brute, 300);
    EXPECT_GT(w.in_solid, 100);  // both sides visited
    EXPECT_GT(w.normals, 500);
  }
}

TEST(Obstacles3, BoxRegionsByHand) {
  // The box [0.5, 1.5] x [1, 3] x [1, 5] (centre (1, 2, 3), half-extents (0.5, 1, 2)): a point
  // off a face, an edge (3-4-5), a corner (2-3-6-7), and inside near the +x face. Tolerances of a
  // few eps of the coordinates (the inputs such as 1.8 are rounded).
  const Obstacle3 box = make_box_obstacle3("b", Vec3(1.0, 2.0, 3.0), Vec3(0.5, 1.0, 2.0), false);
  constexpr double kTol = 4e-15;
  ObstacleContact3 c = closest(box, Vec3(1.8, 2.5, 3.5));  // face +x
  EXPECT_NEAR(c.gap, 0.3, kTol);
  EXPECT_EQ(c.normal, Vec3::UnitX());
  c = closest(box, Vec3(1.8, 3.4, 2.0));  // edge +x +y
  EXPECT_NEAR(c.gap, 0.5, kTol);
  EXPECT_LE((c.normal - Vec3(0.6, 0.8, 0.0)).norm(), kTol);
  c = closest(box, Vec3(0.3, 0.7, 5.6));  // corner -x -y +z: (0.2, 0.3, 0.6), |.| = 0.7
  EXPECT_NEAR(c.gap, 0.7, kTol);
  EXPECT_LE((c.normal - Vec3(-2.0, -3.0, 6.0) / 7.0).norm(), kTol);
  c = closest(box, Vec3(1.2, 2.1, 3.1));  // inside, the +x face 0.3 away
  EXPECT_NEAR(c.gap, -0.3, kTol);
  EXPECT_EQ(c.normal, Vec3::UnitX());
  c = closest(box, Vec3(1.0, 2.0, 4.9));  // inside, the +z face 0.1 away
  EXPECT_NEAR(c.gap, -0.1, kTol);
  EXPECT_EQ(c.normal, Vec3::UnitZ());
  // On the surface: g = 0 exactly for a face point whose coordinates are exact.
  c = closest(box, Vec3(1.5, 2.0, 3.0));
  EXPECT_EQ(c.gap, 0.0);
  EXPECT_EQ(c.normal, Vec3::UnitX());
}

TEST(Obstacles3, CylinderRegionsByHand) {
  // A can along z: centre 0, radius 1, half-length 2. Side, end, rim (3-4-5), inside near the
  // side and near an end, and the same points for the infinite cylinder (no ends).
  const Obstacle3 can = make_cylinder_obstacle3("can", Vec3::Zero(), Vec3::UnitZ(), 1.0, false, 2.0);
  const Obstacle3 pipe = make_cylinder_obstacle3("pipe", Vec3::Zero(), Vec3::UnitZ(), 1.0, false);
  constexpr double kTol = 4e-15;
  ObstacleContact3 c = closest(can, Vec3(1.5, 0.0, 0.5));  // side
  EXPECT_NEAR(c.gap, 0.5, kTol);
  EXPECT_EQ(c.normal, Vec3::UnitX());
  c = closest(can, Vec3(0.2, 0.1, -2.5));  // the -z end
  EXPECT_NEAR(c.gap, 0.5, kTol);
  EXPECT_EQ(c.normal, -Vec3::UnitZ());
  c = closest(can, Vec3(0.0, 1.3, 2.4));  // rim: (0.3, 0.4)
  EXPECT_NEAR(c.gap, 0.5, kTol);
  EXPECT_LE((c.normal - Vec3(0.0, 0.6, 0.8)).norm(), kTol);
  c = closest(can, Vec3(0.6, 0.0, 0.3));  // inside, the side 0.4 away
  EXPECT_NEAR(c.gap, -0.4, kTol);
  EXPECT_EQ(c.normal, Vec3::UnitX());
  c = closest(can, Vec3(0.0, 0.1, 1.9));  // inside, the +z end 0.1 away
  EXPECT_NEAR(c.gap, -0.1, kTol);
  EXPECT_EQ(c.normal, Vec3::UnitZ());
  // The infinite cylinder: the radial distance wherever x is along the axis.
  c = closest(pipe, Vec3(0.0, 1.3, 2.4));
  EXPECT_NEAR(c.gap, 0.3, kTol);
  EXPECT_EQ(c.normal, Vec3::UnitY());
  c = closest(pipe, Vec3(0.0, 0.1, 1e6));
  EXPECT_NEAR(c.gap, -0.9, kTol);
  EXPECT_EQ(c.normal, Vec3::UnitY());
}

TEST(Obstacles3, InsideIsTheSameSurfaceWithTheOtherSide) {
  // inside = true (bowl, bin, pipe interior): the same closest point, g and n negated, bit for bit.
  std::mt19937_64 gen(34), gen_in(34);
  const std::vector<Obstacle3> outs = random_obstacles(gen, false), ins = random_obstacles(gen_in, true);
  ASSERT_EQ(outs.size(), ins.size());
  std::mt19937_64 pts(35);
  long compared = 0;
  for (std::size_t k = 0; k < outs.size(); ++k)
    for (const Vec3& x : points_about(outs[k], pts, 100)) {
      const ObstacleContact3 a = closest(outs[k], x), b = closest(ins[k], x);
      EXPECT_EQ(b.gap, -a.gap) << outs[k].name;
      EXPECT_EQ(b.normal, Vec3(-a.normal)) << outs[k].name;
      ++compared;
    }
  EXPECT_GT(compared, 3000);
}

// ---------------------------------------------------------------------------------------------
// Degenerate points and ties

TEST(Obstacles3, DegeneratePointsUseTheDocumentedNormals) {
  // Sphere centre: n = +y (-y inside), g = -r (+r inside), as the 2D circle.
  const Obstacle3 ball = make_sphere_obstacle3("ball", Vec3(1.0, 2.0, 3.0), 0.5, false);
  const Obstacle3 bowl = make_sphere_obstacle3("bowl", Vec3(1.0, 2.0, 3.0), 0.5, true);
  EXPECT_EQ(closest(ball, ball.center).gap, -0.5);
  EXPECT_EQ(closest(ball, ball.center).normal, Vec3::UnitY());
  EXPECT_EQ(closest(bowl, bowl.center).gap, 0.5);
  EXPECT_EQ(closest(bowl, bowl.center).normal, -Vec3::UnitY());
  // On a cylinder's axis: cylinder_fallback_radial(axis): +y for any axis perpendicular to y
  // (exactly, e.g. along z or x: the extruded 2D circle), +y made perpendicular for a tilted
  // axis, and +z made perpendicular when the axis is within 30 degrees of y.
  EXPECT_EQ(cylinder_fallback_radial(Vec3::UnitZ()), Vec3::UnitY());
  EXPECT_EQ(cylinder_fallback_radial(Vec3::UnitX()), Vec3::UnitY());
  EXPECT_EQ(cylinder_fallback_radial(Vec3::UnitY()), Vec3::UnitZ());
  EXPECT_EQ(cylinder_fallback_radial(-Vec3::UnitY()), Vec3::UnitZ());
  const Vec3 tilted = Vec3(0.0, 0.6, 0.8);  // 53 degrees from y: +y's perpendicular part (0, 0.64, -0.48), /0.8
  EXPECT_LE((cylinder_fallback_radial(tilted) - Vec3(0.0, 0.8, -0.6)).norm(), 4 * kEps);
  const Vec3 steep = Vec3(0.0, 0.8, 0.6);  // 37 degrees from y (cos 0.8 < cos 30 = 0.866): still +y's part
  EXPECT_LE((cylinder_fallback_radial(steep) - Vec3(0.0, 0.6, -0.8)).norm(), 4 * kEps);
  const Vec3 near_y = Vec3(0.0, 0.9, std::sqrt(1.0 - 0.81));  // cos = 0.9 > 0.866: +z made perpendicular
  const Vec3 expect = (Vec3::UnitZ() - near_y.z() * near_y).normalized();
  EXPECT_LE((cylinder_fallback_radial(near_y) - expect).norm(), 4 * kEps);
  std::mt19937_64 gen(36);
  for (int k = 0; k < 1000; ++k) {
    const Vec3 a = random_unit(gen), u = cylinder_fallback_radial(a);
    EXPECT_NEAR(u.norm(), 1.0, 4 * kEps);
    EXPECT_NEAR(u.dot(a), 0.0, 4 * kEps);
  }
  const Obstacle3 pipe = make_cylinder_obstacle3("pipe", Vec3(1.0, 2.0, 3.0), Vec3::UnitZ(), 0.5, false);
  ObstacleContact3 c = closest(pipe, Vec3(1.0, 2.0, -7.0));
  EXPECT_EQ(c.gap, -0.5);
  EXPECT_EQ(c.normal, Vec3::UnitY());
  const Obstacle3 can = make_cylinder_obstacle3("can", Vec3::Zero(), Vec3::UnitX(), 1.0, true, 3.0);
  c = closest(can, Vec3(0.5, 0.0, 0.0));  // on the axis, the side nearest: a can's inside, n = -(+y)
  EXPECT_EQ(c.gap, 1.0);
  EXPECT_EQ(c.normal, -Vec3::UnitY());
}

TEST(Obstacles3, InteriorTiesAddTheTiedNormals) {
  // Inside a box, on the plane where two faces are equally near: g that face distance, n the
  // normalized sum of the two face normals (as the 2D polyline's ties), so that the mirror image
  // of the point gets the mirror image of the normal. The centre of a cube ties all three axes
  // (+ faces: y_i = 0 takes the + side).
  const double s2 = 1.0 / std::sqrt(2.0), s3 = 1.0 / std::sqrt(3.0);
  const Obstacle3 box = make_box_obstacle3("b", Vec3::Zero(), Vec3(1.0, 1.0, 2.0), false);
  ObstacleContact3 c = closest(box, Vec3(0.75, 0.75, 0.1));
  EXPECT_EQ(c.gap, -0.25);
  EXPECT_LE((c.normal - Vec3(s2, s2, 0.0)).norm(), 2 * kEps);
  c = closest(box, Vec3(-0.75, 0.75, -0.1));
  EXPECT_EQ(c.gap, -0.25);
  EXPECT_LE((c.normal - Vec3(-s2, s2, 0.0)).norm(), 2 * kEps);
  // Within 1e-12 of the size (2 m) still a tie; 1e-9 off, the nearer face alone.
  c = closest(box, Vec3(0.75 + 1e-13, 0.75, 0.0));
  EXPECT_LE((c.normal - Vec3(s2, s2, 0.0)).norm(), 2 * kEps);
  c = closest(box, Vec3(0.75 + 1e-9, 0.75, 0.0));
  EXPECT_EQ(c.normal, Vec3::UnitX());
  const Obstacle3 cube = make_box_obstacle3("cube", Vec3::Zero(), Vec3(1.0, 1.0, 1.0), false);
  c = closest(cube, Vec3::Zero());
  EXPECT_EQ(c.gap, -1.0);
  EXPECT_LE((c.normal - Vec3(s3, s3, s3)).norm(), 2 * kEps);
  // A capped cylinder, on the cone where the side and an end are equally near.
  const Obstacle3 can = make_cylinder_obstacle3("can", Vec3::Zero(), Vec3::UnitZ(), 1.0, false, 2.0);
  c = closest(can, Vec3(0.5, 0.0, 1.5));
  EXPECT_EQ(c.gap, -0.5);
  EXPECT_LE((c.normal - Vec3(s2, 0.0, s2)).norm(), 2 * kEps);
  c = closest(can, Vec3(0.0, -0.5, -1.5));
  EXPECT_EQ(c.gap, -0.5);
  EXPECT_LE((c.normal - Vec3(0.0, -s2, -s2)).norm(), 2 * kEps);
}

TEST(Obstacles3, SectionsThroughTheCentreAreThe2dCircle) {
  // A sphere's section z = c_z and a cylinder along z at any z: the 2D circle's gap and normal.
  // The arithmetic is the 2D one plus exact zeros (the z component of x - c is 0, or removed
  // exactly: s a = (0, 0, s)), so the numbers agree to the last bit unless the compiler fuses a
  // multiply-add in the norm of one and not the other: 1 ulp of the scale allowed in the default
  // build, none in a build without contraction (RICOCHET_NO_FP_CONTRACT).
#ifdef RICOCHET_NO_FP_CONTRACT
  constexpr double kUlps = 0.0;
#else
  constexpr double kUlps = 1.0;
#endif
  std::mt19937_64 gen(37);
  std::uniform_real_distribution<double> pos(-3.0, 3.0), size(0.1, 2.0);
  long compared = 0, bitwise = 0;
  for (int k = 0; k < 3000; ++k) {
    const Vec2 c(pos(gen), pos(gen));
    const double r = size(gen), cz = pos(gen);
    const bool inside = k % 2 == 1;
    const Obstacle circle = make_circle_obstacle("c", c, r, inside);
    const Obstacle3 sphere = make_sphere_obstacle3("c", Vec3(c.x(), c.y(), cz), r, inside);
    const Obstacle3 cylinder = make_cylinder_obstacle3("c", Vec3(c.x(), c.y(), cz), Vec3::UnitZ(), r, inside);
    const Vec2 x(pos(gen), pos(gen)), xp(pos(gen), pos(gen));
    const double scale = (x - c).norm() + r;
    const ObstacleContact c2 = closest(circle, x);
    const ObstacleContact f2 = step_frame(circle, x, xp);
    for (const ObstacleContact3& c3 :
         {closest(sphere, Vec3(x.x(), x.y(), cz)), closest(cylinder, Vec3(x.x(), x.y(), pos(gen)))}) {
      EXPECT_NEAR(c3.gap, c2.gap, kUlps * kEps * scale) << k;
      EXPECT_LE((c3.normal - Vec3(c2.normal.x(), c2.normal.y(), 0.0)).norm(), kUlps * kEps) << k;
      EXPECT_EQ(c3.normal.z(), 0.0);
      bitwise += c3.gap == c2.gap && c3.normal == Vec3(c2.normal.x(), c2.normal.y(), 0.0);
      ++compared;
    }
    const double z = pos(gen);
    const ObstacleContact3 f3 = step_frame(cylinder, Vec3(x.x(), x.y(), z), Vec3(xp.x(), xp.y(), z));
    EXPECT_NEAR(f3.gap, f2.gap, 4 * kUlps * kEps * (scale + (xp - x).norm())) << k;
    bitwise += f3.gap == f2.gap;
    ++compared;
  }
  std::printf("[obstacles3] sections: %ld comparisons with the 2D circle, %ld bit for bit\n", compared, bitwise);
}

// ---------------------------------------------------------------------------------------------
// The step frame

TEST(Obstacles3, StepFrameIsExactForAPlaneAndTheMidpointRuleOtherwise) {
  std::mt19937_64 gen(38);
  std::uniform_real_distribution<double> pos(-3.0, 3.0);
  // A plane: closest() at x_pred, bit for bit.
  const Obstacle3 plane = make_plane_obstacle3("p", Vec3(0.1, 0.2, 0.3), Vec3(0.3, 1.0, -0.2));
  for (int k = 0; k < 100; ++k) {
    const Vec3 x0(pos(gen), pos(gen), pos(gen)), xp(pos(gen), pos(gen), pos(gen));
    const ObstacleContact3 a = step_frame(plane, x0, xp), b = closest(plane, xp);
    EXPECT_EQ(a.gap, b.gap);
    EXPECT_EQ(a.normal, b.normal);
  }
  // The others: the normal at the chord's midpoint, the gap linearized from there, bit for bit
  // as written out here.
  for (const Obstacle3& ob : random_obstacles(gen, false)) {
    for (int k = 0; k < 50; ++k) {
      const Vec3 x0 = ob.center + Vec3(pos(gen), pos(gen), pos(gen));
      const Vec3 xp = x0 + 0.1 * Vec3(pos(gen), pos(gen), pos(gen));
      const Vec3 xm = 0.5 * (x0 + xp);
      const ObstacleContact3 m = closest(ob, xm), f = step_frame(ob, x0, xp);
      EXPECT_EQ(f.normal, m.normal) << ob.name;
      EXPECT_EQ(f.gap, m.gap + m.normal.dot(xp - xm)) << ob.name;
    }
  }
  // A node whose step runs along a chord of a great circle of a sphere (a random plane through
  // the centre): the frame's normal is the radial direction at the middle angle, the chord is
  // tangent to it, and the gap is the chord's sagitta, -r (1 - cos(turn / 2)) (not the gap 0 at
  // x_pred, as closest() there would give). To 1e-14: a few rounded operations on unit numbers.
  const Obstacle3 ball = make_sphere_obstacle3("ball", Vec3(0.3, -0.2, 0.1), 1.0, false);
  for (int k = 0; k < 20; ++k) {
    Vec3 e1, e2;
    basis_of(random_unit(gen), e1, e2);
    const double a0 = 0.3 * k, turn = 0.2;
    auto on = [&](double a) { return Vec3(ball.center + std::cos(a) * e1 + std::sin(a) * e2); };
    const ObstacleContact3 f = step_frame(ball, on(a0), on(a0 + turn));
    EXPECT_LE((f.normal - (on(a0 + turn / 2) - ball.center)).norm(), 1e-14) << k;
    EXPECT_NEAR(f.normal.dot(on(a0 + turn) - on(a0)), 0.0, 1e-14) << k;
    EXPECT_NEAR(f.gap, -(1.0 - std::cos(turn / 2)), 1e-14) << k;
    EXPECT_NEAR(closest(ball, on(a0 + turn)).gap, 0.0, 1e-15) << k;
  }
}

TEST(Obstacles3, LinearizedGapBelowTheGapOutsideConvexSolidsAboveItInside) {
  // The signed distance of a convex solid (sphere, box, cylinder with inside = false) is convex,
  // and the step frame's normal at the midpoint is its gradient (away from ties), so the
  // linearized gap g(x_m) + n_m . (x_pred - x_m) is at most the gap at x_pred: a step that the
  // frame lets end at g >= 0 ends outside. For inside = true (bowl, bin, pipe) the gap is the
  // negative of that convex function, concave, and the linearization is at least the gap. Steps
  // from points about each obstacle (all regions) by up to 0.3 of its size in a random direction.
  // Tolerance 8 eps of the scale |x - c| + size: the two sides are equal to second order in short
  // steps and each is rounded to a few eps of the scale.
  std::mt19937_64 gen(39);
  std::uniform_real_distribution<double> step(0.0, 0.3);
  for (bool inside : {false, true}) {
    std::mt19937_64 gen_obs(40);
    long steps = 0, strict = 0;
    for (const Obstacle3& ob : random_obstacles(gen_obs, inside)) {
      const double size = ob.kind == ObstacleKind3::box ? ob.half_extents.maxCoeff()
                          : ob.capped()                  ? std::max(ob.radius, ob.half_length)
                                                         : ob.radius;
      for (const Vec3& x0 : points_about(ob, gen, 100)) {
        const Vec3 xp = x0 + step(gen) * size * random_unit(gen);
        const double linear = step_frame(ob, x0, xp).gap, exact = closest(ob, xp).gap;
        const double tol = 8 * kEps * ((xp - ob.center).norm() + size);
        if (!inside) {
          EXPECT_LE(linear, exact + tol) << ob.name;
        } else {
          EXPECT_GE(linear, exact - tol) << ob.name;
        }
        strict += std::abs(linear - exact) > 1e-6 * size;  // the property is not vacuous
        ++steps;
      }
    }
    std::printf("[obstacles3] linearized gap, inside = %d: %ld steps, %ld with |linear - exact| > 1e-6 size\n",
                inside, steps, strict);
    EXPECT_GT(strict, steps / 10);
  }
}

// ---------------------------------------------------------------------------------------------
// Constructors

TEST(Obstacles3, InvalidGeometryIsRejectedWithTheObstaclesName) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto rejects = [](const char* what, auto make, const std::string& fragment) {
    try {
      make();
      ADD_FAILURE() << what << ": accepted";
    } catch (const std::invalid_argument& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("obstacle \"bad\""), std::string::npos) << what << ": " << m;
      EXPECT_NE(m.find(fragment), std::string::npos) << what << ": " << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << what << ": one line";
    }
  };
  const Vec3 o = Vec3::Zero(), z = Vec3::UnitZ();
  rejects("zero normal", [&] { return make_plane_obstacle3("bad", o, Vec3::Zero()); }, "normal");
  rejects("nan normal", [&] { return make_plane_obstacle3("bad", o, Vec3(nan, 0, 1)); }, "normal");
  rejects("inf point", [&] { return make_plane_obstacle3("bad", Vec3(kInf, 0, 0), z); }, "point");
  rejects("zero radius", [&] { return make_sphere_obstacle3("bad", o, 0.0, false); }, "radius");
  rejects("negative radius", [&] { return make_sphere_obstacle3("bad", o, -1.0, true); }, "radius");
  rejects("nan radius", [&] { return make_sphere_obstacle3("bad", o, nan, false); }, "radius");
  rejects("inf radius", [&] { return make_sphere_obstacle3("bad", o, kInf, false); }, "radius");
  rejects("nan centre", [&] { return make_sphere_obstacle3("bad", Vec3(0, nan, 0), 1.0, false); }, "center");
  rejects("zero half-extent", [&] { return make_box_obstacle3("bad", o, Vec3(1, 0, 1), false); }, "half_extents");
  rejects("negative half-extent", [&] { return make_box_obstacle3("bad", o, Vec3(1, 1, -1), false); },
          "half_extents");
  rejects("inf half-extent", [&] { return make_box_obstacle3("bad", o, Vec3(1, kInf, 1), false); }, "half_extents");
  rejects("inf box centre", [&] { return make_box_obstacle3("bad", Vec3(kInf, 0, 0), Vec3(1, 1, 1), false); },
          "center");
  rejects("zero axis1", [&] { return make_box_obstacle3("bad", o, Vec3(1, 1, 1), false, Vec3::Zero()); }, "axis1");
  rejects("parallel axes",
          [&] { return make_box_obstacle3("bad", o, Vec3(1, 1, 1), false, Vec3(1, 2, 3), Vec3(-2, -4, -6)); },
          "parallel");
  rejects("zero cylinder axis", [&] { return make_cylinder_obstacle3("bad", o, Vec3::Zero(), 1.0, false); }, "axis");
  rejects("zero cylinder radius", [&] { return make_cylinder_obstacle3("bad", o, z, 0.0, false); }, "radius");
  rejects("zero half-length", [&] { return make_cylinder_obstacle3("bad", o, z, 1.0, false, 0.0); }, "half_length");
  rejects("nan half-length", [&] { return make_cylinder_obstacle3("bad", o, z, 1.0, false, nan); }, "half_length");
  rejects("negative half-length", [&] { return make_cylinder_obstacle3("bad", o, z, 1.0, false, -2.0); },
          "half_length");
  // Built directly: obstacle_error checks what the constructors would have made.
  Obstacle3 ob;
  ob.name = "bad";
  EXPECT_EQ(obstacle_error(ob), "");  // the default: the ground y >= 0
  ob.normal = Vec3(0.0, 2.0, 0.0);
  EXPECT_NE(obstacle_error(ob).find("normal must be a finite unit vector"), std::string::npos);
  ob.normal = Vec3::UnitY();
  ob.inside = true;
  EXPECT_NE(obstacle_error(ob).find("inside"), std::string::npos);
  ob = make_box_obstacle3("bad", o, Vec3(1, 1, 1), false);
  ob.axes(0, 1) = 1e-9;
  EXPECT_NE(obstacle_error(ob).find("orthonormal"), std::string::npos);
  ob = make_cylinder_obstacle3("bad", o, z, 1.0, false);
  ob.axis = Vec3(0.0, 0.0, 1.0 + 1e-9);
  EXPECT_NE(obstacle_error(ob).find("axis"), std::string::npos);
  // Accepted: the plane's normal and the cylinder's axis normalized; the box's axes completed to
  // a right-handed orthonormal triple from two directions that are not perpendicular.
  EXPECT_EQ(make_plane_obstacle3("p", o, Vec3(0.0, 0.0, 5.0)).normal, Vec3::UnitZ());
  EXPECT_EQ(make_cylinder_obstacle3("c", o, Vec3(3.0, 0.0, 0.0), 1.0, false).axis, Vec3::UnitX());
  const Obstacle3 tilted = make_box_obstacle3("b", o, Vec3(1, 2, 3), false, Vec3(1, 1, 0), Vec3(0, 1, 0));
  EXPECT_LE((tilted.axes.transpose() * tilted.axes - Mat3::Identity()).cwiseAbs().maxCoeff(), 4 * kEps);
  EXPECT_NEAR(tilted.axes.determinant(), 1.0, 4 * kEps);
  EXPECT_LE((tilted.axes.col(1) - Vec3(-1.0, 1.0, 0.0) / std::sqrt(2.0)).norm(), 4 * kEps);
}

// ---------------------------------------------------------------------------------------------
// The no-suffix overloads of the 3D local law

// A dimension-generic caller, as the schemes will be: one update and the pair's length.
template <class Pair>
double generic_step(const Pair& r, const Pair& x, double w, double mu, double rho, Pair& out) {
  out = bipotential_update(r, x, w, mu, rho);
  return local_norm(out);
}

TEST(Obstacles3, CoulombOverloadsServeGenericCallers) {
  // The 2D calls are untouched by the 3D overloads: a braced pair still means a LocalPair
  // (checked at compile time), and a generic caller reaches both dimensions.
  static_assert(std::is_same_v<decltype(project_coulomb({1.0, 0.3}, 0.3)), LocalPair>);
  static_assert(std::is_same_v<decltype(closed_form_reaction({1.0, 0.3}, 1.0, 0.3)), LocalPair>);
  static_assert(std::is_same_v<decltype(project_coulomb(LocalPair3d{}, 0.3)), LocalPair3d>);
  auto same = [](const LocalPair3d& a, const LocalPair3d& b) { return a.n == b.n && a.t == b.t; };
  std::mt19937_64 gen(41);
  std::uniform_real_distribution<double> uni(-3.0, 3.0), unit(0.0, 1.0);
  long checked = 0;
  for (int k = 0; k < 2000; ++k) {
    const double mu = k % 5 == 0 ? 0.0 : 2.0 * unit(gen), w = std::exp(uni(gen)), rho = std::exp(uni(gen)) / w;
    const LocalPair3d r{uni(gen), Vec2(uni(gen), uni(gen))}, x{uni(gen), Vec2(uni(gen), uni(gen))};
    EXPECT_EQ(local_norm(r), std::hypot(r.n, std::hypot(r.t.x(), r.t.y())));
    // The generic caller: 3D as the direct call, 2D as coulomb.hpp's.
    LocalPair3d out3;
    EXPECT_EQ(generic_step(r, x, w, mu, rho, out3), local_norm(bipotential_update(r, x, w, mu, rho)));
    EXPECT_TRUE(same(out3, bipotential_update(r, x, w, mu, rho)));
    const LocalPair r2{r.n, r.t.x()}, x2{x.n, x.t.x()};
    LocalPair out2;
    const double len2 = generic_step(r2, x2, w, mu, rho, out2);
    const LocalPair ref2 = bipotential_update(r2, x2, w, mu, rho);
    EXPECT_EQ(out2.n, ref2.n);
    EXPECT_EQ(out2.t, ref2.t);
    EXPECT_EQ(len2, std::hypot(ref2.n, ref2.t));
    // A 3D pair with one tangential component zero has the 2D pair's length exactly.
    EXPECT_EQ(local_norm(LocalPair3d{r2.n, Vec2(r2.t, 0.0)}), local_norm(r2));
    ++checked;
  }
  EXPECT_EQ(checked, 2000);
}

// ---------------------------------------------------------------------------------------------
// No heap allocation

TEST(Obstacles3, QueriesDoNotAllocate) {
  // closest() and step_frame() run for every candidate node and step; fixed-size Eigen types
  // only. The counter (alloc_counter.hpp) is first seen to count, so that a zero proves something.
  long before = g_allocations.load();
  {
    std::vector<double> probe(64, 1.0);
    asm volatile("" : : "g"(probe.data()) : "memory");
  }
  ASSERT_GE(g_allocations.load() - before, 1) << "the counter counts";
  std::mt19937_64 gen(42);
  std::vector<Obstacle3> obs = random_obstacles(gen, false);
  obs.push_back(make_plane_obstacle3("p", Vec3::Zero(), Vec3(1.0, 2.0, 3.0)));
  std::uniform_real_distribution<double> pos(-4.0, 4.0);
  std::vector<Vec3> xs(512);
  for (Vec3& x : xs) x = Vec3(pos(gen), pos(gen), pos(gen));
  double sink = 0.0;
  before = g_allocations.load();
  for (const Obstacle3& ob : obs)
    for (std::size_t k = 0; k + 1 < xs.size(); ++k) {
      const ObstacleContact3 c = closest(ob, xs[k]), f = step_frame(ob, xs[k], xs[k + 1]);
      sink += c.gap + f.gap + ContactFrame<3>(f.normal).t1.x();
    }
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace ricochet
