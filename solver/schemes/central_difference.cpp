#include "solver/schemes/central_difference.hpp"

#include <omp.h>

#include "solver/forces/internal_forces.hpp"

namespace ricochet {
namespace {

// fn(i0, i1) over the DOFs i0 <= i < i1: all of them on this thread, or one contiguous part
// per thread where the force pass uses the run's threads (a model of at least
// kForceParallelChunks chunks). fn works on each entry alone, so the results do not depend on
// the number of threads.
template <class Fn>
void for_dof_ranges(const State& s, Fn&& fn) {
  const long n = s.u.size();
  if (s.force_scratch.chunks.size() >= kForceParallelChunks && omp_get_max_threads() > 1) {
#pragma omp parallel
    {
      const long t = omp_get_thread_num(), nt = omp_get_num_threads();
      fn(n * t / nt, n * (t + 1) / nt);
    }
  } else {
    fn(0L, n);
  }
}

// a = M^-1 (f_ext - f_int) on DOFs i0 <= i < i1 (restrict: the loops vectorize).
void accelerations(long i0, long i1, double* __restrict a, const double* __restrict inv_mass,
                   const double* __restrict f_ext, const double* __restrict f_int) {
  for (long i = i0; i < i1; ++i) a[i] = inv_mass[i] * (f_ext[i] - f_int[i]);
}

// v_{n+1/2} = v_{n-1/2} + dt_n a_n, u_{n+1} = u_n + dt v_{n+1/2} on DOFs i0 <= i < i1
// (dt_n = dt for a fixed step).
void advance(long i0, long i1, double dt_n, double dt, double* __restrict v, double* __restrict u,
             const double* __restrict a) {
  for (long i = i0; i < i1; ++i) {
    v[i] += dt_n * a[i];
    u[i] += dt * v[i];
  }
}

}  // namespace

template <class M>
State initial_state(const M& model, const std::vector<PrescribedDof>& prescribed, double dt,
                    const Eigen::VectorXd& initial_displacement, const std::vector<NodalLoad>& loads) {
  constexpr int D = M::kDim;
  const int n = model.num_dofs();
  State s;
  s.dt = dt;
  s.dt_prev = dt;
  s.u = initial_displacement.size() == n ? initial_displacement : Eigen::VectorXd::Zero(n);
  s.v_half = model.initial_velocity;
  s.a = Eigen::VectorXd::Zero(n);
  s.f_int = Eigen::VectorXd::Zero(n);
  s.f_ext.resize(n);
  s.force_scratch = make_force_scratch(model);
  for (int i = 0; i < model.num_nodes(); ++i)
    s.f_ext.segment<D>(D * i) = model.mass(D * i) * model.gravity;
  for (const auto& p : prescribed) {
    if (p.kind == PrescribedDof::Kind::velocity) {
      s.v_half[p.dof] = p.value;
    } else {
      s.u[p.dof] = p.displacement_at(0.0);
      s.v_half[p.dof] = p.ramp > 0.0 ? p.value / p.ramp : 0.0;
    }
  }
  s.loads.reserve(loads.size());
  for (const NodalLoad& l : loads) s.loads.push_back({l, 0.0, 0.0});
  return s;
}

template <class M>
void evaluate(const M& model, const std::vector<PrescribedDof>& prescribed, State& s, bool with_energy,
              const StressTracking* stress) {
  s.forces = internal_forces(model, s.u.data(), s.v_half.data(), s.f_int.data(), with_energy, stress,
                             &s.force_scratch);
  for_dof_ranges(s, [&](long i0, long i1) {
    accelerations(i0, i1, s.a.data(), model.inv_mass.data(), s.f_ext.data(), s.f_int.data());
  });
  // Nodal loads F(t_n), and their work over the last step: 1/2 (F_{n-1} + F_n) (u_n - u_{n-1}).
  for (LoadedDof& l : s.loads) {
    const int d = l.load.dof;
    const double f = l.load.force_at(s.time);
    if (s.step > 0) s.load_work += 0.5 * (l.force_last + f) * (s.u[d] - l.u_last);
    l.force_last = f;
    l.u_last = s.u[d];
    s.a[d] += model.inv_mass[d] * f;
  }
  // The hourglass forces of t_n act on the velocity over dt_n.
  const double dt_n = velocity_step(s);
  s.hourglass_dissipation += dt_n * s.forces.hourglass_power;
  if (s.step == 0) s.v_half -= 0.5 * s.dt_prev * s.a;
  // Prescribed DOFs: the acceleration that lands v_{n+1/2} on its prescribed value; the
  // reaction R = m (a - a_free) works at the rate R v_n, v_n = v_{n-1/2} + dt_{n-1/2}/2 a (the
  // mean of the half steps' velocities when the step is fixed).
  const bool fixed = s.dt_prev == s.dt;
  double power = 0.0;
  for (const auto& p : prescribed) {
    const int d = p.dof;
    const double v_next =
        p.kind == PrescribedDof::Kind::velocity
            ? p.value
            : (p.displacement_at(s.time + s.dt) - s.u[d]) / s.dt;
    if (s.step == 0) s.v_half[d] = v_next;
    const double a = (v_next - s.v_half[d]) / dt_n;
    const double reaction = model.mass[d] * (a - s.a[d]);
    s.a[d] = a;
    const double v_n = fixed ? 0.5 * (s.v_half[d] + v_next) : s.v_half[d] + 0.5 * s.dt_prev * a;
    power += reaction * v_n;
  }
  // Trapezoidal rule over [t_n-1, t_n], of length dt_{n-1/2}.
  if (s.step > 0) s.reaction_work += 0.5 * s.dt_prev * (s.reaction_power + power);
  s.reaction_power = power;
}

void update(State& s) {
  const double dt = s.dt, dt_n = velocity_step(s);
  for_dof_ranges(s, [&](long i0, long i1) { advance(i0, i1, dt_n, dt, s.v_half.data(), s.u.data(), s.a.data()); });
  ++s.step;
  s.dt_prev = dt;
  s.time = s.time_base + static_cast<double>(s.step - s.step_base) * s.dt;
}

// The instantiations: one per model type.
template State initial_state<Model<2>>(const Model<2>&, const std::vector<PrescribedDof>&, double, const Eigen::VectorXd&,
                                    const std::vector<NodalLoad>&);
template void evaluate<Model<2>>(const Model<2>&, const std::vector<PrescribedDof>&, State&, bool, const StressTracking*);
template State initial_state<Model<3>>(const Model<3>&, const std::vector<PrescribedDof>&, double, const Eigen::VectorXd&,
                                     const std::vector<NodalLoad>&);
template void evaluate<Model<3>>(const Model<3>&, const std::vector<PrescribedDof>&, State&, bool, const StressTracking*);

}  // namespace ricochet
