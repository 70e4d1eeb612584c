// What the contact module needs to know of the dimension (docs/architecture.md, Contact: one
// module, three solves, two dimensions). The module's code is written once, as templates on the
// model type M (its dimension D = M::kDim); everything that differs between 2D and 3D is here:
//   - the vector type of a node (Space<D>::Vec),
//   - the local unknowns of one contact, normal and tangential (Space<D>::Local): LocalPair in 2D
//     (the tangent a scalar along t = (n_y, -n_x)), a 2-vector in the tangent plane in 3D,
//   - the frame a contact is solved in, made from its unit normal n alone (ContactFrame<D>): so
//     that a frame stored as its normal is rebuilt bit for bit wherever it is needed.
// The 2D arithmetic of each function here is the arithmetic the module used before it was
// written for two dimensions, operation for operation, so 2D results did not change.
#pragma once

#include <cmath>

#include "solver/contact/coulomb.hpp"
#include "solver/contact/coulomb3d.hpp"  // local_norm, the 3D local pair and frame
#include "solver/model/types.hpp"

namespace ricochet {

template <int D>
using VecD = Eigen::Matrix<double, D, 1>;

template <int D>
struct ContactFrame;

// 2D: n and t = (n_y, -n_x), n rotated by -90 degrees (obstacle.hpp, body_contact.hpp).
template <>
struct ContactFrame<2> {
  Vec2 n, t;
  explicit ContactFrame(const Vec2& normal) : n(normal), t(normal.y(), -normal.x()) {}
  // r_n n + r_t t [N]
  Vec2 global(const LocalPair& r) const { return r.n * n + r.t * t; }
  // (n . v, t . v)
  LocalPair local(const Vec2& v) const { return {n.dot(v), t.dot(v)}; }
  // t . v
  double tangential(const Vec2& v) const { return t.dot(v); }
};

// |(dn, dt)| of two local pairs (and local_norm(), coulomb3d.hpp, |(n, t)| of one): the
// Gauss-Seidel stopping rule.
inline double local_distance(const LocalPair& a, const LocalPair& b) { return std::hypot(a.n - b.n, a.t - b.t); }
// The tangential part of a local pair (a scalar in 2D): its magnitude, the value of magnitude
// `cap` in its direction, and the dot product.
inline double tangential_abs(double t) { return std::abs(t); }
inline double tangential_clamp(double cap, double t) { return std::copysign(cap, t); }
inline double tangential_dot(double a, double b) { return a * b; }
// A reaction's share of ContactStep::tangential_force: r_t, signed along t [N].
inline double tangential_sum_term(const LocalPair& r) { return r.t; }
// The slip work of reaction r over a slip increment `slip` (the tangential part of the relative
// motion, before `scale`): -r_t scale slip [J], >= 0 by the cone.
inline double slip_work(const LocalPair& r, double scale, double slip) { return -r.t * scale * slip; }

}  // namespace ricochet
