#include "solver/schemes/central_difference.hpp"

namespace ricochet {

State initial_state(const Model& model, const std::vector<PrescribedDof>& prescribed, double dt,
                    const Eigen::VectorXd& initial_displacement) {
  const int n = model.num_dofs();
  State s;
  s.dt = dt;
  s.u = initial_displacement.size() == n ? initial_displacement : Eigen::VectorXd::Zero(n);
  s.v_half = model.initial_velocity;
  s.a = Eigen::VectorXd::Zero(n);
  s.f_int = Eigen::VectorXd::Zero(n);
  s.f_ext.resize(n);
  s.force_scratch = make_force_scratch(model);
  for (int i = 0; i < model.num_nodes(); ++i)
    s.f_ext.segment<2>(2 * i) = model.mass(2 * i) * model.gravity;
  for (const auto& p : prescribed) {
    if (p.kind == PrescribedDof::Kind::velocity) {
      s.v_half[p.dof] = p.value;
    } else {
      s.u[p.dof] = p.displacement_at(0.0);
      s.v_half[p.dof] = p.ramp > 0.0 ? p.value / p.ramp : 0.0;
    }
  }
  return s;
}

void evaluate(const Model& model, const std::vector<PrescribedDof>& prescribed, State& s,
              bool with_energy, const StressTracking* stress) {
  s.forces = internal_forces(model, s.u.data(), s.v_half.data(), s.f_int.data(), with_energy, stress,
                             &s.force_scratch);
  s.a = model.inv_mass.cwiseProduct(s.f_ext - s.f_int);
  s.hourglass_dissipation += s.dt * s.forces.hourglass_power;
  if (s.step == 0) s.v_half -= 0.5 * s.dt * s.a;
  // Prescribed DOFs: the acceleration that lands v_{n+1/2} on its prescribed value; the
  // reaction R = m (a - a_free) works at the rate R v_n.
  double power = 0.0;
  for (const auto& p : prescribed) {
    const int d = p.dof;
    const double v_next =
        p.kind == PrescribedDof::Kind::velocity
            ? p.value
            : (p.displacement_at(s.time + s.dt) - s.u[d]) / s.dt;
    if (s.step == 0) s.v_half[d] = v_next;
    const double a = (v_next - s.v_half[d]) / s.dt;
    const double reaction = model.mass[d] * (a - s.a[d]);
    s.a[d] = a;
    power += reaction * 0.5 * (s.v_half[d] + v_next);
  }
  if (s.step > 0) s.reaction_work += 0.5 * s.dt * (s.reaction_power + power);
  s.reaction_power = power;
}

void update(State& s) {
  s.v_half += s.dt * s.a;
  s.u += s.dt * s.v_half;
  ++s.step;
  s.time = static_cast<double>(s.step) * s.dt;
}

}  // namespace ricochet
