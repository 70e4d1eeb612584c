// From a validated case to what the solver runs: meshes built or read, node sets resolved,
// the model assembled, prescribed DOFs and probes placed, the time step fixed.
#pragma once

#include <type_traits>
#include <variant>
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

// The bodies of a case as built, in dimension D: per body its mesh (after scale, offset and the
// scene rotation, with all node sets; Mesh in 2D, Mesh3 in 3D), and the model assembled from them.
template <int D>
struct CaseBodies {
  std::vector<std::conditional_t<D == 2, Mesh, Mesh3>> meshes;
  Model<D> model;
};

struct PreparedCase {
  CaseSpec spec;
  std::variant<CaseBodies<2>, CaseBodies<3>> bodies;  // of spec.dimension
  int dimension() const { return spec.dimension; }
  // The model and meshes of a case of dimension D (std::bad_variant_access for the other one).
  template <int D>
  const Model<D>& model() const { return std::get<CaseBodies<D>>(bodies).model; }
  template <int D>
  const auto& meshes() const { return std::get<CaseBodies<D>>(bodies).meshes; }
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
  if (pc.dimension() == 3) return fn(pc.model<3>());
  return fn(pc.model<2>());
}

// Throws InputError naming the case file and key for anything that cannot be set up
// (unreadable mesh, unknown node set, degenerate cell, conflicting prescriptions).
PreparedCase prepare_case(const CaseSpec& spec);

// Runs the case with its scheme: explicit and semi-explicit and explicit penalty through the
// central-difference loop, implicit through the theta-scheme.
RunResult run_case(const PreparedCase& pc, const ProgressFn& progress = {});

}  // namespace ricochet
