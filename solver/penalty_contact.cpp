#include "solver/penalty_contact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <tuple>
#include <type_traits>

namespace ricochet {

double penalty_bulk_modulus(const Material& material) {
  return std::visit(
      [](const auto& m) {
        using T = std::decay_t<decltype(m)>;
        if constexpr (std::is_same_v<T, StVenantKirchhoff>) {
          return m.lambda_3d + 2.0 * m.shear_modulus / 3.0;
        } else {
          return m.lambda + 2.0 * m.shear_modulus / 3.0;  // NeoHookean::lambda is the 3D value
        }
      },
      material);
}

namespace {

// A cell edge (a < b) and the reference area of the cell using it.
struct Edge {
  int a, b;
  double cell_area;
};

template <class Block>
void collect_edges(const Model& model, const std::vector<Block>& blocks, int body,
                   std::vector<Edge>& edges) {
  for (const auto& block : blocks) {
    if (block.body != body) continue;
    for (const auto& c : block.conn) {
      const int n = static_cast<int>(c.size());
      double twice_area = 0.0;
      for (int k = 0; k < n; ++k) {
        const Vec2 p = model.ref.col(c[k]), q = model.ref.col(c[(k + 1) % n]);
        twice_area += p.x() * q.y() - q.x() * p.y();
      }
      for (int k = 0; k < n; ++k) {
        const int a = c[k], b = c[(k + 1) % n];
        edges.push_back({std::min(a, b), std::max(a, b), 0.5 * twice_area});
      }
    }
  }
}

// Per node of the model: k_i / f_si = sum over its boundary segments of K l^2 e / (2 A_c).
// With `segments`, also every boundary segment's k_s / f_si, keyed by its (min, max) node pair.
std::vector<double> nodal_stiffness_per_scale(const Model& model,
                                              std::map<std::pair<int, int>, double>* segments = nullptr) {
  std::vector<double> k(model.num_nodes(), 0.0);
  std::vector<Edge> edges;
  for (int b = 0; b < static_cast<int>(model.bodies.size()); ++b) {
    const BodyInfo& body = model.bodies[b];
    const double bulk = penalty_bulk_modulus(body.material);
    edges.clear();
    collect_edges(model, model.q4_full, b, edges);
    collect_edges(model, model.q4_hourglass, b, edges);
    collect_edges(model, model.t3, b, edges);
    std::sort(edges.begin(), edges.end(),
              [](const Edge& x, const Edge& y) { return std::tie(x.a, x.b) < std::tie(y.a, y.b); });
    for (std::size_t i = 0; i < edges.size();) {
      std::size_t j = i;
      while (j < edges.size() && edges[j].a == edges[i].a && edges[j].b == edges[i].b) ++j;
      if (j - i == 1) {
        const Edge& e = edges[i];
        const double l2 = (model.ref.col(e.b) - model.ref.col(e.a)).squaredNorm();
        const double ks = bulk * l2 * body.thickness / e.cell_area;
        k[e.a] += 0.5 * ks;
        k[e.b] += 0.5 * ks;
        if (segments) (*segments)[{e.a, e.b}] = ks;
      }
      i = j;
    }
  }
  return k;
}

}  // namespace

PenaltyState make_penalty_state(const Model& model, const std::vector<Obstacle>& obstacles,
                                const std::vector<std::vector<double>>& friction,
                                const std::vector<PrescribedDof>& prescribed,
                                const PenaltySettings& settings, const std::vector<BodyPair>& pairs) {
  if (!(settings.scale_factor > 0.0))
    throw std::invalid_argument("penalty contact: scale factor f_si must be > 0");
  // The candidates, exactly as the bi-potential phase chooses them.
  ContactState c = make_contact_state(model, obstacles, friction, prescribed, pairs);
  PenaltyState p;
  p.candidates = c.candidates;
  p.any_friction = c.any_friction;
  p.scale_factor = settings.scale_factor;
  p.surfaces = std::move(c.surfaces);
  p.boxes = std::move(c.boxes);
  p.stencil = std::move(c.stencil);
  p.segment = std::move(c.segment);
  std::map<std::pair<int, int>, double> k_edge;
  const std::vector<double> k_node = nodal_stiffness_per_scale(model, &k_edge);
  // Per pair and master segment, k_s; per pair the smallest master boundary node mass.
  p.segment_stiffness.resize(p.surfaces.size());
  std::vector<double> m_master(p.surfaces.size()), k_max(p.surfaces.size(), 0.0);
  for (std::size_t q = 0; q < p.surfaces.size(); ++q) {
    for (const SurfaceSegment& sg : p.surfaces[q].segments) {
      const double ks = k_edge.at({std::min(sg.a, sg.b), std::max(sg.a, sg.b)});
      p.segment_stiffness[q].push_back(settings.scale_factor * ks);
      k_max[q] = std::max(k_max[q], ks);
    }
    m_master[q] = std::numeric_limits<double>::infinity();
    for (int j : p.surfaces[q].nodes) m_master[q] = std::min(m_master[q], model.mass[2 * j]);
  }
  if (settings.soft_scale > 0.0) {
    if (!(settings.soft_dt > 0.0)) throw std::logic_error("penalty contact: soft_scale > 0 needs soft_dt > 0");
    p.soft_factor = settings.soft_scale / (2.0 * settings.soft_dt * settings.soft_dt);
  }
  const std::size_t n = p.candidates.size();
  p.stiffness.resize(n);
  p.bulk_stiffness.resize(n);
  p.pair_compliance.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const ContactCandidate& cc = p.candidates[i];
    double k = k_node[cc.node];
    double m_star = model.mass[2 * cc.node];
    if (cc.pair >= 0) {
      k = std::min(k, k_max[cc.pair]);  // the stiffest spring the node can meet (for the step)
      p.pair_compliance[i] = 1.0 / model.mass[2 * cc.node] + 1.0 / m_master[cc.pair];
      m_star = std::min(m_star, m_master[cc.pair]);
    }
    p.bulk_stiffness[i] = settings.scale_factor * k;
    p.stiffness[i] = std::max(p.bulk_stiffness[i], p.soft_factor * m_star);
    if (!(p.bulk_stiffness[i] > 0.0))
      throw std::logic_error("penalty contact: boundary node " + std::to_string(cc.node) + " has no boundary segment");
  }
  p.force_n.assign(n, 0.0);
  p.force_t.assign(n, 0.0);
  p.last_position.assign(n, Vec2::Zero());
  p.normal.assign(n, Vec2::UnitY());
  p.status.assign(n, ContactStatus::open);
  p.active.reserve(n);
  return p;
}

double penalty_critical_dt(const Model& model, const PenaltyState& p) {
  double dt = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < p.candidates.size(); ++i)
    dt = std::min(dt, p.candidates[i].pair < 0
                          ? 2.0 * std::sqrt(model.mass[2 * p.candidates[i].node] / p.stiffness[i])
                          : 2.0 / std::sqrt(p.stiffness[i] * p.pair_compliance[i]));
  return dt;
}

double penalty_combined_critical_dt(const Model& model, const PenaltyState& p) {
  const double de = model.critical_dt, dp = penalty_critical_dt(model, p);
  if (!std::isfinite(dp)) return de;
  return 1.0 / std::sqrt(1.0 / (de * de) + 1.0 / (dp * dp));
}

double penalty_stable_time_step(const Model& model, const PenaltyState& p, double safety) {
  return safety * penalty_combined_critical_dt(model, p);
}

void penalty_phase(const Model& model, const std::vector<Obstacle>& obstacles,
                   PenaltyState& p, State& s) {
  const int count = static_cast<int>(p.candidates.size());
  p.active.clear();
  p.active_count = p.stick_count = p.slip_count = 0;
  p.normal_force = p.tangential_force = 0.0;
  p.normal_energy = p.tangential_energy = 0.0;
  double depth = 0.0;
  const bool first = !p.initialized;
  p.initialized = true;

  auto position = [&](int j) -> Vec2 { return model.ref.col(j) + s.u.segment<2>(2 * j); };
  for (std::size_t q = 0; q < p.surfaces.size(); ++q)
    p.boxes[q] = surface_box(p.surfaces[q], position, p.surfaces[q].max_length);

  for (int k = 0; k < count; ++k) {
    const ContactCandidate& cc = p.candidates[k];
    const int i = cc.node;
    const Vec2 x = position(i);
    Stencil& st = p.stencil[k];
    ObstacleContact oc;
    if (cc.pair < 0) {
      oc = closest(obstacles[cc.obstacle], x);
    } else {
      NodeSegment ns;
      if (pair_contact_geometry(model, p, k, s.u, s.v_half, position, ns)) {  // at t_n: start = evaluation
        oc = {ns.gap, ns.normal};
      } else {
        oc.gap = std::numeric_limits<double>::infinity();  // facing no segment: open
        st.count = 1;
      }
    }
    const double g = oc.gap;
    const Vec2 t = oc.tangent();
    p.normal[k] = oc.normal;
    // Between bodies: f_si min(k_slave, k_s) of the segment met this step, at least the soft
    // constraint's k1 of the stencil's lightest node.
    double stiff = p.stiffness[k];
    if (cc.pair >= 0 && p.segment[k] >= 0) {
      stiff = std::min(p.bulk_stiffness[k], p.segment_stiffness[cc.pair][p.segment[k]]);
      if (p.soft_factor > 0.0) {
        double m_star = model.mass[2 * st.node[0]];
        for (int j = 1; j < st.count; ++j) m_star = std::min(m_star, model.mass[2 * st.node[j]]);
        stiff = std::max(stiff, p.soft_factor * m_star);
      }
    }
    const double fn = g < 0.0 ? -stiff * g : 0.0;
    double ft = 0.0;
    ContactStatus status = fn > 0.0 ? ContactStatus::slip : ContactStatus::open;
    if (cc.friction_coeff > 0.0) {
      // Elastic predictor on the slip increment of the step, then the return map onto
      // |f_t| <= mu f_n (f_n = 0 when open, which returns the spring to zero).
      // For a line t . x_{n-1} is the value stored last step, bit for bit; for a curved
      // obstacle it projects the increment on the current tangent.
      // Between bodies the increment is the relative one, dt t . sum_j coef_j v_{n-1/2,j}.
      double ds = 0.0;
      if (!first && cc.pair < 0) {
        ds = t.dot(x) - t.dot(p.last_position[k]);
      } else if (!first) {
        Vec2 dv = Vec2::Zero();
        for (int j = 0; j < st.count; ++j) dv += st.coef[j] * s.v_half.segment<2>(2 * st.node[j]);
        ds = s.dt * t.dot(dv);
      }
      p.last_position[k] = x;
      const double old = p.force_t[k];
      const double trial = old - stiff * ds;
      const double cap = cc.friction_coeff * fn;
      if (std::abs(trial) <= cap) {
        ft = trial;
        if (fn > 0.0) status = ContactStatus::stick;
      } else {
        ft = std::copysign(cap, trial);
        p.friction_dissipation += (trial - ft) * (old + ft) / (2.0 * stiff);
      }
      p.force_t[k] = ft;
    }
    p.force_n[k] = fn;
    p.status[k] = status;
    if (!(fn > 0.0)) continue;

    depth = std::max(depth, -g);
    p.active.push_back(k);
    const Vec2 force = fn * oc.normal + ft * t;
    for (int j = 0; j < st.count; ++j) s.a.segment<2>(2 * st.node[j]) += st.coef[j] * force * model.inv_mass[2 * st.node[j]];
    p.normal_force += fn;
    p.tangential_force += ft;
    p.normal_energy += 0.5 * stiff * g * g;
    p.tangential_energy += ft * ft / (2.0 * stiff);
    p.stick_count += status == ContactStatus::stick;
    p.slip_count += status == ContactStatus::slip;
  }
  p.active_count = static_cast<int>(p.active.size());
  p.stored_energy = p.normal_energy + p.tangential_energy;
  p.penetration = depth;
  p.penetration_max = std::max(p.penetration_max, depth);
  if (p.active.empty()) return;
  ++p.steps_with_contact;

  // Work of the penalty forces, dt F . v_n with v_n = v_{n-1/2} + dt/2 a_n and the final a_n:
  // the change of the half-step kinetic energy that F causes (as contact_phase records it).
  const double dt = s.dt;
  for (int k : p.active) {
    const Stencil& st = p.stencil[k];
    const Vec2 n = p.normal[k], t{n.y(), -n.x()};
    const Vec2 force = p.force_n[k] * n + p.force_t[k] * t;
    double work = 0.0, work_normal = 0.0;
    for (int j = 0; j < st.count; ++j) {
      const int node = st.node[j];
      const Vec2 v_mid = s.v_half.segment<2>(2 * node) + 0.5 * dt * s.a.segment<2>(2 * node);
      work += (st.coef[j] * force).dot(v_mid);
      work_normal += st.coef[j] * p.force_n[k] * n.dot(v_mid);
    }
    p.contact_work += dt * work;
    p.contact_work_normal += dt * work_normal;
  }
}

}  // namespace ricochet
