// The time step, decided once for every scheme and command (docs/background.md, Critical time
// step): the stable step of a model under a run's contact method.
#pragma once

#include "solver/schemes/run_types.hpp"

namespace ricochet {

// The critical step (safety 1) of a model under a run's contact method [s], the one rule the
// automatic step (safety x this) and the stability search use: the elements' estimate
// model.critical_dt (min L_e / c_p), and with penalty contact the combined limit of elements
// and springs, 1 / sqrt(1 / dt_e^2 + 1 / dt_p^2) (penalty_combined_critical_dt). With penalty
// contact, `penalty_critical_dt` (if not null) receives the springs' own limit dt_p (+infinity
// without springs); it is left alone otherwise. Penalty springs of `settings.penalty.soft`
// depend on settings.penalty.soft_dt, which must be set.
double critical_time_step(const Model& model, const RunSettings& settings, double* penalty_critical_dt = nullptr);

}  // namespace ricochet
