// The local frictional contact problem of one contact in 2D, in its local frame (n, t):
// reaction r = (r_n, r_t), relative quantity x = (x_n, x_t) (a gap and slip increment at the
// position level, a relative velocity at the velocity level), x = x_free + w r with an
// isotropic local compliance w. Sign convention (docs/background.md, The contact law and the
// bi-potential): x_n > 0 separates, r_n >= 0 pushes apart, sliding gives r_t = -mu r_n sign(x_t).
// Pure functions, no state.
#pragma once

#include <cmath>
#include <cstdint>

namespace ricochet {

enum class ContactStatus : std::uint8_t { open, stick, slip };

struct LocalPair {
  double n = 0.0;
  double t = 0.0;
};

// Projection onto the Coulomb cone K_mu = {|r_t| <= mu r_n} (docs/background.md, Projection on
// the Coulomb cone; after GetFEM's De_Saxce_projection): inside -> unchanged (stick); in the polar
// cone -> 0 (separation); otherwise onto the cone surface (slip). mu = 0 gives
// r_n = max(0, r*_n), r_t = 0.
inline LocalPair project_coulomb(LocalPair r, double mu) {
  const double at = std::abs(r.t);
  if (r.n >= 0.0 && at <= mu * r.n) return r;  // r.n >= 0: with mu = 0, 0 <= 0 * r.n holds for r.n < 0
  if (mu * at <= -r.n) return {0.0, 0.0};
  const double rn = (r.n + mu * at) / (1.0 + mu * mu);
  return {rn, std::copysign(mu * rn, r.t)};
}

inline ContactStatus classify(LocalPair r, double mu) {
  if (!(r.n > 0.0)) return ContactStatus::open;
  return std::abs(r.t) < mu * r.n * (1.0 - 1e-12) ? ContactStatus::stick : ContactStatus::slip;
}

// The bi-potential predictor-corrector of paper Eq. (5) at a given x:
//   r* = r - rho (x + mu |x_t| n),  r <- Proj_K(r*).
// Every bi-potential solve uses it: the semi-explicit scheme through bipotential_update, the
// implicit scheme with x evaluated on its condensed problem.
inline LocalPair bipotential_correct(LocalPair r, LocalPair x, double mu, double rho) {
  return project_coulomb({r.n - rho * (x.n + mu * std::abs(x.t)), r.t - rho * x.t}, mu);
}

// One bi-potential update of a local problem with isotropic compliance, x = x_free + w r.
inline LocalPair bipotential_update(LocalPair r, LocalPair x_free, double w, double mu, double rho) {
  return bipotential_correct(r, {x_free.n + w * r.n, x_free.t + w * r.t}, mu, rho);
}

// The fixed point of the iteration with rho = 1/w in closed form ("impulse return map";
// docs/background.md, Rigid obstacle: the closed-form fixed point): r_n = max(0, -x_free_n / w),
// stick if the stick force fits in the cone.
inline LocalPair closed_form_reaction(LocalPair x_free, double w, double mu) {
  const double rn = std::max(0.0, -x_free.n / w);
  const double rt_stick = -x_free.t / w;
  if (std::abs(rt_stick) <= mu * rn) return {rn, rt_stick};
  return {rn, -std::copysign(mu * rn, x_free.t)};
}

}  // namespace ricochet
