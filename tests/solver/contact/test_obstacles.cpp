// Rigid obstacles beyond lines: closest() for lines, circles and polylines, and small bodies
// dropped onto a peg (circle) and into a V (polyline) in the three schemes.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "solver/contact/obstacle.hpp"
#include "solver/contact/penalty_contact.hpp"
#include "solver/schemes/implicit.hpp"
#include "solver/schemes/explicit.hpp"
#include "tests/support/verification_meshes.hpp"

using namespace ricochet;
using namespace ricochet::verification;

namespace {

using Points = std::vector<Vec2, Eigen::aligned_allocator<Vec2>>;
constexpr double kTol = 1e-14;

void expect_near_vec(const Vec2& a, const Vec2& b, double tol = kTol) {
  EXPECT_NEAR(a.x(), b.x(), tol);
  EXPECT_NEAR(a.y(), b.y(), tol);
}

}  // namespace

TEST(Obstacles, LineIsTheOriginalFormula) {
  const Obstacle ob = make_line_obstacle("l", Vec2(1.0, 2.0), Vec2(0.0, 3.0));
  const Vec2 x(0.3, 2.5);
  const ObstacleContact c = closest(ob, x);
  EXPECT_EQ(c.gap, Vec2::UnitY().dot(x - Vec2(1.0, 2.0)));
  EXPECT_EQ(c.normal, Vec2::UnitY());
  expect_near_vec(c.tangent(), Vec2(1.0, 0.0));
  // Aggregate form of the former Obstacle still works.
  const Obstacle old{"ground", Vec2::Zero(), Vec2::UnitY()};
  EXPECT_EQ(closest(old, Vec2(0.0, -0.25)).gap, -0.25);
}

TEST(Obstacles, CircleOutsideAndInside) {
  const Obstacle peg = make_circle_obstacle("peg", Vec2(1.0, 1.0), 0.5, false);
  ObstacleContact c = closest(peg, Vec2(1.0, 2.0));
  EXPECT_NEAR(c.gap, 0.5, kTol);
  expect_near_vec(c.normal, Vec2(0.0, 1.0));
  c = closest(peg, Vec2(1.3, 1.4));  // inside the disk: negative, radial outward
  EXPECT_NEAR(c.gap, -0.0, kTol);
  c = closest(peg, Vec2(1.0 + 0.3, 1.0));
  EXPECT_NEAR(c.gap, -0.2, kTol);
  expect_near_vec(c.normal, Vec2(1.0, 0.0));
  c = closest(peg, Vec2(1.0, 1.0));  // centre: n = +y by convention
  EXPECT_NEAR(c.gap, -0.5, kTol);
  expect_near_vec(c.normal, Vec2(0.0, 1.0));

  const Obstacle ring = make_circle_obstacle("ring", Vec2(0.0, 0.0), 2.0, true);
  c = closest(ring, Vec2(0.0, -1.5));
  EXPECT_NEAR(c.gap, 0.5, kTol);
  expect_near_vec(c.normal, Vec2(0.0, 1.0));  // towards the centre
  c = closest(ring, Vec2(3.0, 0.0));
  EXPECT_NEAR(c.gap, -1.0, kTol);
  expect_near_vec(c.normal, Vec2(-1.0, 0.0));
  expect_near_vec(c.tangent(), Vec2(0.0, 1.0));
}

TEST(Obstacles, PolylineSegmentsCornersAndRays) {
  // A V opening upwards, allowed side left of travel = above.
  const Obstacle vee = make_polyline_obstacle("v", Points{{-1.0, 1.0}, {0.0, 0.0}, {1.0, 1.0}}, true);
  const double s = 1.0 / std::sqrt(2.0);
  ObstacleContact c = closest(vee, Vec2(0.5, 0.6));  // above the right arm
  EXPECT_NEAR(c.gap, 0.1 * s, kTol);
  expect_near_vec(c.normal, Vec2(-s, s));
  c = closest(vee, Vec2(-0.5, 0.4));  // below the left arm: negative
  EXPECT_NEAR(c.gap, -0.1 * s, kTol);
  expect_near_vec(c.normal, Vec2(s, s));
  c = closest(vee, Vec2(0.0, -0.3));  // behind the concave corner: vertex distance, negative
  EXPECT_NEAR(c.gap, -0.3, kTol);
  expect_near_vec(c.normal, Vec2(0.0, 1.0));
  c = closest(vee, Vec2(0.0, 0.5));  // on the bisector: tie, n = bisector
  EXPECT_NEAR(c.gap, 0.5 * s, 1e-12);
  expect_near_vec(c.normal, Vec2(0.0, 1.0), 1e-12);
  c = closest(vee, Vec2(3.0, 2.0));  // beyond the last point: the end ray y = x
  EXPECT_NEAR(c.gap, -1.0 * s, kTol);
  expect_near_vec(c.normal, Vec2(-s, s));

  // The same chain with side = right: a ridge (allowed below); the corner is convex.
  const Obstacle ridge = make_polyline_obstacle("r", Points{{-1.0, 1.0}, {0.0, 0.0}, {1.0, 1.0}}, false);
  c = closest(ridge, Vec2(0.0, -0.3));  // in the corner's wedge: vertex distance, positive
  EXPECT_NEAR(c.gap, 0.3, kTol);
  expect_near_vec(c.normal, Vec2(0.0, -1.0));
  c = closest(ridge, Vec2(0.3, -0.4));
  EXPECT_NEAR(c.gap, 0.5, kTol);
  expect_near_vec(c.normal, Vec2(0.6, -0.8));
  c = closest(ridge, Vec2(0.5, 0.6));
  EXPECT_NEAR(c.gap, -0.1 * s, kTol);
  expect_near_vec(c.normal, Vec2(s, -s));

  // A 2-point polyline is a line.
  const Obstacle flat = make_polyline_obstacle("f", Points{{0.0, 0.0}, {1.0, 0.0}}, true);
  c = closest(flat, Vec2(5.0, -0.2));
  EXPECT_NEAR(c.gap, -0.2, kTol);
  expect_near_vec(c.normal, Vec2(0.0, 1.0));
}

TEST(Obstacles, StepFrameAtTheChordMidpointForCurvedObstacles) {
  // A line: the gap at the predicted point and the line's normal, bit for bit as closest().
  const Obstacle line = make_line_obstacle("l", {0.0, 0.1}, {0.3, 1.0});
  const Vec2 x0(0.2, 0.15), xp(0.35, 0.05);
  const ObstacleContact a = step_frame(line, x0, xp), b = closest(line, xp);
  EXPECT_EQ(a.gap, b.gap);
  EXPECT_EQ(a.normal, b.normal);
  // A circle: the normal at the chord's midpoint, the gap linearized from there.
  const Obstacle peg = make_circle_obstacle("c", {0.0, 0.0}, 1.0, false);
  const double turn = 0.2;  // a node whose step runs along a chord of the circle
  const Vec2 s0(std::cos(0.5), std::sin(0.5)), s1(std::cos(0.5 + turn), std::sin(0.5 + turn));
  const ObstacleContact f = step_frame(peg, s0, s1);
  EXPECT_TRUE(f.normal.isApprox(Vec2(std::cos(0.5 + turn / 2), std::sin(0.5 + turn / 2)), 1e-14));
  EXPECT_NEAR(f.normal.dot(s1 - s0), 0.0, 1e-15);  // the chord is tangent to the frame
  EXPECT_NEAR(f.gap, -(1.0 - std::cos(turn / 2)), 1e-14);
  // Below the gap everywhere outside the circle (convex): the end position keeps g >= 0.
  for (int k = 0; k < 50; ++k) {
    const double th = 0.37 * k, r0 = 1.0 + 0.02 * (k % 5), r1 = 0.98 + 0.03 * (k % 7);
    const Vec2 p0 = r0 * Vec2(std::cos(th), std::sin(th)), p1 = r1 * Vec2(std::cos(th + 0.1), std::sin(th + 0.1));
    EXPECT_LE(step_frame(peg, p0, p1).gap, closest(peg, p1).gap + 1e-15) << k;
  }
}

TEST(Obstacles, InvalidGeometryIsRejected) {
  EXPECT_THROW(make_circle_obstacle("c", Vec2::Zero(), 0.0, false), std::invalid_argument);
  EXPECT_THROW(make_polyline_obstacle("p", Points{{0.0, 0.0}}, true), std::invalid_argument);
  EXPECT_THROW(make_polyline_obstacle("p", Points{{0.0, 0.0}, {1.0, 0.0}, {1.0, 0.0}}, true),
               std::invalid_argument);
  EXPECT_THROW(make_line_obstacle("l", Vec2::Zero(), Vec2::Zero()), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// Drops: a 20 mm x 10 mm block (4 x 2 Q4) with gravity, starting 1 mm above the obstacle.

namespace {

enum class Scheme { semi_explicit, penalty, implicit };

struct Drop {
  RunResult result;
  double mass = 0.0, initial_energy = 0.0;
};

Drop drop(Scheme scheme, const Obstacle& ob, double y0, double mu, double end_time,
          const ImplicitSettings& implicit = {}) {
  Mesh mesh = grid_mesh(0.02, 0.01, 4, 2, 0.0, false);
  mesh.nodes.row(1).array() += y0;
  const Material mat = StVenantKirchhoff::make(1e7, 0.3, 1000.0, PlaneMode::stress);
  Model<2> model = single_body_model(mesh, mat, PlaneMode::stress, ElementKind::q4_full, 0.01, 0.1,
                                  Vec2(0.0, -100.0));
  for (int i = 0; i < model.num_nodes(); ++i) model.initial_velocity[2 * i + 1] = -0.2;
  RunSettings set;
  set.obstacles = std::vector<Obstacle>{ob};
  set.friction = {{mu}};
  set.end_time = end_time;
  set.sample_interval = 0.0;
  set.energy_growth_limit = 1e9;
  Drop d;
  d.mass = 0.5 * model.mass.sum();
  d.initial_energy = 0.5 * d.mass * 0.04;
  if (scheme == Scheme::penalty) {
    set.contact_method = RunSettings::ContactMethod::penalty;
    const PenaltyContact p = make_penalty_contact(model, obstacles_of(set, model), set.friction, {}, set.penalty);
    set.dt = penalty_stable_time_step(model, p, 0.5);
  } else {
    set.dt = 0.5 * model.critical_dt;
  }
  d.result = scheme == Scheme::implicit ? run_implicit(model, set, implicit) : run_explicit(model, set);
  return d;
}

// Mean of a history column over the last quarter of the run.
double tail_mean(const RunResult& r, const std::string& col) {
  const History& h = r.history;
  const std::size_t c = h.column(col), n = h.rows(), from = n - n / 4;
  double s = 0.0;
  for (std::size_t i = from; i < n; ++i) s += h.at(i, c);
  return s / static_cast<double>(n - from);
}

double max_abs(const RunResult& r, const std::string& col) {
  const History& h = r.history;
  const std::size_t c = h.column(col);
  double m = 0.0;
  for (std::size_t i = 0; i < h.rows(); ++i) m = std::max(m, std::abs(h.at(i, c)));
  return m;
}

void check_rest(const char* what, Scheme scheme, const Drop& d, double vy_rest) {
  const RunResult& r = d.result;
  ASSERT_EQ(r.status, RunStatus::ok) << what << ": " << r.reason;
  const double p0 = d.mass * 0.2;
  const double vy_tail = std::abs(tail_mean(r, "momentum_y")) / d.mass;
  // Energy balance E = kinetic + strain (+ penalty springs) - work of gravity.
  const std::size_t ce = r.history.column("total_energy"), cw = r.history.column("external_work");
  auto balance = [&](std::size_t i) { return r.history.at(i, ce) - r.history.at(i, cw); };
  double e_max = -1e300;
  for (std::size_t i = 0; i < r.history.rows(); ++i) e_max = std::max(e_max, balance(i));
  const double e0 = balance(0);
  const double pen = r.penetration_max;
  const double e_end = r.history.at(r.history.rows() - 1, r.history.column("total_energy")) -
                      r.history.at(r.history.rows() - 1, r.history.column("external_work"));
  std::printf("[obstacles] %s: penetration_max %.3e m, tail |v_y| %.3e m/s, max |p_x| / p0 %.2e, "
              "energy_error_max %.3e, total energy start %.3e max %.3e end %.3e J\n",
              what, pen, vy_tail, max_abs(r, "momentum_x") / p0, r.energy_error_max, e0, e_max, e_end);
  // Energy sane: contact never creates energy (the bi-potential impacts dissipate).
  // (Penalty: the springs' entry/exit error of the explicit step, ~1e-3 here.)
  EXPECT_LT(e_max, e0 * (1.0 + (scheme == Scheme::penalty ? 1e-2 : 1e-6))) << what;
  EXPECT_LT(vy_tail, vy_rest) << what << ": comes to rest";
  if (scheme == Scheme::penalty) {
    EXPECT_GT(pen, 0.0) << what;
    EXPECT_LT(pen, 5e-4) << what << ": penalty penetration bounded (block height 10 mm)";
  } else {
    EXPECT_LT(pen, 1e-12) << what << ": no penetration beyond round-off";
  }
  EXPECT_TRUE(std::isfinite(r.energy_error_max));
}

const char* name(Scheme s) {
  return s == Scheme::semi_explicit ? "semi_explicit" : s == Scheme::penalty ? "penalty" : "implicit";
}

}  // namespace

TEST(Obstacles, BlockOnPegComesToRest) {
  // Peg of radius 5 mm under the block's centre, top at y = 0; block bottom at y = 1 mm.
  const Obstacle peg = make_circle_obstacle("peg", Vec2(0.01, -0.005), 0.005, false);
  for (Scheme s : {Scheme::semi_explicit, Scheme::penalty, Scheme::implicit}) {
    const Drop d = drop(s, peg, 0.001, 0.3, 0.1);
    check_rest((std::string("peg ") + name(s)).c_str(), s, d, 0.05);
  }
}

TEST(Obstacles, SymmetricFrictionlessDropIntoVConservesXMomentum) {
  // V with vertex (0.01, 0) and 45-degree arms; the block's bottom corners touch at y0 = 10 mm.
  const Obstacle vee =
      make_polyline_obstacle("vee", Points{{-0.01, 0.02}, {0.01, 0.0}, {0.03, 0.02}}, true);
  // The implicit scheme with full Newton (a new factor every iteration): each step then ends
  // far below the Newton tolerance, at round-off, like the explicit schemes. Its default
  // modified Newton stops just below the tolerance (|G| <= 1e-10 x the momentum scale), which
  // leaves an asymmetry of that order: checked separately below, as does the mass iteration that
  // `auto` picks at this step (docs/implicit.md), which also stops just below the tolerance.
  ImplicitSettings full_newton;
  full_newton.linear_solver = LinearSolverKind::direct;
  full_newton.refactor_contraction = 0.0;
  for (Scheme s : {Scheme::semi_explicit, Scheme::penalty, Scheme::implicit}) {
    const Drop d = drop(s, vee, 0.011, 0.0, 0.03, full_newton);
    // Over 30 ms the block is wedged in the V (its mean vertical velocity ~0 against a free-fall
    // speed of 3.2 m/s; the elastic vibration of the impact remains: no damping). Over longer
    // runs the frictionless wedged block's rocking amplifies round-off asymmetry (measured:
    // |p_x| ~ p0 by 100 ms), so the symmetry check stops at 30 ms.
    check_rest((std::string("vee ") + name(s)).c_str(), s, d, 0.3);
    const double p0 = d.mass * 0.2;
    EXPECT_LT(max_abs(d.result, "momentum_x"), 1e-7 * p0) << name(s) << ": x-momentum of a symmetric drop";
  }
  // The default (auto: the mass iteration at this step; before it, modified Newton): measured max
  // |p_x| = 1.14e-7 p0 (modified Newton: 1.35e-7; full Newton above: 3.2e-8 when this was
  // written, 9.57e-8 since b9e72f0 at the latest, 4 % under its bound: the wedged block's
  // rocking amplifies round-off, so a change of summation order in the implicit step can move
  // it), the Newton tolerance's level; bound 1e-6 p0, about 7 x the measurement.
  const Drop d = drop(Scheme::implicit, vee, 0.011, 0.0, 0.03);
  std::printf("[obstacles] vee implicit, default solver: max |p_x| / p0 %.2e\n",
              max_abs(d.result, "momentum_x") / (d.mass * 0.2));
  EXPECT_LT(max_abs(d.result, "momentum_x"), 1e-6 * d.mass * 0.2) << "implicit, default solver";
}
