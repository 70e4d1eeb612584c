// Frictional contact of body nodes with rigid obstacles, solved implicitly by the bi-potential
// method inside an explicit step (the paper's semi-explicit scheme, Eqs. (4)-(5)):
// after evaluate() gives the free accelerations, contact_phase() finds the reactions R at
// t+dt so that U = U_lib + U_c, U_c = dt^2 M^-1 R, leaves no contact node inside an obstacle,
// and adds R/m to the accelerations.
#pragma once

#include <string>
#include <vector>

#include "solver/body_contact.hpp"
#include "solver/central_difference.hpp"
#include "solver/coulomb.hpp"

namespace ricochet {

// A rigid obstacle (a rigid foundation). One geometric query, closest(), serves
// every scheme: the signed gap g of a point x (g >= 0 on the allowed side, g < 0 inside the
// obstacle) and the unit outward normal n at the closest point of the obstacle's boundary,
// pointing to the allowed side; the tangent is t = (n_y, -n_x) (n rotated by -90 degrees).
// For every kind g = n . (x - q) with q the closest boundary point, so the first-order gap
// about x is g(x + du) ~ g + n . du.
//   line:     the half-plane behind the line through `point` with unit outward normal
//             `normal`: g = normal . (x - point), n = normal (the same arithmetic as
//             before circles and polylines existed);
//   circle:   centre `center`, radius `radius` > 0. inside = false: the rigid disk is the
//             obstacle (bodies stay outside, e.g. a peg): g = |x - c| - r, n = (x - c)/|x - c|.
//             inside = true: everything outside the circle is the obstacle (bodies stay inside
//             a rigid ring or bowl): g = r - |x - c|, n = -(x - c)/|x - c|. At x = c exactly the
//             radial direction is undefined and n = +y is used.
//   polyline: an open chain points[0..m] (m >= 1 segments, none of zero length). The allowed
//             side is to the left (left = true) or right of the direction of travel from
//             points[0] to points[m]; the outward normal of segment j is its direction rotated
//             by +90 degrees (left) or -90 degrees (right). The first and last segments extend
//             to infinity as rays, so the chain divides the plane in two like a line does (a
//             2-point polyline is a line); the rays must not cross the chain (not checked).
//             g is the signed distance to the nearest segment:
//               - nearest point inside segment j (or on an end ray): g = n_j . (x - p_j), n = n_j;
//               - nearest point an interior vertex v (x in the corner's wedge): |g| = |x - v|, the
//                 sign that of (x - v) . b with b the bisector of the two segment normals
//                 (positive in the wedge outside a convex corner, negative in the wedge behind
//                 a concave one), and n = sign * (x - v)/|x - v| (n = b if x = v);
//               - ties (x equidistant from several segments within 1e-12 of the chain's length
//                 scale, e.g. on the bisector of a concave corner such as the bottom of a V):
//                 g is that of the first nearest segment and n the normalized sum of the tied
//                 normals (the bisector), so a symmetric chain stays symmetric; if the tied
//                 normals cancel, n is the first one's.
//             Cost O(m) per query.
// Every scheme evaluates closest() once per candidate and step at its predicted position
// (semi-explicit: x at t+dt of the free motion; implicit: x at the predicted u of the Newton
// iterate; penalty: x at u_n) and freezes n (and t) for the step: the reactions act along that
// frame and the gap is linearized about the predicted point. For a line this is exact; for a
// circle or a polyline the linearization is first order (the boundary's curvature, or a switch
// of the nearest segment, enters at the next step), consistent with the position-level scheme.
enum class ObstacleKind { line, circle, polyline };

struct Obstacle {
  std::string name;
  Vec2 point = Vec2::Zero();    // line: a point of the line [m]
  Vec2 normal = Vec2::UnitY();  // line: unit outward normal [-]
  ObstacleKind kind = ObstacleKind::line;
  Vec2 center = Vec2::Zero();   // circle: centre [m]
  double radius = 0.0;          // circle: radius > 0 [m]
  bool inside = false;          // circle: bodies inside the circle (ring/bowl) instead of outside
  std::vector<Vec2, Eigen::aligned_allocator<Vec2>> points{};  // polyline: >= 2 vertices [m]
  bool left = true;             // polyline: allowed side left (true) or right of the chain
  Vec2 tangent() const { return {normal.y(), -normal.x()}; }  // line: t = n rotated by -90 degrees
};

// Result of closest(): signed gap [m] and unit outward normal at the closest point.
struct ObstacleContact {
  double gap = 0.0;
  Vec2 normal = Vec2::UnitY();
  Vec2 tangent() const { return {normal.y(), -normal.x()}; }
};

// Checked constructors (throw std::invalid_argument with a one-line message on bad geometry).
Obstacle make_line_obstacle(std::string name, const Vec2& point, const Vec2& normal);  // normal normalized
Obstacle make_circle_obstacle(std::string name, const Vec2& center, double radius, bool inside);
Obstacle make_polyline_obstacle(std::string name, std::vector<Vec2, Eigen::aligned_allocator<Vec2>> points,
                                bool left);
// Empty if `ob` is valid, else what is wrong (one line).
std::string obstacle_error(const Obstacle& ob);

ObstacleContact closest_circle(const Obstacle& ob, const Vec2& x);
ObstacleContact closest_polyline(const Obstacle& ob, const Vec2& x);

inline ObstacleContact closest(const Obstacle& ob, const Vec2& x) {
  switch (ob.kind) {
    case ObstacleKind::circle: return closest_circle(ob, x);
    case ObstacleKind::polyline: return closest_polyline(ob, x);
    case ObstacleKind::line: break;
  }
  return {ob.normal.dot(x - ob.point), ob.normal};
}

// The frame a step's contact with a rigid obstacle is solved in, for a node that starts the step
// at x_start and whose motion is predicted to x_pred. A line: the gap at x_pred and the line's
// normal (exact). A circle or a polyline: the normal at the midpoint x_m of the step's chord and
// the gap linearized from there, g(x_m) + n_m . (x_pred - x_m). For a node sliding fast along
// a curved obstacle, the normal at x_pred has turned by the whole step's angle against the
// node's path and the reaction pushed the node out, doing positive work; the midpoint normal
// has turned by half of it. In the Kim-Kwak problem's tripping impact this halves the normal
// reactions' work, +0.021 -> +0.010 J (docs/kim-kwak-type.md). For a convex gap function
// (outside a circle) the linearization stays below the gap, so g >= 0 still holds at the end.
inline ObstacleContact step_frame(const Obstacle& ob, const Vec2& x_start, const Vec2& x_pred) {
  if (ob.kind == ObstacleKind::line) return closest(ob, x_pred);
  const Vec2 x_mid = 0.5 * (x_start + x_pred);
  const ObstacleContact m = closest(ob, x_mid);
  return {m.gap + m.normal.dot(x_pred - x_mid), m.normal};
}

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
};

// One potential contact: a boundary node of a body facing an obstacle (pair = -1), or a
// boundary node of a pair's slave body facing its master body's surface (obstacle = -1).
struct ContactCandidate {
  int node = 0;
  int obstacle = 0;
  double friction_coeff = 0.0;  // mu of this body-obstacle (or body-body) pair [-]
  int pair = -1;                // index into the body pairs; -1 for a rigid obstacle
};

// Preallocated working set and per-step results of the contact phase.
struct ContactState {
  std::vector<ContactCandidate> candidates;
  std::vector<LocalPair> reaction;       // per candidate, last step's r (N)
  std::vector<LocalPair> x_free;         // per candidate, this step's free x
  std::vector<ContactStatus> status;     // per candidate
  std::vector<int> active;               // candidate indices active this step
  std::vector<double> weight;            // per candidate, w = local compliance
  // Per candidate, the outward normal of closest() at the predicted position, frozen for the
  // step: `reaction` is expressed in this frame (n, t = (n_y, -n_x)).
  std::vector<Vec2, Eigen::aligned_allocator<Vec2>> normal;
  std::vector<Vec2, Eigen::aligned_allocator<Vec2>> node_reaction;  // per node, sum of r in global axes [N]
  bool any_friction = false;
  // Contact between bodies (body_contact.hpp): per pair the master's surface and, per step, its
  // bounding box; per candidate the nodes its reaction acts on and the tracked master segment.
  std::vector<Surface> surfaces;
  std::vector<Box2> boxes;
  std::vector<Stencil> stencil;          // per candidate (rigid obstacles: the node alone)
  std::vector<int> segment;              // per candidate, master segment of the last step (-1 none)

  // Results of the last step.
  int active_count = 0, stick_count = 0, slip_count = 0;
  int sweeps = 0;                 // Gauss-Seidel sweeps of the last step
  bool converged = true;
  double normal_force = 0.0;      // sum r_n [N]
  double tangential_force = 0.0;  // sum r_t along each obstacle's tangent [N]
  // Accumulated over the run.
  double friction_dissipation = 0.0;  // sum -r_t x_t (slip work) [J]
  double contact_work = 0.0;          // work of all contact reactions on the bodies [J]
  double contact_work_normal = 0.0;   // the part of contact_work done by the normal reactions [J]
  long sweeps_total = 0, steps_with_contact = 0;
  int sweeps_max = 0;
  long unconverged_steps = 0;
};

// Candidates: the boundary nodes of each body paired with each obstacle, then the boundary
// nodes of each pair's slave body, less nodes with a prescribed DOF. `friction[b][o]` is mu of
// body b against obstacle o.
ContactState make_contact_state(const Model& model, const std::vector<Obstacle>& obstacles,
                                const std::vector<std::vector<double>>& friction,
                                const std::vector<PrescribedDof>& prescribed,
                                const std::vector<BodyPair>& pairs = {});

// After evaluate(): solves the contact reactions of step n -> n+1 and adds them to s.a.
void contact_phase(const Model& model, const std::vector<Obstacle>& obstacles,
                   const ContactSettings& settings, ContactState& c, State& s);

// Largest depth of any candidate node behind its obstacle, or inside its pair's master body
// (depth_inside), at u (>= 0) [m]. Every scheme measures penetration with this, on its own
// candidate list; `surfaces` are the pairs' master surfaces (may be empty without pairs).
double penetration(const Model& model, const std::vector<Obstacle>& obstacles,
                   const std::vector<Surface>& surfaces, const std::vector<ContactCandidate>& candidates,
                   const Eigen::VectorXd& u);
inline double penetration(const Model& model, const std::vector<Obstacle>& obstacles,
                          const std::vector<ContactCandidate>& candidates, const Eigen::VectorXd& u) {
  return penetration(model, obstacles, {}, candidates, u);
}

// Fills candidate k's stencil, gap, frame and segment for a body pair: the segment choice of
// body_contact.hpp with the start positions X + u and the evaluation positions eval(j). Returns
// false (and clears the tracked segment) when the node faces no master segment. `Set` is a
// ContactState or a PenaltyState (same candidate, surface, box, segment and stencil arrays).
template <class Set, class Eval>
bool pair_contact_geometry(const Model& model, Set& c, int k, const Eigen::VectorXd& u,
                           const Eigen::VectorXd& v, const Eval& eval, NodeSegment& out) {
  const ContactCandidate& cc = c.candidates[k];
  const Surface& surf = c.surfaces[cc.pair];
  if (!c.boxes[cc.pair].contains(eval(cc.node))) {
    c.segment[k] = -1;
    return false;
  }
  auto start = [&](int j) -> Vec2 { return model.ref.col(j) + u.segment<2>(2 * j); };
  auto vel = [&](int j) -> Vec2 { return v.segment<2>(2 * j); };
  out = find_segment(surf, cc.node, c.segment[k], start, eval, vel);
  c.segment[k] = out.segment;
  if (out.segment < 0) return false;
  const SurfaceSegment& sg = surf.segments[out.segment];
  Stencil& st = c.stencil[k];
  st.count = 3;
  st.node = {cc.node, sg.a, sg.b};
  st.coef = {1.0, -(1.0 - out.xi), -out.xi};
  return true;
}

}  // namespace ricochet
