// The types every scheme's run shares: what a run is asked (RunSettings) and what it gives
// (RunResult, with its History and field snapshots). Typed structs in, typed results out: no
// files here. The schemes' loops are run_explicit() (explicit.hpp) and run_implicit() (implicit.hpp).
#pragma once

#include <array>
#include <functional>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "solver/contact/contact_set.hpp"
#include "solver/materials/stress.hpp"
#include "solver/model/model.hpp"

namespace ricochet {

struct Probe {
  std::string name;
  int node = 0;  // global node index
};

// A quasi-static start (solver/schemes/relaxation.hpp, docs/background.md, Quasi-static start):
// before the clock starts, the scene is brought to equilibrium under its t = 0 loads by
// dynamic relaxation with kinetic damping (Cundall 1976; Underwood 1983), with the contact
// treatment of the run's scheme.
struct RelaxationSettings {
  bool enabled = false;
  // Converged when the force residual ||f_ext - f_int + R|| / ||f_ext|| over the free DOFs is
  // <= tolerance and the kinetic energy is <= tolerance^2 x its peak over the relaxation.
  double tolerance = 1e-6;  // [-]
  long max_steps = 100000;  // relaxation steps before it is reported as not converged
  // Step of the relaxation [s]; <= 0: relaxation_step() (relaxation.hpp), half the run's step
  // (explicit schemes) or half of 0.9 x the elements' critical step (the implicit scheme, which
  // relaxes with the semi-explicit loop).
  double dt = 0.0;
};

// What the relaxation did (summary.json `relaxation`).
struct RelaxationReport {
  bool converged = false;
  long steps = 0;             // relaxation steps taken
  long velocity_resets = 0;   // kinetic-energy peaks at which all velocities were zeroed
  double dt = 0.0;            // its step [s]
  double residual = 0.0;      // force residual ratio at the end [-]
  double kinetic_ratio = 0.0; // kinetic energy / its peak at the end [-]
  double settlement = 0.0;    // largest node displacement from the start state to the relaxed one [m]
  double wall_seconds = 0.0;  // its wall-clock time (not in the run's wall_seconds) [s]
  std::string reason;         // why it did not converge
};

// The rigid obstacles of a run, all of its model's dimension (contact/obstacle.hpp): Obstacle for
// a Model<2>, Obstacle3 for a Model<3>.
using ObstacleList = std::variant<std::vector<Obstacle>, std::vector<Obstacle3>>;
inline std::size_t obstacle_count(const ObstacleList& l) {
  return std::visit([](const auto& v) { return v.size(); }, l);
}

struct RunSettings {
  double dt = 0.0;                  // fixed time step [s]; with a variable step, the first one
  double end_time = 0.0;            // [s]; the run takes ceil(end_time/dt) steps (fixed step)
  // Variable step (time.dt_update_interval; docs/background.md, Variable time step): with
  // dt_update_interval = N > 0 the explicit loop (run_explicit) sets the step every N steps to
  // dt_safety x the critical step of the current configuration (StepControl, time_step.hpp),
  // shortens the last step to end on end_time, and samples the history and fields by time.
  // 0: the step stays dt. The implicit scheme takes a fixed step only (it rejects N > 0).
  int dt_update_interval = 0;       // [steps]
  double dt_safety = 0.9;           // [-]
  double dt_min_ratio = 0.01;       // a recomputed step below dt_min_ratio x dt is a divergence [-]
  double sample_interval = 0.0;     // history sampling [s]; <= 0 samples every step
  std::vector<double> field_times;  // field snapshots at the steps nearest these times [s]
  std::vector<Probe> probes;
  std::vector<PrescribedDof> prescribed;
  std::vector<NodalLoad> loads;      // time-dependent nodal forces (central_difference.hpp)
  RelaxationSettings relaxation;     // a quasi-static start (off by default)
  double energy_growth_limit = 2.0;  // diverged when total energy > limit * reference energy [-]
  int monitor_every = 50;            // divergence checks at least every this many steps
  Eigen::VectorXd initial_displacement;  // optional, 2n [m]
  // OpenMP threads of the run's element loops: 0 = every core, n >= 1 = n (threads.hpp,
  // resolve_threads). Results are the same for any count; only the time changes.
  int threads = 0;
  // Fewer threads than `threads` while other processes hold the cores (threads.hpp,
  // ThreadScope); false: always `threads`.
  bool adapt_threads = true;

  // Rigid obstacles, with friction[b][o] the coefficient of body b against obstacle o. The
  // explicit loop treats contact by the bi-potential method (the semi-explicit scheme:
  // contact_phase() between evaluate and update) or by penalty springs (the explicit penalty
  // scheme); the implicit scheme by its condensed bi-potential problem.
  enum class ContactMethod { bipotential, penalty };
  ObstacleList obstacles;  // of the model's dimension; obstacles_of(), obstacles_in() below
  std::vector<std::vector<double>> friction;
  // Contact between bodies, node to segment (body_contact.hpp), treated by the same method.
  std::vector<BodyPair> body_pairs;
  ContactMethod contact_method = ContactMethod::bipotential;
  // The measure of von_mises_max, the history column and the fields; the peaks of all three
  // are tracked at every step (stress.hpp).
  StressMeasure stress_measure = StressMeasure::cauchy;
  // Stress peaks at every step (true), or at the history samples only (false: cheaper, and
  // von_mises_max then depends on the sampling interval).
  bool stress_every_step = true;
  ContactSettings contact;
  PenaltySettings penalty;
};

// The rigid obstacles of a run for a model of type M: RunSettings::obstacles as the list of
// M's dimension. A list of the other dimension is an error unless it is empty (a run without
// obstacles).
template <class M>
const std::vector<ObstacleOf<M>>& obstacles_of(const RunSettings& s, const M&) {
  static const std::vector<ObstacleOf<M>> none;
  if (const auto* list = std::get_if<std::vector<ObstacleOf<M>>>(&s.obstacles)) return *list;
  if (obstacle_count(s.obstacles))
    throw std::invalid_argument("run settings: obstacles of another dimension than the model's");
  return none;
}
// The same list to fill: an empty list of the other dimension becomes one of M's.
template <class M>
std::vector<ObstacleOf<M>>& obstacles_in(RunSettings& s, const M&) {
  if (!std::holds_alternative<std::vector<ObstacleOf<M>>>(s.obstacles)) {
    if (obstacle_count(s.obstacles))
      throw std::invalid_argument("run settings: obstacles of another dimension than the model's");
    s.obstacles.template emplace<std::vector<ObstacleOf<M>>>();
  }
  return std::get<std::vector<ObstacleOf<M>>>(s.obstacles);
}

enum class RunStatus { ok, diverged };

// History columns, in order; then per contact interface (contact_interface_names(), when the
// run has contact candidates) <name>_normal_force, _tangential_force, _contact_nodes,
// _contact_work, _friction_dissipation; then per probe <name>_ux, _uy, _vx, _vy (in 3D _ux,
// _uy, _uz, _vx, _vy, _vz). `dimension` 2 or 3 (3D: momentum_z, and angular_momentum_x, _y,
// _z in place of angular_momentum).
std::vector<std::string> history_columns(const std::vector<Probe>& probes,
                                         const std::vector<std::string>& interfaces = {}, int dimension = 2);

struct History {
  std::vector<std::string> columns;
  std::vector<double> values;  // row-major, columns.size() per row
  std::size_t rows() const { return columns.empty() ? 0 : values.size() / columns.size(); }
  double at(std::size_t row, std::size_t col) const { return values[row * columns.size() + col]; }
  std::size_t column(const std::string& name) const;  // throws std::out_of_range
};

// One field snapshot (docs/outputs.md, fields/*.vtu): nodes and cells in the model's order.
struct FieldSnapshot {
  long step = 0;
  double time = 0.0;               // [s]
  Eigen::VectorXd u;               // 2n [m]
  Eigen::VectorXd v;               // 2n, v_n [m/s]
  std::vector<double> von_mises;   // per cell [Pa]
  // Per cell, 6 values each (XX, YY, ZZ, XY, YZ, XZ): the Cauchy stress [Pa] and the
  // Green-Lagrange strain [-] (cell_tensors(), internal_forces.hpp).
  std::vector<double> cauchy, green_lagrange;
  // Per node (node_contact_fields(), contact_set.hpp): the contact force, 2 per node, global
  // axes [N]; the signed gap [m]; the NodeContactStatus code.
  std::vector<double> contact_force, contact_gap;
  std::vector<int> contact_status;
};

// Where and when a von Mises peak was reached: the largest value over every step of a run.
struct StressPeak {
  double value = 0.0;     // [Pa]
  double time = 0.0;      // [s]
  int cell = -1;          // global cell index; -1 if never reached (no cell, or zero stress)
  int body = -1;          // index of the body
  int element = -1;       // index of the cell within its body (its quads, then its triangles)
  double x = 0.0, y = 0.0;  // the cell's centroid at that time (mean of its current nodes) [m]
  double z = 0.0;           // 3D: its z (0 in 2D) [m]
};

// How long a run took and on how many threads (summary.json: threads, threads_min,
// wall_seconds, cpu_seconds, element_steps_per_second).
struct RunTiming {
  int threads = 0;                 // threads the run may use: resolve_threads(settings.threads)
  int threads_min = 0;             // the fewest it used (adapt_threads: others held the cores)
  double wall_seconds = 0.0;       // time loop only
  double cpu_seconds = 0.0;        // time loop only, process CPU time
  double element_steps_per_second = 0.0;
  // The process's peak resident memory when the run ended (getrusage's ru_maxrss): the run's own
  // for `ricochet run`; in a sweep, the largest of the runs so far in that process [bytes].
  double peak_memory_bytes = 0.0;
};

// What contact did over the run (summary.json: contact_candidates, contact_impulse,
// contact_iterations, ...; docs/outputs.md).
struct RunContact {
  int candidates = 0;              // boundary node-obstacle pairs watched
  double sweeps_mean = 0.0;        // Gauss-Seidel sweeps per step with contact
  int sweeps_max = 0;
  long steps = 0;                  // steps with at least one active contact
  long unconverged_steps = 0;      // steps that hit the sweep cap
  long status_changes = 0;         // sum over the steps of the candidates whose status changed
  long status_change_steps = 0;    // steps in which at least one status changed
  double time = 0.0;               // sum of the steps with an active contact [s]
  double impulse_normal = 0.0;     // sum over steps of normal_force * dt [N s]
  double impulse_tangential = 0.0; // sum over steps of tangential_force * dt [N s]
  double first_time = -1.0;        // start of the first step with an active contact [s]; -1: none
  double last_time = -1.0;         // end of the last step with an active contact [s]; -1: none
};

// The run's von Mises peaks (summary.json: von_mises_max, von_mises_peak, ...).
struct RunStress {
  StressMeasure measure = StressMeasure::cauchy;
  // Stress peaks at every step (true), or at the history samples only (false: cheaper, and
  // von_mises_max then depends on the sampling interval).
  bool every_step = true;
  double von_mises_max = 0.0;       // of `measure`, over every step and cell [Pa]
  double von_mises_max_time = 0.0;  // [s]
  StressPeak peak;                  // of `measure` over every step, all cells
  StressPeak interior_peak;         // the same over the cells off the contact boundary
  VonMises2 sampled_max{0.0, 0.0, 0.0};  // per measure, over the history samples [Pa]
};

// The implicit scheme's solver counters (summary.json: newton_iterations, linear_solver, ...).
struct RunImplicit {
  long newton_iterations = 0;      // Newton iterations (linear solves of the free motion)
  long linear_iterations = 0;      // CG iterations, all solves
  bool direct_solver = false;      // CHOLMOD Cholesky (true) or PCG (false)
  bool mass_solver = false;        // steps start with the mass iteration (then the factor)
  bool supernodal = false;         // direct solver: the factor is supernodal (else simplicial)
  bool single_solves = false;      // direct solver: solves with a single-precision copy of L
  long mass_iterations = 0;        // Newton iterations solved with the lumped mass matrix
  long factorizations = 0;         // direct solver: numeric factorizations of A
  int refactor_iterations = 0;     // direct solver: the refactorization cap in effect (0: none)
  // Wall time of the scheme's phases over the run [s] (summary.json implicit.phase_seconds):
  // assembly of A, its factorizations (with the shifts), linear solves (those of the contact
  // problem included), the contact problem less its solves, and the residual's force passes.
  double assembly_seconds = 0.0, factorization_seconds = 0.0, solve_seconds = 0.0, contact_seconds = 0.0,
         residual_seconds = 0.0;
};

// What a run returns: its status and steps, its outcome (energy, penetration, work, drift), its
// history and fields, and the groups above. summary.json writes every field
// (harness/outputs/run_outputs.cpp; the keys in docs/outputs.md).
struct RunResult {
  RunStatus status = RunStatus::ok;
  bool relaxed = false;            // the run started with a relaxation (`relaxation` is its report)
  RelaxationReport relaxation;
  std::string reason;              // why a run diverged
  long diverged_step = -1;
  double diverged_time = 0.0;      // [s]
  double dt = 0.0;                 // [s]; with a variable step, the first one
  long steps = 0;                  // steps taken
  long planned_steps = 0;          // ceil(end_time / dt); with a variable step an estimate
  int dt_update_interval = 0;      // RunSettings::dt_update_interval (0: fixed step)
  double dt_min = 0.0, dt_max = 0.0;  // smallest and largest step taken, a last step shortened to end on end_time aside [s]
  long dt_updates = 0;             // recomputations of the step (variable step)
  double dt_floor = 0.0;           // dt_min_ratio x dt (variable step) [s]
  double end_time = 0.0;           // time reached [s]
  History history;
  std::vector<FieldSnapshot> fields;
  double initial_energy = 0.0;     // E_0 [J]
  double energy_error_max = 0.0;   // over samples [-]
  double total_mass = 0.0;         // [kg]
  double penetration_max = 0.0;    // over samples [m]
  // Largest displacement of any node from the start state (the relaxed one after a
  // relaxation), |u_n - u_0|, over the monitor steps [m]: over the whole run, and over the
  // steps up to rest_until, the first time a nodal load changes (the end without such loads).
  double displacement_max = 0.0;
  double drift_max = 0.0;
  int drift_node = -1;             // global node of drift_max; -1: none moved
  double rest_until = 0.0;         // [s]
  double friction_dissipation = 0.0;  // at the end [J]
  double contact_work = 0.0;       // at the end [J]
  RunContact contact;
  RunStress stress;
  RunImplicit implicit;
  RunTiming timing;
};

// Called at monitor steps so a long run can show progress; must not modify anything.
using ProgressFn = std::function<void(long step, long planned_steps, double time)>;

}  // namespace ricochet
