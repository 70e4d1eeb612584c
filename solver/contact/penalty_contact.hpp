// The explicit penalty scheme's contact solve, LS-DYNA style (the paper's comparison scheme;
// docs/background.md, Penalty contact). The candidates, frames and observables are the shared
// contact module's (contact_set.hpp); this file holds the springs only. It plugs in where the
// bi-potential contact_phase() does: after evaluate() gives the free accelerations at t_n, penalty_phase() adds
// the forces of springs acting on the candidate nodes that lie behind an obstacle at u_n, and
// update() integrates them like any other force. No contact condition is enforced: the penalty lets
// a node penetrate until its spring balances the impact.
//
// Stiffness (2D form of LS-DYNA's SOFT = 0 rule k = f_si K A^2 / V; docs/background.md,
// Penalty contact):
//   every boundary segment s (a cell edge used by exactly one cell) of a body has the
//   segment stiffness
//       k_s = f_si K (l_s e)^2 / (A_c e) = f_si K l_s^2 e / A_c,
//   with l_s its reference length, e the body's thickness, A_c the reference area of the
//   one cell that owns s (so A = l_s e is the segment area and V = A_c e the owning element's
//   volume). A node receives half the stiffness of each boundary segment it ends:
//       k_i = sum over the boundary segments s of node i of k_s / 2.
//   When the node's two segments have the same length l and owning-cell area A_c this is
//   exactly f_si K A_i^2 / V with A_i = l e the node's tributary boundary area and V = A_c e;
//   on a uniform grid of h x h cells every boundary node (corners too) gets k = f_si K e.
//   The share of a segment that does not face the obstacle (a side edge ending at a bottom
//   corner) is counted as well: the stiffness is a property of the node, as in LS-DYNA's
//   slave-node option, not of the pair.
// Soft constraint (PenaltySettings::soft_scale > 0, LS-DYNA SOFT = 1): every spring is at least
//   k1 = soft_scale m* / (2 soft_dt^2)   (m* the lightest node of the contact's stencil),
// so that a soft body meeting a stiff one, whose step is set by the stiff one, is not stopped by
// springs scaled to its own small bulk modulus only.
// Bulk modulus K: the 3D value K = lambda + 2 mu / 3 = E / (3 (1 - 2 nu)) of the material's
// (E, nu), in plane stress and plane strain alike. LS-DYNA takes K from the material card whatever
// the element formulation (its plane-stress solids, ELFORM 12, included), and the penetration
// estimate delta / h ~ sigma / (f_si K) (docs/background.md, Penalty contact) uses this K, so f_si
// keeps its LS-DYNA meaning here. (The plane-stress 2D bulk modulus lambda* + mu = E / (2 (1 - nu))
// would be 14 % smaller at nu = 0.3 and stays bounded as nu -> 1/2, where the 3D value diverges.)
//
// Forces at t_n, per candidate with (g, n) = closest(obstacle, X + u_n) (g = n . (x - point) for a
// line; for circles and polylines n is the normal at the closest point, t = (n_y, -n_x), both
// frozen for the step, see contact.hpp):
//   normal:     f_n = -k g if g < 0, else 0 (pushes along n);
//   tangential: an elastic spring of the same k on the slip, with a return map:
//                 f* = f_t,old - k ds, ds = t . x_n - t . x_{n-1} the node's slip increment along
//                 the current tangent t over the last step,
//                 f_t = f* if |f*| <= mu f_n (stick), else mu f_n sign(f*) (slip);
//               an open contact (f_n = 0) returns f_t to 0. mu = 0 skips all of it.
//   Force on the node: f_n n + f_t t, added to s.a as f / m.
// Energies: the stored (penalty) energy U = sum over active candidates of
//   1/2 k g^2 + f_t^2 / (2 k); the friction dissipation of a step is
//   D = (f* - f_t) (f_t,old + f_t) / (2 k): the returned (plastic) slip (f* - f_t) / k times the
//   step's mean friction force. With the trapezoidal work W = (f_t,old + f_t) ds / 2 of the
//   tangential spring this makes U_t + D = -W exactly, step by step (the rule under which the
//   central-difference kinetic energy changes by the forces' work). On opening the stored
//   f_t,old^2 / (2 k) goes to D, less the work of the step.
#pragma once

#include <cmath>
#include <vector>

#include "solver/contact/contact_set.hpp"

namespace ricochet {

// The contact set and the springs: per candidate its stiffness and the tangential spring's
// state (the spring force f_t is set.reaction[k].t, the normal force f_n set.reaction[k].n).
template <int D>
struct PenaltyContactT {
  ContactSetT<D> set;
  std::vector<double> stiffness;             // per candidate, k [N/m] (between bodies: the largest, for the step)
  std::vector<double> bulk_stiffness;        // per candidate, f_si min(k_i, largest k_s) between bodies [N/m]
  double soft_factor = 0.0;                  // soft_scale / (2 soft_dt^2): k1 = soft_factor m* [1/s^2]
  std::vector<VecD<D>, Eigen::aligned_allocator<VecD<D>>> last_position;  // per candidate, x at the last step [m]
  // Between bodies: `pair_compliance` = 1/m_slave + 1/m_master,min for a pair candidate (the
  // spring between the slave node and the lightest master node).
  std::vector<double> pair_compliance;       // per candidate, 0 for rigid obstacles [1/kg]
  std::vector<std::vector<double>> segment_stiffness;  // per pair and master segment, f_si k_s [N/m]
  double scale_factor = 0.1;                 // f_si used for `stiffness` [-]
  bool initialized = false;                  // last_position holds the previous step's positions

  // Of the last step (at t_n); their sum is set.last.stored_energy.
  double normal_energy = 0.0;     // sum 1/2 k g^2 over active candidates [J]
  double tangential_energy = 0.0; // sum f_t^2 / (2 k) [J]
  double penetration = 0.0;       // largest depth -g of any candidate (>= 0) [m]
};
using PenaltyContact = PenaltyContactT<2>;

// The combination above of an element limit dt_e and a spring limit dt_p; dt_e when dt_p is
// not finite (no springs) [s].
inline double combined_critical_dt(double dt_e, double dt_p) {
  if (!std::isfinite(dt_p)) return dt_e;
  return 1.0 / std::sqrt(1.0 / (dt_e * dt_e) + 1.0 / (dt_p * dt_p));
}

// Bulk modulus used by the penalty stiffness: the 3D K = lambda + 2 mu / 3 [Pa] (see above).
double penalty_bulk_modulus(const Material& material);
double penalty_bulk_modulus(const Material3& material);

// The contact set (make_contact_set) with each candidate's stiffness k_i from `settings`, and
// every working array allocated.
// Body pairs (body_contact.hpp): the slave node's spring is k = f_si min(k_i, k_s), k_i the
// slave node's stiffness and k_s that of the master segment it meets this step (LS-DYNA's
// default PENO = 1: the minimum of the slave node's and the master segment's stiffness); the
// force -k g n acts on the slave node and, with weights -(1 - xi) and -xi, on the segment's
// nodes. `stiffness` holds f_si min(k_i, largest k_s of the master), which sets the step.
// In 3D the master face plays the segment's part: k_s = K A^2 / V of the face the node meets
// (LS-DYNA's solid-segment stiffness, A the face's reference area, V its cell's volume), also at
// an edge or vertex of that face; the force acts on the slave node and, with weights -N_a, on
// the face's corners (body_contact3.hpp).
template <class M>
PenaltyContactT<M::kDim> make_penalty_contact(const M& model, const std::vector<ObstacleOf<M>>& obstacles,
                                    const std::vector<std::vector<double>>& friction,
                                    const std::vector<PrescribedDof>& prescribed,
                                    const PenaltySettings& settings,
                                    const std::vector<BodyPair>& pairs = {});

// Largest stable step of the contact springs alone: min over candidates of 2 sqrt(m_i / k_i)
// (a node mass on a spring to the ground; between bodies 2 / sqrt(k (1/m_s + 1/m_master,min)),
// two masses on a spring), +infinity without candidates [s].
template <class M>
double penalty_critical_dt(const M& model, const PenaltyContactT<M::kDim>& p);

// Critical step of the elements and the springs together [s]:
//   dt_c = 1 / sqrt(1 / dt_e^2 + 1 / dt_p^2),  dt_e = model.critical_dt, dt_p = penalty_critical_dt.
// The springs only add stiffness, so omega_max^2 <= omega_e^2 + omega_p^2 (Weyl), and with
// dt_e and dt_p both bounds dt_c is one too. min(dt_e, dt_p) is not: near dt_e = dt_p the
// coupled system is up to sqrt(2) faster (see tests/solver/contact/test_penalty_contact.cpp, PenaltyTimeStep).
template <class M>
double penalty_combined_critical_dt(const M& model, const PenaltyContactT<M::kDim>& p) {
  return combined_critical_dt(model.critical_dt, penalty_critical_dt(model, p));
}


// safety * penalty_combined_critical_dt: the fixed step of a penalty run [s]. Stable is not
// accurate: when the springs set the step (f_si >~ 3 on square cells), an impact at 0.9 x the
// springs' limit (omega dt = 1.8) gains 40-100 % energy at the nodes' entry into and exit from
// their one-sided springs; 0.3-0.7 x brings it to ~1 % (measured, test_penalty_contact.cpp).
// With the LS-DYNA default f_si = 0.1 the elements set the step and the springs have
// omega dt ~ 0.35.
template <class M>
double penalty_stable_time_step(const M& model, const PenaltyContactT<M::kDim>& p, double safety) {
  return safety * penalty_combined_critical_dt(model, p);
}

// After evaluate(): the penalty forces of the state at t_n, added to s.a; the step's results and
// energies recorded in p.set. Allocates nothing.
template <class M>
void penalty_phase(const M& model, const std::vector<ObstacleOf<M>>& obstacles, PenaltyContactT<M::kDim>& p,
                   State& s);

}  // namespace ricochet
