// The contact module the three schemes share (docs/architecture.md, Contact): which boundary
// nodes may touch what (candidates), where and in which frame each contact acts this step
// (gap, normal, stencil), and every contact observable (forces, statuses, work, friction
// dissipation, stored energy, iterations), recorded in one place. A scheme supplies only its
// solve, the reactions of the step:
//   - the semi-explicit bi-potential update at position level (bipotential_contact.hpp),
//   - the implicit scheme's condensed problem (condensed_contact.hpp),
//   - the explicit penalty springs (penalty_contact.hpp).
//
// A step of any scheme runs the same frame:
//   update_boxes(c, eval)                       the body pairs' bounding boxes at eval
//   for each candidate k:
//     candidate_frame(..., k, ...)              gap and frame (n, t) of k, its stencil
//     ... the scheme's solve gives c.reaction[k] (r_n, r_t in that frame) ...
//     record(c, k, status)                      the verdict: status, counts, force sums
//   record_work(c, k, ...)                      per active contact, the work of its reaction
//   finish_step(c, iterations, converged)       run totals
//
// Adding an observable means a field in ContactStep or ContactTotals and its computation in
// record() / record_work() / finish_step() (contact_set.cpp); every scheme then has it.
#pragma once

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

#include "solver/contact/body_contact.hpp"
#include "solver/contact/body_contact3.hpp"
#include "solver/contact/contact_space.hpp"
#include "solver/contact/coulomb.hpp"
#include "solver/contact/obstacle.hpp"
#include "solver/core/loads.hpp"
#include "solver/core/state.hpp"
#include "solver/model/model.hpp"

namespace ricochet {

// The types of the contact module in dimension D (contact_space.hpp has the frame): a rigid
// obstacle and its closest() result, a stencil (the nodes one reaction acts on), and for contact
// between bodies the master surface and its bounding box.
template <int D>
struct Space;
template <>
struct Space<2> {
  using Vec = Vec2;
  using Local = LocalPair;
  using Obstacle = ricochet::Obstacle;
  using ObstacleContact = ricochet::ObstacleContact;
  using Stencil = ricochet::Stencil;
  using Surface = ricochet::Surface;
  using Box = Box2;
};
// The master surface of a 3D body pair: Surface3, its faces (body_contact3.hpp), and the
// node-to-face contact of find_face(): the stencil of a face contact is the slave node and the
// face's corners (5 nodes for a quadrilateral, 4 for a triangle; 3 and 2 at an edge or vertex).
template <>
struct Space<3> {
  using Vec = Vec3;
  using Local = LocalPair3d;
  using Obstacle = Obstacle3;
  using ObstacleContact = ObstacleContact3;
  using Stencil = StencilN<5>;  // a node and the 4 corners of a quadrilateral face
  using Surface = Surface3;
  using Box = BoxD<3>;
};
// The obstacle type of a model type.
template <class M>
using ObstacleOf = typename Space<M::kDim>::Obstacle;

// Settings of the bi-potential solves (semi-explicit and implicit).
// Which quantity x the local problem is written on (docs/background.md, Rigid obstacle: the
// closed-form fixed point; an open question of Cros et al. 2010, Eq. (5)).
enum class ContactLevel {
  position,  // x = (gap at t+dt, slip increment over the step), w = dt^2/m: no penetration at t+dt
  velocity,  // x = relative velocity v_{n+1/2}, w = dt/m, active when the predicted gap <= 0
};

struct ContactSettings {
  ContactLevel level = ContactLevel::position;
  double rho_factor = 1.0;    // rho = rho_factor / w per contact (1 = inverse local compliance)
  double tolerance = 1e-10;   // Gauss-Seidel stops when every |dr| <= tolerance |r|
  int max_sweeps = 200;       // Gauss-Seidel sweep cap per step
  // Semi-explicit scheme at position level: after the sweeps, the active contacts' gaps and
  // frames are taken again at the positions the reactions give, and the sweeps run again, this
  // many times (0 = the paper's frame, frozen at the predicted positions for the step). Implicit
  // scheme: a step with active contacts runs this many Newton iterations more, each taking the
  // frames again at its iterate.
  int frame_updates = 0;
};

// Settings of the penalty springs (penalty_contact.hpp).
struct PenaltySettings {
  double scale_factor = 0.1;  // f_si (LS-DYNA SLSFAC default) [-]
  // LS-DYNA's SOFT = 1 (soft constraint): with soft_scale > 0 every spring is at least
  //   k1 = soft_scale m* / (2 soft_dt^2),
  // m* the smallest nodal mass of the contact (the slave node; between bodies also the master
  // segment's nodes), soft_dt the step the run starts with. k = max(f_si k_bulk, k1): for a
  // soft body against a stiff one, whose bulk-modulus springs are too soft to stop it. k1 keeps
  // every spring's own step limit 2 sqrt(m*/(2 k1)) >= 2 soft_dt / sqrt(soft_scale).
  double soft_scale = 0.0;  // SOFSCL; 0 = SOFT = 0 (bulk-modulus springs only) [-]
  double soft_dt = 0.0;     // [s], > 0 when soft_scale > 0
};

// One potential contact: a boundary node of a body facing an obstacle (pair = -1), or a
// boundary node of a pair's slave body facing its master body's surface (obstacle = -1).
struct ContactCandidate {
  int node = 0;
  int obstacle = 0;
  double friction_coeff = 0.0;  // mu of this body-obstacle (or body-body) pair [-]
  int pair = -1;                // index into the body pairs; -1 for a rigid obstacle
};

// Results of the last step.
struct ContactStep {
  int active = 0, stick = 0, slip = 0;  // contacts with a reaction, and how they hold
  int status_changes = 0;               // candidates whose status (open, stick, slip) changed
  int iterations = 0;                   // sweeps of the solve (bi-potential schemes)
  bool converged = true;                // the solve met its tolerance
  double normal_force = 0.0;            // sum r_n [N]
  double tangential_force = 0.0;        // sum r_t along each contact's tangent [N]
  double stored_energy = 0.0;           // energy held by the contact (penalty springs) [J]
};

// Accumulated over the run.
struct ContactTotals {
  double friction_dissipation = 0.0;  // [J]
  double contact_work = 0.0;          // work of all contact reactions on the bodies [J]
  double contact_work_normal = 0.0;   // the part of contact_work done by the normal reactions [J]
  long steps_with_contact = 0;
  long iterations_total = 0;          // over the steps with contact
  int iterations_max = 0;
  long unconverged_steps = 0;         // steps whose solve hit its iteration cap
  long status_changes = 0;            // sum of ContactStep::status_changes
  long steps_with_status_changes = 0; // steps with ContactStep::status_changes > 0
};

// An interface: one rigid obstacle, or one contact pair (both passes of a two-pass pair are
// one interface). Its share of ContactStep and ContactTotals, for the history's per-interface
// columns (docs/outputs.md).
struct InterfaceStep {
  int active = 0;                  // contacts with a reaction this step
  double normal_force = 0.0;       // sum r_n [N]
  double tangential_force = 0.0;   // sum r_t along each contact's tangent [N]
};
struct InterfaceTotals {
  double contact_work = 0.0;          // [J]
  double friction_dissipation = 0.0;  // [J]
};

// The interfaces in order: the obstacles, then the body pairs by name (pairs with the same
// name are one interface; an unnamed pair is one of its own, named "pair<q>").
template <class Ob>
std::vector<std::string> contact_interface_names(const std::vector<Ob>& obstacles,
                                                 const std::vector<BodyPair>& pairs) {
  std::vector<std::string> names;
  for (const Ob& o : obstacles) names.push_back(o.name);
  for (std::size_t q = 0; q < pairs.size(); ++q) {
    const std::string name = pairs[q].name.empty() ? "pair" + std::to_string(q) : pairs[q].name;
    if (std::find(names.begin() + static_cast<long>(obstacles.size()), names.end(), name) == names.end())
      names.push_back(name);
  }
  return names;
}


// The candidates, their per-step geometry and reactions, and the observables, in dimension D.
template <int D>
struct ContactSetT {
  using Vec = VecD<D>;
  using Local = typename Space<D>::Local;

  std::vector<ContactCandidate> candidates;
  std::vector<int> interface;  // per candidate, its index in contact_interface_names()
  bool any_friction = false;
  // Contact between bodies (body_contact.hpp): per pair the master's surface and, per step, its
  // bounding box.
  std::vector<typename Space<D>::Surface> surfaces;
  std::vector<typename Space<D>::Box> boxes;
  // Per candidate.
  std::vector<typename Space<D>::Stencil> stencil;          // the nodes its reaction acts on (rigid obstacles: the node alone)
  std::vector<int> segment;              // master segment (3D: face) of the last step (-1 none)
  // The outward normal of the step's frame (ContactFrame<D>, contact_space.hpp), frozen for the
  // step: `reaction` is expressed in it.
  std::vector<Vec, Eigen::aligned_allocator<Vec>> normal;
  std::vector<Local> reaction;           // r of the step (r_n, r_t) [N]
  std::vector<ContactStatus> status;     // of the last step
  std::vector<int> active;               // candidates with a reaction this step, ascending

  ContactStep last;
  ContactTotals total;
  std::vector<InterfaceStep> interface_last;     // per interface, of the last step
  std::vector<InterfaceTotals> interface_total;  // per interface, over the run
};
using ContactSet = ContactSetT<2>;

// Candidates: the boundary nodes of each body paired with each obstacle, then the boundary
// nodes of each pair's slave body, less nodes with a prescribed DOF. `friction[b][o]` is mu of
// body b against obstacle o. Every per-candidate array is allocated.
template <class M>
ContactSetT<M::kDim> make_contact_set(const M& model, const std::vector<ObstacleOf<M>>& obstacles,
                                      const std::vector<std::vector<double>>& friction,
                                      const std::vector<PrescribedDof>& prescribed,
                                      const std::vector<BodyPair>& pairs = {});

// The body pairs' bounding boxes at positions eval(j), grown by the longest master segment.
template <int D, class Eval>
void update_boxes(ContactSetT<D>& c, const Eval& eval) {
  for (std::size_t q = 0; q < c.surfaces.size(); ++q)
    c.boxes[q] = surface_box(c.surfaces[q], eval, c.surfaces[q].max_length);
}

// Candidate k's gap and frame for the step, with its stencil: for a rigid obstacle the
// step_frame() of the node from its start position X + u_start to eval(node); for a body pair
// the segment choice of body_contact.hpp, in 3D the face choice of body_contact3.hpp (start
// positions X + u_start, velocities v_start, evaluation positions eval(j)). Returns false (and
// clears the tracked segment or face) when a pair's node faces no master segment or face. Inlined into each scheme's contact loop (its one call site
// there): out of line, as GCC left it once it was a template on the model type, the
// semi-explicit contact phase took 26 % more instructions (callgrind).
template <class M, class Eval>
[[gnu::always_inline]] inline bool candidate_frame(const M& model, const std::vector<ObstacleOf<M>>& obstacles, ContactSetT<M::kDim>& c, int k,
                     const Eigen::VectorXd& u_start, const Eigen::VectorXd& v_start, const Eval& eval,
                     typename Space<M::kDim>::ObstacleContact& out) {
  constexpr int D = M::kDim;
  const ContactCandidate& cc = c.candidates[k];
  if (cc.pair < 0) {
    out = step_frame(obstacles[cc.obstacle],
                     VecD<D>(model.ref.col(cc.node) + u_start.template segment<D>(D * cc.node)), eval(cc.node));
    return true;
  }
  if constexpr (D == 3) {
    // Node to face (body_contact3.hpp, find_face): the tracked face of the last step first.
    const Surface3& surf = c.surfaces[cc.pair];
    if (!c.boxes[cc.pair].contains(eval(cc.node))) {
      c.segment[k] = -1;
      return false;
    }
    auto start = [&](int j) -> Vec3 { return model.ref.col(j) + u_start.template segment<3>(3 * j); };
    auto vel = [&](int j) -> Vec3 { return v_start.template segment<3>(3 * j); };
    const NodeFace nf = find_face(surf, cc.node, c.segment[k], start, eval, vel);
    c.segment[k] = nf.face;
    if (nf.face < 0) return false;
    c.stencil[k] = nf.stencil;
    out = {nf.gap, nf.normal};
    return true;
  } else {
    const Surface& surf = c.surfaces[cc.pair];
    if (!c.boxes[cc.pair].contains(eval(cc.node))) {
      c.segment[k] = -1;
      return false;
    }
    auto start = [&](int j) -> Vec2 { return model.ref.col(j) + u_start.segment<2>(2 * j); };
    auto vel = [&](int j) -> Vec2 { return v_start.segment<2>(2 * j); };
    const NodeSegment ns = find_segment(surf, cc.node, c.segment[k], start, eval, vel);
    c.segment[k] = ns.segment;
    if (ns.segment < 0) return false;
    const SurfaceSegment& sg = surf.segments[ns.segment];
    Stencil& st = c.stencil[k];
    st.count = 3;
    st.node = {cc.node, sg.a, sg.b};
    st.coef = {1.0, -(1.0 - ns.xi), -ns.xi};
    out = {ns.gap, ns.normal};
    return true;
  }
}

// Start of a step's bookkeeping: the last-step results cleared.
template <int D>
void begin_step(ContactSetT<D>& c) {
  c.active.clear();
  c.last = ContactStep{};
  for (InterfaceStep& i : c.interface_last) i = InterfaceStep{};
}

// The step's verdict on candidate k: its status (open, stick, slip) with its final reaction in
// c.reaction[k]. Counts the status change, and for a closed contact the stick/slip counts and
// the force sums. Call it once per candidate and step; the closed ones in ascending order.
template <int D>
void record(ContactSetT<D>& c, int k, ContactStatus status) {
  c.last.status_changes += status != c.status[k];
  c.status[k] = status;
  if (status == ContactStatus::open) return;
  c.last.stick += status == ContactStatus::stick;
  c.last.slip += status == ContactStatus::slip;
  c.last.normal_force += c.reaction[k].n;
  c.last.tangential_force += tangential_sum_term(c.reaction[k]);
  InterfaceStep& i = c.interface_last[c.interface[k]];
  ++i.active;
  i.normal_force += c.reaction[k].n;
  i.tangential_force += tangential_sum_term(c.reaction[k]);
}

// Slip work of candidate k added to the friction dissipation (the run's and its interface's).
template <int D>
void add_dissipation(ContactSetT<D>& c, int k, double work) {
  c.total.friction_dissipation += work;
  c.interface_total[c.interface[k]].friction_dissipation += work;
}

// Work of active contact k's reaction F = r_n n + r_t t over the step: scale * sum_j coef_j F .
// work_motion(j) over its stencil (the normal part likewise), and with `slip` its slip work
// -r_t slip_scale t . sum_j coef_j slip_motion(j) added to the friction dissipation. The explicit
// schemes measure the work on v dt_n (scale dt_n, work_motion = v_{n-1/2} + dt_n/2 a_n, v_n for
// a fixed step) and the slip on v_{n+1/2} dt_{n+1/2} (slip_scale dt_{n+1/2}; central_difference.hpp);
// the implicit one on the step's displacement (scale 1, both u_{n+1} - u_n).
template <int D, class WorkMotion, class SlipMotion>
void record_work(ContactSetT<D>& c, int k, double scale, const WorkMotion& work_motion, bool slip,
                 const SlipMotion& slip_motion, double slip_scale) {
  using Vec = VecD<D>;
  const auto& st = c.stencil[k];
  const ContactFrame<D> f(c.normal[k]);
  const Vec n = f.n;
  const auto r = c.reaction[k];
  const Vec force = f.global(r);
  Vec relative = Vec::Zero();
  double work = 0.0, work_normal = 0.0;
  for (int j = 0; j < st.count; ++j) {
    const int node = st.node[j];
    const Vec d = work_motion(node);
    if (slip) relative += st.coef[j] * slip_motion(node);
    work += (st.coef[j] * force).dot(d);
    work_normal += st.coef[j] * r.n * n.dot(d);
  }
  if (slip) add_dissipation(c, k, slip_work(r, slip_scale, f.tangential(relative)));
  c.total.contact_work += scale * work;
  c.total.contact_work_normal += scale * work_normal;
  c.interface_total[c.interface[k]].contact_work += scale * work;
}
// The same with slip_scale = scale.
template <int D, class WorkMotion, class SlipMotion>
void record_work(ContactSetT<D>& c, int k, double scale, const WorkMotion& work_motion, bool slip,
                 const SlipMotion& slip_motion) {
  record_work(c, k, scale, work_motion, slip, slip_motion, scale);
}

// End of a step: the active count and the run totals. `iterations` and `converged` describe the
// step's solve (0 and true for the penalty springs).
template <int D>
void finish_step(ContactSetT<D>& c, int iterations, bool converged);

// What the contact set holds, per node, for a field snapshot (docs/outputs.md, fields/*.vtu).
// Node status codes (the `contact_status` point array):
enum NodeContactStatus : int {
  kNodeNoCandidate = 0,  // the node is no contact candidate (an interior node, a prescribed one,
                         // or a master body's node in a one-way pair)
  kNodeOpen = 1,         // a candidate, every one of its contacts open in the last step
  kNodeStick = 2,        // at least one of its contacts sticks, none slips
  kNodeSlip = 3,         // at least one of its contacts slips (frictionless contacts slip)
};
// Fills, for every node i of the model (n = model.num_nodes()):
//   force[Di .. Di + D - 1]   the sum of the contact reactions acting on node i, in global axes
//                             [N]: over every closed contact (status stick or slip, the ones
//                             record() sums into normal_force), coef_j (r_n n + r_t t) for each
//                             node j of its stencil, so a body pair's master nodes get their
//                             share -(1 - xi) r, -xi r (3D: a face's corners -N_a r);
//   gap[i]                    the smallest signed gap of node i over its candidates at the
//                             positions X + u [m]: closest() for a rigid obstacle, the signed
//                             distance to the master body (signed_distance(), body_contact.hpp,
//                             body_contact3.hpp) for a pair; negative inside. 0 for a node that is no candidate;
//   status[i]                 its NodeContactStatus, the strongest over its candidates' statuses.
// The reactions, normals, stencils and statuses are those of the set's last step, read as they
// are (whatever step the scheme last recorded). Allocates nothing; O(candidates) plus, for body
// pairs, O(candidates x master segments (faces)).
template <class M>
void node_contact_fields(const M& model, const std::vector<ObstacleOf<M>>& obstacles,
                         const ContactSetT<M::kDim>& c, const Eigen::VectorXd& u, double* force, double* gap,
                         int* status);

// The depth of one candidate at u (>= 0) [m]: behind its obstacle (minus closest()'s gap, when
// negative), or inside its pair's master body (depth_inside). A node outside the bounding box of
// the master surface's nodes is outside the body: only nodes inside it are measured against every
// segment (face). A pair's candidates are contiguous, so the box is kept from one call to the next
// and taken again only when the pair changes. Allocates nothing.
template <class M>
class CandidateDepth {
 public:
  static constexpr int D = M::kDim;
  using Vec = VecD<D>;
  CandidateDepth(const M& model, const std::vector<ObstacleOf<M>>& obstacles,
                 const std::vector<typename Space<D>::Surface>& surfaces, const Eigen::VectorXd& u)
      : model_(model), obstacles_(obstacles), surfaces_(surfaces), u_(u) {}

  double operator()(const ContactCandidate& cc) { return std::max(0.0, unclamped(cc)); }

  // The same before the clamp at 0: minus the gap, negative in front of an obstacle (the
  // largest over candidates clamps once: penetration()).
  double unclamped(const ContactCandidate& cc) {
    const Vec x = position(cc.node);
    if (cc.pair < 0) return -closest(obstacles_[cc.obstacle], x).gap;
    if (cc.pair != boxed_) {
      box_ = surface_box(surfaces_.at(cc.pair), [this](int j) { return position(j); }, 0.0);
      boxed_ = cc.pair;
    }
    return box_.contains(x) ? depth_inside(model_, surfaces_[cc.pair], u_, x) : 0.0;
  }

 private:
  Vec position(int j) const { return model_.ref.col(j) + u_.template segment<D>(D * j); }

  const M& model_;
  const std::vector<ObstacleOf<M>>& obstacles_;
  const std::vector<typename Space<D>::Surface>& surfaces_;
  const Eigen::VectorXd& u_;
  int boxed_ = -1;
  typename Space<D>::Box box_;
};

// Largest depth of any candidate node behind its obstacle, or inside its pair's master body
// (CandidateDepth), at u (>= 0) [m]. Every scheme measures penetration with this.
template <class M>
double penetration(const M& model, const std::vector<ObstacleOf<M>>& obstacles,
                   const std::vector<typename Space<M::kDim>::Surface>& surfaces,
                   const std::vector<ContactCandidate>& candidates, const Eigen::VectorXd& u);
template <class M>
double penetration(const M& model, const std::vector<ObstacleOf<M>>& obstacles, const ContactSetT<M::kDim>& c,
                   const Eigen::VectorXd& u) {
  return penetration(model, obstacles, c.surfaces, c.candidates, u);
}

}  // namespace ricochet
