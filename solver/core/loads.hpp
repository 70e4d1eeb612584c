// What a case imposes on single degrees of freedom: prescribed motion and nodal loads
// (docs/case-format.md, [[prescribed]] and [[loads]]), the same in every scheme and dimension.
#pragma once

namespace ricochet {

// A prescribed DOF: either a constant velocity, or a displacement reached linearly over
// `ramp` seconds (ramp = 0: imposed from t = 0), u(t) = value * min(1, t / ramp).
struct PrescribedDof {
  enum class Kind { velocity, displacement };
  int dof = 0;
  Kind kind = Kind::velocity;
  double value = 0.0;  // [m/s] or [m]
  double ramp = 0.0;   // [s]

  double displacement_at(double t) const {
    return ramp > 0.0 && t < ramp ? value * t / ramp : value;
  }
};

// A nodal force on one DOF that is switched on at `start` and ramped up linearly over `ramp`
// seconds (ramp = 0: a step at `start`): F(t) = value * clamp((t - start) / ramp, 0, 1), and 0
// before `start` (case key [[loads]], docs/case-format.md). Its work is accumulated in
// State::load_work.
struct NodalLoad {
  int dof = 0;
  double value = 0.0;  // [N]
  double start = 0.0;  // [s]
  double ramp = 0.0;   // [s]

  double force_at(double t) const {
    if (t < start) return 0.0;
    return ramp > 0.0 && t < start + ramp ? value * (t - start) / ramp : value;
  }
  // Constant from t = 0 on (the loads a quasi-static start relaxes under, and that do not end
  // a body's rest: summary.json `drift`).
  bool constant() const { return start <= 0.0 && ramp <= 0.0; }
};

// A loaded DOF of a run: its load, and what the trapezoidal work rule needs of the last step.
struct LoadedDof {
  NodalLoad load;
  double force_last = 0.0;  // F at the last evaluate() [N]
  double u_last = 0.0;      // u of that DOF then [m]
};

}  // namespace ricochet
