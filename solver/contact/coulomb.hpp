// The local frictional contact problem of one contact, in its local frame, in either dimension:
// reaction r = (r_n, r_t), relative quantity x = (x_n, x_t) (a gap and slip increment at the
// position level, a relative velocity at the velocity level), x = x_free + w r with an
// isotropic local compliance w. The tangential part is a scalar along t = (n_y, -n_x) in 2D
// (LocalPair) and a 2-vector of the tangent plane, its components on (t1, t2), in 3D
// (LocalPair3d). Sign convention (docs/background.md, The contact law and the bi-potential):
// x_n > 0 separates, r_n >= 0 pushes apart, sliding gives r_t = -mu r_n x_t / |x_t|. The 3D
// formulas are in docs/three-dimensions.md, Contact in 3D: the Coulomb cone (De Saxcé & Feng
// 1991, 1998: the bi-potential and its projection onto Coulomb's cone).
//
// Each law is written once, for either pair; only the tangential part's |.| and direction
// differ (tangential_norm, tangential_along). In 3D |.| is std::hypot: no overflow or
// underflow of the squares, and hypot(a, 0) = |a| exactly, so a 3D problem whose tangential
// data lie along one tangent gives the 2D numbers (tests/solver/contact/test_coulomb3d.cpp).
// A braced argument, as in project_coulomb({1.0, 0.3}, mu), is a 2D pair (the default template
// argument); a 3D one is written LocalPair3d{...}.
// Pure functions on scalars and fixed-size Eigen types: no state, no heap allocation.
#pragma once

#include <algorithm>
#include <cmath>
#include <concepts>
#include <cstdint>

#include "solver/core/types.hpp"

namespace ricochet {

enum class ContactStatus : std::uint8_t { open, stick, slip };

// 2D local components: normal n, tangential t along (n_y, -n_x).
struct LocalPair {
  double n = 0.0;
  double t = 0.0;
};

// 3D local components: normal n, tangential t = (t1 component, t2 component).
struct LocalPair3d {
  double n = 0.0;
  Vec2 t = Vec2::Zero();
};

template <class P>
concept LocalPairType = std::same_as<P, LocalPair> || std::same_as<P, LocalPair3d>;

// |t|: |t| in 2D, hypot(t1, t2) in 3D (exact when one component is zero).
inline double tangential_norm(double t) { return std::abs(t); }
inline double tangential_norm(const Vec2& t) { return std::hypot(t.x(), t.y()); }
// The value of magnitude `cap` >= 0 along t, given norm = |t| > 0. The 3D unit direction is
// formed before it is scaled, so that along one tangent it is exactly +-1 and the result is
// the 2D one bit for bit.
inline double tangential_along(double cap, double t, double /*norm*/) { return std::copysign(cap, t); }
inline Vec2 tangential_along(double cap, const Vec2& t, double norm) { return cap * (t / norm); }

// Projection onto the Coulomb cone K_mu = {|r_t| <= mu r_n} (docs/background.md, Projection on
// the Coulomb cone; after GetFEM's De_Saxce_projection): inside -> unchanged (stick); in the polar
// cone {mu |r_t| <= -r_n} -> 0 (separation); otherwise onto the cone surface along r_t / |r_t|
// (slip): r_n = (r*_n + mu |r*_t|) / (1 + mu^2), |r_t| = mu r_n. mu = 0 gives
// r_n = max(0, r*_n), r_t = 0. No 0/0: the slip branch has |r*_t| > 0 (with |r*_t| = 0 the
// first test fails only for r*_n < 0, and then the second holds).
template <LocalPairType P = LocalPair>
inline P project_coulomb(const P& r, double mu) {
  const double at = tangential_norm(r.t);
  if (r.n >= 0.0 && at <= mu * r.n) return r;  // r.n >= 0: with mu = 0, 0 <= 0 * r.n holds for r.n < 0
  if (mu * at <= -r.n) return {};
  const double rn = (r.n + mu * at) / (1.0 + mu * mu);
  return {rn, tangential_along(mu * rn, r.t, at)};
}

// The status a reaction stands for: open unless r_n > 0; stick strictly inside the cone (a
// relative margin of 1e-12, so that a projected slip reaction, whose |r_t| = mu r_n is rounded,
// stays slip); slip on its surface. Frictionless contact with a reaction is slip (no stick
// force is available).
template <LocalPairType P = LocalPair>
inline ContactStatus classify(const P& r, double mu) {
  if (!(r.n > 0.0)) return ContactStatus::open;
  return tangential_norm(r.t) < mu * r.n * (1.0 - 1e-12) ? ContactStatus::stick : ContactStatus::slip;
}

// De Saxcé's modified relative quantity x + mu |x_t| n (the bi-potential's implicit normality
// rule written as one projection): the normal part grows by mu |x_t|, the tangential part stays.
template <LocalPairType P = LocalPair>
inline P de_saxce_modified(const P& x, double mu) {
  return {x.n + mu * tangential_norm(x.t), x.t};
}

// The bi-potential predictor-corrector of paper Eq. (5) at a given x:
//   r* = r - rho (x + mu |x_t| n),  r <- Proj_K(r*).
// Every bi-potential solve uses it: the semi-explicit scheme through bipotential_update, the
// implicit scheme with x evaluated on its condensed problem.
template <LocalPairType P = LocalPair>
inline P bipotential_correct(const P& r, const P& x, double mu, double rho) {
  using T = decltype(P::t);
  const P m = de_saxce_modified(x, mu);
  return project_coulomb(P{r.n - rho * m.n, T(r.t - rho * m.t)}, mu);
}

// One bi-potential update of a local problem with isotropic compliance, x = x_free + w r.
template <LocalPairType P = LocalPair>
inline P bipotential_update(const P& r, const P& x_free, double w, double mu, double rho) {
  using T = decltype(P::t);
  return bipotential_correct(r, P{x_free.n + w * r.n, T(x_free.t + w * r.t)}, mu, rho);
}

// The fixed point of the iteration with rho = 1/w in closed form ("impulse return map";
// docs/background.md, Rigid obstacle: the closed-form fixed point): r_n = max(0, -x_free_n / w);
// stick r_t = -x_free_t / w if it fits in the cone, otherwise slip r_t = mu r_n along
// -x_free_t / |x_free_t| (with an isotropic compliance the slip keeps the direction of the free
// slip). The slip branch has |x_free_t| > 0 (the stick test holds for x_free_t = 0), so no 0/0.
template <LocalPairType P = LocalPair>
inline P closed_form_reaction(const P& x_free, double w, double mu) {
  using T = decltype(P::t);
  const double rn = std::max(0.0, -x_free.n / w);
  const T rt_stick = T(-x_free.t / w);
  const double at = tangential_norm(rt_stick);
  if (at <= mu * rn) return {rn, rt_stick};
  return {rn, tangential_along(mu * rn, rt_stick, at)};
}

// |(n, t)| of a local pair and |(dn, dt)| of two, as the local solves' stopping test measures
// them: hypot(n, |t|) (no overflow or underflow of the squares; a 3D pair with one tangential
// component zero has the 2D pair's length exactly).
template <LocalPairType P = LocalPair>
inline double local_norm(const P& a) {
  return std::hypot(a.n, tangential_norm(a.t));
}
template <LocalPairType P = LocalPair>
inline double local_distance(const P& a, const P& b) {
  using T = decltype(P::t);
  return std::hypot(a.n - b.n, tangential_norm(T(a.t - b.t)));
}

}  // namespace ricochet
