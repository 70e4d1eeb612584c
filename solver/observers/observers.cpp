#include "solver/observers/observers.hpp"

#include <cmath>

namespace ricochet {

Energies observe_energies(const Model& model, const State& s, const Eigen::VectorXd& u0) {
  Energies e;
  const Eigen::VectorXd& m = model.mass;
  double kinetic = 0.0;
  for (int d = 0; d < model.num_dofs(); ++d) {
    const double v = velocity_at_step(s, d);
    kinetic += m[d] * v * v;
  }
  e.kinetic = 0.5 * kinetic;
  e.strain = s.forces.strain_energy;
  e.hourglass = s.forces.hourglass_energy + s.hourglass_dissipation;
  e.external_work = s.f_ext.dot(s.u - u0) + s.reaction_work;
  if (!s.loads.empty()) e.external_work += s.load_work;  // (a run without loads keeps its bits)
  return e;
}

Vec2 linear_momentum(const Model& model, const State& s) {
  Vec2 p = Vec2::Zero();
  for (int i = 0; i < model.num_nodes(); ++i)
    for (int k = 0; k < 2; ++k) p[k] += model.mass[2 * i + k] * velocity_at_step(s, 2 * i + k);
  return p;
}

double energy_error(const Energies& e, double initial_energy, double reference_energy) {
  if (!(reference_energy > 0.0)) return 0.0;
  return std::abs(e.total() + e.friction_dissipation - initial_energy - e.external_work) /
         reference_energy;
}

}  // namespace ricochet
