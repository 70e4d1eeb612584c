// Element force kernel: one call of internal_forces(model, u, v, f, with_energy = false) on a
// 100 x 100-cell plate (20 000 triangles for T3) with a small smooth displacement and velocity
// field, for every element formulation x material in plane stress. The stress variants also
// track the Cauchy von Mises peak as every explicit step does (internal_forces.hpp):
// `element_forces_stress_all/...` ranks every integration point (threshold 0, as at a history
// sample), `element_forces_stress_bound/...` has a threshold no point reaches, so each point
// costs only the upper bound that lets it skip the exact value (most points of most steps).
// Their ratios to `element_forces/...` are the cost of the tracking.
// Reported: time per call, and element_steps_per_second = cells processed per second
// [cells/s] (items_per_second counts the same cells).
#include <cstdint>
#include <string>
#include <vector>

#include "bench/bench_common.hpp"
#include "solver/forces/internal_forces.hpp"

namespace ricochet::bench {
namespace {

constexpr int plate_cells = 100;  // cells per side

enum class StressMode { off, all, bound };

void element_forces(benchmark::State& state, ElementKind element, MaterialKind material, StressMode mode) {
  const Model<2>& model = plate_model(element, material, plate_cells);
  const Eigen::VectorXd u = plate_field(model, plate_cells, 1e-5);  // [m], strain ~3e-4
  const Eigen::VectorXd v = plate_field(model, plate_cells, 1.0);   // [m/s]
  Eigen::VectorXd f(model.num_dofs());
  const double cells = model.num_cells();
  // Every tenth cell counts as on a contact boundary, so both peaks are tracked.
  std::vector<std::uint8_t> contact_cell(model.num_cells(), 0);
  for (std::size_t c = 0; c < contact_cell.size(); c += 10) contact_cell[c] = 1;
  StressTracking tracking;
  tracking.contact_cell = contact_cell.data();
  if (mode == StressMode::bound) tracking.threshold = 1e300;
  const StressTracking* stress = mode == StressMode::off ? nullptr : &tracking;

  ForceTotals totals;
  for (auto _ : state) {
    totals = internal_forces(model, u.data(), v.data(), f.data(), /*with_energy=*/false, stress);
    benchmark::DoNotOptimize(totals);
    benchmark::DoNotOptimize(f.data());
    benchmark::ClobberMemory();
  }

  if (!f.allFinite() || !(f.norm() > 0.0) || !(totals.min_jacobian > 0.9))
    fail(state, "invalid internal forces");
  if (mode == StressMode::all && !(totals.stress.all > 0.0 && totals.stress.interior_cell >= 0))
    fail(state, "no stress peak tracked");
  if (mode == StressMode::bound && totals.stress.all_cell >= 0) fail(state, "a point passed an unreachable threshold");
  state.SetItemsProcessed(state.iterations() * model.num_cells());
  state.counters["element_steps_per_second"] =
      benchmark::Counter(cells, benchmark::Counter::kIsIterationInvariantRate);
}

const bool registered = [] {
  for (const ElementKind e : {ElementKind::q4_full_2x2, ElementKind::q4_one_point_viscous,
                              ElementKind::q4_one_point_stiffness, ElementKind::t3})
    for (const MaterialKind m : {MaterialKind::st_venant_kirchhoff, MaterialKind::neo_hookean}) {
      for (const StressMode mode : {StressMode::off, StressMode::all, StressMode::bound}) {
        const char* prefix = mode == StressMode::off   ? "element_forces/"
                             : mode == StressMode::all ? "element_forces_stress_all/"
                                                       : "element_forces_stress_bound/";
        const std::string name = prefix + std::string(element_name(e)) + "/" + std::string(material_name(m));
        benchmark::RegisterBenchmark(name.c_str(), element_forces, e, m, mode)->Unit(benchmark::kMicrosecond);
      }
    }
  return true;
}();

}  // namespace
}  // namespace ricochet::bench
