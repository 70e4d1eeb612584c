#include "solver/contact/penalty_contact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
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

double penalty_bulk_modulus(const Material3& material) {
  // Every 3D law stores its small-strain lambda and mu (material3d.hpp).
  return std::visit([](const auto& m) { return m.lambda + 2.0 * m.shear_modulus / 3.0; }, material);
}

namespace {

// k_s / f_si = K l^2 e / A_c of one boundary segment (its length l, its cell's area A_c).
double segment_stiffness_per_scale(const Model<2>& model, const BodyInfo<2>& body, const BoundaryEdge& e, double bulk) {
  const double l2 = (model.ref.col(e.b) - model.ref.col(e.a)).squaredNorm();
  return bulk * l2 * body.thickness / e.cell_area;
}

// Per node of the model: k_i / f_si = sum over its boundary segments of k_s / (2 f_si).
std::vector<double> nodal_stiffness_per_scale(const Model<2>& model) {
  std::vector<double> k(model.num_nodes(), 0.0);
  for (const BodyInfo<2>& body : model.bodies) {
    const double bulk = penalty_bulk_modulus(body.material);
    for (const BoundaryEdge& e : body.boundary_edges) {
      const double ks = segment_stiffness_per_scale(model, body, e, bulk);
      k[e.a] += 0.5 * ks;
      k[e.b] += 0.5 * ks;
    }
  }
  return k;
}

// The same in 3D, LS-DYNA's solid-segment stiffness: per boundary face k_s / f_si = K A^2 / V,
// A the face's reference area (a quadrilateral's |d13 x d24| / 2, exact for a flat face; a
// triangle's |e1 x e2| / 2), V its cell's reference volume; each of the face's corners gets
// k_s / corners. (2D is this with A = l e, V = A_c e.)
double face_stiffness_per_scale(const Model<3>& model, const BoundaryFace& f, double bulk) {
  auto x = [&](int a) -> Vec3 { return model.ref.col(f.nodes[a]); };
  const Vec3 normal2 = f.corners == 4 ? Vec3((x(2) - x(0)).cross(x(3) - x(1))) : Vec3((x(1) - x(0)).cross(x(2) - x(0)));
  const double area = 0.5 * normal2.norm();
  return bulk * area * area / f.cell_volume;
}

std::vector<double> nodal_stiffness_per_scale(const Model<3>& model) {
  std::vector<double> k(model.num_nodes(), 0.0);
  for (const BodyInfo<3>& body : model.bodies) {
    const double bulk = penalty_bulk_modulus(body.material);
    for (const BoundaryFace& f : body.boundary_faces) {
      const double ks = face_stiffness_per_scale(model, f, bulk);
      for (int a = 0; a < f.corners; ++a) k[f.nodes[a]] += ks / f.corners;
    }
  }
  return k;
}

}  // namespace

template <class M>
PenaltyContactT<M::kDim> make_penalty_contact(const M& model, const std::vector<ObstacleOf<M>>& obstacles,
                                              const std::vector<std::vector<double>>& friction,
                                              const std::vector<PrescribedDof>& prescribed,
                                              const PenaltySettings& settings, const std::vector<BodyPair>& pairs) {
  constexpr int D = M::kDim;
  if (!(settings.scale_factor > 0.0))
    throw std::invalid_argument("penalty contact: scale factor f_si must be > 0");
  PenaltyContactT<D> p;
  p.set = make_contact_set(model, obstacles, friction, prescribed, pairs);
  const ContactSetT<D>& c = p.set;
  p.scale_factor = settings.scale_factor;
  const std::vector<double> k_node = nodal_stiffness_per_scale(model);
  // Per pair and master segment (the master's boundary edges, in order), f_si k_s; per pair the
  // smallest master boundary node mass.
  p.segment_stiffness.resize(c.surfaces.size());
  std::vector<double> m_master(c.surfaces.size()), k_max(c.surfaces.size(), 0.0);
  if constexpr (D == 2)
  for (std::size_t q = 0; q < c.surfaces.size(); ++q) {
    const BodyInfo<2>& master = model.bodies[c.surfaces[q].body];
    const double bulk = penalty_bulk_modulus(master.material);
    for (const BoundaryEdge& e : master.boundary_edges) {
      const double ks = segment_stiffness_per_scale(model, master, e, bulk);
      p.segment_stiffness[q].push_back(settings.scale_factor * ks);
      k_max[q] = std::max(k_max[q], ks);
    }
    m_master[q] = std::numeric_limits<double>::infinity();
    for (int j : c.surfaces[q].nodes) m_master[q] = std::min(m_master[q], model.mass[D * j]);
  }
  // 3D: per master face (Surface3::faces are the master's boundary faces, in order) its
  // k_s = f_si K A^2 / V, the face the slave node meets playing the 2D segment's part.
  if constexpr (D == 3)
  for (std::size_t q = 0; q < c.surfaces.size(); ++q) {
    const BodyInfo<3>& master = model.bodies[c.surfaces[q].body];
    const double bulk = penalty_bulk_modulus(master.material);
    for (const BoundaryFace& f : master.boundary_faces) {
      const double ks = face_stiffness_per_scale(model, f, bulk);
      p.segment_stiffness[q].push_back(settings.scale_factor * ks);
      k_max[q] = std::max(k_max[q], ks);
    }
    m_master[q] = std::numeric_limits<double>::infinity();
    for (int j : c.surfaces[q].nodes) m_master[q] = std::min(m_master[q], model.mass[D * j]);
  }
  if (settings.soft_scale > 0.0) {
    if (!(settings.soft_dt > 0.0)) throw std::logic_error("penalty contact: soft_scale > 0 needs soft_dt > 0");
    p.soft_factor = settings.soft_scale / (2.0 * settings.soft_dt * settings.soft_dt);
  }
  const std::size_t n = c.candidates.size();
  p.stiffness.resize(n);
  p.bulk_stiffness.resize(n);
  p.pair_compliance.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const ContactCandidate& cc = c.candidates[i];
    double k = k_node[cc.node];
    double m_star = model.mass[D * cc.node];
    if (cc.pair >= 0) {
      k = std::min(k, k_max[cc.pair]);  // the stiffest spring the node can meet (for the step)
      p.pair_compliance[i] = 1.0 / model.mass[D * cc.node] + 1.0 / m_master[cc.pair];
      m_star = std::min(m_star, m_master[cc.pair]);
    }
    p.bulk_stiffness[i] = settings.scale_factor * k;
    p.stiffness[i] = std::max(p.bulk_stiffness[i], p.soft_factor * m_star);
    if (!(p.bulk_stiffness[i] > 0.0))
      throw std::logic_error("penalty contact: boundary node " + std::to_string(cc.node) + " has no boundary segment");
  }
  p.last_position.assign(n, VecD<D>::Zero());
  return p;
}

template <class M>
double penalty_critical_dt(const M& model, const PenaltyContactT<M::kDim>& p) {
  constexpr int D = M::kDim;
  const std::vector<ContactCandidate>& cand = p.set.candidates;
  double dt = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < cand.size(); ++i)
    dt = std::min(dt, cand[i].pair < 0 ? 2.0 * std::sqrt(model.mass[D * cand[i].node] / p.stiffness[i])
                                       : 2.0 / std::sqrt(p.stiffness[i] * p.pair_compliance[i]));
  return dt;
}


template <class M>
void penalty_phase(const M& model, const std::vector<ObstacleOf<M>>& obstacles, PenaltyContactT<M::kDim>& p,
                   State& s) {
  constexpr int D = M::kDim;
  using Vec = VecD<D>;
  using Local = typename Space<D>::Local;
  using Tangent = decltype(Local::t);  // double in 2D, a 2-vector of the tangent plane in 3D
  ContactSetT<D>& c = p.set;
  const int count = static_cast<int>(c.candidates.size());
  begin_step(c);
  p.normal_energy = p.tangential_energy = 0.0;
  double depth = 0.0;
  const bool first = !p.initialized;
  p.initialized = true;

  auto position = [&](int j) -> Vec { return model.ref.col(j) + s.u.segment<D>(D * j); };
  update_boxes(c, position);

  for (int k = 0; k < count; ++k) {
    const ContactCandidate& cc = c.candidates[k];
    const Vec x = position(cc.node);
    auto& st = c.stencil[k];
    // The frame at u_n (start and evaluation positions coincide).
    typename Space<D>::ObstacleContact oc;
    if (!candidate_frame(model, obstacles, c, k, s.u, s.v_half, position, oc)) {
      oc.gap = std::numeric_limits<double>::infinity();  // facing no segment: open
      st.count = 1;
    }
    const double g = oc.gap;
    const ContactFrame<D> f(oc.normal);
    c.normal[k] = oc.normal;
    // Between bodies: f_si min(k_slave, k_s) of the segment met this step, at least the soft
    // constraint's k1 of the stencil's lightest node.
    double stiff = p.stiffness[k];
    if (cc.pair >= 0 && c.segment[k] >= 0) {
      stiff = std::min(p.bulk_stiffness[k], p.segment_stiffness[cc.pair][c.segment[k]]);
      if (p.soft_factor > 0.0) {
        double m_star = model.mass[D * st.node[0]];
        for (int j = 1; j < st.count; ++j) m_star = std::min(m_star, model.mass[D * st.node[j]]);
        stiff = std::max(stiff, p.soft_factor * m_star);
      }
    }
    const double fn = g < 0.0 ? -stiff * g : 0.0;
    Tangent ft = Local{}.t;  // 0
    ContactStatus status = fn > 0.0 ? ContactStatus::slip : ContactStatus::open;
    if (cc.friction_coeff > 0.0) {
      // Elastic predictor on the slip increment of the step, then the return map onto
      // |f_t| <= mu f_n (f_n = 0 when open, which returns the spring to zero).
      // For a line t . x_{n-1} is the value stored last step, bit for bit; for a curved
      // obstacle it projects the increment on the current tangent.
      // Between bodies the increment is the relative one over the last step,
      // dt_{n-1/2} t . sum_j coef_j v_{n-1/2,j}.
      Tangent ds = Local{}.t;  // 0
      if (!first && cc.pair < 0) {
        ds = f.tangential(x) - f.tangential(p.last_position[k]);
      } else if (!first) {
        Vec dv = Vec::Zero();
        for (int j = 0; j < st.count; ++j) dv += st.coef[j] * s.v_half.segment<D>(D * st.node[j]);
        ds = s.dt_prev * f.tangential(dv);
      }
      p.last_position[k] = x;
      const Tangent old = c.reaction[k].t;
      const Tangent trial = old - stiff * ds;
      const double cap = cc.friction_coeff * fn;
      if (tangential_norm(trial) <= cap) {
        ft = trial;
        if (fn > 0.0) status = ContactStatus::stick;
      } else {
        ft = tangential_clamp(cap, trial);
        add_dissipation(c, k, tangential_dot(trial - ft, old + ft) / (2.0 * stiff));
      }
    }
    c.reaction[k] = Local{fn, ft};
    record(c, k, status);
    if (!(fn > 0.0)) continue;

    depth = std::max(depth, -g);
    c.active.push_back(k);
    const Vec force = f.global(c.reaction[k]);
    for (int j = 0; j < st.count; ++j)
      s.a.segment<D>(D * st.node[j]) += st.coef[j] * force * model.inv_mass[D * st.node[j]];
    p.normal_energy += 0.5 * stiff * g * g;
    p.tangential_energy += tangential_dot(ft, ft) / (2.0 * stiff);
  }
  c.last.stored_energy = p.normal_energy + p.tangential_energy;
  p.penetration = depth;
  // Work of the penalty forces, dt_n F . v with v = v_{n-1/2} + dt_n/2 a_n (v_n for a fixed
  // step; dt_n = (dt_{n-1/2} + dt_{n+1/2}) / 2, central_difference.hpp) and the final a_n: the
  // change of the half-step kinetic energy that F causes (as contact_phase records it). The
  // friction dissipation is the return map's, above.
  const double dt = velocity_step(s);
  auto v_mid = [&](int j) -> Vec { return s.v_half.segment<D>(D * j) + 0.5 * dt * s.a.segment<D>(D * j); };
  for (int k : c.active) record_work(c, k, dt, v_mid, false, v_mid);
  finish_step(c, 0, true);
}

// The instantiations: one per model type.
#define RICOCHET_PENALTY_FOR(M)                                                                                \
  template PenaltyContactT<M::kDim> make_penalty_contact<M>(                                                   \
      const M&, const std::vector<ObstacleOf<M>>&, const std::vector<std::vector<double>>&,                    \
      const std::vector<PrescribedDof>&, const PenaltySettings&, const std::vector<BodyPair>&);                \
  template double penalty_critical_dt<M>(const M&, const PenaltyContactT<M::kDim>&);                           \
  template void penalty_phase<M>(const M&, const std::vector<ObstacleOf<M>>&, PenaltyContactT<M::kDim>&, State&);
RICOCHET_PENALTY_FOR(Model<2>)
RICOCHET_PENALTY_FOR(Model<3>)
#undef RICOCHET_PENALTY_FOR

}  // namespace ricochet
