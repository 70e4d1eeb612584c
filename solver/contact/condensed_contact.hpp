// The implicit scheme's contact problem in condensed form (docs/implicit.md, Contact): the
// reactions R of the active contacts such that x = x_free + W R, W = c dt H A^-1 H^T, and each
// contact's local x and r obey Coulomb's law through the bi-potential (Cros, Feng & Magnain 2010,
// Eq. (5)). H maps nodal vectors to the contacts' frames (their stencils, contact_set.hpp), A is
// the scheme's iteration matrix, c its level factor (dt theta at the position level, 1 at the
// velocity level). The scheme sets each active contact's x_free and diagonal compliance estimate
// w (set_local); this class solves for R given a solve of A y = b: by Uzawa sweeps (uzawa(), one
// solve per sweep, fast when A is mass-dominated), or with W built exactly and Gauss-Seidel over
// the contacts, each local problem on its block W_kk by solve_local_map (exact()). Then
// impulse() = H^T R and response() = A^-1 (dt H^T R). Sized once (reserve); nothing allocates
// in a solve.
//
// W from the nodes' compliance (exact()): a contact direction d on a stencil is H = sum_j coef_j
// e_(node j) d^T, so every entry of W is made of the blocks u^T E_p^T A^-1 E_q v between the
// nodes p, q of the active stencils (E_p: node p's D unit vectors) along the directions u, v
// asked of them. Each node keeps an orthonormal basis: the first direction asked of it alone (a
// frictionless contact along a fixed normal needs no more), completed to all D directions once
// another is asked; G holds A^-1 between all the kept (node, basis vector) pairs. A basis
// vector costs one column A^-1 E_p u, which also gives its entries of G with every kept pair;
// the new columns of one exact() call are solved together, up to four per sweep over the factor.
// G stays valid while the factor does, so a contact whose direction, stencil or activity
// changes costs no solve when its nodes already know the directions. Memory: G over
// (D x the nodes that can be in a stencil)^2 and W over the active directions; no dense
// n x contacts storage. The response A^-1 dt H^T R is the sum of the columns it needs when they
// are kept (a pool of columns as large as the integrator allows, by default the factor's
// nonzeros per row), else one more solve.
#pragma once

#include <algorithm>
#include <array>
#include <tuple>
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
  // without only its normal. The nodes a stencil can hold are the candidates' nodes and the
  // master surfaces' nodes.
  // pool_columns: how many columns A^-1 E_p u to keep for the response (n x pool_columns
  // doubles; the integrator sizes it like the factor's own storage).
  void reserve(const ContactSetT<D>& cs, int num_dofs, int pool_columns) {
    const int candidates = static_cast<int>(cs.candidates.size());
    dirs_ = cs.any_friction ? D : 1;
    const int slots = dirs_ * candidates;
    x_free_.assign(candidates, Local{});
    weight_.assign(candidates, 0.0);
    active_directions_.reserve(slots);
    w_.resize(slots, slots);
    node_cache_.assign(num_dofs / D, -1);
    std::vector<unsigned char> contact_node(num_dofs / D, 0);
    for (const ContactCandidate& cc : cs.candidates) contact_node[cc.node] = 1;
    for (const auto& surface : cs.surfaces)
      for (int j : surface.nodes) contact_node[j] = 1;
    const int capacity = static_cast<int>(std::count(contact_node.begin(), contact_node.end(), 1));
    cached_nodes_.reserve(capacity);
    basis_.resize(capacity);
    rank_.assign(capacity, 0);
    pending_.reserve(D * capacity);
    g_.resize(D * capacity, D * capacity);
    pool_.setZero(num_dofs, std::min(pool_columns, D * capacity));
    pool_index_.assign(D * capacity, -1);
    slot_weight_.assign(D * capacity, 0.0);
    touched_.reserve(D * capacity);
    touched_flag_.assign(D * capacity, 0);
    unit_.setZero(num_dofs, kMaxBlock);
    unit_response_.setZero(num_dofs, kMaxBlock);
    for (Eigen::VectorXd* v : {&impulse_, &y_, &rhs_}) v->setZero(num_dofs);
    impulse_mark_.assign(num_dofs / D, 0);
    impulse_nodes_.reserve(num_dofs / D);
    y_nodes_.reserve(num_dofs / D);
    y_dense_ = false;
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
    zero_impulse();
    for (int k = 0; k < static_cast<int>(cs.candidates.size()); ++k) add_impulse(cs, k);
  }
  void impulse_of_active(const ContactSetT<D>& cs) {
    zero_impulse();
    for (const int k : cs.active) add_impulse(cs, k);
  }
  // No active contact: R = 0.
  void clear() {
    zero_impulse();
    zero_response();
    sweeps_ = 0;
  }
  // x += response(), over the nodes it is not zero at when A is diagonal (exact()'s
  // diagonal_inverse).
  void add_response(Eigen::VectorXd& x) const {
    if (y_dense_) {
      x += y_;
      return;
    }
    for (int j : y_nodes_) x.template segment<D>(D * j) += y_.template segment<D>(D * j);
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
      y_dense_ = true;
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

  // The exact W and Gauss-Seidel, at most max_sweeps. `solve_block(b, x, ncol)`: x = A^-1 b for
  // ncol (1 to 4) columns. `factor_id`: the identity of the factor the solves use (G computed with
  // it is reused), or -1 when they have no fixed factor (CG: G is computed anew).
  // `diagonal_inverse`: A is diagonal (the mass iteration's M) and this is 1 / its entries; the
  // response is then the impulse's nodes' entries alone, (dt H^T R) / A, the same numbers as a
  // solve, without a pass over every DOF. False only when a linear solve fails; whether
  // Gauss-Seidel converged is converged().
  template <class Solve, class SolveBlock>
  bool exact(ContactSetT<D>& cs, double c, double dt, int max_sweeps, double tol, const Solve& solve,
             const SolveBlock& solve_block, long factor_id, const Eigen::VectorXd* diagonal_inverse = nullptr) {
    const int m = dirs_ * static_cast<int>(cs.active.size());
    ++exact_solves_;
    converged_ = false;
    if (factor_id < 0 || factor_id != cache_factor_) forget_nodes(factor_id);
    pending_.clear();
    active_directions_.clear();
    for (int a = 0; a < m; ++a) {
      active_directions_.push_back(direction(cs, a));
      const Stencil& st = cs.stencil[cs.active[a / dirs_]];
      for (int j = 0; j < st.count; ++j) ask(st.node[j], active_directions_[a]);
    }
    if (!solve_pending(solve_block)) return false;
    // W(a, b) = c dt sum_i sum_j coef_i coef_j (d_a . u) (d_b . v) G(u of node i, v of node j).
    const double cdt = c * dt;
    for (int a = 0; a < m; ++a) {
      const Stencil& sa = cs.stencil[cs.active[a / dirs_]];
      for (int i = 0; i < sa.count; ++i) coord_a_[i] = coords(sa.node[i], active_directions_[a]);
      for (int b = 0; b <= a; ++b) {
        const Stencil& sb = cs.stencil[cs.active[b / dirs_]];
        double h = 0.0;
        for (int j = 0; j < sb.count; ++j) {
          const int q = sb.node[j];
          const int bq = D * node_cache_[q];
          const Vec cb = coords(q, active_directions_[b]);
          for (int i = 0; i < sa.count; ++i) {
            const int bp = D * node_cache_[sa.node[i]];
            double e = 0.0;
            for (int x = 0; x < rank_[node_cache_[sa.node[i]]]; ++x)
              for (int y = 0; y < rank_[node_cache_[q]]; ++y) e += coord_a_[i][x] * g_(bp + x, bq + y) * cb[y];
            h += sa.coef[i] * sb.coef[j] * e;
          }
        }
        w_(a, b) = w_(b, a) = cdt * h;
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
    impulse_of_active(cs);
    if (diagonal_inverse) {
      zero_response();
      y_nodes_.assign(impulse_nodes_.begin(), impulse_nodes_.end());
      for (int j : y_nodes_)
        for (int x = 0; x < D; ++x) y_[D * j + x] = (dt * impulse_[D * j + x]) * (*diagonal_inverse)[D * j + x];
      return true;
    }
    if (response_from_pool(cs, dt)) return true;
    rhs_ = dt * impulse_;
    y_.setZero();
    y_dense_ = true;
    return solve(rhs_, y_);
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
    for (int j = 0; j < st.count; ++j) {
      const int node = st.node[j];
      impulse_.template segment<D>(D * node) += st.coef[j] * r;
      if (!impulse_mark_[node]) {
        impulse_mark_[node] = 1;
        impulse_nodes_.push_back(node);
      }
    }
  }
  // The impulse and the response back to zero, over the entries that were set.
  void zero_impulse() {
    for (int j : impulse_nodes_) {
      impulse_.template segment<D>(D * j).setZero();
      impulse_mark_[j] = 0;
    }
    impulse_nodes_.clear();
  }
  void zero_response() {
    if (y_dense_) {
      y_.setZero();
      y_dense_ = false;
    } else {
      for (int j : y_nodes_) y_.template segment<D>(D * j).setZero();
    }
    y_nodes_.clear();
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

  // G is emptied: a new factor (or none, on the CG path) makes every entry stale.
  void forget_nodes(long factor_id) {
    for (int node : cached_nodes_) {
      const int cp = node_cache_[node];
      for (int x = 0; x < D; ++x) pool_index_[D * cp + x] = -1;
      node_cache_[node] = -1;
    }
    cached_nodes_.clear();
    pool_used_ = 0;
    cache_factor_ = factor_id;
  }

  // The response y = A^-1 dt H^T R as the sum of the kept columns, sum_s w_s A^-1 E_p u_s with
  // w_s = dt sum over the active directions a and their stencil nodes j of r_a coef_j (u_s . d_a),
  // when every column it needs is in the pool (n x m flops instead of a solve); false otherwise.
  bool response_from_pool(const ContactSetT<D>& cs, double dt) {
    touched_.clear();
    const int m = static_cast<int>(active_directions_.size());
    for (int a = 0; a < m; ++a) {
      const int k = cs.active[a / dirs_];
      const double r = dt * component(cs.reaction[k], a % dirs_);
      if (r == 0.0) continue;
      const Stencil& st = cs.stencil[k];
      for (int j = 0; j < st.count; ++j) {
        const int cp = node_cache_[st.node[j]];
        for (int x = 0; x < rank_[cp]; ++x) {
          const int slot = D * cp + x;
          if (pool_index_[slot] < 0) {
            for (int t : touched_) {
              slot_weight_[t] = 0.0;
              touched_flag_[t] = 0;
            }
            return false;
          }
          if (!touched_flag_[slot]) {
            touched_flag_[slot] = 1;
            touched_.push_back(slot);
          }
          slot_weight_[slot] += r * st.coef[j] * basis_[cp].col(x).dot(active_directions_[a]);
        }
      }
    }
    y_.setZero();
    y_dense_ = true;
    for (int slot : touched_) {
      y_.noalias() += slot_weight_[slot] * pool_.col(pool_index_[slot]);
      slot_weight_[slot] = 0.0;
      touched_flag_[slot] = 0;
    }
    return true;
  }

  // d's coordinates in node p's basis (the first rank entries; the others 0).
  Vec coords(int p, const Vec& d) const { return basis_[node_cache_[p]].transpose() * d; }

  // Node p is asked for direction d (a unit vector). Its basis is either d alone (rank 1: a
  // frictionless contact along a fixed normal needs no more) or, once a direction not parallel
  // to it to round-off is asked, completed to an orthonormal basis of all D directions; the new
  // vectors wait in pending_ for their columns A^-1 E_p u.
  void ask(int p, const Vec& d) {
    int cp = node_cache_[p];
    if (cp < 0) {
      cp = static_cast<int>(cached_nodes_.size());
      node_cache_[p] = cp;
      cached_nodes_.push_back(p);
      basis_[cp].setZero();
      basis_[cp].col(0) = d.normalized();
      rank_[cp] = 1;
      pending_.push_back(D * cp);
      return;
    }
    if (rank_[cp] == D) return;
    const Vec b0 = basis_[cp].col(0);
    Vec u = d - b0.dot(d) * b0;
    u -= b0.dot(u) * b0;  // twice, for orthogonality to round-off
    if (!(u.norm() > kParallelTolerance * d.norm())) return;
    if constexpr (D == 2) {
      basis_[cp].col(1) = Vec(-b0.y(), b0.x());
    } else {
      const Vec b1 = u.normalized();
      basis_[cp].col(1) = b1;
      basis_[cp].col(2) = b0.cross(b1);
    }
    rank_[cp] = D;
    for (int k = 1; k < D; ++k) pending_.push_back(D * cp + k);
  }

  // The columns of the pending basis vectors, up to kMaxBlock per solve, and their entries of G
  // with every kept (node, basis vector) pair: G(t, s) = u_t . (A^-1 E_p u_s) at t's node, and
  // G(s, t) the same (A is symmetric).
  template <class SolveBlock>
  bool solve_pending(const SolveBlock& solve_block) {
    for (std::size_t first = 0; first < pending_.size(); first += kMaxBlock) {
      const int ncol = static_cast<int>(std::min<std::size_t>(kMaxBlock, pending_.size() - first));
      for (int k = 0; k < ncol; ++k) {
        const int s = pending_[first + k];
        unit_.col(k).setZero();
        unit_.col(k).template segment<D>(D * cached_nodes_[s / D]) = basis_[s / D].col(s % D);
      }
      if (!solve_block(unit_.data(), unit_response_.data(), ncol)) return false;
      for (int k = 0; k < ncol; ++k) {
        const int s = pending_[first + k];
        const auto column = unit_response_.col(k);
        if (pool_used_ < pool_.cols()) {
          pool_index_[s] = pool_used_;
          pool_.col(pool_used_++) = column;
        }
        for (int cq = 0; cq < static_cast<int>(cached_nodes_.size()); ++cq) {
          const Vec yq = column.template segment<D>(D * cached_nodes_[cq]);
          for (int y = 0; y < rank_[cq]; ++y) {
            const int t = D * cq + y;
            g_(t, s) = g_(s, t) = basis_[cq].col(y).dot(yq);
          }
        }
      }
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
  std::vector<Vec, Eigen::aligned_allocator<Vec>> active_directions_;  // per active direction
  Eigen::MatrixXd w_;  // condensed compliance (m x m)
  // G: node_cache_[p] is node p's index in the cache (-1: not kept with this factor);
  // cached_nodes_ the kept nodes in that order; basis_[i] the orthonormal directions of kept node
  // i (its first rank_[i] columns); G(D i + x, D j + y) = u_ix^T E_(node i)^T A^-1 E_(node j) u_jy.
  static constexpr double kParallelTolerance = 1e-13;  // |d - (d.b) b| below this x |d|: d is b
  static constexpr int kMaxBlock = 4;             // columns per solve
  std::vector<int> node_cache_;
  std::vector<int> cached_nodes_;
  std::vector<Eigen::Matrix<double, D, D>, Eigen::aligned_allocator<Eigen::Matrix<double, D, D>>> basis_;
  std::vector<int> rank_;
  std::vector<int> pending_;  // G indices D i + x waiting for their column
  long cache_factor_ = -1;
  Eigen::MatrixXd g_;
  Eigen::Matrix<double, Eigen::Dynamic, kMaxBlock> unit_, unit_response_;  // E_p u and A^-1 E_p u
  // The columns A^-1 E_p u kept for the response (response_from_pool): pool_index_[D i + x] its
  // column in pool_ (-1: none); the pool's width is reserve()'s pool_columns.
  Eigen::MatrixXd pool_;
  std::vector<int> pool_index_;
  int pool_used_ = 0;
  std::vector<double> slot_weight_;  // w_s of response_from_pool, 0 outside it
  std::vector<int> touched_;
  std::vector<unsigned char> touched_flag_;
  std::array<Vec, std::tuple_size_v<decltype(Stencil::node)>> coord_a_;  // row contact's coordinates per stencil node
  Eigen::VectorXd impulse_, y_, rhs_;
  // The nodes impulse_ is not zero at (marked in impulse_mark_), so that it is emptied without a
  // pass over every DOF; y_dense_: y_ came from a solve or the pool (else it is zero outside
  // y_nodes_: the diagonal response).
  std::vector<unsigned char> impulse_mark_;
  std::vector<int> impulse_nodes_;
  std::vector<int> y_nodes_;  // the nodes the diagonal response is not zero at
  bool y_dense_ = false;
  int sweeps_ = 0;
  bool converged_ = true;
  long exact_solves_ = 0;
};

}  // namespace ricochet
