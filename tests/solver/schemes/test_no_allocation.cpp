// The explicit step performs no heap allocation (design 4): after initial_state, any number of
// evaluate() + update() calls, with or without energies, with prescribed DOFs, nodal loads,
// gravity and every element formulation, must not allocate; nor do the steps of a relaxation
// (a quasi-static start), nor the variable step (StepControl's recomputation of the step,
// set_step) with either contact solve.
//
// Every allocation of this executable is counted in one global atomic counter (alloc_counter.hpp):
// operator new and also the C allocation functions (malloc, calloc, realloc, aligned_alloc,
// posix_memalign, memalign), because Eigen allocates dynamic matrices and temporaries with
// std::malloc, not operator new. In a normal build the counter interposes these functions; in
// an AddressSanitizer build (ci/sanitize) it counts through a hook in ASan's allocator. The
// first test checks that the counter sees every kind of allocation in either build.
#include <gtest/gtest.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>
#include <vector>

#include "solver/contact/bipotential_contact.hpp"
#include "solver/contact/obstacle.hpp"
#include "solver/contact/penalty_contact.hpp"
#include "solver/schemes/central_difference.hpp"
#include "solver/schemes/relaxation.hpp"
#include "solver/schemes/time_step.hpp"
#include "solver/observers/observers.hpp"
#include "tests/support/meshes3.hpp"
#include "tests/support/verification_meshes.hpp"
#include "solver/schemes/implicit.hpp"

#include "tests/support/alloc_counter.hpp"
#include "solver/schemes/threads.hpp"

namespace ricochet {
namespace {

using verification::element_name;
using verification::ElementKind;

TEST(NoAllocation, CounterSeesEveryKindOfAllocation) {
  // The counter itself must work, or a zero below would prove nothing.
  long before = g_allocations.load();
  int* a = new int(3);
  escape(a);
  delete a;
  EXPECT_GE(g_allocations.load() - before, 1) << "operator new";

  before = g_allocations.load();
  std::vector<double> v(100, 1.0);
  escape(v.data());
  EXPECT_GE(g_allocations.load() - before, 1) << "std::vector";

  before = g_allocations.load();
  struct alignas(128) Wide {
    double x[16];
  };
  Wide* w = new Wide();
  escape(w);
  delete w;
  EXPECT_GE(g_allocations.load() - before, 1) << "aligned operator new";

  before = g_allocations.load();
  Eigen::VectorXd x = Eigen::VectorXd::Ones(100);
  Eigen::VectorXd y = x + x;  // a fresh dynamic vector: Eigen allocates with std::malloc
  escape(y.data());
  EXPECT_GE(g_allocations.load() - before, 2) << "Eigen dynamic storage";

  // The C functions one by one (each block freed only after its count is read).
  before = g_allocations.load();
  void* m = std::malloc(24);
  escape(m);
  EXPECT_EQ(g_allocations.load() - before, 1) << "malloc";
  before = g_allocations.load();
  void* c = std::calloc(3, 8);
  escape(c);
  EXPECT_EQ(g_allocations.load() - before, 1) << "calloc";
  before = g_allocations.load();
  m = std::realloc(m, 4096);
  escape(m);
  EXPECT_GE(g_allocations.load() - before, 1) << "realloc";
  before = g_allocations.load();
  void* al = std::aligned_alloc(64, 256);
  escape(al);
  EXPECT_EQ(g_allocations.load() - before, 1) << "aligned_alloc";
  before = g_allocations.load();
  void* pm = nullptr;
  ASSERT_EQ(posix_memalign(&pm, 64, 256), 0);
  escape(pm);
  EXPECT_EQ(g_allocations.load() - before, 1) << "posix_memalign";
  // An allocation made inside a shared library (glibc's strdup calls malloc), as CHOLMOD's are.
  before = g_allocations.load();
  char* dup = strdup("shared library");
  escape(dup);
  EXPECT_GE(g_allocations.load() - before, 1) << "malloc inside a shared library";
  std::free(dup);
  std::free(pm);
  std::free(al);
  std::free(c);
  std::free(m);
}

struct StepCase {
  ElementKind kind;
  Material material;
  PlaneMode plane;
};

TEST(NoAllocation, ExplicitStepsDoNotAllocate) {
  const double young = 200e9, nu = 0.3, rho = 7800.0;
  std::vector<StepCase> cases;
  for (ElementKind kind : verification::all_element_kinds()) {
    cases.push_back({kind, StVenantKirchhoff::make(young, nu, rho, PlaneMode::strain),
                     PlaneMode::strain});
    cases.push_back(
        {kind, NeoHookean::make(young, nu, rho, PlaneMode::stress), PlaneMode::stress});
  }
  for (const StepCase& c : cases) {
    const Mesh mesh = verification::grid_mesh(2.0, 0.5, 8, 2, 0.2, c.kind);
    Model<2> model = verification::single_body_model(mesh, c.material, c.plane, c.kind, 0.01, 0.1,
                                                  Vec2(0.0, -9.81));
    for (int i = 0; i < model.num_nodes(); ++i)
      model.initial_velocity[2 * i + 1] = std::sin(3.0 * model.ref(0, i));
    // Prescribed DOFs of every kind: held, pulled at constant velocity, displacement ramp.
    std::vector<PrescribedDof> prescribed;
    for (int n : mesh.node_sets.at("left")) {
      prescribed.push_back({2 * n, PrescribedDof::Kind::velocity, 0.0, 0.0});
      prescribed.push_back({2 * n + 1, PrescribedDof::Kind::velocity, 0.0, 0.0});
    }
    for (int n : mesh.node_sets.at("right"))
      prescribed.push_back({2 * n, PrescribedDof::Kind::displacement, 1e-4, 1e-4});
    prescribed.push_back({2 * mesh.node_sets.at("top").front() + 1,
                          PrescribedDof::Kind::velocity, 0.5, 0.0});

    // Nodal loads: one on from the start, one switched on and ramped during the steps.
    const std::vector<NodalLoad> loads = {{2 * mesh.node_sets.at("top").back(), -3.0, 0.0, 0.0},
                                          {2 * mesh.node_sets.at("top").back() + 1, 2.0, 1e-5, 1e-4}};

    for (bool with_prescribed : {false, true}) {
      const std::vector<PrescribedDof> none;
      const std::vector<PrescribedDof>& p = with_prescribed ? prescribed : none;
      State s = initial_state(model, p, 0.9 * model.critical_dt, {}, loads);
      const Eigen::VectorXd u0 = s.u;
      std::vector<double> cell_vm(model.num_cells());
      double sink = 0.0;

      // Stress tracking as every explicit step does it, both ranking every point and skipping.
      std::vector<std::uint8_t> contact_cell(model.num_cells(), 0);
      StressTracking tracking;
      tracking.contact_cell = contact_cell.data();
      const long before = g_allocations.load();
      for (int n = 0; n < 60; ++n) {
        tracking.threshold = n % 2 == 0 ? 0.0 : 1e6;
        evaluate(model, p, s, n % 3 != 0, n % 5 != 0 ? &tracking : nullptr);
        update(s);
      }
      const long steps_allocs = g_allocations.load() - before;
      EXPECT_EQ(steps_allocs, 0) << element_name(c.kind) << (with_prescribed ? " prescribed" : "");

      // The observers sampled between steps do not allocate either.
      const long before_obs = g_allocations.load();
      for (int n = 0; n < 10; ++n) {
        evaluate(model, p, s, true);
        const Energies e = observe_energies(model, s, u0);
        sink += energy_error(e, 1.0, 1.0) + linear_momentum(model, s).norm();
        cell_von_mises(model, s.u.data(), StressMeasure::pk2, cell_vm.data());
        sink += von_mises_maxima(model, s.u.data())[0];
        update(s);
      }
      EXPECT_EQ(g_allocations.load() - before_obs, 0)
          << element_name(c.kind) << (with_prescribed ? " prescribed" : "") << " observers";
      // The steps did something: the body moved and the results are finite.
      EXPECT_TRUE(std::isfinite(sink));
      EXPECT_GT(s.u.norm(), 0.0);
      EXPECT_EQ(s.step, 70);
    }
  }
}

// A relaxation step (solver/schemes/relaxation.hpp): evaluate() with the held prescribed DOFs
// and the loads at their t = 0 value, the contact solve of either explicit scheme, the residual,
// the kinetic damping with its resets. A block resting on the ground under gravity with
// friction, a held node and a load; after the set-up no step allocates.
TEST(NoAllocation, RelaxationStepsDoNotAllocate) {
  const Mesh mesh = verification::grid_mesh(0.1, 0.05, 10, 5, 0.0, false);
  const Model<2> model = verification::single_body_model(
      mesh, StVenantKirchhoff::make(1e9, 0.3, 1000.0, PlaneMode::stress), PlaneMode::stress,
      ElementKind::q4_full, 0.05, 0.1, Vec2(0.0, -9.81));
  RunSettings settings;
  settings.dt = 0.9 * model.critical_dt;
  settings.end_time = 1.0;
  settings.obstacles = std::vector<Obstacle>{make_line_obstacle("ground", Vec2::Zero(), Vec2::UnitY())};
  settings.friction = {{0.5}};
  settings.prescribed = {{2 * mesh.node_sets.at("top").front(), PrescribedDof::Kind::velocity, 0.0, 0.0}};
  settings.loads = {{2 * mesh.node_sets.at("top").back() + 1, -1.0, 0.0, 0.0}};
  settings.relaxation.enabled = true;
  settings.relaxation.tolerance = 1e-14;  // not reached in these steps
  const Eigen::VectorXd u0 = Eigen::VectorXd::Zero(model.num_dofs());
  for (const bool penalty : {false, true}) {
    SCOPED_TRACE(penalty ? "penalty" : "bi-potential");
    BipotentialContact bipotential = make_bipotential_contact(model, obstacles_of(settings, model), settings.friction,
                                                              settings.prescribed);
    PenaltyContact springs = make_penalty_contact(model, obstacles_of(settings, model), settings.friction,
                                                  settings.prescribed, PenaltySettings{});
    Relaxation r(model, settings, 0.5 * settings.dt, u0,
                 {penalty ? nullptr : &bipotential, penalty ? &springs : nullptr});
    for (int n = 0; n < 5; ++n) ASSERT_EQ(r.step(), Relaxation::Status::running);
    const long before = g_allocations.load();
    for (int n = 0; n < 300; ++n) ASSERT_EQ(r.step(), Relaxation::Status::running);
    EXPECT_EQ(g_allocations.load() - before, 0);
    EXPECT_GT(r.report().velocity_resets, 0);  // the resets ran too
    EXPECT_GT(r.state().u.norm(), 0.0);
  }
}

// The variable step (docs/background.md, Variable time step): StepControl::begin_step, which
// recomputes the step from the current configuration every step here and shortens the last one,
// with evaluate(), either contact solve and update() at a step that changes every step, for
// every element formulation, allocates nothing.
TEST(NoAllocation, VariableStepsDoNotAllocate) {
  for (ElementKind kind : verification::all_element_kinds()) {
    Mesh mesh = verification::grid_mesh(0.04, 0.02, 8, 4, 0.2, kind);
    mesh.nodes.row(1).array() += 1e-5;
    Model<2> model = verification::single_body_model(mesh, NeoHookean::make(1e6, 0.3, 1000.0, PlaneMode::strain),
                                                  PlaneMode::strain, kind, 0.01, 0.1, Vec2(0.0, -9.81));
    for (int i = 0; i < model.num_nodes(); ++i) model.initial_velocity.segment<2>(2 * i) = Vec2(1.0, -5.0);
    const std::vector<Obstacle> line{{"ground", Vec2::Zero(), Vec2::UnitY()}};
    std::vector<PrescribedDof> prescribed;
    for (int n : mesh.node_sets.at("top")) prescribed.push_back({2 * n, PrescribedDof::Kind::displacement, 1e-4, 1e-3});
    for (bool penalty : {false, true}) {
      RunSettings settings;
      settings.dt_safety = 0.9;
      settings.dt = 0.9 * model.critical_dt;
      settings.end_time = 60.5 * settings.dt;  // about 60 steps, the last one shortened to end on it
      settings.dt_update_interval = 1;
      BipotentialContact b = make_bipotential_contact(model, line, {{0.3}}, prescribed);
      PenaltyContact p = make_penalty_contact(model, line, {{0.3}}, prescribed, PenaltySettings{});
      StepControl control(model, settings, penalty ? penalty_critical_dt(model, p) : 1e300);
      State s = initial_state(model, prescribed, settings.dt);
      // The first step sets up the contact solves' warm starts; count from the second.
      ASSERT_TRUE(control.begin_step(s));
      evaluate(model, prescribed, s, true);
      if (penalty) penalty_phase(model, line, p, s);
      else contact_phase(model, line, ContactSettings{}, b, s);
      update(s);
      const long before = g_allocations.load();
      long steps = 0, contact_steps = 0;
      while (control.begin_step(s)) {
        evaluate(model, prescribed, s, steps % 3 == 0);
        if (penalty) {
          penalty_phase(model, line, p, s);
          contact_steps += p.set.last.active > 0;
        } else {
          contact_phase(model, line, ContactSettings{}, b, s);
          contact_steps += b.set.last.active > 0;
        }
        update(s);
        ++steps;
      }
      EXPECT_EQ(g_allocations.load() - before, 0) << element_name(kind) << (penalty ? " penalty" : " bi-potential");
      EXPECT_TRUE(control.failure().empty()) << control.failure();
      EXPECT_GT(steps, 40);
      EXPECT_EQ(s.time, settings.end_time);
      EXPECT_GT(contact_steps, 0) << "the body reached the line";
    }
  }
}

// The threaded force pass (two threads, a plate of more cells than kForceParallelChunks chunks
// hold, so the chunks run in a parallel region): after the first step, which creates the
// OpenMP runtime's thread team once per process, no step allocates, sample passes and the
// variable step's threaded recomputation included.
TEST(NoAllocation, ThreadedForcePassDoesNotAllocate) {
  const Mesh mesh = verification::grid_mesh(2.0, 1.0, 48, 24, 0.2, ElementKind::q4_full);
  const Model<2> model = verification::single_body_model(
      mesh, StVenantKirchhoff::make(200e9, 0.3, 7800.0, PlaneMode::stress), PlaneMode::stress, ElementKind::q4_full, 0.01);
  ASSERT_GE(model.num_cells(), static_cast<int>(kForceParallelChunks * kForceChunkCells));
  const ThreadScope threads(2);
  State s = initial_state(model, {}, 0.9 * model.critical_dt);
  for (int i = 0; i < model.num_nodes(); ++i) s.v_half[2 * i + 1] = std::sin(3.0 * model.ref(0, i));
  std::vector<std::uint8_t> contact_cell(model.num_cells(), 0);
  std::vector<double> cells(model.num_cells());
  VonMises2 sampled{0.0, 0.0, 0.0};
  StressTracking tracking;
  tracking.contact_cell = contact_cell.data();
  // The variable step's recomputation on the same threads (StepControl::critical).
  RunSettings settings;
  settings.dt = s.dt;
  settings.end_time = 1.0;
  const StepControl control(model, settings, 1e300);
  double dt_sum = 0.0;
  evaluate(model, {}, s, true, &tracking);
  update(s);
  const long before = g_allocations.load();
  for (int n = 0; n < 30; ++n) {
    dt_sum += control.critical(s.u, nullptr, true);
    tracking.threshold = n % 2 == 0 ? 0.0 : 1e6;
    tracking.sampled_max = n % 3 == 0 ? &sampled : nullptr;
    tracking.cell_von_mises = n % 3 == 0 ? cells.data() : nullptr;
    evaluate(model, {}, s, n % 3 == 0, n % 5 != 0 ? &tracking : nullptr);
    update(s);
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_GT(dt_sum, 0.0);
  EXPECT_GT(sampled[0], 0.0);
  EXPECT_GT(s.u.norm(), 0.0);
}

// The implicit step on a 3D model allocates nothing either: the 3D system matrix's assembly
// (element matrices on the geometry rebuilt per cell), the CHOLMOD factorizations, the contact
// columns on three directions per contact and the 3D cone's local solves. A block of hexahedra
// (2x2x2 and one point, viscous) and a block of tetrahedra hit a plane obliquely, with and
// without friction, by PCG, modified Newton and full Newton. (The first contact node bounces off:
// the trapezoidal scheme's position-level contact reflects it. The counted steps, 2e-2 s, run
// until the body's deformation brings the bottom back down, for the one-point hexahedra too,
// whose corner motion is an hourglass mode and returns slowly.)
TEST(NoAllocation, ImplicitSteps3DoNotAllocate) {
  struct Config {
    LinearSolverKind solver;
    double refactor_contraction;
    const char* name;
    FactorPrecision precision = FactorPrecision::double_;
  };
  const Material3 m = NeoHookean3::make(1e7, 0.3, 1000.0);
  for (test3::Kind kind : {test3::Kind::hex8, test3::Kind::hex8_viscous, test3::Kind::tet4}) {
    BodyInput<3> b = test3::body_of(kind, test3::distorted_box(3, 2, 2, test3::is_tet(kind), 0.1), m);
    b.initial_velocity = Vec3(3.0, -5.0, 1.0);
    const Model<3> model = build_model({b}, Vec3::Zero());
    const double low = model.ref.row(1).minCoeff();
    for (const Config& config : {Config{LinearSolverKind::pcg, 0.5, "pcg"}, Config{LinearSolverKind::direct, 0.5, "direct"},
                                 Config{LinearSolverKind::direct, 0.0, "direct, full Newton"},
                                 Config{LinearSolverKind::direct, 0.5, "direct, single-precision solves",
                                        FactorPrecision::single}})
      for (double mu : {0.0, 0.3}) {
        // The single-precision copy's solves are the same for every element kind: one is enough
        // (this test is among the longest under the sanitizers).
        if (config.precision == FactorPrecision::single && kind != test3::Kind::hex8) continue;
        SCOPED_TRACE(std::string(test3::kind_name(kind)) + ", " + config.name + ", mu " + std::to_string(mu));
        RunSettings s;
        s.dt = 2e-5;
        s.obstacles = std::vector<Obstacle3>{make_plane_obstacle3("ground", Vec3(0.0, low, 0.0), Vec3::UnitY())};
        s.friction = {{mu}};
        ImplicitSettings im;
        im.linear_solver = config.solver;
        im.refactor_contraction = config.refactor_contraction;
        im.factor_precision = config.precision;
        ImplicitIntegratorT<Model<3>> integrator(model, s, im);
        for (int n = 0; n < 3; ++n) ASSERT_TRUE(integrator.step(false)) << integrator.failure();  // warm up
        const long before = g_allocations.load();
        int active = 0;
        for (int n = 0; n < 1000; ++n) {
          ASSERT_TRUE(integrator.step(n % 5 == 0)) << integrator.failure();
          active = std::max(active, integrator.contact().last.active);
        }
        EXPECT_EQ(g_allocations.load() - before, 0);
        EXPECT_GT(active, 0);
      }
  }
}

}  // namespace
}  // namespace ricochet
