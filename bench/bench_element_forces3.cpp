// The 3D force pass: one call of internal_forces(model3, u, v, f, with_energy = false) on a
// cube of n x n x n cells (6 n^3 tetrahedra for tet4) with a small smooth displacement and
// velocity field plus a checkerboard (hourglass) part, so every force term works, for every
// element formulation x material, on one thread (the serial pass, as bench_element_forces.cpp):
// - element_forces3/<element>/<material>: the cube of 20^3 = 8000 cells (48 000 tetrahedra);
// - element_forces3_stress_all/..., _stress_bound/...: with the per-step Cauchy von Mises
//   tracking, every point ranked (threshold 0) or every point skipped by the bound;
// - element_forces3_scaling/<element>/svk/<n>: cubes of n = 10, 22, 46, 100 a side (1e3, 1.06e4,
//   9.7e4, 1e6 cells);
// - explicit_step3/<element>/svk/<n>[/threads:2]: a whole explicit step on those cubes (tet4:
//   6 n^3 cells), one and two threads.
// Reported: time per call, and element_steps_per_second = cells processed per second
// [cells/s] (items_per_second counts the same cells).
#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "bench/bench_common.hpp"
#include "bench/explicit_steps.hpp"
#include "harness/input/mesh_generators3.hpp"
#include "solver/forces/internal_forces.hpp"
#include "solver/schemes/central_difference.hpp"
#include "solver/schemes/threads.hpp"

namespace ricochet::bench {
namespace {

enum class Element3 { hex8_2x2x2, hex8_one_point_viscous, hex8_one_point_stiffness, tet4 };

std::string_view element3_name(Element3 e) {
  switch (e) {
    case Element3::hex8_2x2x2: return "hex8_2x2x2";
    case Element3::hex8_one_point_viscous: return "hex8_one_point_viscous_hg";
    case Element3::hex8_one_point_stiffness: return "hex8_one_point_stiffness_hg";
    case Element3::tet4: return "tet4";
  }
  return "unknown";
}

constexpr double cube_side = 0.1;  // [m]

// Steel-like (E = 200 GPa, nu = 0.3, rho = 7800 kg/m^3), hourglass coefficient 0.1. The last
// model built is cached (the library calls a benchmark function several times).
const Model<3>& cube_model(Element3 element, MaterialKind material, int n) {
  struct Cached {
    Element3 element;
    MaterialKind material;
    int n = 0;
    Model<3> model;
  };
  static std::optional<Cached> cache;
  if (cache && cache->element == element && cache->material == material && cache->n == n) return cache->model;
  cache.reset();
  BoxSpec spec;
  spec.size = Vec3::Constant(cube_side);
  spec.nx = spec.ny = spec.nz = n;
  spec.tetrahedra = element == Element3::tet4;
  BodyInput<3> body;
  body.name = "cube";
  body.mesh = make_box(spec);
  if (material == MaterialKind::st_venant_kirchhoff)
    body.material = StVenantKirchhoff3::make(200e9, 0.3, 7800.0);
  else
    body.material = NeoHookean3::make(200e9, 0.3, 7800.0);
  body.hex_element = element == Element3::hex8_2x2x2 ? HexElement::full_2x2x2 : HexElement::one_point_hourglass;
  body.hourglass.form =
      element == Element3::hex8_one_point_stiffness ? HourglassForm::stiffness : HourglassForm::viscous;
  cache = Cached{element, material, n, build_model({body}, Vec3::Zero())};
  return cache->model;
}

// Per DOF (3n): amplitude * (a smooth mode of wavelength 2 cube_side + 1e-3 * a checkerboard).
Eigen::VectorXd cube_field(const Model<3>& model, int n, double amplitude) {
  const double k = std::numbers::pi / cube_side;
  Eigen::VectorXd a(model.num_dofs());
  for (int p = 0; p < model.num_nodes(); ++p) {
    const double x = model.ref(0, p), y = model.ref(1, p), z = model.ref(2, p);
    const int i = p % (n + 1), j = p / (n + 1) % (n + 1), l = p / ((n + 1) * (n + 1));
    const double checker = (i + j + l) % 2 == 0 ? 1e-3 : -1e-3;
    a(3 * p) = amplitude * (std::sin(k * x) * std::cos(k * y) * std::cos(k * z) + checker);
    a(3 * p + 1) = amplitude * (std::cos(k * x) * std::sin(k * y) * std::cos(k * z) - checker);
    a(3 * p + 2) = amplitude * (std::cos(k * x) * std::cos(k * y) * std::sin(k * z) + checker);
  }
  return a;
}

enum class StressMode { off, all, bound };

void element_forces3(benchmark::State& state, Element3 element, MaterialKind material, int n, StressMode mode) {
  const Model<3>& model = cube_model(element, material, n);
  const Eigen::VectorXd u = cube_field(model, n, 1e-5);  // [m], strain ~3e-4
  const Eigen::VectorXd v = cube_field(model, n, 1.0);   // [m/s]
  Eigen::VectorXd f(model.num_dofs());
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

  if (!f.allFinite() || !(f.norm() > 0.0) || !(totals.min_jacobian > 0.9)) fail(state, "invalid internal forces");
  if (mode == StressMode::all && !(totals.stress.all > 0.0 && totals.stress.interior_cell >= 0))
    fail(state, "no stress peak tracked");
  if (mode == StressMode::bound && totals.stress.all_cell >= 0) fail(state, "a point passed an unreachable threshold");
  state.SetItemsProcessed(state.iterations() * model.num_cells());
  state.counters["element_steps_per_second"] =
      benchmark::Counter(model.num_cells(), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["cells"] = model.num_cells();
}

// A full explicit step of the 3D model without energies: evaluate() (the threaded force pass,
// accelerations) then update(), on the cube vibrating from the small smooth field above
// (dt = 0.5 x model.critical_dt), one thread, or two for the names ending in /threads:2 (wall
// time): the 3D rows of the scaling table of docs/performance.md.
void explicit_step3(benchmark::State& state, Element3 element, int n, int threads) {
  const ThreadScope scope(threads);
  const Model<3>& model = cube_model(element, MaterialKind::st_venant_kirchhoff, n);
  const std::vector<PrescribedDof> prescribed;
  State s = initial_state(model, prescribed, 0.5 * model.critical_dt, cube_field(model, n, 1e-5));
  s.v_half = cube_field(model, n, 1.0);
  evaluate(model, prescribed, s, /*with_energy=*/false);
  update(s);
  s = time_explicit_steps(state, model, prescribed, State(s));
  if (!s.u.allFinite() || !(s.forces.min_jacobian > 0.9)) fail(state, "state left the small-strain regime");
  state.SetItemsProcessed(state.iterations() * model.num_cells());
  state.counters["element_steps_per_second"] =
      benchmark::Counter(model.num_cells(), benchmark::Counter::kIsIterationInvariantRate);
}

const bool registered = [] {
  constexpr int n = 20;
  for (const Element3 e : {Element3::hex8_2x2x2, Element3::hex8_one_point_viscous, Element3::hex8_one_point_stiffness,
                           Element3::tet4})
    for (const MaterialKind m : {MaterialKind::st_venant_kirchhoff, MaterialKind::neo_hookean})
      for (const StressMode mode : {StressMode::off, StressMode::all, StressMode::bound}) {
        const char* prefix = mode == StressMode::off   ? "element_forces3/"
                             : mode == StressMode::all ? "element_forces3_stress_all/"
                                                       : "element_forces3_stress_bound/";
        const std::string name = prefix + std::string(element3_name(e)) + "/" + std::string(material_name(m));
        benchmark::RegisterBenchmark(name.c_str(), element_forces3, e, m, n, mode)->Unit(benchmark::kMicrosecond);
      }
  for (const Element3 e : {Element3::hex8_2x2x2, Element3::hex8_one_point_viscous, Element3::hex8_one_point_stiffness})
    for (const int side : {10, 22, 46, 100}) {
      const std::string name = "element_forces3_scaling/" + std::string(element3_name(e)) + "/svk/" + std::to_string(side);
      benchmark::RegisterBenchmark(name.c_str(), element_forces3, e, MaterialKind::st_venant_kirchhoff, side,
                                   StressMode::off)
          ->Unit(benchmark::kMillisecond);
    }
  for (const Element3 e : {Element3::hex8_2x2x2, Element3::hex8_one_point_viscous, Element3::tet4})
    for (const int side : {10, 22, 46, 100})
      for (const int threads : {1, 2}) {
        const std::string name = "explicit_step3/" + std::string(element3_name(e)) + "/svk/" + std::to_string(side) +
                                 (threads > 1 ? "/threads:2" : "");
        auto* b = benchmark::RegisterBenchmark(name.c_str(), explicit_step3, e, side, threads)
                      ->Unit(benchmark::kMillisecond);
        if (threads > 1) b->UseRealTime();
      }
  return true;
}();

}  // namespace
}  // namespace ricochet::bench
