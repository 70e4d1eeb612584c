// The resolved case that an external scheme's adapter is given: case.json (docs/peers.md,
// "case.json: what the adapter is given"). Everything in it is what ricochet itself would run:
// the meshes after every transform, the lumped masses, the initial velocities, the obstacles,
// the contact candidates with ricochet's own penalty stiffness, the step prepare_case chose.
#pragma once

#include "harness/input/case_setup.hpp"
#include "harness/outputs/json_io.hpp"

namespace ricochet {

// case.json of a prepared case whose scheme is external (format "ricochet-external-case",
// version 1).
Json external_case_json(const PreparedCase& pc);

}  // namespace ricochet
