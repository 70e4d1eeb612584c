// Frictional contact of body nodes with rigid obstacles, solved implicitly by the bi-potential
// method inside an explicit step (the paper's semi-explicit scheme, Eqs. (4)-(5)):
// after evaluate() gives the free accelerations, contact_phase() finds the reactions R at
// t+dt so that U = U_lib + U_c, U_c = dt^2 M^-1 R, leaves no contact node inside an obstacle,
// and adds R/m to the accelerations.
#pragma once

#include <string>
#include <vector>

#include "solver/central_difference.hpp"
#include "solver/coulomb.hpp"

namespace ricochet {

// A rigid straight obstacle: the half-plane behind the line through `point` with unit
// outward normal `normal`; the gap of a point x is g = normal . (x - point), g >= 0 allowed.
struct LineObstacle {
  std::string name;
  Vec2 point = Vec2::Zero();    // [m]
  Vec2 normal = Vec2::UnitY();  // unit [-]
  Vec2 tangent() const { return {normal.y(), -normal.x()}; }  // t: n rotated by -90 degrees
};

// Which quantity x the local problem is written on (literature 2.5 and open question 6.1).
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

// One potential contact: a boundary node of a body facing an obstacle.
struct ContactCandidate {
  int node = 0;
  int obstacle = 0;
  double friction_coeff = 0.0;  // mu of this body-obstacle pair [-]
};

// Preallocated working set and per-step results of the contact phase.
struct ContactState {
  std::vector<ContactCandidate> candidates;
  std::vector<LocalPair> reaction;       // per candidate, last step's r (N)
  std::vector<LocalPair> x_free;         // per candidate, this step's free x
  std::vector<ContactStatus> status;     // per candidate
  std::vector<int> active;               // candidate indices active this step
  std::vector<double> weight;            // per candidate, w = local compliance
  std::vector<Vec2, Eigen::aligned_allocator<Vec2>> node_reaction;  // per node, sum of r in global axes [N]
  bool any_friction = false;

  // Results of the last step.
  int active_count = 0, stick_count = 0, slip_count = 0;
  int sweeps = 0;                 // Gauss-Seidel sweeps of the last step
  bool converged = true;
  double normal_force = 0.0;      // sum r_n [N]
  double tangential_force = 0.0;  // sum r_t along each obstacle's tangent [N]
  // Accumulated over the run.
  double friction_dissipation = 0.0;  // sum -r_t x_t (slip work) [J]
  double contact_work = 0.0;          // work of all contact reactions on the bodies [J]
  long sweeps_total = 0, steps_with_contact = 0;
  int sweeps_max = 0;
  long unconverged_steps = 0;
};

// Candidates: the boundary nodes of each body paired with each obstacle, less nodes with a
// prescribed DOF. `friction[b][o]` is mu of body b against obstacle o.
ContactState make_contact_state(const Model& model, const std::vector<LineObstacle>& obstacles,
                                const std::vector<std::vector<double>>& friction,
                                const std::vector<PrescribedDof>& prescribed);

// After evaluate(): solves the contact reactions of step n -> n+1 and adds them to s.a.
void contact_phase(const Model& model, const std::vector<LineObstacle>& obstacles,
                   const ContactSettings& settings, ContactState& c, State& s);

// Largest depth of any candidate node behind its obstacle at u (>= 0) [m]. Every scheme
// measures penetration with this, on its own candidate list.
double penetration(const Model& model, const std::vector<LineObstacle>& obstacles,
                   const std::vector<ContactCandidate>& candidates, const Eigen::VectorXd& u);

}  // namespace ricochet
