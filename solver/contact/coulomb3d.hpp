// The local frictional contact problem of one contact in 3D, in its local frame (n; t1, t2): the
// 3D counterpart of coulomb.hpp, with the same conventions, rules and function names, overloaded
// on LocalPair3d, so that code templated over the dimension calls project_coulomb(r, mu),
// bipotential_update(r, x, w, mu, rho), ... for either pair. A braced pair such as {1.0, 0.3}
// cannot initialize a LocalPair3d (its tangential part, an Eigen vector, has no implicit
// conversion from a number), so it still means a 2D LocalPair; only an empty {} fits both.
// Reaction r = (r_n, r_t), relative quantity x = (x_n, x_t) (a gap and slip increment at the
// position level, a relative velocity at the velocity level), each with a tangential part in the contact's tangent plane, given by its components on
// (t1, t2); x = x_free + w r with an isotropic local compliance w. Sign convention
// (docs/background.md, The contact law and the bi-potential): x_n > 0 separates, r_n >= 0 pushes
// apart, sliding gives r_t = -mu r_n x_t / |x_t|. The formulas are in docs/three-dimensions.md,
// Contact in 3D: the Coulomb cone (De Saxcé & Feng 1991, 1998: the bi-potential and its
// projection onto Coulomb's cone).
//
// |.| of a tangential part is std::hypot: no overflow or underflow of the squares (a tangential
// part of 1e-200 or 1e200 keeps its length), and hypot(a, 0) = |a| exactly, so a problem whose
// tangential data lie along one tangent gives the 2D functions' numbers (tests/solver/contact/test_coulomb3d.cpp).
// Pure functions on fixed-size Eigen types: no state, no heap allocation.
#pragma once

#include <algorithm>
#include <cmath>

#include "solver/contact/coulomb.hpp"  // ContactStatus, shared with 2D
#include "solver/core/types.hpp"

namespace ricochet {

// Local components: normal n, tangential t = (t1 component, t2 component).
struct LocalPair3d {
  double n = 0.0;
  Vec2 t = Vec2::Zero();
};

// |t| without overflow or underflow of the squares; exact when one component is zero.
inline double tangential_norm_3d(const Vec2& t) { return std::hypot(t.x(), t.y()); }

// De Saxcé's modified relative quantity x + mu |x_t| n (the bi-potential's implicit normality
// rule written as one projection): the normal part grows by mu |x_t|, the tangential part stays.
inline LocalPair3d de_saxce_modified_3d(const LocalPair3d& x, double mu) {
  return {x.n + mu * tangential_norm_3d(x.t), x.t};
}

// Projection onto the Coulomb cone K_mu = {|r_t| <= mu r_n}, with the three cases of
// project_coulomb (coulomb.hpp): inside -> unchanged (stick); in the polar cone
// {mu |r_t| <= -r_n} -> 0 (separation); otherwise onto the cone surface along r_t / |r_t| (slip):
// r_n = (r*_n + mu |r*_t|) / (1 + mu^2), r_t = mu r_n r*_t / |r*_t|. mu = 0 gives
// r_n = max(0, r*_n), r_t = 0.
// No 0/0: the slip branch has |r*_t| > 0 (with |r*_t| = 0 the first test fails only for
// r*_n < 0, and then the second holds), and there r*_t / |r*_t| has components in [-1, 1].
// The unit direction is formed before it is scaled, so that along one tangent it is exactly
// +-1 and the result is the 2D one bit for bit.
inline LocalPair3d project_coulomb(const LocalPair3d& r, double mu) {
  const double at = tangential_norm_3d(r.t);
  if (r.n >= 0.0 && at <= mu * r.n) return r;  // r.n >= 0: with mu = 0, 0 <= 0 * r.n holds for r.n < 0
  if (mu * at <= -r.n) return {};
  const double rn = (r.n + mu * at) / (1.0 + mu * mu);
  const Vec2 direction = r.t / at;
  return {rn, (mu * rn) * direction};
}

// The status a reaction stands for, with classify's rule (coulomb.hpp): open unless r_n > 0;
// stick strictly inside the cone (a relative margin of 1e-12, so that a projected slip reaction,
// whose |r_t| = mu r_n is rounded, stays slip); slip on its surface. Frictionless contact with
// a reaction is slip (no stick force is available).
inline ContactStatus classify(const LocalPair3d& r, double mu) {
  if (!(r.n > 0.0)) return ContactStatus::open;
  return tangential_norm_3d(r.t) < mu * r.n * (1.0 - 1e-12) ? ContactStatus::stick : ContactStatus::slip;
}

// The bi-potential predictor-corrector of paper Eq. (5) at a given x:
//   r* = r - rho (x + mu |x_t| n),  r <- Proj_K(r*).
inline LocalPair3d bipotential_correct(const LocalPair3d& r, const LocalPair3d& x, double mu, double rho) {
  const LocalPair3d m = de_saxce_modified_3d(x, mu);
  return project_coulomb({r.n - rho * m.n, Vec2(r.t - rho * m.t)}, mu);
}

// One bi-potential update of a local problem with isotropic compliance, x = x_free + w r.
inline LocalPair3d bipotential_update(const LocalPair3d& r, const LocalPair3d& x_free, double w, double mu,
                                         double rho) {
  return bipotential_correct(r, {x_free.n + w * r.n, Vec2(x_free.t + w * r.t)}, mu, rho);
}

// The fixed point of the iteration in closed form, as closed_form_reaction (coulomb.hpp):
// r_n = max(0, -x_free_n / w); stick r_t = -x_free_t / w if it fits in the cone, otherwise slip
// r_t = mu r_n along -x_free_t / |x_free_t| (with an isotropic compliance the slip keeps the
// direction of the free slip). The slip branch has |x_free_t| > 0 (the stick test holds for
// x_free_t = 0), so no 0/0.
inline LocalPair3d closed_form_reaction(const LocalPair3d& x_free, double w, double mu) {
  const double rn = std::max(0.0, -x_free.n / w);
  const Vec2 rt_stick = -x_free.t / w;
  const double at = tangential_norm_3d(rt_stick);
  if (at <= mu * rn) return {rn, rt_stick};
  const Vec2 direction = rt_stick / at;
  return {rn, (mu * rn) * direction};
}

// The length |(n, t)| of a local pair in either dimension, as solve_local's stopping test
// measures it: hypot(n, t) in 2D, hypot(n, hypot(t1, t2)) in 3D (no overflow or underflow of the
// squares; a 3D pair with one tangential component zero has the 2D pair's length exactly).
inline double local_norm(const LocalPair& a) { return std::hypot(a.n, a.t); }
inline double local_norm(const LocalPair3d& a) { return std::hypot(a.n, tangential_norm_3d(a.t)); }

// The contact frame of a unit normal n: tangents t1, t2 with (t1, t2, n) orthonormal and
// right-handed (t1 x t2 = n). The tangents follow Duff, Burgess, Christensen, Hery, Kensler,
// Liani & Villemin (2017), "Building an orthonormal basis, revisited", J. Computer Graphics
// Techniques 6(1), 1-8, Listing 3 (branchless): Frisvad's (2012) construction with the sign of
// n_z folded in, so that 1 / (sign + n_z) never divides by a cancelled difference (Frisvad's
// form loses all precision as n_z -> -1). Any frame built from n alone jumps somewhere (here
// where n_z changes sign); the isotropic Coulomb law does not mind, since a rotation of (t1, t2)
// in the tangent plane rotates x_t and r_t alike.
struct Frame3d {
  Vec3 t1, t2, n;
};

inline Frame3d contact_frame_3d(const Vec3& n) {
  const double sign = std::copysign(1.0, n.z());
  const double a = -1.0 / (sign + n.z());
  const double b = n.x() * n.y() * a;
  return {Vec3(1.0 + sign * n.x() * n.x() * a, sign * b, -sign * n.x()),
          Vec3(b, sign + n.y() * n.y() * a, -n.y()), n};
}

}  // namespace ricochet
