// Contact between deformable bodies, node to segment (solver/contact/body_contact.hpp), in the three
// schemes: the segment choice, momentum conservation to round-off (the contact forces between
// two bodies sum to zero), frictional sliding across many master segments, and no allocation
// in a step.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "harness/input/case_setup.hpp"
#include "harness/input/case_spec.hpp"
#include "harness/input/input_error.hpp"
#include "harness/input/mesh_generators.hpp"
#include "solver/contact/bipotential_contact.hpp"
#include "solver/contact/penalty_contact.hpp"
#include "solver/schemes/central_difference.hpp"
#include "solver/schemes/explicit.hpp"
#include "solver/schemes/implicit.hpp"
// Last: it declares the C allocation functions that Eigen's headers declare differently.
#include "tests/support/alloc_counter.hpp"

namespace ricochet {
namespace {

BodyInput<2> bar(const std::string& name, double width, double height, int nx, int ny, Vec2 origin, Vec2 velocity,
              double young = 2.0e11, double density = 8000.0) {
  RectangleSpec r;
  r.width = width;
  r.height = height;
  r.nx = nx;
  r.ny = ny;
  r.origin = origin;
  BodyInput<2> b;
  b.name = name;
  b.mesh = make_rectangle(r);
  b.material = StVenantKirchhoff::make(young, 0.0, density, PlaneMode::stress);
  b.thickness = 0.02;
  b.initial_velocity = velocity;
  return b;
}

std::vector<double> column(const History& h, const std::string& name) {
  const std::size_t c = h.column(name);
  std::vector<double> out(h.rows());
  for (std::size_t i = 0; i < h.rows(); ++i) out[i] = h.at(i, c);
  return out;
}

enum class Scheme { semi_explicit, penalty, implicit };
const char* name(Scheme s) {
  return s == Scheme::semi_explicit ? "semi_explicit" : s == Scheme::penalty ? "explicit_penalty" : "implicit";
}

RunResult run(const Model<2>& model, RunSettings s, Scheme scheme) {
  if (scheme == Scheme::penalty) {
    s.contact_method = RunSettings::ContactMethod::penalty;
    const PenaltyContact p = make_penalty_contact(model, obstacles_of(s, model), s.friction, s.prescribed, s.penalty, s.body_pairs);
    s.dt = std::min(s.dt, penalty_stable_time_step(model, p, 0.9));
  }
  if (scheme == Scheme::implicit) return run_implicit(model, s, ImplicitSettings{});
  return run_explicit(model, s);
}

TEST(BodyContact, SurfaceIsTheOrientedBoundary) {
  const Model<2> model = build_model({bar("b", 2.0, 1.0, 2, 1, Vec2::Zero(), Vec2::Zero())}, PlaneMode::stress, Vec2::Zero());
  const Surface s = make_surface(model, 0);
  ASSERT_EQ(s.segments.size(), 6u);
  EXPECT_DOUBLE_EQ(s.max_length, 1.0);
  EXPECT_EQ(s.nodes.size(), 6u);
  for (const SurfaceSegment& sg : s.segments) {
    // The chain is closed and the body is on the left: the outward normal points away from the
    // centre (1, 0.5).
    ASSERT_GE(sg.prev, 0);
    ASSERT_GE(sg.next, 0);
    EXPECT_EQ(s.segments[sg.next].a, sg.b);
    EXPECT_EQ(s.segments[sg.prev].b, sg.a);
    const Vec2 a = model.ref.col(sg.a), b = model.ref.col(sg.b);
    const SegmentProjection p = project_on_segment(a, b, 0.5 * (a + b));
    EXPECT_GT(p.normal.dot(0.5 * (a + b) - Vec2(1.0, 0.5)), 0.0);
  }
}

TEST(BodyContact, SegmentChoice) {
  // Master: the unit square [0, 2] x [0, 1] of 2 cells. Slave points are given directly.
  const Model<2> model = build_model({bar("m", 2.0, 1.0, 2, 1, Vec2::Zero(), Vec2::Zero())}, PlaneMode::stress, Vec2::Zero());
  const Surface s = make_surface(model, 0);
  std::vector<Vec2, Eigen::aligned_allocator<Vec2>> x(model.num_nodes() + 1), v(model.num_nodes() + 1);
  for (int j = 0; j < model.num_nodes(); ++j) x[j] = model.ref.col(j), v[j] = Vec2::Zero();
  const int p = model.num_nodes();  // the slave point
  auto pos = [&](int j) { return x[j]; };
  auto vel = [&](int j) { return v[j]; };
  auto find = [&](Vec2 at, Vec2 velocity, int tracked = -1) {
    x[p] = at;
    v[p] = velocity;
    return find_segment(s, p, tracked, pos, pos, vel);
  };
  auto top = [&](const NodeSegment& r) { return r.segment >= 0 && r.normal.isApprox(Vec2(0, 1)); };
  auto right = [&](const NodeSegment& r) { return r.segment >= 0 && r.normal.isApprox(Vec2(1, 0)); };

  // Just inside the top face: the top face, negative gap, xi along it.
  NodeSegment r = find({0.5, 1.0 - 1e-3}, {0, -1});
  EXPECT_TRUE(top(r));
  EXPECT_NEAR(r.gap, -1e-3, 1e-15);
  EXPECT_NEAR(r.xi, 0.5, 1e-12);
  // Exactly on the top-right corner: a tie between the top and the right face, resolved by the
  // approach direction.
  EXPECT_TRUE(right(find({2.0, 1.0}, {-1, 0})));
  EXPECT_TRUE(top(find({2.0, 1.0}, {0, -1})));
  // Outside the convex corner (in its wedge): no face contains the projection, so the contact
  // is with the corner node (2, 1), along the direction from it to the node.
  r = find({2.5, 1.5}, {-1, -1});
  ASSERT_GE(r.segment, 0);
  EXPECT_TRUE(r.vertex);
  EXPECT_TRUE(r.normal.isApprox(Vec2(1, 1).normalized()));
  EXPECT_NEAR(r.gap, std::sqrt(0.5), 1e-15);
  const SurfaceSegment& corner_seg = s.segments[r.segment];
  EXPECT_TRUE((r.xi == 0.0 ? x[corner_seg.a] : x[corner_seg.b]).isApprox(Vec2(2, 1)));
  // Tracking: the node tracked on the top face's right segment slides left past its end onto
  // the next segment of the chain (the top chain runs right to left: body on the left).
  const NodeSegment first = find({1.5, 1.0 - 1e-4}, {-1, 0});
  ASSERT_TRUE(top(first));
  const NodeSegment moved = find({0.5, 1.0 - 1e-4}, {-1, 0}, first.segment);
  ASSERT_TRUE(top(moved));
  EXPECT_NE(moved.segment, first.segment);
  EXPECT_EQ(moved.segment, s.segments[first.segment].next);
  EXPECT_NEAR(moved.gap, -1e-4, 1e-15);
}

// Vertex contact (solver/contact/body_contact.hpp): a node that moves diagonally from the wedge of a
// convex corner into the body within one step would find no face at the start of the step;
// a node pressed into a concave corner ends up in that corner's wedge inside the body, where
// no face contains its projection either.
TEST(BodyContact, VertexContact) {
  // Convex: the 2 x 1 master of SegmentChoice, a node that starts outside the top-right corner
  // and is predicted inside it.
  {
    const Model<2> model = build_model({bar("m", 2.0, 1.0, 2, 1, Vec2::Zero(), Vec2::Zero())}, PlaneMode::stress, Vec2::Zero());
    const Surface s = make_surface(model, 0);
    const int p = model.num_nodes();
    std::vector<Vec2, Eigen::aligned_allocator<Vec2>> x0(p + 1), x1(p + 1), v(p + 1, Vec2::Zero());
    for (int j = 0; j < p; ++j) x0[j] = x1[j] = model.ref.col(j);
    x0[p] = {2.01, 1.01};
    x1[p] = {1.99, 0.99};
    v[p] = {-1, -1};
    const NodeSegment r = find_segment(s, p, -1, [&](int j) { return x0[j]; }, [&](int j) { return x1[j]; },
                                       [&](int j) { return v[j]; });
    ASSERT_GE(r.segment, 0);
    EXPECT_TRUE(r.vertex);
    EXPECT_TRUE(r.normal.isApprox(Vec2(1, 1).normalized()));
    EXPECT_NEAR(r.gap, -0.01 * std::sqrt(2.0), 1e-12);  // inside: the constraint acts
    // Tracked on the top face's right segment, a node sliding right past the corner into the
    // wedge keeps a vertex contact instead of losing contact.
    const int top_right = [&] {
      for (int q = 0; q < static_cast<int>(s.segments.size()); ++q)
        if (x0[s.segments[q].a].isApprox(Vec2(2, 1))) return q;
      return -1;
    }();
    ASSERT_GE(top_right, 0);
    x0[p] = x1[p] = {2.002, 1.001};
    const NodeSegment w = find_segment(s, p, top_right, [&](int j) { return x0[j]; }, [&](int j) { return x1[j]; },
                                       [&](int j) { return v[j]; });
    ASSERT_GE(w.segment, 0);
    EXPECT_TRUE(w.vertex);
    EXPECT_NEAR(w.gap, std::hypot(0.002, 0.001), 1e-12);
  }
  // Concave: an L of three unit cells (the top-right one missing). The corner (1, 1) is
  // concave; a node at (0.9, 0.9) is inside the body in that corner's wedge.
  {
    BodyInput<2> b;
    b.name = "L";
    b.mesh.nodes.resize(2, 8);
    b.mesh.nodes << 0, 1, 2, 0, 1, 2, 0, 1,  //
                    0, 0, 0, 1, 1, 1, 2, 2;
    b.mesh.quads = {{0, 1, 4, 3}, {1, 2, 5, 4}, {3, 4, 7, 6}};
    b.material = StVenantKirchhoff::make(1e9, 0.3, 1000.0, PlaneMode::stress);
    const Model<2> model = build_model({b}, PlaneMode::stress, Vec2::Zero());
    const Surface s = make_surface(model, 0);
    ASSERT_EQ(s.segments.size(), 8u);
    const int p = model.num_nodes();
    std::vector<Vec2, Eigen::aligned_allocator<Vec2>> x(p + 1), v(p + 1, Vec2::Zero());
    for (int j = 0; j < p; ++j) x[j] = model.ref.col(j);
    x[p] = {0.9, 0.9};
    auto pos = [&](int j) { return x[j]; };
    auto vel = [&](int j) { return v[j]; };
    const NodeSegment r = find_segment(s, p, -1, pos, pos, vel);
    ASSERT_GE(r.segment, 0);
    EXPECT_TRUE(r.vertex);
    EXPECT_TRUE(r.normal.isApprox(Vec2(1, 1).normalized()));  // the bisector of (0, 1) and (1, 0)
    EXPECT_NEAR(r.gap, -0.2 / std::sqrt(2.0), 1e-12);
    const SurfaceSegment& sg = s.segments[r.segment];
    EXPECT_EQ(r.xi == 0.0 ? sg.a : sg.b, 4);  // node 4 is (1, 1)
    // Just outside the concave corner, above the lower right cell's top: that face.
    x[p] = {1.1, 1.05};
    const NodeSegment f = find_segment(s, p, -1, pos, pos, vel);
    EXPECT_FALSE(f.vertex);
    EXPECT_TRUE(f.normal.isApprox(Vec2(0, 1)));
    EXPECT_NEAR(f.gap, 0.05, 1e-12);
  }
}

// Two identical bars end to end (docs/background.md, Independent benchmarks, B2b): a striker at v0
// hits a bar at rest, mu = 0.
struct HeadOn {
  Model<2> model;
  RunSettings settings;
  double mass = 0.0, v0 = 1.0;
  explicit HeadOn(double mu = 0.0, Vec2 velocity = {1.0, 0.0}) {
    model = build_model({bar("striker", 0.2, 0.02, 40, 2, {-0.2, 0.0}, velocity),
                         bar("target", 0.2, 0.02, 40, 2, {0.0, 0.0}, Vec2::Zero())},
                        PlaneMode::stress, Vec2::Zero());
    mass = 0.5 * model.mass.sum();
    settings.dt = 0.9 * model.critical_dt;
    settings.end_time = 1.2e-4;
    settings.monitor_every = 1;
    settings.body_pairs = {{0, 1, mu, "pair"}};
  }
};

TEST(BodyContact, HeadOnConservesMomentumToRoundOff) {
  for (Scheme scheme : {Scheme::semi_explicit, Scheme::penalty, Scheme::implicit}) {
    HeadOn h;
    if (scheme == Scheme::implicit) h.settings.dt = 1e-7;
    const RunResult r = run(h.model, h.settings, scheme);
    ASSERT_EQ(r.status, RunStatus::ok) << name(scheme) << ": " << r.reason;
    const auto px = column(r.history, "momentum_x"), py = column(r.history, "momentum_y");
    const auto f = column(r.history, "normal_force");
    const double p0 = 0.5 * h.mass * h.v0;  // the striker is half the mass
    double dev = 0.0, impulse = 0.0;
    for (std::size_t i = 0; i < px.size(); ++i) {
      dev = std::max({dev, std::abs(px[i] - p0), std::abs(py[i])});
      if (i > 0) impulse += 0.5 * (f[i] + f[i - 1]) * (column(r.history, "time")[i] - column(r.history, "time")[i - 1]);
    }
    // Round-off: a few ulps of the momentum per sample, not a modelling tolerance.
    EXPECT_LT(dev, 1e-13 * p0) << name(scheme);
    // The contact did act: the striker's momentum p0 passed to the target (impulse p0, within
    // the few per cent that the step-wise force sampling and the penalty spring allow).
    EXPECT_NEAR(impulse, p0, 0.03 * p0) << name(scheme);
    // Penalty: the interface force rho c v0 A / 2 = 8000 N shared by the striker's end nodes,
    // 4000 N on the middle one, on its spring f_si K l^2 e / A_c = 0.1 (E/3) 1e-4 0.02 / 5e-5
    // = 2.67e8 N/m: 1.5e-5 m, and up to 2x in the first overshoot of the front.
    EXPECT_LT(r.penetration_max, scheme == Scheme::penalty ? 3e-5 : 1e-15) << name(scheme);
  }
}

TEST(BodyContact, ObliqueFrictionalImpactConservesMomentum) {
  // A block falls obliquely onto a free block (no gravity), mu = 0.3: the friction forces are
  // internal too, both momentum components stay, and sliding dissipates energy.
  for (Scheme scheme : {Scheme::semi_explicit, Scheme::penalty, Scheme::implicit}) {
    Model<2> model = build_model({bar("top", 0.04, 0.02, 4, 2, {0.01, 0.02}, {2.0, -1.0}, 1e8, 1000.0),
                               bar("bottom", 0.1, 0.02, 10, 2, {0.0, 0.0}, Vec2::Zero(), 1e8, 1000.0)},
                              PlaneMode::stress, Vec2::Zero());
    RunSettings s;
    s.dt = scheme == Scheme::implicit ? 1e-6 : 0.9 * model.critical_dt;
    s.end_time = 2e-4;
    s.monitor_every = 1;
    s.body_pairs = {{0, 1, 0.3, "pair"}};
    const RunResult r = run(model, s, scheme);
    ASSERT_EQ(r.status, RunStatus::ok) << name(scheme) << ": " << r.reason;
    const auto px = column(r.history, "momentum_x"), py = column(r.history, "momentum_y");
    const double m_top = 1000.0 * 0.04 * 0.02 * 0.02;
    const double p0x = 2.0 * m_top, p0y = -1.0 * m_top;
    for (std::size_t i = 0; i < px.size(); ++i) {
      ASSERT_LT(std::abs(px[i] - p0x), 1e-13 * std::abs(p0x)) << name(scheme) << " row " << i;
      ASSERT_LT(std::abs(py[i] - p0y), 1e-13 * std::abs(p0x)) << name(scheme) << " row " << i;
    }
    EXPECT_GT(r.friction_dissipation, 0.0) << name(scheme);
    EXPECT_GE(r.contact.steps, 5) << name(scheme);  // contact lasts ~2h/c = 1.3e-4 s
  }
}

TEST(BodyContact, BlockSlidingOnADeformableFloorDeceleratesAtMuG) {
  // A block slides at v0 = 1 m/s on a deformable floor held at its base, mu = 0.3, g = 9.81:
  // deceleration mu g while it slides across the floor's 1 cm segments (about 14 of them in
  // 0.15 s), node by node from segment to segment.
  const double mu = 0.3, g = 9.81;
  Model<2> model = build_model({bar("block", 0.1, 0.05, 10, 5, {0.0, 0.02}, {1.0, 0.0}, 1e9, 1000.0),
                             bar("floor", 0.6, 0.02, 60, 2, {-0.05, 0.0}, Vec2::Zero(), 1e9, 1000.0)},
                            PlaneMode::stress, Vec2(0.0, -g));
  RunSettings s;
  s.dt = 0.9 * model.critical_dt;
  s.end_time = 0.15;
  s.sample_interval = 1e-3;
  s.body_pairs = {{0, 1, mu, "pair"}};
  const int floor0 = model.bodies[1].first_node;
  for (int i = 0; i <= 60; ++i)  // the floor's bottom row
    for (int k = 0; k < 2; ++k) s.prescribed.push_back({2 * (floor0 + i) + k, PrescribedDof::Kind::velocity, 0.0, 0.0});
  const int centre = 2 * 11 + 5;  // block node (5, 2): local = global index (the block is body 0)
  s.probes = {{"c", centre}};
  const RunResult r = run_explicit(model, s);
  ASSERT_EQ(r.status, RunStatus::ok) << r.reason;
  const auto t = column(r.history, "time"), vx = column(r.history, "c_vx"), ux = column(r.history, "c_ux");
  // Least-squares slope of v_x over 0.02-0.14 s (after the initial settling).
  double st = 0, sv = 0, stt = 0, stv = 0;
  int n = 0;
  for (std::size_t i = 0; i < t.size(); ++i)
    if (t[i] >= 0.02 && t[i] <= 0.14) {
      st += t[i], sv += vx[i], stt += t[i] * t[i], stv += t[i] * vx[i];
      ++n;
    }
  const double slope = (n * stv - st * sv) / (n * stt - st * st);
  EXPECT_NEAR(-slope, mu * g, 0.01 * mu * g);
  // Slid v0 t - mu g t^2 / 2 = 0.117 m, across a dozen floor segments.
  EXPECT_NEAR(ux.back(), 0.15 - 0.5 * mu * g * 0.15 * 0.15, 0.002);
  EXPECT_LT(r.penetration_max, 1e-9);
}

TEST(BodyContact, CaseFileContactPairs) {
  const std::string head_on = std::string(RICOCHET_SOURCE_DIR) + "/cases/verification/head_on.toml";
  // Read into one one-way pair (striker -> target); two_pass adds the reverse pair.
  PreparedCase pc = prepare_case(read_case(head_on, {}));
  ASSERT_EQ(pc.settings.body_pairs.size(), 1u);
  EXPECT_EQ(pc.settings.body_pairs[0].slave, 0);
  EXPECT_EQ(pc.settings.body_pairs[0].master, 1);
  pc = prepare_case(read_case(head_on, {"contact_pairs[0].two_pass=true", "contact_pairs[0].friction=0.2"}));
  ASSERT_EQ(pc.settings.body_pairs.size(), 2u);
  EXPECT_EQ(pc.settings.body_pairs[1].slave, 1);
  EXPECT_EQ(pc.settings.body_pairs[1].master, 0);
  EXPECT_EQ(pc.settings.body_pairs[1].friction, 0.2);
  // Bad input: one line naming the file and the key.
  auto rejects = [&](const std::vector<std::string>& set, const std::string& key, const std::string& word) {
    try {
      read_case(head_on, set);
      ADD_FAILURE() << set.front() << ": accepted";
    } catch (const InputError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("head_on.toml"), std::string::npos) << m;
      EXPECT_NE(m.find(key), std::string::npos) << m;
      EXPECT_NE(m.find(word), std::string::npos) << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    }
  };
  rejects({"contact_pairs[0].slave=\"nobody\""}, "slave", "no body named");
  rejects({"contact_pairs[0].master=\"striker\""}, "master", "self-contact");
  rejects({"contact_pairs[0].friction=-0.1"}, "friction", "friction");
  rejects({"contact_pairs[0].side=\"left\""}, "side", "unknown");
  rejects({"scheme=\"explicit\""}, "scheme", "contact_pairs");
  // [penalty] soft / soft_scale (LS-DYNA SOFT = 1, SOFSCL): based on the elements' automatic
  // step, or on a fixed time.dt.
  const std::string penalty = "scheme=\"explicit_penalty\"";
  pc = prepare_case(read_case(head_on, {penalty}));
  EXPECT_EQ(pc.settings.penalty.soft_scale, 0.0);
  pc = prepare_case(read_case(head_on, {penalty, "penalty.soft=true"}));
  EXPECT_EQ(pc.settings.penalty.soft_scale, 0.1);
  EXPECT_EQ(pc.settings.penalty.soft_dt, stable_time_step(pc.model<2>(), pc.spec.dt_safety));
  EXPECT_LE(pc.settings.dt, pc.settings.penalty.soft_dt);
  pc = prepare_case(read_case(head_on, {penalty, "penalty.soft=true", "penalty.soft_scale=0.3", "time.dt=1e-8"}));
  EXPECT_EQ(pc.settings.penalty.soft_scale, 0.3);
  EXPECT_EQ(pc.settings.penalty.soft_dt, 1e-8);
  rejects({penalty, "penalty.soft_scale=2"}, "soft_scale", "1");
  rejects({penalty, "penalty.soft=1"}, "soft", "true or false");
}

TEST(BodyContact, PairStepsDoNotAllocate) {
  for (Scheme scheme : {Scheme::semi_explicit, Scheme::penalty}) {
    HeadOn h(0.2, {1.0, -0.3});
    const double dt = 0.5 * h.model.critical_dt;
    State s = initial_state(h.model, {}, dt);
    BipotentialContact c = make_bipotential_contact(h.model, {}, {{}, {}}, {}, h.settings.body_pairs);
    PenaltyContact p = make_penalty_contact(h.model, {}, {{}, {}}, {}, {}, h.settings.body_pairs);
    for (int n = 0; n < 5; ++n) {  // warm up
      evaluate(h.model, {}, s, false);
      if (scheme == Scheme::penalty) penalty_phase(h.model, {}, p, s);
      else contact_phase(h.model, {}, h.settings.contact, c, s);
      update(s);
    }
    const long before = g_allocations.load();
    int active = 0;
    for (int n = 0; n < 100; ++n) {
      evaluate(h.model, {}, s, false);
      if (scheme == Scheme::penalty) {
        penalty_phase(h.model, {}, p, s);
        active = std::max(active, p.set.last.active);
      } else {
        contact_phase(h.model, {}, h.settings.contact, c, s);
        active = std::max(active, c.set.last.active);
      }
      update(s);
    }
    EXPECT_EQ(g_allocations.load() - before, 0) << name(scheme);
    EXPECT_GT(active, 0) << name(scheme);
  }
}

// The implicit step allocates nothing either, with both linear solvers (the direct path
// refactorizes through CHOLMOD and builds the exact condensed compliance W by column solves),
// between bodies and against a rigid plane, with and without friction.
TEST(BodyContact, ImplicitStepsDoNotAllocate) {
  // The direct solver both with its default modified Newton (factor and contact columns reused)
  // and with full Newton (refactor_contraction = 0: a CHOLMOD factorization in every iteration
  // of the counted steps).
  struct Config {
    LinearSolverKind solver;
    double refactor_contraction;
    const char* name;
  };
  for (const Config& config : {Config{LinearSolverKind::pcg, 0.5, "pcg"}, Config{LinearSolverKind::direct, 0.5, "direct"},
                               Config{LinearSolverKind::direct, 0.0, "direct, full Newton"}}) {
    for (double mu : {0.0, 0.2}) {
      SCOPED_TRACE(std::string(config.name) + " mu " + std::to_string(mu));
      HeadOn h(mu, {1.0, -0.3});
      h.settings.dt = 1e-7;
      h.settings.obstacles = std::vector<Obstacle>{make_line_obstacle("floor", Vec2::Zero(), Vec2::UnitY())};
      h.settings.friction = {{mu}, {mu}};
      ImplicitSettings im;
      im.linear_solver = config.solver;
      im.refactor_contraction = config.refactor_contraction;
      ImplicitIntegrator integrator(h.model, h.settings, im);
      for (int n = 0; n < 5; ++n) ASSERT_TRUE(integrator.step(false)) << integrator.failure();  // warm up
      const long factorizations = integrator.factorizations();
      const long before = g_allocations.load();
      int active = 0;
      for (int n = 0; n < 200; ++n) {
        ASSERT_TRUE(integrator.step(n % 10 == 0)) << integrator.failure();
        active = std::max(active, integrator.contact().last.active);
      }
      EXPECT_EQ(g_allocations.load() - before, 0);
      EXPECT_GT(active, 2);  // the bars' interface and the striker on the floor
      EXPECT_EQ(integrator.direct_solver(), config.solver == LinearSolverKind::direct);
      if (config.solver == LinearSolverKind::direct) {
        EXPECT_GT(integrator.exact_contact_solves(), 0);
        std::printf("[body contact] implicit %s mu %.1f: %ld factorizations in the counted steps\n",
                    config.name, mu, integrator.factorizations() - factorizations);
        if (config.refactor_contraction == 0.0) {
          EXPECT_GE(integrator.factorizations() - factorizations, 200);
        }
      }
    }
  }
}

// A contact solve that reaches contact.max_sweeps is not fatal in the implicit scheme either: as
// in the semi-explicit scheme the last Gauss-Seidel iterate is used and the step is counted in
// contact_unconverged_steps. The head-on bars with two passes (redundant constraints where the
// end faces meet node on node) and a cap of 2 sweeps: the run ends, the steps are counted, and
// the momentum, which no reaction of a body pair can change, is still conserved.
TEST(BodyContact, ImplicitUnconvergedContactIsCountedNotFatal) {
  for (LinearSolverKind solver : {LinearSolverKind::pcg, LinearSolverKind::direct}) {
    SCOPED_TRACE(solver == LinearSolverKind::pcg ? "pcg" : "direct");
    HeadOn h(0.2, {1.0, -0.3});
    h.settings.body_pairs.push_back({1, 0, 0.2, "reverse"});
    h.settings.dt = 1e-7;
    h.settings.end_time = 6e-5;
    h.settings.contact.max_sweeps = 2;
    ImplicitSettings im;
    im.linear_solver = solver;
    im.uzawa_sweeps = 1;
    const RunResult r = run_implicit(h.model, h.settings, im);
    ASSERT_EQ(r.status, RunStatus::ok) << r.reason;
    EXPECT_GT(r.contact.unconverged_steps, 0);
    EXPECT_LE(r.contact.unconverged_steps, r.contact.steps);
    const auto px = column(r.history, "momentum_x"), py = column(r.history, "momentum_y");
    for (std::size_t i = 0; i < px.size(); ++i) {
      EXPECT_NEAR(px[i], px.front(), 1e-13 * h.mass);
      EXPECT_NEAR(py[i], py.front(), 1e-13 * h.mass);
    }
  }
}

}  // namespace
}  // namespace ricochet

