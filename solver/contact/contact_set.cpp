#include "solver/contact/contact_set.hpp"

#include <algorithm>
#include <stdexcept>

namespace ricochet {

template <class M>
ContactSetT<M::kDim> make_contact_set(const M& model, const std::vector<ObstacleOf<M>>& obstacles,
                                      const std::vector<std::vector<double>>& friction,
                                      const std::vector<PrescribedDof>& prescribed,
                                      const std::vector<BodyPair>& pairs) {
  constexpr int D = M::kDim;
  using Vec = VecD<D>;
  ContactSetT<D> c;
  std::vector<bool> held(model.num_nodes(), false);
  for (const auto& p : prescribed) held[p.dof / D] = true;
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
    if constexpr (D == 2)
      c.surfaces.push_back(make_surface(model, bp.master));
    else
      c.surfaces.push_back(make_surface3(model, bp.master));
    for (int node : model.bodies[bp.slave].boundary_nodes)
      if (!held[node]) {
        c.candidates.push_back({node, -1, bp.friction, q});
        c.any_friction = c.any_friction || bp.friction > 0.0;
      }
  }
  // Interfaces: obstacle o is interface o; pair q the interface of its name.
  const std::vector<std::string> names = contact_interface_names(obstacles, pairs);
  c.interface.reserve(c.candidates.size());
  for (const ContactCandidate& cc : c.candidates) {
    if (cc.pair < 0) {
      c.interface.push_back(cc.obstacle);
      continue;
    }
    const std::string& pn = pairs[cc.pair].name;
    const std::string name = pn.empty() ? "pair" + std::to_string(cc.pair) : pn;
    c.interface.push_back(static_cast<int>(
        std::find(names.begin() + static_cast<long>(obstacles.size()), names.end(), name) - names.begin()));
  }
  c.interface_last.assign(names.size(), {});
  c.interface_total.assign(names.size(), {});
  c.boxes.resize(pairs.size());
  const std::size_t n = c.candidates.size();
  c.reaction.assign(n, {});
  c.status.assign(n, ContactStatus::open);
  c.normal.assign(n, Vec::UnitY());
  c.stencil.resize(n);
  c.segment.assign(n, -1);
  for (std::size_t k = 0; k < n; ++k) {
    const ContactCandidate& cc = c.candidates[k];
    c.stencil[k].node[0] = cc.node;
    if (cc.pair < 0) c.normal[k] = closest(obstacles[cc.obstacle], model.ref.col(cc.node)).normal;
  }
  c.active.reserve(n);
  return c;
}

template <int D>
void finish_step(ContactSetT<D>& c, int iterations, bool converged) {
  c.last.active = static_cast<int>(c.active.size());
  c.last.iterations = iterations;
  c.last.converged = converged;
  c.total.status_changes += c.last.status_changes;
  c.total.steps_with_status_changes += c.last.status_changes > 0;
  if (!converged) ++c.total.unconverged_steps;
  if (c.active.empty()) return;
  ++c.total.steps_with_contact;
  c.total.iterations_total += iterations;
  c.total.iterations_max = std::max(c.total.iterations_max, iterations);
}

template <class M>
void node_contact_fields(const M& model, const std::vector<ObstacleOf<M>>& obstacles,
                         const ContactSetT<M::kDim>& c, const Eigen::VectorXd& u, double* force, double* gap,
                         int* status) {
  constexpr int D = M::kDim;
  using Vec = VecD<D>;
  const int n = model.num_nodes();
  std::fill(force, force + D * n, 0.0);
  std::fill(gap, gap + n, 0.0);
  std::fill(status, status + n, static_cast<int>(kNodeNoCandidate));
  for (std::size_t k = 0; k < c.candidates.size(); ++k) {
    const ContactCandidate& cc = c.candidates[k];
    const Vec x = model.ref.col(cc.node) + u.segment<D>(D * cc.node);
    double g = 0.0;
    if (cc.pair < 0)
      g = closest(obstacles[cc.obstacle], x).gap;
    else
      g = signed_distance(model, c.surfaces[cc.pair], u, x);
    const int code = c.status[k] == ContactStatus::stick  ? kNodeStick
                     : c.status[k] == ContactStatus::slip ? kNodeSlip
                                                          : kNodeOpen;
    gap[cc.node] = status[cc.node] == kNodeNoCandidate ? g : std::min(gap[cc.node], g);
    status[cc.node] = std::max(status[cc.node], code);
    if (c.status[k] == ContactStatus::open) continue;
    const Vec r = ContactFrame<D>(c.normal[k]).global(c.reaction[k]);
    const auto& st = c.stencil[k];
    for (int j = 0; j < st.count; ++j)
      for (int i = 0; i < D; ++i) force[D * st.node[j] + i] += st.coef[j] * r[i];
  }
}

template <class M>
double penetration(const M& model, const std::vector<ObstacleOf<M>>& obstacles,
                   const std::vector<typename Space<M::kDim>::Surface>& surfaces,
                   const std::vector<ContactCandidate>& candidates, const Eigen::VectorXd& u) {
  CandidateDepth<M> depth_of(model, obstacles, surfaces, u);
  double depth = 0.0;
  for (const ContactCandidate& cc : candidates) depth = std::max(depth, depth_of.unclamped(cc));
  return depth;
}

// The instantiations: one per model type.
#define RICOCHET_CONTACT_SET_FOR(M)                                                                              \
  template ContactSetT<M::kDim> make_contact_set<M>(const M&, const std::vector<ObstacleOf<M>>&,                 \
                                                    const std::vector<std::vector<double>>&,                     \
                                                    const std::vector<PrescribedDof>&, const std::vector<BodyPair>&); \
  template void finish_step<M::kDim>(ContactSetT<M::kDim>&, int, bool);                                          \
  template void node_contact_fields<M>(const M&, const std::vector<ObstacleOf<M>>&, const ContactSetT<M::kDim>&,  \
                                       const Eigen::VectorXd&, double*, double*, int*);                          \
  template double penetration<M>(const M&, const std::vector<ObstacleOf<M>>&,                                    \
                                 const std::vector<typename Space<M::kDim>::Surface>&,                           \
                                 const std::vector<ContactCandidate>&, const Eigen::VectorXd&);
RICOCHET_CONTACT_SET_FOR(Model<2>)
RICOCHET_CONTACT_SET_FOR(Model<3>)
#undef RICOCHET_CONTACT_SET_FOR

}  // namespace ricochet
