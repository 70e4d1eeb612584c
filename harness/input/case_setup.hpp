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
  Vec2 position;          // reference coordinates of that node [m]
  double distance = 0.0;  // from the requested point [m]
};

struct PreparedCase {
  CaseSpec spec;
  std::vector<Mesh> meshes;  // per body, after scale and offset, with all node sets
  Model model;
  RunSettings settings;     // settings.dt: the step of the run, decided by prepare_case
  // The step was chosen automatically (time.dt absent): safety x critical_time_step().
  bool dt_auto() const { return !spec.dt.has_value(); }
  double penalty_critical_dt = 0.0;  // 2 sqrt(m/k) over the penalty springs [s]; 0 if none
  std::vector<ProbeInfo> probes;
};

// Throws InputError naming the case file and key for anything that cannot be set up
// (unreadable mesh, unknown node set, degenerate cell, conflicting prescriptions).
PreparedCase prepare_case(const CaseSpec& spec);

// Runs the case with its scheme: explicit and semi-explicit and explicit penalty through the
// central-difference loop, implicit through the theta-scheme.
RunResult run_case(const PreparedCase& pc, const ProgressFn& progress = {});

}  // namespace ricochet
