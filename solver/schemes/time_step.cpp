#include "solver/schemes/time_step.hpp"

#include "solver/contact/penalty_contact.hpp"

namespace ricochet {

double critical_time_step(const Model& model, const RunSettings& settings, double* penalty_critical) {
  const bool contact = !settings.obstacles.empty() || !settings.body_pairs.empty();
  if (settings.contact_method != RunSettings::ContactMethod::penalty || !contact) return model.critical_dt;
  const PenaltyContact springs = make_penalty_contact(model, settings.obstacles, settings.friction,
                                                      settings.prescribed, settings.penalty, settings.body_pairs);
  if (penalty_critical) *penalty_critical = penalty_critical_dt(model, springs);
  return penalty_combined_critical_dt(model, springs);
}

}  // namespace ricochet
