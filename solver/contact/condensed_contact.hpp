// The implicit scheme's contact problem in condensed form (docs/implicit.md, Contact): the
// reactions R of the active contacts such that x = x_free + W R, W = c dt H A^-1 H^T, and each
// contact's local x and r obey Coulomb's law through the bi-potential (Cros, Feng & Magnain 2010,
// Eq. (5)). H maps nodal vectors to the contacts' frames (their stencils, contact_set.hpp), A is
// the scheme's iteration matrix, c its level factor (dt theta at the position level, 1 at the
// velocity level). The scheme sets each active contact's x_free and diagonal compliance estimate
// w (set_local); this class solves for R given a solve of A y = b: by Uzawa sweeps (uzawa(), one
// solve per sweep, fast when A is mass-dominated), or with W built column by column and
// Gauss-Seidel over the contacts, each local problem on its block W_kk by solve_local_map
// (exact()). Then impulse() = H^T R and response() = A^-1 (dt H^T R). Sized once (reserve);
// nothing allocates in a solve.
#pragma once

#include <algorithm>
#include <vector>

#include <Eigen/Dense>

#include "solver/contact/contact_set.hpp"
#include "solver/contact/contact_space.hpp"

namespace ricochet {

// Component d of a contact's local vector: 0 the normal, 1 (and 2 in 3D) the tangential ones,
// in the order of its frame's directions (n, t) or (n, t1, t2).
inline double component(const LocalPair& r, int d) { return d == 0 ? r.n : r.t; }
inline double component(const LocalPair3d& r, int d) { return d == 0 ? r.n : r.t[d - 1]; }
inline void set_component(LocalPair& r, int d, double x) { (d == 0 ? r.n : r.t) = x; }
inline void set_component(LocalPair3d& r, int d, double x) { (d == 0 ? r.n : r.t[d - 1]) = x; }
// Direction d of the frame of normal n: n, t (2D), or n, t1, t2 (3D).
inline Vec2 frame_direction(const ContactFrame<2>& f, int d) { return d == 0 ? f.n : f.t; }
inline Vec3 frame_direction(const ContactFrame<3>& f, int d) { return d == 0 ? f.n : d == 1 ? f.t1 : f.t2; }

template <int N>
bool same_stencil(const StencilN<N>& a, const StencilN<N>& b) {
  if (a.count != b.count) return false;
  for (int j = 0; j < a.count; ++j)
    if (a.node[j] != b.node[j] || a.coef[j] != b.coef[j]) return false;
  return true;
}

template <int D>
class CondensedContact {
 public:
  using Vec = VecD<D>;
  using Local = typename Space<D>::Local;
  using Stencil = typename Space<D>::Stencil;

  // Inside an exact() sweep, a contact's local problem (its block W_kk is anisotropic in
  // friction) is solved to kLocalTolerance times the sweep's tolerance, so that what is left of
  // it is not taken for a change between sweeps, in at most kLocalMaxUpdates updates (an
  // unfinished one goes on in the next sweep, from where it stopped). Our choice: Cros, Feng &
  // Magnain (2010) do not say how the implicit scheme's local problems are solved
  // (docs/implicit.md).
  static constexpr double kLocalTolerance = 1e-3;
  static constexpr int kLocalMaxUpdates = 200;

  // For the candidates of `cs` on `num_dofs` DOFs: with friction each contact has D directions,
  // without only its normal.
  void reserve(const ContactSetT<D>& cs, int num_dofs) {
    const int candidates = static_cast<int>(cs.candidates.size());
    dirs_ = cs.any_friction ? D : 1;
    const int slots = dirs_ * candidates;
    x_free_.assign(candidates, Local{});
    weight_.assign(candidates, 0.0);
    columns_.resize(num_dofs, slots);
    column_factor_.assign(slots, -1);
    column_direction_.assign(slots, Vec::Zero());
    column_stencil_.assign(slots, Stencil{});
    active_columns_.reserve(slots);
    w_.resize(slots, slots);
    r_vec_.resize(slots);
    for (Eigen::VectorXd* v : {&impulse_, &y_, &rhs_}) v->setZero(num_dofs);
  }

  // Candidate k's local problem for this iterate: x = x_free + w r (w: the diagonal estimate of
  // its local compliance, the Uzawa step's scale).
  void set_local(int k, const Local& x_free, double w) {
    x_free_[k] = x_free;
    weight_[k] = w;
  }

  // impulse = H^T R over every candidate (the last step's reactions, in the frames and on the
  // stencils they were solved in), or over the active ones.
  void impulse_of_all(const ContactSetT<D>& cs) {
    impulse_.setZero();
    for (int k = 0; k < static_cast<int>(cs.candidates.size()); ++k) add_impulse(cs, k);
  }
  void impulse_of_active(const ContactSetT<D>& cs) {
    impulse_.setZero();
    for (const int k : cs.active) add_impulse(cs, k);
  }
  // No active contact: R = 0.
  void clear() {
    impulse_.setZero();
    y_.setZero();
    sweeps_ = 0;
  }

  // Uzawa sweeps, at most max_sweeps: x(R) exact through one solve of A per sweep,
  // rho = omega / w; omega halves whenever the largest reaction change grows. True when the
  // reactions converged (|dR| <= tol |R|) and the last solve succeeded.
  template <class Solve>
  bool uzawa(ContactSetT<D>& cs, double c, double dt, int max_sweeps, double tol, const Solve& solve) {
    double omega = 1.0, last_change = 1e300;
    for (sweeps_ = 1; sweeps_ <= max_sweeps; ++sweeps_) {
      impulse_of_active(cs);
      rhs_ = dt * impulse_;
      if (!solve(rhs_, y_)) return false;
      double change = 0.0, size = 0.0;
      for (int k : cs.active) {
        const Local hy = stencil_dot(cs, k, y_);
        const Local x{x_free_[k].n + c * hy.n, decltype(Local::t)(x_free_[k].t + c * hy.t)};
        Local& r = cs.reaction[k];
        const Local next = bipotential_correct(r, x, cs.candidates[k].friction_coeff, omega / weight_[k]);
        change = std::max(change, local_distance(next, r));
        size = std::max(size, local_norm(next));
        r = next;
      }
      if (change <= tol * size || change == 0.0) {
        impulse_of_active(cs);
        rhs_ = dt * impulse_;
        return solve(rhs_, y_);
      }
      if (change > last_change) omega *= 0.5;
      last_change = change;
    }
    return false;
  }

  // The exact W and Gauss-Seidel, at most max_sweeps. `factor_id`: the identity of the factor
  // solve() uses (columns computed with it are reused), or -1 when solve() has no fixed factor
  // (CG). False only when a linear solve fails; whether Gauss-Seidel converged is converged().
  template <class Solve>
  bool exact(ContactSetT<D>& cs, double c, double dt, int max_sweeps, double tol, const Solve& solve, long factor_id) {
    const int m = dirs_ * static_cast<int>(cs.active.size());
    ++exact_solves_;
    converged_ = false;
    if (!compute_columns(cs, m, solve, factor_id)) return false;
    for (int a = 0; a < m; ++a) {
      const Stencil& st = cs.stencil[cs.active[a / dirs_]];
      const Vec d = direction(cs, a);
      for (int b = 0; b < m; ++b) {
        double h = 0.0;
        for (int j = 0; j < st.count; ++j)
          h += st.coef[j] * d.dot(columns_.col(active_columns_[b]).template segment<D>(D * st.node[j]));
        w_(a, b) = c * dt * h;
      }
    }
    for (sweeps_ = 1; sweeps_ <= max_sweeps; ++sweeps_) {
      double change = 0.0, size = 0.0;
      for (int i = 0; i < static_cast<int>(cs.active.size()); ++i) {
        Local& r = cs.reaction[cs.active[i]];
        const Local next = local_reaction(cs, i, tol);
        change = std::max(change, local_distance(next, r));
        size = std::max(size, local_norm(next));
        r = next;
      }
      if (change <= tol * size || change == 0.0) {
        converged_ = true;
        break;
      }
    }
    sweeps_ = std::min(sweeps_, max_sweeps);
    for (int a = 0; a < m; ++a) r_vec_[a] = dt * component(cs.reaction[cs.active[a / dirs_]], a % dirs_);
    y_.setZero();
    for (int a = 0; a < m; ++a) y_.noalias() += r_vec_[a] * columns_.col(active_columns_[a]);
    impulse_of_active(cs);
    return true;
  }

  const Eigen::VectorXd& impulse() const { return impulse_; }  // H^T R [N]
  const Eigen::VectorXd& response() const { return y_; }       // A^-1 (dt H^T R)
  int sweeps() const { return sweeps_; }                        // of the last solve
  bool converged() const { return converged_; }                 // the last exact() met its tolerance
  long exact_solves() const { return exact_solves_; }

 private:
  // impulse += H_k^T R_k: contact k's reaction in its frame, spread over its stencil.
  void add_impulse(const ContactSetT<D>& cs, int k) {
    const Vec r = ContactFrame<D>(cs.normal[k]).global(cs.reaction[k]);
    const Stencil& st = cs.stencil[k];
    for (int j = 0; j < st.count; ++j) impulse_.template segment<D>(D * st.node[j]) += st.coef[j] * r;
  }

  // (n . y, t . y) of a contact's stencil: sum_j coef_j y_j projected on its frame.
  static Local stencil_dot(const ContactSetT<D>& cs, int k, const Eigen::VectorXd& y) {
    const Stencil& st = cs.stencil[k];
    Vec sum = Vec::Zero();
    for (int j = 0; j < st.count; ++j) sum += st.coef[j] * y.template segment<D>(D * st.node[j]);
    return ContactFrame<D>(cs.normal[k]).local(sum);
  }

  // Active direction a: direction a % dirs of contact a / dirs's frame.
  Vec direction(const ContactSetT<D>& cs, int a) const {
    return frame_direction(ContactFrame<D>(cs.normal[cs.active[a / dirs_]]), a % dirs_);
  }

  // A^-1 H^T e per active contact direction e into its column (slot dirs k + d of candidate k).
  template <class Solve>
  bool compute_columns(const ContactSetT<D>& cs, int m, const Solve& solve, long factor_id) {
    active_columns_.clear();
    for (int a = 0; a < m; ++a) {
      const int slot = dirs_ * cs.active[a / dirs_] + a % dirs_;
      active_columns_.push_back(slot);
      const Stencil& st = cs.stencil[cs.active[a / dirs_]];
      const Vec d = direction(cs, a);
      if (factor_id >= 0 && column_factor_[slot] == factor_id && column_direction_[slot] == d &&
          same_stencil(column_stencil_[slot], st))
        continue;
      rhs_.setZero();
      for (int j = 0; j < st.count; ++j) rhs_.template segment<D>(D * st.node[j]) += st.coef[j] * d;
      y_.setZero();
      if (!solve(rhs_, y_)) return false;
      columns_.col(slot) = y_;
      column_factor_[slot] = factor_id;
      column_direction_[slot] = d;
      column_stencil_[slot] = st;
    }
    return true;
  }

  // Active contact i's reaction for one Gauss-Seidel sweep: x = x_base + W_ii r, with x_base =
  // x_free + the other contacts' share (row d of W: the contact's direction d, in its frame's
  // order). Without friction the closed form r_n = max(0, -x_base_n / W_ii); with friction the
  // bi-potential iteration with rho = 1 / max diag(W_ii).
  Local local_reaction(const ContactSetT<D>& cs, int i, double tol) const {
    const int k = cs.active[i];
    const int dirs = dirs_;  // a local: the compiler keeps it in a register across the stores
    Local base = x_free_[k];
    for (int j = 0; j < static_cast<int>(cs.active.size()); ++j) {
      if (j == i) continue;
      const Local rj = cs.reaction[cs.active[j]];
      for (int d = 0; d < dirs; ++d) {
        double sum = w_(dirs * i + d, dirs * j) * rj.n;
        for (int e = 1; e < dirs; ++e) sum += w_(dirs * i + d, dirs * j + e) * component(rj, e);
        set_component(base, d, component(base, d) + sum);
      }
    }
    Local next{};
    if (dirs == 1) {
      next.n = std::max(0.0, -base.n / w_(i, i));
      return next;
    }
    double w_max = w_(dirs * i, dirs * i);
    for (int d = 1; d < dirs; ++d) w_max = std::max(w_max, w_(dirs * i + d, dirs * i + d));
    auto x_of = [&](const Local& q) {
      Local x = base;
      for (int d = 0; d < dirs; ++d) {
        double xd = component(base, d);
        for (int e = 0; e < dirs; ++e) xd += w_(dirs * i + d, dirs * i + e) * component(q, e);
        set_component(x, d, xd);
      }
      return x;
    };
    return solve_local_map(x_of, cs.candidates[k].friction_coeff, 1.0 / w_max, cs.reaction[k],
                           kLocalTolerance * tol, kLocalMaxUpdates)
        .r;
  }

  int dirs_ = 1;
  std::vector<Local> x_free_;
  std::vector<double> weight_;
  // A^-1 H^T e per candidate k and direction d in column dirs k + d; on the direct path a column
  // is reused while the factor, the candidate's stencil and its direction are those it was
  // computed with.
  Eigen::MatrixXd columns_;
  std::vector<long> column_factor_;  // factor_id of each column, -1: none
  std::vector<Vec, Eigen::aligned_allocator<Vec>> column_direction_;
  std::vector<Stencil> column_stencil_;
  std::vector<int> active_columns_;  // column of each active contact direction
  Eigen::MatrixXd w_;                // condensed compliance (m x m)
  Eigen::VectorXd r_vec_;            // dt R per active contact direction
  Eigen::VectorXd impulse_, y_, rhs_;
  int sweeps_ = 0;
  bool converged_ = true;
  long exact_solves_ = 0;
};

}  // namespace ricochet
