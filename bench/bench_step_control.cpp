// The variable step's recomputation (StepControl::critical, solver/schemes/time_step.hpp): the
// critical step of the current configuration, min over cells of L_e(X + u) / c_p, on the
// plates of explicit_step (bench_explicit_step.cpp) with their small smooth displacement, on
// one thread, or two for the names ending in /threads:2 (wall time), as the explicit loop runs
// it where its force pass is threaded. Compare its time with one explicit_step of the same
// plate: the cost of recomputing the step every step (time.dt_update_interval = 1),
// docs/performance.md.
// Reported: time per recomputation, and cells per second (items_per_second).
#include <limits>
#include <string>

#include "bench/bench_common.hpp"
#include "solver/schemes/threads.hpp"
#include "solver/schemes/time_step.hpp"

namespace ricochet::bench {
namespace {

void critical_step(benchmark::State& state, ElementKind element, MaterialKind material, int nx, int threads) {
  const ThreadScope scope(threads);
  const Model<2>& model = plate_model(element, material, nx);
  RunSettings settings;
  settings.dt = 0.5 * model.critical_dt;
  settings.end_time = 1.0;
  settings.dt_update_interval = 1;
  const StepControl control(model, settings, std::numeric_limits<double>::infinity());
  const Eigen::VectorXd u = plate_field(model, nx, 1e-5);
  double dt = 0.0;
  for (auto _ : state) {
    dt = control.critical(u, nullptr, threads > 1);
    benchmark::DoNotOptimize(dt);
  }
  if (!(dt > 0.0) || !(dt < 2.0 * model.critical_dt)) fail(state, "critical step out of range");
  state.SetItemsProcessed(state.iterations() * model.num_cells());
}

const bool registered = [] {
  for (const ElementKind element : {ElementKind::q4_one_point_viscous, ElementKind::q4_full_2x2, ElementKind::t3})
    for (const int nx : {32, 100, 256})
      for (const int threads : {1, 2}) {
        const std::string name = "critical_step/" + std::string(element_name(element)) + "/" +
                                 std::string(material_name(MaterialKind::st_venant_kirchhoff)) + "/" +
                                 std::to_string(nx) + "x" + std::to_string(nx) + (threads > 1 ? "/threads:2" : "");
        auto* b = benchmark::RegisterBenchmark(name.c_str(), critical_step, element, MaterialKind::st_venant_kirchhoff,
                                               nx, threads)
                      ->Unit(benchmark::kMicrosecond);
        if (threads > 1) b->UseRealTime();
      }
  return true;
}();

}  // namespace
}  // namespace ricochet::bench
