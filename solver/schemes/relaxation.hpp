// A quasi-static start (case table [relaxation], docs/case-format.md; the method and its
// criterion in docs/background.md, Quasi-static start): before the clock starts, the scene is
// brought to equilibrium under its t = 0 loads by dynamic relaxation (Underwood 1983) with
// kinetic damping (Cundall 1976): the scheme's own central-difference steps with its own contact
// treatment run under the constant loads, and all velocities are set to zero whenever the total
// kinetic energy passes a peak. The relaxed state is then an equilibrium of that scheme: the
// penalty springs keep their penetration and their friction springs' state, the bi-potential
// contacts keep their reactions as the warm start of the first step.
//
// During the relaxation the prescribed DOFs are held where they are at t = 0, and each nodal
// load acts with its value at t = 0 (so a load that starts later, or ramps up from 0, does not
// act). After it, the run starts at t = 0 from the relaxed displacement, which becomes the
// reference u_0 of the energy balance, with the case's initial velocities.
//
// Converged when, at a step,
//   ||f_ext - f_int(u_n) + R_n||_2 <= tolerance ||f_ext||_2   over the free DOFs, and
//   E_kin(v_{n-1/2}) <= tolerance^2 max over the relaxation of E_kin,
// with f_ext the constant loads (body forces and the loads active at t = 0) and R_n the contact
// reactions of the step (the residual is M a_n after the contact solve). Without any load,
// ||f_int(u_n)||_2 (the supports' forces) replaces ||f_ext||_2; with neither, the start is at
// rest and in equilibrium.
#pragma once

#include "solver/contact/bipotential_contact.hpp"
#include "solver/contact/penalty_contact.hpp"
#include "solver/schemes/run_types.hpp"

namespace ricochet {

// The relaxation's step as a fraction of the run's explicit step. Kinetic damping zeroes
// v_{n+1/2} at a kinetic-energy peak; with the displacement then set to the step's midpoint
// (u_{n+1} - dt/2 v_{n+1/2}), a reset removes 1/2 v^T (M - dt^2 K / 4) v from the energy the
// central-difference step conserves (for a linear system: 1/2 v_{n+1/2}^T M v_{n+1/2} +
// 1/2 u_n^T K u_{n+1} - f^T (u_n + u_{n+1}) / 2), so it never adds energy; but a mode with
// omega dt near 2 loses almost nothing. At the run's own step (safety 0.9: omega dt up to 1.8)
// the frictionless block on flat ground locked into a period-3 cycle of resets with its
// residual at 9e-4 for 1e5 steps; at half the step (omega dt <= 0.9: every reset at a mode's
// peak removes >= 80 % of its kinetic energy) it converged in 243 steps
// (docs/background.md, Quasi-static start).
inline constexpr double kRelaxationStepFactor = 0.5;

// The relaxation's step [s]: settings.relaxation.dt if > 0, else kRelaxationStepFactor x the
// run's step (explicit schemes) or x 0.9 x the elements' critical step (implicit scheme).
template <class M>
double relaxation_step(const M& model, const RunSettings& settings, bool implicit);

// The contact treatment a relaxation steps with: the run's own (at most one; none without
// contact candidates).
template <int D>
struct RelaxationContactT {
  BipotentialContactT<D>* bipotential = nullptr;
  PenaltyContactT<D>* penalty = nullptr;
};

template <class M>
class RelaxationT {
 public:
  enum class Status { running, converged, failed };

  // Set-up (allocates): the relaxation's state at the displacement u_start (the run's t = 0
  // displacement), at rest, with the prescribed DOFs held and the loads at their t = 0 value.
  RelaxationT(const M& model, const RunSettings& settings, double dt, const Eigen::VectorXd& u_start,
              RelaxationContactT<M::kDim> contact);

  // One relaxation step: evaluate() and the contact solve at u_n, the convergence test; unless
  // converged, update() and the kinetic damping. failed: an inverted element, a non-finite
  // residual, or settings.relaxation.max_steps steps taken (report().reason). Allocates nothing.
  Status step();

  const State& state() const { return s_; }
  const RelaxationReport& report() const { return report_; }

 private:
  void contact();

  const M& model_;
  const RunSettings& settings_;
  RelaxationContactT<M::kDim> contact_;
  std::vector<PrescribedDof> held_;  // the prescribed DOFs, held at their t = 0 value
  std::vector<unsigned char> fixed_;  // per DOF: prescribed
  State s_;
  double load_norm_ = 0.0;      // ||f_ext + F(0)||_2 [N]
  double kinetic_last_ = 0.0;   // E_kin of v_{n-1/2} after the damping [J]
  double kinetic_peak_ = 0.0;   // [J]
  RelaxationReport report_;
};

// The explicit schemes: relaxes from s, the run's initial state, with the run's contact
// objects at relaxation_step(), and hands over. On success s is the run's initial state at the
// relaxed displacement (initial_state() with the case's initial velocities and loads), except
// that v_half holds v_0 - dt/2 M^-1 R with R the relaxed contact forces (see
// relaxation.cpp: the first step then starts from v_{-1/2} = v_0 - dt/2 a_0 with the contact
// forces in a_0), and the contact sets keep their reactions, statuses and penalty springs, with
// their observables reset. Returns false when the relaxation did not converge (report.reason);
// s is then the initial state at its last iterate.
template <class M>
bool relax_explicit_start(const M& model, const RunSettings& settings, RelaxationContactT<M::kDim> contact,
                          State& s, RelaxationReport& report);

// The implicit scheme: relaxes with the semi-explicit loop (central differences and the same
// bi-potential contact law, on a contact set of its own) at relaxation_step(), and gives the
// relaxed displacement. A static equilibrium does
// not depend on the integrator that reached it: at u with v = 0 and f_int(u) = f_ext + R, R in
// the Coulomb cone and the contacts closed, the implicit step's solution is v1 = 0 with the
// same R. Returns false when it did not converge (report.reason); u is then its last iterate.
template <class M>
bool relax_displacement(const M& model, const RunSettings& settings, Eigen::VectorXd& u,
                        RelaxationReport& report);

using RelaxationContact = RelaxationContactT<2>;
using Relaxation = RelaxationT<Model<2>>;

}  // namespace ricochet
