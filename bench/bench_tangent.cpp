// Implicit iteration matrix: one call of assemble_system(model, u, v, 1, theta xi dt^2, xi dt,
// s, f, with_energy = false), i.e. A = M + k K_T + c C and f_int in one element pass, on the
// oblique-plate mesh M2 (make_arc_plate 36 x 91 = 3276 Q4 cells, 3404 nodes, 6808 DOFs;
// cases/oblique_plate.toml: E = 1e7 Pa, nu = 0.25, rho = 1000 kg/m^3, t = 0.01 m, plane stress)
// with Q4 2x2, for both materials, under a smooth displacement of ~1 % strain with a small
// hourglass component and a smooth velocity. The pattern (make_system_matrix) is built once
// outside the timed loop.
// Reported: time per call, and elements_per_second = cells assembled per second [cells/s]
// (items_per_second counts the same cells). For scale, internal_forces alone on the same model
// and fields runs as tangent_assembly/forces_only/....
#include <cmath>
#include <numbers>
#include <string>

#include "bench/bench_common.hpp"
#include "harness/input/mesh_generators.hpp"
#include "solver/forces/internal_forces.hpp"
#include "solver/forces/tangent.hpp"

namespace ricochet::bench {
namespace {

constexpr int arc_nx = 36, arc_ny = 91;

Model<2> arc_plate_model(MaterialKind material) {
  constexpr double young = 1.0e7, poisson = 0.25, density = 1000.0;
  constexpr PlaneMode plane = PlaneMode::stress;
  ArcPlateSpec spec;
  spec.width = 0.04;
  spec.height = 0.08;
  spec.radius = 0.101;
  spec.nx = arc_nx;
  spec.ny = arc_ny;
  BodyInput<2> body;
  body.name = "plate";
  body.mesh = make_arc_plate(spec);
  if (material == MaterialKind::st_venant_kirchhoff)
    body.material = StVenantKirchhoff::make(young, poisson, density, plane);
  else
    body.material = NeoHookean::make(young, poisson, density, plane);
  body.quad_element = QuadElement::full_2x2;
  body.thickness = 0.01;
  return build_model({body}, plane, Vec2::Zero());
}

// amplitude * (smooth mode of wavelength 0.08 m + 1e-3 * checkerboard), per DOF.
Eigen::VectorXd arc_field(const Model<2>& model, double amplitude) {
  const double k = std::numbers::pi / 0.04;
  Eigen::VectorXd a(model.num_dofs());
  for (int n = 0; n < model.num_nodes(); ++n) {
    const double x = model.ref(0, n), y = model.ref(1, n);
    const int i = n % (arc_nx + 1), j = n / (arc_nx + 1);
    const double checker = (i + j) % 2 == 0 ? 1e-3 : -1e-3;
    a(2 * n) = amplitude * (std::sin(k * x) * std::cos(k * y) + checker);
    a(2 * n + 1) = amplitude * (std::cos(k * x) * std::sin(k * y) - checker);
  }
  return a;
}

void tangent_assembly(benchmark::State& state, MaterialKind material) {
  const Model<2> model = arc_plate_model(material);
  const Eigen::VectorXd u = arc_field(model, 1e-4);  // [m], strain ~ 1e-4 * pi / 0.04 ~ 1 %
  const Eigen::VectorXd v = arc_field(model, 1.0);   // [m/s]
  SystemMatrix s = make_system_matrix(model);
  Eigen::VectorXd f(model.num_dofs());
  const double dt = 1e-6, theta = 0.5, xi = 0.5;  // [s], [-], [-]
  const double cells = model.num_cells();

  ForceTotals totals;
  for (auto _ : state) {
    totals = assemble_system(model, u.data(), v.data(), 1.0, theta * xi * dt * dt, xi * dt, s,
                             f.data(), /*with_energy=*/false);
    benchmark::DoNotOptimize(totals);
    benchmark::DoNotOptimize(s.matrix.valuePtr());
    benchmark::DoNotOptimize(f.data());
    benchmark::ClobberMemory();
  }

  if (!f.allFinite() || !(f.norm() > 0.0) || !(totals.min_jacobian > 0.9) ||
      !s.diagonal.allFinite() || !(s.diagonal.minCoeff() > 0.0))
    fail(state, "invalid system matrix or internal forces");
  state.SetItemsProcessed(state.iterations() * model.num_cells());
  state.counters["elements_per_second"] =
      benchmark::Counter(cells, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["nonzeros"] = static_cast<double>(s.matrix.nonZeros());
}

// The force evaluation alone on the same model and fields (the explicit scheme's kernel).
void forces_only(benchmark::State& state, MaterialKind material) {
  const Model<2> model = arc_plate_model(material);
  const Eigen::VectorXd u = arc_field(model, 1e-4);
  const Eigen::VectorXd v = arc_field(model, 1.0);
  Eigen::VectorXd f(model.num_dofs());
  ForceTotals totals;
  for (auto _ : state) {
    totals = internal_forces(model, u.data(), v.data(), f.data(), /*with_energy=*/false);
    benchmark::DoNotOptimize(totals);
    benchmark::DoNotOptimize(f.data());
    benchmark::ClobberMemory();
  }
  if (!f.allFinite() || !(f.norm() > 0.0) || !(totals.min_jacobian > 0.9))
    fail(state, "invalid internal forces");
  state.SetItemsProcessed(state.iterations() * model.num_cells());
  state.counters["elements_per_second"] = benchmark::Counter(
      model.num_cells(), benchmark::Counter::kIsIterationInvariantRate);
}

const bool registered = [] {
  for (const MaterialKind m : {MaterialKind::st_venant_kirchhoff, MaterialKind::neo_hookean}) {
    const std::string name = "tangent_assembly/q4_2x2/" + std::string(material_name(m)) +
                             "/arc_plate_36x91";
    benchmark::RegisterBenchmark(name.c_str(), tangent_assembly, m)
        ->Unit(benchmark::kMicrosecond);
  }
  for (const MaterialKind m : {MaterialKind::st_venant_kirchhoff, MaterialKind::neo_hookean}) {
    const std::string name = "tangent_assembly/forces_only/q4_2x2/" +
                             std::string(material_name(m)) + "/arc_plate_36x91";
    benchmark::RegisterBenchmark(name.c_str(), forces_only, m)->Unit(benchmark::kMicrosecond);
  }
  return true;
}();

}  // namespace
}  // namespace ricochet::bench
