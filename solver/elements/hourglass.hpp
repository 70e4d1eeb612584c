// Hourglass control of the one-point elements (Q4 in 2D, the hexahedron in 3D), shared by both
// dimensions: the form and the coefficient a body's case gives ([bodies.hourglass],
// docs/case-format.md); the elements turn them into the coefficient c of their own geometry.
#pragma once

namespace ricochet {

enum class HourglassForm { viscous, stiffness };

// Flanagan-Belytschko hourglass control of one-point Q4 (docs/background.md, Hourglass control),
// with q = sum_I gamma_I a_I (a = velocity for viscous, displacement for stiffness), Q = c q and
// nodal forces f_I = gamma_I Q:
//   viscous:   c = coeff * rho * c_p * t * sqrt(A0)           [kg/s]
//   stiffness: c = coeff * rho * c_p^2 * t * A0 * (B:B) / 2   [N/m]
// (the hexahedron's c: element3d.hpp, hex8_one_point_geometry).
struct HourglassControl {
  HourglassForm form = HourglassForm::viscous;
  double coeff = 0.1;  // [-]
};

}  // namespace ricochet
