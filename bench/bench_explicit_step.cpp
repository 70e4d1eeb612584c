// Full explicit step without energies: evaluate() (internal forces, accelerations) then
// update() (velocities, displacements), on an n x n-cell free plate vibrating from a small
// smooth initial displacement and velocity, dt = 0.5 x model.critical_dt.
// The step's force pass is the threaded one (State::force_scratch): one thread, or two for the
// names ending in /threads:2, timed in wall time (the speed-up of the second core).
// Reported: time per step, and element_steps_per_second = cells x steps per second
// [cells/s] (items_per_second counts the same cells).
#include <string>
#include <vector>

#include "bench/bench_common.hpp"
#include "bench/explicit_steps.hpp"
#include "solver/schemes/central_difference.hpp"
#include "solver/schemes/threads.hpp"

namespace ricochet::bench {
namespace {

void explicit_step(benchmark::State& state, ElementKind element, MaterialKind material, int nx, int threads) {
  const ThreadScope scope(threads);
  const Model<2>& model = plate_model(element, material, nx);
  const std::vector<PrescribedDof> prescribed;
  const double dt = 0.5 * model.critical_dt;  // [s]
  const double cells = model.num_cells();

  // Start after step 0 so every timed evaluate() is an ordinary step.
  State s = initial_state(model, prescribed, dt, plate_field(model, nx, 1e-5));
  s.v_half = plate_field(model, nx, 1.0);
  evaluate(model, prescribed, s, /*with_energy=*/false);
  update(s);
  const State start = s;
  s = time_explicit_steps(state, model, prescribed, start);

  if (!s.u.allFinite() || !s.v_half.allFinite() || !(s.forces.min_jacobian > 0.9))
    fail(state, "state left the small-strain regime");
  state.SetItemsProcessed(state.iterations() * model.num_cells());
  state.counters["element_steps_per_second"] =
      benchmark::Counter(cells, benchmark::Counter::kIsIterationInvariantRate);
}

const bool registered = [] {
  struct Case {
    ElementKind element;
    MaterialKind material;
  };
  // The scaling table of docs/performance.md: about 1e3, 1e4, 1e5 and 1e6 cells per element
  // type (32^2, 100^2, 316^2, 1000^2 quads; T3 has twice as many cells), and 256^2, the
  // plate of the two-thread target.
  for (const Case c : {Case{ElementKind::q4_one_point_viscous, MaterialKind::st_venant_kirchhoff},
                       Case{ElementKind::q4_full_2x2, MaterialKind::st_venant_kirchhoff},
                       Case{ElementKind::t3, MaterialKind::st_venant_kirchhoff}})
    for (const int nx : {32, 100, 256, 316, 1000})
      for (const int threads : {1, 2}) {
        const std::string name = "explicit_step/" + std::string(element_name(c.element)) + "/" +
                                 std::string(material_name(c.material)) + "/" + std::to_string(nx) + "x" +
                                 std::to_string(nx) + (threads > 1 ? "/threads:2" : "");
        auto* b = benchmark::RegisterBenchmark(name.c_str(), explicit_step, c.element, c.material, nx, threads)
                      ->Unit(benchmark::kMicrosecond);
        if (threads > 1) b->UseRealTime();
      }
  return true;
}();

}  // namespace
}  // namespace ricochet::bench
