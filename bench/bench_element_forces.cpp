// Element force kernel: one call of internal_forces(model, u, v, f, with_energy = false) on a
// 100 x 100-cell plate (20 000 triangles for T3) with a small smooth displacement and velocity
// field, for every element formulation x material in plane stress.
// Reported: time per call, and element_steps_per_second = cells processed per second
// [cells/s] (items_per_second counts the same cells).
#include <string>

#include "bench/bench_common.hpp"
#include "solver/internal_forces.hpp"

namespace ricochet::bench {
namespace {

constexpr int plate_cells = 100;  // cells per side

void element_forces(benchmark::State& state, ElementKind element, MaterialKind material) {
  const Model& model = plate_model(element, material, plate_cells);
  const Eigen::VectorXd u = plate_field(model, plate_cells, 1e-5);  // [m], strain ~3e-4
  const Eigen::VectorXd v = plate_field(model, plate_cells, 1.0);   // [m/s]
  Eigen::VectorXd f(model.num_dofs());
  const double cells = model.num_cells();

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
  state.counters["element_steps_per_second"] =
      benchmark::Counter(cells, benchmark::Counter::kIsIterationInvariantRate);
}

const bool registered = [] {
  for (const ElementKind e : {ElementKind::q4_full_2x2, ElementKind::q4_one_point_viscous,
                              ElementKind::q4_one_point_stiffness, ElementKind::t3})
    for (const MaterialKind m : {MaterialKind::st_venant_kirchhoff, MaterialKind::neo_hookean}) {
      const std::string name =
          "element_forces/" + std::string(element_name(e)) + "/" + std::string(material_name(m));
      benchmark::RegisterBenchmark(name.c_str(), element_forces, e, m)
          ->Unit(benchmark::kMicrosecond);
    }
  return true;
}();

}  // namespace
}  // namespace ricochet::bench
