// The explicit time loop (central differences) of the semi-explicit and the explicit penalty
// schemes: evaluate, the contact solve of the run's method, the observers, update.
#pragma once

#include "solver/schemes/run_types.hpp"

namespace ricochet {

// M is the model type (Model<2>: 2D), instantiated in explicit.cpp.
template <class M>
RunResult run_explicit(const M& model, const RunSettings& settings, const ProgressFn& progress = {});

}  // namespace ricochet
