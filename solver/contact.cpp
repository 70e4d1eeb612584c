#include "solver/contact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace ricochet {

Obstacle make_line_obstacle(std::string name, const Vec2& point, const Vec2& normal) {
  Obstacle ob;
  ob.name = std::move(name);
  ob.kind = ObstacleKind::line;
  ob.point = point;
  ob.normal = normal.norm() > 0.0 ? Vec2(normal.normalized()) : normal;
  if (const std::string e = obstacle_error(ob); !e.empty()) throw std::invalid_argument(e);
  return ob;
}

Obstacle make_circle_obstacle(std::string name, const Vec2& center, double radius, bool inside) {
  Obstacle ob;
  ob.name = std::move(name);
  ob.kind = ObstacleKind::circle;
  ob.center = center;
  ob.radius = radius;
  ob.inside = inside;
  if (const std::string e = obstacle_error(ob); !e.empty()) throw std::invalid_argument(e);
  return ob;
}

Obstacle make_polyline_obstacle(std::string name, std::vector<Vec2, Eigen::aligned_allocator<Vec2>> points,
                                bool left) {
  Obstacle ob;
  ob.name = std::move(name);
  ob.kind = ObstacleKind::polyline;
  ob.points = std::move(points);
  ob.left = left;
  if (const std::string e = obstacle_error(ob); !e.empty()) throw std::invalid_argument(e);
  return ob;
}

std::string obstacle_error(const Obstacle& ob) {
  const std::string who = "obstacle \"" + ob.name + "\": ";
  switch (ob.kind) {
    case ObstacleKind::line:
      if (!ob.point.allFinite()) return who + "point must be finite";
      if (!ob.normal.allFinite() || !(std::abs(ob.normal.norm() - 1.0) <= 1e-12))
        return who + "normal must be a finite unit vector";
      return {};
    case ObstacleKind::circle:
      if (!ob.center.allFinite()) return who + "center must be finite";
      if (!(ob.radius > 0.0) || !std::isfinite(ob.radius)) return who + "radius must be finite and > 0";
      return {};
    case ObstacleKind::polyline:
      if (ob.points.size() < 2) return who + "a polyline needs at least 2 points";
      for (std::size_t j = 0; j < ob.points.size(); ++j) {
        if (!ob.points[j].allFinite()) return who + "point " + std::to_string(j) + " is not finite";
        if (j > 0 && !((ob.points[j] - ob.points[j - 1]).norm() > 0.0))
          return who + "segment " + std::to_string(j - 1) + " (points " + std::to_string(j - 1) + " and " +
                 std::to_string(j) + ") has zero length";
      }
      return {};
  }
  return who + "unknown kind";
}

ObstacleContact closest_circle(const Obstacle& ob, const Vec2& x) {
  const Vec2 r = x - ob.center;
  const double d = r.norm();
  const double sign = ob.inside ? -1.0 : 1.0;
  const Vec2 radial = d > 0.0 ? Vec2(r / d) : Vec2(Vec2::UnitY());
  return {sign * (d - ob.radius), sign * radial};
}

ObstacleContact closest_polyline(const Obstacle& ob, const Vec2& x) {
  const auto& p = ob.points;
  const int segments = static_cast<int>(p.size()) - 1;
  const double side = ob.left ? 1.0 : -1.0;
  auto seg_normal = [&](int j) -> Vec2 {
    const Vec2 e = (p[j + 1] - p[j]).normalized();
    return side * Vec2(-e.y(), e.x());  // left: direction rotated by +90 degrees
  };
  // Nearest feature: per segment, the projection parameter clamped to [0, 1] (not clamped at
  // the free ends of the end segments, which extend as rays).
  double best = std::numeric_limits<double>::infinity();
  double scale = 0.0;
  for (int j = 0; j < segments; ++j) scale = std::max(scale, (p[j + 1] - p[j]).norm());
  // First pass: nearest distance.
  auto feature = [&](int j, int& vertex) -> double {
    const Vec2 e = p[j + 1] - p[j];
    const double s = (x - p[j]).dot(e) / e.squaredNorm();
    vertex = -1;
    if (s <= 0.0 && j > 0) vertex = j;
    else if (s >= 1.0 && j < segments - 1) vertex = j + 1;
    if (vertex >= 0) return (x - p[vertex]).norm();
    return std::abs(seg_normal(j).dot(x - p[j]));
  };
  int first = -1, first_vertex = -1;
  for (int j = 0; j < segments; ++j) {
    int v;
    const double d = feature(j, v);
    if (d < best) {
      best = d;
      first = j;
      first_vertex = v;
    }
  }
  // Signed gap and normal of one feature.
  auto signed_feature = [&](int j, int vertex) -> ObstacleContact {
    if (vertex < 0) {
      const Vec2 n = seg_normal(j);
      return {n.dot(x - p[j]), n};
    }
    const Vec2 r = x - p[vertex];
    const Vec2 b = (seg_normal(vertex - 1) + seg_normal(vertex)).normalized();
    const double d = r.norm();
    if (!(d > 0.0)) return {0.0, b};
    const double sgn = r.dot(b) >= 0.0 ? 1.0 : -1.0;
    return {sgn * d, sgn * r / d};
  };
  ObstacleContact out = signed_feature(first, first_vertex);
  // Ties: the other features within 1e-12 of the length scale add their normals.
  const double tie = 1e-12 * std::max(scale, best);
  Vec2 sum = out.normal;
  int tied = 0;
  for (int j = first + 1; j < segments; ++j) {
    int v;
    const double d = feature(j, v);
    if (!(d - best <= tie)) continue;
    if (v >= 0 && v == first_vertex) continue;  // the same vertex seen from its other segment
    sum += signed_feature(j, v).normal;
    ++tied;
  }
  if (tied > 0 && sum.norm() > 1e-12) out.normal = sum.normalized();
  return out;
}

ContactState make_contact_state(const Model& model, const std::vector<Obstacle>& obstacles,
                                const std::vector<std::vector<double>>& friction,
                                const std::vector<PrescribedDof>& prescribed,
                                const std::vector<BodyPair>& pairs) {
  ContactState c;
  std::vector<bool> held(model.num_nodes(), false);
  for (const auto& p : prescribed) held[p.dof / 2] = true;
  for (int b = 0; b < static_cast<int>(model.bodies.size()); ++b)
    for (int o = 0; o < static_cast<int>(obstacles.size()); ++o)
      for (int node : model.bodies[b].boundary_nodes)
        if (!held[node]) {
          c.candidates.push_back({node, o, friction[b][o]});
          c.any_friction = c.any_friction || friction[b][o] > 0.0;
        }
  for (int q = 0; q < static_cast<int>(pairs.size()); ++q) {
    const BodyPair& bp = pairs[q];
    if (bp.slave == bp.master) throw std::invalid_argument("body pair: self-contact is not treated");
    c.surfaces.push_back(make_surface(model, bp.master));
    for (int node : model.bodies[bp.slave].boundary_nodes)
      if (!held[node]) {
        c.candidates.push_back({node, -1, bp.friction, q});
        c.any_friction = c.any_friction || bp.friction > 0.0;
      }
  }
  c.boxes.resize(pairs.size());
  const std::size_t n = c.candidates.size();
  c.reaction.assign(n, {});
  c.x_free.assign(n, {});
  c.status.assign(n, ContactStatus::open);
  c.weight.assign(n, 0.0);
  c.normal.assign(n, Vec2::UnitY());
  c.stencil.resize(n);
  c.segment.assign(n, -1);
  for (std::size_t k = 0; k < n; ++k) {
    const ContactCandidate& cc = c.candidates[k];
    c.stencil[k].node[0] = cc.node;
    if (cc.pair < 0) c.normal[k] = closest(obstacles[cc.obstacle], model.ref.col(cc.node)).normal;
  }
  c.active.reserve(n);
  c.node_reaction.assign(model.num_nodes(), Vec2::Zero());
  return c;
}

namespace {

// Gauss-Seidel sweeps over the active contacts; each contact sees the current reactions of
// the other contacts on its node through x = x_free + w (r_own + r_others). Returns sweeps.
template <bool kFriction>
int gauss_seidel(const ContactSettings& set, ContactState& c) {
  for (int sweep = 1; sweep <= set.max_sweeps; ++sweep) {
    bool converged = true;
    for (int k : c.active) {
      const ContactCandidate& cc = c.candidates[k];
      const Stencil& st = c.stencil[k];
      const Vec2 n = c.normal[k], t{n.y(), -n.x()};
      const double w = c.weight[k];
      LocalPair& r = c.reaction[k];
      const Vec2 own = r.n * n + r.t * t;
      // x = x_free + sum_j coef_j w_j (reactions on node j other than this contact's own).
      LocalPair xf = c.x_free[k];
      for (int j = 0; j < st.count; ++j) {
        const Vec2 other = c.node_reaction[st.node[j]] - st.coef[j] * own;
        xf.n += st.factor[j] * n.dot(other);
        xf.t += st.factor[j] * t.dot(other);
      }
      const double rho = set.rho_factor / w;
      LocalPair next;
      if constexpr (kFriction) {
        next = bipotential_update(r, xf, w, cc.friction_coeff, rho);
      } else {
        next = {std::max(0.0, r.n - rho * (xf.n + w * r.n)), 0.0};
      }
      const double change = std::hypot(next.n - r.n, next.t - r.t);
      if (change > set.tolerance * std::hypot(next.n, next.t)) converged = false;
      const Vec2 delta = (next.n - r.n) * n + (next.t - r.t) * t;
      for (int j = 0; j < st.count; ++j) c.node_reaction[st.node[j]] += st.coef[j] * delta;
      r = next;
    }
    if (converged) {
      c.converged = true;
      return sweep;
    }
  }
  c.converged = false;
  return set.max_sweeps;
}

}  // namespace

void contact_phase(const Model& model, const std::vector<Obstacle>& obstacles,
                   const ContactSettings& set, ContactState& c, State& s) {
  const double dt = s.dt;
  const bool position = set.level == ContactLevel::position;
  // Free motion to t+dt: v_{n+1/2} without contact and the predicted position.
  auto v_free = [&](int j) -> Vec2 { return s.v_half.segment<2>(2 * j) + dt * s.a.segment<2>(2 * j); };
  auto predicted = [&](int j) -> Vec2 { return model.ref.col(j) + s.u.segment<2>(2 * j) + dt * v_free(j); };
  for (std::size_t q = 0; q < c.surfaces.size(); ++q)
    c.boxes[q] = surface_box(c.surfaces[q], predicted, c.surfaces[q].max_length);
  c.active.clear();
  // Broad phase: only boundary nodes whose free motion ends behind an obstacle (or inside a
  // master body) at t+dt.
  for (int k = 0; k < static_cast<int>(c.candidates.size()); ++k) {
    const ContactCandidate& cc = c.candidates[k];
    const int i = cc.node;
    Stencil& st = c.stencil[k];
    // Gap and frame at the predicted position, frozen for the step.
    ObstacleContact oc;
    if (cc.pair < 0) {
      oc = step_frame(obstacles[cc.obstacle], model.ref.col(i) + s.u.segment<2>(2 * i), predicted(i));
    } else {
      NodeSegment ns;
      if (!pair_contact_geometry(model, c, k, s.u, s.v_half, predicted, ns)) {
        c.reaction[k] = {};
        c.status[k] = ContactStatus::open;
        continue;
      }
      oc = {ns.gap, ns.normal};
    }
    if (!(oc.gap < 0.0)) {
      c.reaction[k] = {};
      c.status[k] = ContactStatus::open;
      continue;
    }
    c.normal[k] = oc.normal;
    const Vec2 t = oc.tangent();
    // Relative free velocity and compliance of the stencil: w = sum_j coef_j^2 w_j.
    Vec2 v_rel = Vec2::Zero();
    double w = 0.0;
    for (int j = 0; j < st.count; ++j) {
      const int node = st.node[j];
      v_rel += st.coef[j] * v_free(node);
      const double wj = position ? dt * dt / model.mass[2 * node] : dt / model.mass[2 * node];
      st.factor[j] = st.coef[j] * wj;
      w += st.coef[j] * st.factor[j];
      c.node_reaction[node].setZero();
    }
    c.x_free[k] = position ? LocalPair{oc.gap, dt * t.dot(v_rel)} : LocalPair{oc.normal.dot(v_rel), t.dot(v_rel)};
    c.weight[k] = w;
    c.active.push_back(k);
  }
  c.active_count = static_cast<int>(c.active.size());
  c.stick_count = c.slip_count = 0;
  c.normal_force = c.tangential_force = 0.0;
  c.sweeps = 0;
  c.converged = true;
  if (c.active.empty()) return;

  // Warm start from the last step's reactions.
  for (int k : c.active) {
    const Vec2 n = c.normal[k], t{n.y(), -n.x()};
    const Stencil& st = c.stencil[k];
    const Vec2 r = c.reaction[k].n * n + c.reaction[k].t * t;
    for (int j = 0; j < st.count; ++j) c.node_reaction[st.node[j]] += st.coef[j] * r;
  }
  c.sweeps = c.any_friction ? gauss_seidel<true>(set, c) : gauss_seidel<false>(set, c);
  ++c.steps_with_contact;
  c.sweeps_total += c.sweeps;
  c.sweeps_max = std::max(c.sweeps_max, c.sweeps);
  if (!c.converged) ++c.unconverged_steps;

  // U_c = dt^2 M^-1 R: the reactions enter the accelerations of step n.
  for (int k : c.active) {
    const ContactCandidate& cc = c.candidates[k];
    const Stencil& st = c.stencil[k];
    const Vec2 n = c.normal[k], t{n.y(), -n.x()};
    const LocalPair r = c.reaction[k];
    const Vec2 force = r.n * n + r.t * t;
    for (int j = 0; j < st.count; ++j) s.a.segment<2>(2 * st.node[j]) += st.coef[j] * force / model.mass[2 * st.node[j]];
    c.normal_force += r.n;
    c.tangential_force += r.t;
    c.status[k] = classify(r, cc.friction_coeff);
    c.stick_count += c.status[k] == ContactStatus::stick;
    c.slip_count += c.status[k] == ContactStatus::slip;
  }
  // Energy bookkeeping with the final reactions. Slip work: -r_t times the slip increment
  // dt t.v_{n+1/2} of the step (>= 0 by the cone). Contact work: dt R.v_n with
  // v_n = v_{n-1/2} + dt/2 a_n, exactly the change of the half-step kinetic energy
  // 1/2 m v_{n+1/2}^2 - 1/2 m v_{n-1/2}^2 that R causes (a node stopped dead loses 1/2 m v^2).
  // Between bodies both are sums over the stencil (relative slip; work on all three nodes).
  for (int k : c.active) {
    const Stencil& st = c.stencil[k];
    const Vec2 n = c.normal[k], t{n.y(), -n.x()};
    const LocalPair r = c.reaction[k];
    const Vec2 force = r.n * n + r.t * t;
    Vec2 v_next = Vec2::Zero();
    double work = 0.0, work_normal = 0.0;
    for (int j = 0; j < st.count; ++j) {
      const int node = st.node[j];
      const Vec2 a = s.a.segment<2>(2 * node);
      const Vec2 v_mid = s.v_half.segment<2>(2 * node) + 0.5 * dt * a;
      v_next += st.coef[j] * (s.v_half.segment<2>(2 * node) + dt * a);
      work += (st.coef[j] * force).dot(v_mid);
      work_normal += st.coef[j] * r.n * n.dot(v_mid);
    }
    c.friction_dissipation -= r.t * dt * t.dot(v_next);
    c.contact_work += dt * work;
    c.contact_work_normal += dt * work_normal;
  }
}

double penetration(const Model& model, const std::vector<Obstacle>& obstacles,
                   const std::vector<Surface>& surfaces, const std::vector<ContactCandidate>& candidates,
                   const Eigen::VectorXd& u) {
  double depth = 0.0;
  auto position = [&](int j) -> Vec2 { return model.ref.col(j) + u.segment<2>(2 * j); };
  int boxed = -1;  // a pair's candidates are contiguous: one bounding box per pair
  Box2 box;
  for (const ContactCandidate& cc : candidates) {
    const Vec2 x = position(cc.node);
    if (cc.pair < 0) {
      depth = std::max(depth, -closest(obstacles[cc.obstacle], x).gap);
      continue;
    }
    if (cc.pair != boxed) {
      box = surface_box(surfaces.at(cc.pair), position, 0.0);
      boxed = cc.pair;
    }
    if (box.contains(x)) depth = std::max(depth, depth_inside(model, surfaces[cc.pair], u, x));
  }
  return depth;
}

}  // namespace ricochet
