// From a validated case to what the solver runs: meshes built or read, node sets resolved,
// the model assembled, prescribed DOFs and probes placed, the time step fixed.
#pragma once

#include <vector>

#include "harness/input/case_spec.hpp"
#include "solver/schemes/explicit.hpp"

namespace ricochet {

struct ProbeInfo {
  std::string name;
  std::string body;
  int node = 0;           // global node index
  Vec3 position;          // reference coordinates of that node [m]; z = 0 in 2D
  double distance = 0.0;  // from the requested point [m]
};

// A 2D case (spec.dimension 2) has its meshes and model in `meshes` and `model`, a 3D one in
// `meshes3` and `model3`; the others stay empty. Code for both reaches the case's model through
// with_model().
struct PreparedCase {
  CaseSpec spec;
  std::vector<Mesh> meshes;  // per body, after scale and offset, with all node sets (2D)
  Model<2> model;
  std::vector<Mesh3> meshes3;  // the same in 3D
  Model<3> model3;
  int dimension() const { return spec.dimension; }
  RunSettings settings;     // settings.dt: the step of the run, decided by prepare_case
  // The step was chosen automatically (time.dt absent): safety x critical_time_step().
  bool dt_auto() const { return !spec.dt.has_value(); }
  double penalty_critical_dt = 0.0;  // 2 sqrt(m/k) over the penalty springs [s]; 0 if none
  std::vector<ProbeInfo> probes;
};

// fn(model) with the case's model, a Model<2> or a Model<3> (they share the names fn may use:
// bodies, num_nodes(), num_cells(), critical_dt, critical_cell, ref, mass, kDim).
template <class Fn>
decltype(auto) with_model(const PreparedCase& pc, Fn&& fn) {
  if (pc.dimension() == 3) return fn(pc.model3);
  return fn(pc.model);
}

// Throws InputError naming the case file and key for anything that cannot be set up
// (unreadable mesh, unknown node set, degenerate cell, conflicting prescriptions).
PreparedCase prepare_case(const CaseSpec& spec);

// Runs the case with its scheme: explicit and semi-explicit and explicit penalty through the
// central-difference loop, implicit through the theta-scheme.
RunResult run_case(const PreparedCase& pc, const ProgressFn& progress = {});

}  // namespace ricochet
