#include "solver/observers/observers.hpp"

#include <cmath>

#include "solver/model/model.hpp"

namespace ricochet {

template <class M>
Energies observe_energies(const M& model, const State& s, const Eigen::VectorXd& u0) {
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

template <class M>
Eigen::Matrix<double, M::kDim, 1> linear_momentum(const M& model, const State& s) {
  constexpr int D = M::kDim;
  Eigen::Matrix<double, D, 1> p = Eigen::Matrix<double, D, 1>::Zero();
  for (int i = 0; i < model.num_nodes(); ++i)
    for (int k = 0; k < D; ++k) p[k] += model.mass[D * i + k] * velocity_at_step(s, D * i + k);
  return p;
}

template Energies observe_energies<Model<2>>(const Model<2>&, const State&, const Eigen::VectorXd&);
template Vec2 linear_momentum<Model<2>>(const Model<2>&, const State&);
template Energies observe_energies<Model<3>>(const Model<3>&, const State&, const Eigen::VectorXd&);
template Vec3 linear_momentum<Model<3>>(const Model<3>&, const State&);

double energy_error(const Energies& e, double initial_energy, double reference_energy) {
  if (!(reference_energy > 0.0)) return 0.0;
  return std::abs(e.total() + e.friction_dissipation - initial_energy - e.external_work) /
         reference_energy;
}

}  // namespace ricochet
