#include "solver/contact/contact_set.hpp"

#include <algorithm>
#include <stdexcept>

namespace ricochet {

std::vector<std::string> contact_interface_names(const std::vector<Obstacle>& obstacles,
                                                 const std::vector<BodyPair>& pairs) {
  std::vector<std::string> names;
  for (const Obstacle& o : obstacles) names.push_back(o.name);
  for (std::size_t q = 0; q < pairs.size(); ++q) {
    const std::string name = pairs[q].name.empty() ? "pair" + std::to_string(q) : pairs[q].name;
    if (std::find(names.begin() + static_cast<long>(obstacles.size()), names.end(), name) == names.end())
      names.push_back(name);
  }
  return names;
}

ContactSet make_contact_set(const Model& model, const std::vector<Obstacle>& obstacles,
                            const std::vector<std::vector<double>>& friction,
                            const std::vector<PrescribedDof>& prescribed, const std::vector<BodyPair>& pairs) {
  ContactSet c;
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
  c.normal.assign(n, Vec2::UnitY());
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

void finish_step(ContactSet& c, int iterations, bool converged) {
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

void node_contact_fields(const Model& model, const std::vector<Obstacle>& obstacles, const ContactSet& c,
                         const Eigen::VectorXd& u, double* force, double* gap, int* status) {
  const int n = model.num_nodes();
  std::fill(force, force + 2 * n, 0.0);
  std::fill(gap, gap + n, 0.0);
  std::fill(status, status + n, static_cast<int>(kNodeNoCandidate));
  for (std::size_t k = 0; k < c.candidates.size(); ++k) {
    const ContactCandidate& cc = c.candidates[k];
    const Vec2 x = model.ref.col(cc.node) + u.segment<2>(2 * cc.node);
    const double g = cc.pair < 0 ? closest(obstacles[cc.obstacle], x).gap
                                 : signed_distance(model, c.surfaces[cc.pair], u, x);
    const int code = c.status[k] == ContactStatus::stick  ? kNodeStick
                     : c.status[k] == ContactStatus::slip ? kNodeSlip
                                                          : kNodeOpen;
    gap[cc.node] = status[cc.node] == kNodeNoCandidate ? g : std::min(gap[cc.node], g);
    status[cc.node] = std::max(status[cc.node], code);
    if (c.status[k] == ContactStatus::open) continue;
    const Vec2 nk = c.normal[k], t{nk.y(), -nk.x()};
    const Vec2 r = c.reaction[k].n * nk + c.reaction[k].t * t;
    const Stencil& st = c.stencil[k];
    for (int j = 0; j < st.count; ++j) {
      force[2 * st.node[j]] += st.coef[j] * r.x();
      force[2 * st.node[j] + 1] += st.coef[j] * r.y();
    }
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
