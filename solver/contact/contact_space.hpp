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
#include <type_traits>

#include "solver/contact/coulomb.hpp"
#include "solver/core/types.hpp"

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

// The tangential part of a local pair (a scalar in 2D): the dot product.
inline double tangential_dot(double a, double b) { return a * b; }
// A reaction's share of ContactStep::tangential_force: r_t, signed along t [N].
inline double tangential_sum_term(const LocalPair& r) { return r.t; }
// The slip work of reaction r over a slip increment `slip` (the tangential part of the relative
// motion, before `scale`): -r_t scale slip [J], >= 0 by the cone.
inline double slip_work(const LocalPair& r, double scale, double slip) { return -r.t * scale * slip; }

// 3D: tangents t1, t2 with (t1, t2, n) orthonormal and right-handed (t1 x t2 = n), the local
// pair LocalPair3d (r_n; r_t on (t1, t2)). The tangents follow Duff, Burgess, Christensen, Hery,
// Kensler, Liani & Villemin (2017), "Building an orthonormal basis, revisited", J. Computer
// Graphics Techniques 6(1), 1-8, Listing 3 (branchless): Frisvad's (2012) construction with the
// sign of n_z folded in, so that 1 / (sign + n_z) never divides by a cancelled difference
// (Frisvad's form loses all precision as n_z -> -1). Any frame built from n alone jumps somewhere
// (here where n_z changes sign); the isotropic Coulomb law does not mind, since a rotation of
// (t1, t2) in the tangent plane rotates x_t and r_t alike.
template <>
struct ContactFrame<3> {
  Vec3 n, t1, t2;
  explicit ContactFrame(const Vec3& normal) : n(normal) {
    const double sign = std::copysign(1.0, n.z());
    const double a = -1.0 / (sign + n.z());
    const double b = n.x() * n.y() * a;
    t1 = Vec3(1.0 + sign * n.x() * n.x() * a, sign * b, -sign * n.x());
    t2 = Vec3(b, sign + n.y() * n.y() * a, -n.y());
  }
  // r_n n + r_t1 t1 + r_t2 t2 [N]
  Vec3 global(const LocalPair3d& r) const { return r.n * n + r.t.x() * t1 + r.t.y() * t2; }
  // (n . v, (t1 . v, t2 . v))
  LocalPair3d local(const Vec3& v) const { return {n.dot(v), Vec2(t1.dot(v), t2.dot(v))}; }
  // (t1 . v, t2 . v)
  Vec2 tangential(const Vec3& v) const { return Vec2(t1.dot(v), t2.dot(v)); }
};

// The 3D counterparts of the 2D helpers above (the tangential part a 2-vector of the tangent plane).
inline double tangential_dot(const Vec2& a, const Vec2& b) { return a.dot(b); }
// In 3D a reaction's share of ContactStep::tangential_force is its magnitude |r_t| [N]: the
// tangents of different contacts are different directions, so only magnitudes add up to a
// scalar (the history's tangential_force column is then >= 0).
inline double tangential_sum_term(const LocalPair3d& r) { return tangential_norm(r.t); }
inline double slip_work(const LocalPair3d& r, double scale, const Vec2& slip) { return -scale * r.t.dot(slip); }

// The value of magnitude `cap` along t (t != 0: called only when |t| > cap >= 0).
template <class T>
inline T tangential_clamp(double cap, const T& t) {
  return tangential_along(cap, t, tangential_norm(t));
}

// The local problem of one contact, in either dimension: the reaction r such that x(r) and r obey
// Coulomb's law, found with the bi-potential predictor-corrector (de Saxcé & Feng 1991; Cros,
// Feng & Magnain 2010, Section 2) r <- bipotential_correct(r, x(r), mu, rho) from r0 until
// |r_{i+1} - r_i| <= tol |r_{i+1}| (or no change) or max_iterations updates. x_of(r) is the
// contact's local compliance: x_free + w r (solve_local below), or x_base + W_kk r with the
// implicit scheme's condensed block W_kk (condensed_contact.hpp).
template <class Pair>
struct LocalSolutionT {
  Pair r;
  int iterations = 0;  // predictor-corrector updates performed
  bool converged = false;
};
using LocalSolution = LocalSolutionT<LocalPair>;
using LocalSolution3d = LocalSolutionT<LocalPair3d>;

template <class Pair, class Compliance>
LocalSolutionT<Pair> solve_local_map(const Compliance& x_of, double mu, double rho, const Pair& r0, double tol,
                                     int max_iterations) {
  LocalSolutionT<Pair> s{r0, 0, false};
  while (s.iterations < max_iterations) {
    const Pair next = bipotential_correct(s.r, x_of(s.r), mu, rho);
    ++s.iterations;
    const double change = local_distance(next, s.r);
    s.r = next;
    if (change <= tol * local_norm(next) || change == 0.0) {
      s.converged = true;
      break;
    }
  }
  return s;
}

// With an isotropic compliance, x = x_free + w r (the semi-explicit scheme's local problem, and
// the closed form's: with rho = 1/w and mu = 0 the first update is exact). r0's type follows
// x_free's, so a braced {0.0, 0.0} is a 2D pair.
template <class Pair>
LocalSolutionT<Pair> solve_local(const Pair& x_free, double w, double mu, double rho,
                                 const std::type_identity_t<Pair>& r0, double tol, int max_iterations) {
  using Tangential = decltype(Pair::t);
  auto x_of = [&](const Pair& r) { return Pair{x_free.n + w * r.n, Tangential(x_free.t + w * r.t)}; };
  return solve_local_map(x_of, mu, rho, r0, tol, max_iterations);
}

}  // namespace ricochet
