// What a run will do, checked before it starts: the number of steps and history rows against
// the case's ceilings, the memory it will hold against the machine's, and the automatic step
// against time.end (docs/reliability.md, "Limits and how to raise them"). Each check fails
// with one InputError line naming the keys involved, before anything is built or written.
#pragma once

#include <cstddef>
#include <string>

#include "harness/input/case_spec.hpp"

namespace ricochet {

struct PreparedCase;

// The memory this process may use [bytes]: the machine's physical memory, or the cgroup's
// limit (cgroup v2 memory.max) when that is lower; 0 if neither can be read.
double machine_memory_bytes();

// The default of limits.max_memory [GiB]: 80 % of machine_memory_bytes() (64 GiB if unknown).
double default_max_memory_gib();

// Estimated bytes a model of `nodes` nodes and `cells` cells holds while it runs (mesh, model,
// state, element workspace, contact data; measured on rectangle meshes of 1e5 to 1e6 cells
// with a margin: docs/reliability.md).
double model_bytes(double nodes, double cells);

// The nodes and cells a generated mesh will have (its generator's formula), or -1 for a mesh
// read from a file (known only once read).
double generated_nodes(const MeshSpec& m);
double generated_cells(const MeshSpec& m);

// Before any mesh is built: the generated meshes' estimated memory against limits.max_memory.
void check_mesh_plan(const CaseSpec& c);

// Once the step is decided (pc.settings.dt): the automatic step is a positive finite time no
// longer than time.end; ceil(time.end / dt) <= limits.max_steps; the history rows <=
// limits.max_history_rows; and the model, the history and the field snapshots held until they
// are written fit in limits.max_memory.
void check_run_plan(const PreparedCase& pc);

// The history rows a fixed-step run of `steps` steps of dt, sampled every `interval` (0: every
// step), writes: an upper bound, computed without overflow.
double planned_history_rows(double steps, double dt, double interval);

}  // namespace ricochet
