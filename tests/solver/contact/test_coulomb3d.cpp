// Verification of the 3D local Coulomb law (solver/contact/coulomb.hpp; docs/three-dimensions.md,
// Contact in 3D: the Coulomb cone): the projection onto the cone K_mu = {|r_t| <= mu r_n} with a
// 2D tangent plane against two independent characterisations (Moreau's decomposition, and the
// nearest point over the cone's generator rays found by a bisection on the angle), its corner
// cases (r_t = 0, mu = 0, tangential parts of 1e-200 and 1e200); the bi-potential
// predictor-corrector's fixed points against the Coulomb law itself and against a solve by
// enumeration of its three cases; the reduction to the 2D functions when the
// tangential data lie along one tangent; the contact frame (Duff et al. 2017); no heap allocation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Geometry>  // cross()

#include "solver/contact/contact_space.hpp"  // solve_local
#include "solver/contact/coulomb.hpp"

#include "tests/support/alloc_counter.hpp"

namespace ricochet {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// |(n, t)| of a local triple, and of a difference of two.
double norm3(const LocalPair3d& a) { return std::sqrt(a.n * a.n + a.t.squaredNorm()); }
double dist3(const LocalPair3d& a, const LocalPair3d& b) {
  return std::sqrt((a.n - b.n) * (a.n - b.n) + (a.t - b.t).squaredNorm());
}

Vec2 unit_at(double phi) { return {std::cos(phi), std::sin(phi)}; }

// The angle phi that maximises a . (cos phi, sin phi), found without atan2 and without dividing
// by |a|: the derivative h(phi) = -a_1 sin phi + a_2 cos phi = |a| sin(alpha - phi) changes sign
// from + to - exactly once per turn, at the maximum; a grid of 8 brackets it and a bisection
// takes it to the last bit (h is evaluated to a few eps of |a| and has slope |a| there, so phi
// is found to a few eps). Returns false for a = 0, where every phi is as good.
bool best_angle(const Vec2& a, double& phi) {
  auto h = [&](double p) { return -a.x() * std::sin(p) + a.y() * std::cos(p); };
  constexpr int kGrid = 8;
  for (int i = 0; i < kGrid; ++i) {
    double lo = kTwoPi * i / kGrid, hi = kTwoPi * (i + 1) / kGrid;
    if (!(h(lo) >= 0.0 && h(hi) < 0.0)) continue;
    for (int k = 0; k < 200; ++k) {
      const double mid = 0.5 * (lo + hi);
      if (mid <= lo || mid >= hi) break;
      (h(mid) >= 0.0 ? lo : hi) = mid;
    }
    phi = lo;
    return true;
  }
  phi = 0.0;
  return false;
}

// The projection onto K_mu by another route than the solver's: K_mu is the union of its
// generator rays d(phi) = (1, mu cos phi, mu sin phi) / sqrt(1 + mu^2) and their insides. A
// point of K is its own projection; otherwise the projection lies on the boundary, i.e. on a
// ray, and the nearest point of a ray is max(0, y . d) d at squared distance |y|^2 - max(0, y.d)^2,
// so the best ray maximises y . d(phi) = (y_n + mu y_t . (cos phi, sin phi)) / sqrt(1 + mu^2):
// phi from best_angle(y_t). mu = 0 needs no special case (d = (1, 0, 0)).
LocalPair3d projection_by_rays(const LocalPair3d& y, double mu) {
  if (y.n >= 0.0 && std::sqrt(y.t.squaredNorm()) <= mu * y.n) return y;  // the definition of K
  double phi = 0.0;
  best_angle(y.t, phi);
  const double c = 1.0 / std::sqrt(1.0 + mu * mu);
  const LocalPair3d d{c, Vec2(c * mu * unit_at(phi))};
  const double s = std::max(0.0, y.n * d.n + y.t.dot(d.t));
  return {s * d.n, Vec2(s * d.t)};
}

// The solution of the local Coulomb problem x = x_free + w r by enumeration of its three cases
// (the law has exactly one solution for an isotropic w > 0):
// - separation: x_free_n >= 0 gives r = 0, x = x_free;
// - contact otherwise, x_n = 0: r_n = -x_free_n / w; stick if r_t = -x_free_t / w (x_t = 0) lies
//   in the cone;
// - slip: x_t = s e with s > 0 and r_t = -mu r_n e; x_t = x_free_t + w r_t gives
//   (s + w mu r_n) e = x_free_t, so e is the unit vector best aligned with x_free_t (best_angle,
//   not a division by |x_free_t|) and s = x_free_t . e - w mu r_n, checked > 0.
struct CoulombSolution {
  LocalPair3d r;
  ContactStatus status;
  double slip_speed = 0.0;  // s = |x_t| in the slip case
};

CoulombSolution coulomb_by_cases(const LocalPair3d& xf, double w, double mu) {
  if (xf.n >= 0.0) return {{}, ContactStatus::open};
  const double rn = -xf.n / w;
  const Vec2 rt_stick = -xf.t / w;
  if (std::sqrt(rt_stick.squaredNorm()) <= mu * rn) return {{rn, rt_stick}, ContactStatus::stick};
  double phi = 0.0;
  best_angle(xf.t, phi);
  const Vec2 e = unit_at(phi);
  return {{rn, Vec2(-mu * rn * e)}, ContactStatus::slip, xf.t.dot(e) - w * mu * rn};
}

// Random samples: y in [-5, 5]^3, plus the axis (y_t = 0, signed zeros included) and points on
// the cone's and the polar cone's surfaces for each mu.
std::vector<LocalPair3d> projection_samples(double mu, std::mt19937_64& gen) {
  std::uniform_real_distribution<double> uni(-5.0, 5.0), angle(0.0, kTwoPi);
  std::vector<LocalPair3d> ys;
  for (int k = 0; k < 4000; ++k) ys.push_back({uni(gen), Vec2(uni(gen), uni(gen))});
  for (double yn : {-2.0, -0.5, -0.0, 0.0, 0.5, 2.0}) {
    ys.push_back({yn, Vec2(0.0, 0.0)});
    ys.push_back({yn, Vec2(-0.0, 0.0)});
    ys.push_back({yn, Vec2(0.0, -0.0)});
  }
  for (int k = 0; k < 200; ++k) {
    const double a = std::abs(uni(gen));
    ys.push_back({a, Vec2(mu * a * unit_at(angle(gen)))});   // on the cone
    ys.push_back({-mu * a, Vec2(a * unit_at(angle(gen)))});  // on the polar cone
  }
  return ys;
}

const double kMus[] = {0.0, 0.1, 0.3, 0.5, 1.0, 2.0};

// ---------------------------------------------------------------------------------------------
// project_coulomb

TEST(Coulomb3d, ProjectionSatisfiesMoreauDecomposition) {
  // Moreau: y = p + q with p in K, q in the polar cone K° = {mu |q_t| <= -q_n} and p . q = 0
  // holds for p = Proj_K(y) and for no other p. The solver's p rounds a hypot, a sum, a
  // division and a product, and the residuals below a few more operations, each 1/2 ulp of
  // numbers of size (1 + mu) |y|: tolerance 16 eps (1 + mu) |y| (and |y| times that for p . q).
  std::mt19937_64 gen(20100101);
  double worst = 0.0;  // largest residual / ((1 + mu) |y| eps)
  for (double mu : kMus) {
    for (const LocalPair3d& y : projection_samples(mu, gen)) {
      const double scale = (1.0 + mu) * norm3(y);
      const double tol = 16 * kEps * scale;
      const LocalPair3d p = project_coulomb(y, mu);
      const LocalPair3d q{y.n - p.n, Vec2(y.t - p.t)};
      const double residuals[] = {
          -p.n,                                           // p_n >= 0
          tangential_norm(p.t) - mu * p.n,             // p in K
          mu * tangential_norm(q.t) + q.n,             // q in K°
          std::abs(p.n * q.n + p.t.dot(q.t)) / std::max(norm3(y), 1e-300),  // p . q = 0
      };
      for (double res : residuals) {
        ASSERT_LE(res, tol) << "mu " << mu << " y = (" << y.n << ", " << y.t.transpose() << ") -> ("
                            << p.n << ", " << p.t.transpose() << ")";
        if (scale > 0.0) worst = std::max(worst, res / (scale * kEps));
      }
    }
  }
  std::printf("[coulomb3d] Moreau residuals: max %.2f eps (1 + mu)|y| (tolerance 16)\n", worst);
}

TEST(Coulomb3d, ProjectionMatchesNearestPointOverTheConesRays) {
  // Against projection_by_rays (its angle by bisection, its ray by cos/sin/sqrt, each a few
  // eps): agreement to 1e-12 |y| is a margin of ~1e3 over the rounding of both sides, far below
  // any error of a formula, and tighter than the 1e-10.
  std::mt19937_64 gen(18);
  double worst = 0.0;
  long compared = 0;
  for (double mu : kMus) {
    for (const LocalPair3d& y : projection_samples(mu, gen)) {
      const LocalPair3d p = project_coulomb(y, mu);
      const LocalPair3d ref = projection_by_rays(y, mu);
      const double err = dist3(p, ref);
      ASSERT_LE(err, 1e-12 * norm3(y)) << "mu " << mu << " y = (" << y.n << ", " << y.t.transpose()
                                       << ") -> (" << p.n << ", " << p.t.transpose() << ") vs ("
                                       << ref.n << ", " << ref.t.transpose() << ")";
      ASSERT_TRUE(std::isfinite(p.n) && std::isfinite(p.t.x()) && std::isfinite(p.t.y()));
      if (norm3(y) > 0.0) worst = std::max(worst, err / norm3(y));
      ++compared;
    }
  }
  std::printf("[coulomb3d] projection vs rays: %ld points, max |p - p_ref| / |y| = %.2e (tolerance 1e-12)\n",
              compared, worst);
}

TEST(Coulomb3d, ProjectionCasesInsidePolarIdempotent) {
  // Inside K: returned bit for bit (stick). In K°: exactly 0 (separation). Projecting twice
  // moves the point by round-off only (|p_t| is a rounded hypot of mu r_n times a rounded unit
  // vector, so p may sit an ulp outside the surface): 8 eps (1 + mu) |y|.
  std::mt19937_64 gen(5);
  std::uniform_real_distribution<double> uni(-5.0, 5.0);
  int inside = 0, polar = 0;
  for (double mu : kMus) {
    for (int k = 0; k < 4000; ++k) {
      const LocalPair3d y{uni(gen), Vec2(uni(gen), uni(gen))};
      const double yt = std::sqrt(y.t.squaredNorm());
      const LocalPair3d p = project_coulomb(y, mu);
      if (y.n >= 0.0 && yt <= mu * y.n) {
        ++inside;
        ASSERT_EQ(p.n, y.n);
        ASSERT_EQ(p.t.x(), y.t.x());
        ASSERT_EQ(p.t.y(), y.t.y());
      } else if (mu * yt <= -y.n) {
        ++polar;
        ASSERT_EQ(p.n, 0.0);
        ASSERT_EQ(p.t.x(), 0.0);
        ASSERT_EQ(p.t.y(), 0.0);
      }
      const LocalPair3d pp = project_coulomb(p, mu);
      ASSERT_LE(dist3(pp, p), 8 * kEps * (1.0 + mu) * norm3(y));
    }
  }
  EXPECT_GT(inside, 1000);  // every case drawn often (mu = 2 puts most points inside)
  EXPECT_GT(polar, 1000);
}

TEST(Coulomb3d, ProjectionWithZeroTangentialPartHasNoNaN) {
  // r_t = 0 (every signed zero) with r_n of both signs, with and without friction: r_n >= 0 is
  // inside K (unchanged), r_n < 0 in K° (zero); never 0/0.
  for (double mu : {0.0, 0.3, 2.0}) {
    for (double rn : {-2.0, -1e-300, -0.0, 0.0, 1e-300, 2.0}) {
      for (const Vec2& t : {Vec2(0.0, 0.0), Vec2(-0.0, 0.0), Vec2(0.0, -0.0), Vec2(-0.0, -0.0)}) {
        const LocalPair3d p = project_coulomb(LocalPair3d{rn, t}, mu);
        EXPECT_TRUE(std::isfinite(p.n) && std::isfinite(p.t.x()) && std::isfinite(p.t.y()))
            << "mu " << mu << " rn " << rn;
        EXPECT_EQ(p.n, std::max(0.0, rn)) << "mu " << mu << " rn " << rn;
        EXPECT_EQ(p.t.x(), 0.0);
        EXPECT_EQ(p.t.y(), 0.0);
      }
    }
  }
}

TEST(Coulomb3d, FrictionlessProjectionIsTheHalfLine) {
  // mu = 0: K_0 is the half-line {r_n >= 0, r_t = 0}, the projection (max(0, r_n), 0), exactly
  // (the slip branch divides r_n by 1 + 0 and scales the direction by 0).
  std::mt19937_64 gen(3);
  std::uniform_real_distribution<double> uni(-5.0, 5.0);
  for (int k = 0; k < 2000; ++k) {
    const LocalPair3d y{uni(gen), Vec2(uni(gen), uni(gen))};
    const LocalPair3d p = project_coulomb(y, 0.0);
    ASSERT_EQ(p.n, std::max(0.0, y.n));
    ASSERT_EQ(p.t.x(), 0.0);
    ASSERT_EQ(p.t.y(), 0.0);
  }
}

TEST(Coulomb3d, ProjectionIsPositivelyHomogeneousAtExtremeScales) {
  // Proj_K(s y) = s Proj_K(y) for s > 0. With s a power of two the scaling itself is exact, so
  // only the solver's rounding differs: 8 eps (1 + mu) relative. At s = 2^-700 the squares of
  // the tangential components underflow and at 2^+700 they overflow: a |r_t| formed as
  // sqrt(t1^2 + t2^2) would give 0 or inf there (wrong branch, or NaN); hypot does not.
  std::mt19937_64 gen(11);
  std::uniform_real_distribution<double> uni(-5.0, 5.0);
  for (double mu : {0.1, 0.5, 2.0}) {
    for (int k = 0; k < 1000; ++k) {
      const LocalPair3d y{uni(gen), Vec2(uni(gen), uni(gen))};
      const LocalPair3d p = project_coulomb(y, mu);
      for (int e : {-700, 700}) {
        const double s = std::ldexp(1.0, e);
        const LocalPair3d ps = project_coulomb(LocalPair3d{s * y.n, Vec2(s * y.t)}, mu);
        const LocalPair3d back{ps.n / s, Vec2(ps.t / s)};
        ASSERT_LE(dist3(back, p), 8 * kEps * (1.0 + mu) * norm3(y))
            << "mu " << mu << " scale 2^" << e << " y = (" << y.n << ", " << y.t.transpose() << ")";
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// de_saxce_modified, bipotential_update, solve_local, closed_form_reaction

const double kRhos[] = {1e-3, 0.1, 0.5, 1.0, 2.0, 10.0, 1e3};

TEST(Bipotential3d, ModifiedVelocityAddsMuTimesSlipToTheNormal) {
  // x + mu |x_t| n: hand values with |x_t| = 5 (a 3-4-5 triangle, exact), and x_t = 0.
  const LocalPair3d x{-1.0, Vec2(3.0, -4.0)};
  const LocalPair3d m = de_saxce_modified(x, 0.5);
  EXPECT_EQ(m.n, -1.0 + 2.5);
  EXPECT_EQ(m.t.x(), 3.0);
  EXPECT_EQ(m.t.y(), -4.0);
  const LocalPair3d m0 = de_saxce_modified(LocalPair3d{0.7, Vec2(0.0, -0.0)}, 0.5);
  EXPECT_EQ(m0.n, 0.7);
  EXPECT_EQ(de_saxce_modified(x, 0.0).n, -1.0);
}

TEST(Bipotential3d, CoulombStatesAreFixedPointsForAnyRho) {
  // For tangential directions all round the circle and rho over six decades:
  // - stick: r inside the cone, x_free = -w r, so x = 0 exactly and r* = r, returned bit for bit;
  // - slip: x_n = 0, x_t = s e, r_t = -mu r_n e; r*_t = -(mu r_n + rho s) e and
  //   r*_n = r_n - rho mu s project back onto r; e and the projection round, a few eps of
  //   |r*| ~ r_n + rho s: tolerance 16 eps (1 + mu) (r_n + rho s);
  // - separation: x_n > 0, r = 0: r* lies in the polar cone, so exactly 0.
  const double w = 0.5, mu = 0.25;
  std::mt19937_64 gen(9);
  std::uniform_real_distribution<double> angle(0.0, kTwoPi);
  for (int k = 0; k < 200; ++k) {
    const Vec2 e = unit_at(angle(gen));
    const LocalPair3d stick{2.0, Vec2(0.3 * mu * 2.0 * e)};
    const LocalPair3d xf_stick{-w * stick.n, Vec2(-w * stick.t)};
    const double rn = 2.0, s = 1.5;
    const LocalPair3d slip{rn, Vec2(-mu * rn * e)};
    const LocalPair3d xf_slip{-w * rn, Vec2(s * e - w * slip.t)};
    for (double rho : kRhos) {
      const LocalPair3d a = bipotential_update(stick, xf_stick, w, mu, rho);
      ASSERT_EQ(a.n, stick.n);
      ASSERT_EQ(a.t.x(), stick.t.x());
      ASSERT_EQ(a.t.y(), stick.t.y());
      const LocalPair3d b = bipotential_update(slip, xf_slip, w, mu, rho);
      ASSERT_LE(dist3(b, slip), 16 * kEps * (1.0 + mu) * (rn + rho * s)) << "rho " << rho;
      for (double m : {0.0, mu}) {
        const LocalPair3d c = bipotential_update(LocalPair3d{}, LocalPair3d{0.3, Vec2(0.7 * e)}, w, m, rho);
        ASSERT_EQ(c.n, 0.0);
        ASSERT_EQ(c.t.x(), 0.0);
        ASSERT_EQ(c.t.y(), 0.0);
      }
    }
  }
}

TEST(Bipotential3d, FixedPointSatisfiesCoulombLawAndMatchesCaseEnumeration) {
  // Random local problems: w log-uniform over 8 decades, x_free = w (a, b e) with a in [-3, 1.5]
  // (a third separate), b in [0, 3], e a random direction; mu in kMus; rho = f / w for
  // f in {0.5, 1, 1.5}; from r0 = 0 and from a random r0 in the cone. solve_local stops at
  // |dr| <= 1e-14 |r| (or, below round-off, see the loop); the iteration contracts (factor
  // <= mu^2/(1+mu^2) = 0.8 in slip at f = 1), so its error is then at most a few 1e-13 of the
  // problem's scale. Checks, to 1e-10 as the issue asks (relative
  // to R = |r| + |x_free| / w, and X = w R for x):
  // - the Coulomb law on r and x = x_free + w r: r_n >= 0, |r_t| <= mu r_n, x_n >= 0,
  //   r_n x_n = 0, r_t |x_t| + mu r_n x_t = 0 (stick: x_t = 0; slip: r_t opposite to x_t with
  //   |r_t| = mu r_n), and when clearly slipping (|x_t| > 1e-6 X) those two separately;
  // - r against coulomb_by_cases, and the status classify gives against the case;
  // - r against closed_form_reaction (the solver's own closed form).
  std::mt19937_64 gen(20101);
  std::uniform_real_distribution<double> uni(0.0, 1.0), angle(0.0, kTwoPi);
  const double tol = 1e-10;
  double worst_law = 0.0, worst_ref = 0.0, worst_closed = 0.0;
  int counts[3] = {0, 0, 0};
  int max_iterations = 0, stalled = 0;
  for (double mu : kMus) {
    for (int k = 0; k < 400; ++k) {
      const double w = std::exp((uni(gen) * 2.0 - 1.0) * 9.0);
      const LocalPair3d xf{w * (-3.0 + 4.5 * uni(gen)), Vec2(w * 3.0 * uni(gen) * unit_at(angle(gen)))};
      const CoulombSolution ref = coulomb_by_cases(xf, w, mu);
      ++counts[static_cast<int>(ref.status)];
      if (ref.status == ContactStatus::slip) {
        ASSERT_GT(ref.slip_speed, 0.0);
      }
      const double big_r = norm3(ref.r) + norm3(xf) / w, big_x = w * big_r;
      const double r0n = 2.0 * uni(gen);
      const LocalPair3d r0_random{r0n, Vec2(mu * r0n * uni(gen) * unit_at(angle(gen)))};
      for (const LocalPair3d& r0 : {LocalPair3d{}, r0_random}) {
        for (double f : {0.5, 1.0, 1.5}) {
          const LocalSolution3d s = solve_local(xf, w, mu, f / w, r0, 1e-14, 20000);
          if (s.converged) {
            max_iterations = std::max(max_iterations, s.iterations);
          } else {
            // The stopping test |dr| <= 1e-14 |r| lies below round-off when |r| << |x_free| / w
            // (a grazing contact sliding fast: r_n is the difference of two numbers ~ rho |x|),
            // and the iterates then cycle at that floor. Accepted only there: one more update
            // moves r by less than 1e-13 of the problem's scale.
            ++stalled;
            ASSERT_LE(dist3(bipotential_update(s.r, xf, w, mu, f / w), s.r), 1e-13 * big_r)
                << "mu " << mu << " f " << f << " w " << w << " xf (" << xf.n << ", " << xf.t.transpose() << ")";
          }
          const LocalPair3d& r = s.r;
          const LocalPair3d x{xf.n + w * r.n, Vec2(xf.t + w * r.t)};
          const double rt = tangential_norm(r.t), xt = tangential_norm(x.t);
          const double law[] = {
              -r.n / big_r,
              (rt - mu * r.n) / big_r,
              -x.n / big_x,
              std::abs(r.n * x.n) / (big_r * big_x),
              tangential_norm(r.t * xt + mu * r.n * x.t) / (big_r * big_x),
          };
          for (double res : law) {
            ASSERT_LE(res, tol) << "mu " << mu << " f " << f << " w " << w << " xf (" << xf.n << ", "
                                << xf.t.transpose() << ")";
            worst_law = std::max(worst_law, res);
          }
          if (xt > 1e-6 * big_x) {  // clearly slipping
            ASSERT_LE(std::abs(rt - mu * r.n), tol * big_r);
            ASSERT_LE(tangential_norm(r.t + mu * r.n * (x.t / xt)), tol * big_r);
          }
          const double err = dist3(r, ref.r) / big_r;
          ASSERT_LE(err, tol) << "mu " << mu << " f " << f << " w " << w << " xf (" << xf.n << ", "
                              << xf.t.transpose() << "): r (" << r.n << ", " << r.t.transpose()
                              << ") vs cases (" << ref.r.n << ", " << ref.r.t.transpose() << ")";
          worst_ref = std::max(worst_ref, err);
          // Status: frictionless contact with a reaction is slip (classify's rule); away from the
          // stick/slip boundary (|r_t| within 1e-9 of mu r_n) the case decides.
          const ContactStatus status = classify(r, mu);
          if (ref.status == ContactStatus::open || mu == 0.0) {
            ASSERT_EQ(status, mu == 0.0 && ref.r.n > 0.0 ? ContactStatus::slip : ref.status);
          } else if (std::abs(tangential_norm(ref.r.t) - mu * ref.r.n) > 1e-9 * big_r) {
            ASSERT_EQ(status, ref.status) << "mu " << mu << " w " << w;
          }
        }
      }
      const double err_closed = dist3(closed_form_reaction(xf, w, mu), ref.r) / big_r;
      ASSERT_LE(err_closed, 16 * kEps) << "closed form: a division and a unit vector, a few eps";
      worst_closed = std::max(worst_closed, err_closed);
    }
  }
  std::printf("[coulomb3d] local solves: open %d, stick %d, slip %d problems (x 6 solves); "
              "max Coulomb-law residual %.2e, max |r - r_cases| / R %.2e (tolerance 1e-10); "
              "closed form vs cases %.2e; at most %d iterations; %d of %d solves stopped at the "
              "round-off floor above 1e-14 |r|\n",
              counts[0], counts[1], counts[2], worst_law, worst_ref, worst_closed, max_iterations, stalled,
              6 * (counts[0] + counts[1] + counts[2]));
  EXPECT_GE(counts[static_cast<int>(ContactStatus::open)], 200);
  EXPECT_GE(counts[static_cast<int>(ContactStatus::stick)], 200);
  EXPECT_GE(counts[static_cast<int>(ContactStatus::slip)], 200);
}

TEST(Bipotential3d, FrictionlessUpdateIsExactAndZeroSlipStaysZero) {
  // mu = 0, rho = 1/w: r* = r0 - (x_free + w r0) / w = -x_free / w whatever r0, projected onto
  // the half-line: one update gives (max(0, -x_free_n / w), 0), up to the cancellation r0 - r0
  // (8 eps of |r0| + |x_free| / w), and solve_local confirms it with a second.
  // x_free_t = 0 exactly with friction: x_t stays 0, so r_t = 0 exactly (no 0/0 in the
  // modified velocity or the projection) and r_n = max(0, -x_free_n / w).
  std::mt19937_64 gen(7);
  std::uniform_real_distribution<double> uni(-3.0, 3.0);
  for (int k = 0; k < 500; ++k) {
    const double w = std::exp(uni(gen) * 3.0);
    const LocalPair3d xf{uni(gen) * w, Vec2(uni(gen) * w, uni(gen) * w)};
    const double rn_exact = std::max(0.0, -xf.n / w);
    for (const LocalPair3d& r0 : {LocalPair3d{}, LocalPair3d{std::abs(uni(gen)), Vec2(uni(gen), uni(gen))}}) {
      const LocalPair3d r1 = bipotential_update(r0, xf, w, 0.0, 1.0 / w);
      const double tol = 8 * kEps * (norm3(r0) + norm3(xf) / w);
      ASSERT_NEAR(r1.n, rn_exact, tol);
      ASSERT_EQ(r1.t.x(), 0.0);
      ASSERT_EQ(r1.t.y(), 0.0);
    }
    const LocalSolution3d s = solve_local(xf, w, 0.0, 1.0 / w, {}, 1e-14, 100);
    ASSERT_TRUE(s.converged);
    ASSERT_LE(s.iterations, 2) << "exact in one update, confirmed by the second";

    const LocalPair3d xf0{xf.n, Vec2(0.0, -0.0)};
    for (double mu : {0.0, 0.3, 2.0}) {
      for (double f : {0.5, 1.0, 1.5}) {
        const LocalSolution3d s0 = solve_local(xf0, w, mu, f / w, {}, 1e-14, 10000);
        ASSERT_TRUE(s0.converged);
        ASSERT_TRUE(std::isfinite(s0.r.n));
        ASSERT_NEAR(s0.r.n, rn_exact, 1e-13 * (rn_exact + std::abs(xf.n) / w));
        ASSERT_EQ(s0.r.t.x(), 0.0);
        ASSERT_EQ(s0.r.t.y(), 0.0);
      }
      const LocalPair3d c = closed_form_reaction(xf0, w, mu);
      ASSERT_EQ(c.n, rn_exact);
      ASSERT_EQ(c.t.x(), 0.0);
      ASSERT_EQ(c.t.y(), 0.0);
    }
  }
}

TEST(Bipotential3d, ClassifyOpenStickSlip) {
  // classify's cases (coulomb.hpp) with the tangential part along random directions, and every
  // projected slip reaction classifies as slip although its |r_t| = mu r_n is rounded.
  const double mu = 0.3;
  std::mt19937_64 gen(13);
  std::uniform_real_distribution<double> uni(-5.0, 5.0), angle(0.0, kTwoPi);
  for (int k = 0; k < 100; ++k) {
    const Vec2 e = unit_at(angle(gen));
    EXPECT_EQ(classify(LocalPair3d{0.0, Vec2::Zero()}, mu), ContactStatus::open);
    EXPECT_EQ(classify(LocalPair3d{-1.0, Vec2::Zero()}, mu), ContactStatus::open);
    EXPECT_EQ(classify(LocalPair3d{0.0, Vec2(0.1 * e)}, mu), ContactStatus::open);
    EXPECT_EQ(classify(LocalPair3d{1.0, Vec2::Zero()}, mu), ContactStatus::stick);
    EXPECT_EQ(classify(LocalPair3d{1.0, Vec2(0.29 * e)}, mu), ContactStatus::stick);
    EXPECT_EQ(classify(LocalPair3d{1.0, Vec2(0.31 * e)}, mu), ContactStatus::slip);
    EXPECT_EQ(classify(LocalPair3d{1.0, Vec2::Zero()}, 0.0), ContactStatus::slip);
  }
  int slips = 0;
  for (int k = 0; k < 20000; ++k) {
    const LocalPair3d y{uni(gen), Vec2(uni(gen), uni(gen))};
    const double yt = std::sqrt(y.t.squaredNorm());
    if ((y.n >= 0.0 && yt <= mu * y.n) || mu * yt <= -y.n) continue;
    ++slips;
    ASSERT_EQ(classify(project_coulomb(y, mu), mu), ContactStatus::slip);
  }
  EXPECT_GT(slips, 5000);
}

// ---------------------------------------------------------------------------------------------
// The 2D link: tangential data along one tangent give coulomb.hpp's numbers.

TEST(Coulomb3d, TangentialDataAlongOneTangentGiveThe2dResults) {
  // With every tangential quantity along t1 (or t2), |t| = hypot(a, 0) = |a| exactly and the
  // unit direction is exactly +-1, so the 3D functions do the 2D functions' operations in the
  // same order: agreement to round-off, 2 eps of the problem's scale (an ulp where a compiler
  // fuses a multiply-add in one code and not the other), and the other tangential component
  // exactly 0. Along a random unit direction e the 3D result is the 2D one times e (the law is
  // isotropic in the tangent plane), to 16 eps (the components of e are rounded).
  std::mt19937_64 gen(2010);
  std::uniform_real_distribution<double> uni(-3.0, 3.0), unit(0.0, 1.0), angle(0.0, kTwoPi);
  long compared = 0, bitwise = 0;
  double worst_axis = 0.0, worst_dir = 0.0, worst_dir_solve = 0.0;
  auto embed = [](const LocalPair& a, const Vec2& e) { return LocalPair3d{a.n, Vec2(a.t * e)}; };
  auto check = [&](const char* what, const LocalPair& two, const LocalPair3d& three, const Vec2& e,
                   double scale, double dir_tol_eps = 16.0) {
    const bool axis = (e.x() == 1.0 && e.y() == 0.0) || (e.x() == 0.0 && e.y() == 1.0);
    const double along = three.t.dot(e), across = e.x() * three.t.y() - e.y() * three.t.x();
    const double err = std::max(std::abs(three.n - two.n), std::abs(along - two.t));
    if (axis) {
      EXPECT_LE(err, 2 * kEps * scale) << what;
      EXPECT_EQ(across, 0.0) << what;
      bitwise += (three.n == two.n && along == two.t);
      worst_axis = std::max(worst_axis, err / (kEps * scale));
    } else {
      EXPECT_LE(std::max(err, std::abs(across)), dir_tol_eps * kEps * scale) << what;
      if (dir_tol_eps == 16.0) worst_dir = std::max(worst_dir, std::max(err, std::abs(across)) / (kEps * scale));
      else worst_dir_solve = std::max(worst_dir_solve, std::max(err, std::abs(across)) / scale);
    }
    ++compared;
  };
  for (int k = 0; k < 2000; ++k) {
    const double mu = k % 5 == 0 ? 0.0 : 2.0 * unit(gen);
    const double w = std::exp(uni(gen) * 3.0);
    const double rho = std::exp(uni(gen)) / w;
    const LocalPair r{uni(gen), uni(gen)}, x{uni(gen) * w, uni(gen) * w}, xf{uni(gen) * w, uni(gen) * w};
    const double rn0 = std::abs(uni(gen));
    const LocalPair r_cone{rn0, mu * rn0 * (2.0 * unit(gen) - 1.0)};
    const double scale_r = std::abs(r.n) + std::abs(r.t);
    const double scale_update = scale_r + rho * (1.0 + mu) * (std::abs(x.n) + std::abs(x.t));
    const double scale_solve = (std::abs(xf.n) + std::abs(xf.t)) / w * (1.0 + mu);
    for (const Vec2& e : {Vec2(1.0, 0.0), Vec2(0.0, 1.0), Vec2(unit_at(angle(gen)))}) {
      check("project", project_coulomb(r, mu), project_coulomb(embed(r, e), mu), e, scale_r);
      const LocalPair3d m = de_saxce_modified(embed(x, e), mu);
      check("modified", {x.n + mu * std::abs(x.t), x.t}, m, e, std::abs(x.n) + (1.0 + mu) * std::abs(x.t));
      check("correct", bipotential_correct(r, x, mu, rho),
            bipotential_correct(embed(r, e), embed(x, e), mu, rho), e, scale_update);
      check("update", bipotential_update(r_cone, xf, w, mu, rho),
            bipotential_update(embed(r_cone, e), embed(xf, e), w, mu, rho), e,
            rn0 * (1.0 + mu) + rho * (1.0 + mu) * (std::abs(xf.n) + std::abs(xf.t) + w * rn0 * (1.0 + mu)));
      check("closed form", closed_form_reaction(xf, w, mu), closed_form_reaction(embed(xf, e), w, mu), e,
            scale_solve);
      EXPECT_EQ(classify(embed(r, e), mu), classify(r, mu));
      // The iteration (rho = 1/w): along t1/t2 the same iterates, so the same count and the
      // same result. Along a random e the iterates differ by round-off, and either iteration may
      // stop one update earlier, where |dr| <= 1e-14 |r|: tolerance 1e-13 of the scale.
      const LocalSolution s2 = solve_local(xf, w, mu, 1.0 / w, {}, 1e-14, 10000);
      const LocalSolution3d s3 = solve_local(embed(xf, e), w, mu, 1.0 / w, {}, 1e-14, 10000);
      ASSERT_TRUE(s2.converged && s3.converged);
      check("solve_local", s2.r, s3.r, e, scale_solve, 1e-13 / kEps);
      if (e.x() == 1.0) {
        EXPECT_EQ(s3.iterations, s2.iterations);
      }
    }
  }
  std::printf("[coulomb3d] 2D link: %ld comparisons; along t1/t2 %ld bit for bit, max %.2f eps "
              "(tolerance 2); along a random e max %.2f eps (tolerance 16), solve_local %.2e "
              "(tolerance 1e-13)\n",
              compared, bitwise, worst_axis, worst_dir, worst_dir_solve);
}

// ---------------------------------------------------------------------------------------------
// ContactFrame<3>

TEST(ContactFrame3d, OrthonormalAndRightHandedEverywhere) {
  // Random unit normals (normalised Gaussian triples: uniform on the sphere), the poles
  // (0, 0, +-1) and normals approaching them from 1e-1 to 1e-300 off the axis, the equator with
  // n_z = +0 and -0. (t1, t2, n): unit lengths and dot products to 8 eps (Duff et al. 2017
  // measure a few ulps; the normalised input is itself unit only to ~1 eps), t1 x t2 = n to 8
  // eps (right-handed, the determinant +1). ContactFrame<3>::local and global are inverse to 8 eps.
  std::mt19937_64 gen(2017);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<Vec3> normals;
  for (int k = 0; k < 100000; ++k) {
    Vec3 v(normal(gen), normal(gen), normal(gen));
    normals.push_back(v.normalized());
  }
  for (double z : {1.0, -1.0}) {
    normals.push_back(Vec3(0.0, 0.0, z));
    for (double off = 1e-1; off > 1e-300; off *= 1e-3) {
      for (const Vec2& d : {Vec2(1.0, 0.0), Vec2(0.0, -1.0), Vec2(0.6, -0.8), Vec2(-0.8, -0.6)}) {
        normals.push_back(Vec3(off * d.x(), off * d.y(), z * std::sqrt(1.0 - off * off)));
      }
    }
  }
  for (double z : {0.0, -0.0}) {
    for (const Vec2& d : {Vec2(1.0, 0.0), Vec2(-1.0, 0.0), Vec2(0.0, 1.0), Vec2(0.6, -0.8)}) {
      normals.push_back(Vec3(d.x(), d.y(), z));
    }
  }
  double worst = 0.0;
  for (const Vec3& n : normals) {
    const ContactFrame<3> f(n);
    ASSERT_EQ(f.n, n);
    Eigen::Matrix3d q;
    q << f.t1, f.t2, f.n;
    const double ortho = (q.transpose() * q - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    const double hand = (f.t1.cross(f.t2) - n).cwiseAbs().maxCoeff();
    ASSERT_TRUE(q.allFinite()) << n.transpose();
    ASSERT_LE(ortho, 8 * kEps) << "n = " << n.transpose();
    ASSERT_LE(hand, 8 * kEps) << "n = " << n.transpose();
    ASSERT_GT(q.determinant(), 0.0);
    worst = std::max({worst, ortho / kEps, hand / kEps});
    const Vec3 v(1.5, -0.25, 3.0);
    ASSERT_LE((f.global(f.local(v)) - v).cwiseAbs().maxCoeff(), 8 * kEps * 3.0);
    const LocalPair3d ln = f.local(n);
    ASSERT_NEAR(ln.n, 1.0, 8 * kEps);
    ASSERT_LE(ln.t.cwiseAbs().maxCoeff(), 8 * kEps);
  }
  std::printf("[coulomb3d] frame: %zu normals, max orthonormality / handedness error %.2f eps (tolerance 8)\n",
              normals.size(), worst);
  // The poles themselves, exactly: (0, 0, 1) -> t1 = x, t2 = y; (0, 0, -1) -> t1 = x, t2 = -y.
  const ContactFrame<3> up(Vec3(0.0, 0.0, 1.0)), down(Vec3(0.0, 0.0, -1.0));
  EXPECT_EQ(up.t1, Vec3(1.0, 0.0, 0.0));
  EXPECT_EQ(up.t2, Vec3(0.0, 1.0, 0.0));
  EXPECT_EQ(down.t1, Vec3(1.0, 0.0, 0.0));
  EXPECT_EQ(down.t2, Vec3(0.0, -1.0, 0.0));
}

// ---------------------------------------------------------------------------------------------
// No heap allocation

TEST(Coulomb3d, LocalSolveAndFrameDoNotAllocate) {
  // The functions run inside the contact sweep of every step; fixed-size Eigen types only. The
  // counter (alloc_counter.hpp) is first seen to count, so that a zero proves something.
  long before = g_allocations.load();
  {
    std::vector<double> probe(64, 1.0);
    asm volatile("" : : "g"(probe.data()) : "memory");
  }
  ASSERT_GE(g_allocations.load() - before, 1) << "the counter counts";

  std::mt19937_64 gen(1);
  std::uniform_real_distribution<double> uni(-3.0, 3.0);
  std::vector<LocalPair3d> inputs(512);
  std::vector<Vec3> normals(512);
  for (auto& y : inputs) y = {uni(gen), Vec2(uni(gen), uni(gen))};
  for (auto& n : normals) n = Vec3(uni(gen), uni(gen), uni(gen)).normalized();
  double sink = 0.0;
  before = g_allocations.load();
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    const LocalPair3d& y = inputs[k];
    const LocalPair3d p = project_coulomb(y, 0.3);
    const LocalSolution3d s = solve_local(y, 0.5, 0.3, 2.0, {}, 1e-14, 1000);
    const ContactFrame<3> f(normals[k]);
    const Vec3 g = f.global(s.r);
    sink += p.n + s.r.n + g.x() + f.local(g).t.y() + closed_form_reaction(y, 0.5, 0.3).n +
            static_cast<double>(classify(p, 0.3));
  }
  const long allocations = g_allocations.load() - before;
  EXPECT_EQ(allocations, 0);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace ricochet
