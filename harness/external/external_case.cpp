#include "harness/external/external_case.hpp"

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "harness/outputs/run_outputs.hpp"
#include "solver/contact/penalty_contact.hpp"
#include "solver/schemes/threads.hpp"

namespace ricochet {
namespace {

template <class V>
Json vec_json(const V& v) {
  Json a = Json::array();
  for (int k = 0; k < v.size(); ++k) a.push_back(v(k));
  return a;
}

Json material_json(const MaterialSpec& m) {
  Json j = Json::object();
  j["model"] = m.model;
  j["density"] = m.density;
  if (m.model == "saint_venant_kirchhoff" || m.model == "neo_hookean") {
    j["young"] = m.young;
    j["poisson"] = m.poisson;
  } else if (m.model == "mooney_rivlin") {
    j["c10"] = m.c10;
    j["c01"] = m.c01;
    j["bulk_modulus"] = m.bulk_modulus;
  } else {
    j["shear_modulus"] = m.shear_modulus;
  }
  return j;
}

// A cell's corners as global node indices.
template <std::size_t N>
Json cells_json(const std::vector<std::array<int, N>>& cells, int first_node) {
  Json a = Json::array();
  for (const auto& c : cells) {
    Json cell = Json::array();
    for (int n : c) cell.push_back(n + first_node);
    a.push_back(cell);
  }
  return a;
}

Json obstacle_json(const Obstacle& ob) {
  Json j = Json::object();
  j["name"] = ob.name;
  switch (ob.kind) {
    case ObstacleKind::line:
      j["type"] = "line";
      j["point"] = vec_json(ob.point);
      j["normal"] = vec_json(ob.normal);
      break;
    case ObstacleKind::circle: j["type"] = "circle"; break;
    case ObstacleKind::polyline: j["type"] = "polyline"; break;
  }
  return j;
}

Json obstacle_json(const Obstacle3& ob) {
  Json j = Json::object();
  j["name"] = ob.name;
  switch (ob.kind) {
    case ObstacleKind3::plane:
      j["type"] = "plane";
      j["point"] = vec_json(ob.point);
      j["normal"] = vec_json(ob.normal);
      break;
    case ObstacleKind3::sphere: j["type"] = "sphere"; break;
    case ObstacleKind3::box: j["type"] = "box"; break;
    case ObstacleKind3::cylinder: j["type"] = "cylinder"; break;
  }
  return j;
}

// Each node's share of the boundary it ends [m^2]: half of each boundary edge's length times
// the thickness (2D), a quarter of each quadrilateral face's area and a third of each
// triangle's (3D).
std::vector<double> boundary_areas(const Model<2>& m) {
  std::vector<double> area(m.num_nodes(), 0.0);
  for (const auto& b : m.bodies)
    for (const BoundaryEdge& e : b.boundary_edges) {
      const double share = 0.5 * (m.ref.col(e.b) - m.ref.col(e.a)).norm() * b.thickness;
      area[e.a] += share;
      area[e.b] += share;
    }
  return area;
}

std::vector<double> boundary_areas(const Model<3>& m) {
  std::vector<double> area(m.num_nodes(), 0.0);
  for (const auto& b : m.bodies)
    for (const BoundaryFace& f : b.boundary_faces) {
      const auto x = [&](int k) { return Vec3(m.ref.col(f.nodes[k])); };
      // A quadrilateral's area through its diagonals (exact when it is planar), a triangle's
      // through two edges.
      const double a = f.corners == 4 ? 0.5 * (x(2) - x(0)).cross(x(3) - x(1)).norm()
                                      : 0.5 * (x(1) - x(0)).cross(x(2) - x(0)).norm();
      for (int k = 0; k < f.corners; ++k) area[f.nodes[k]] += a / f.corners;
    }
  return area;
}

template <int D>
void add_model(Json& j, const PreparedCase& pc) {
  const Model<D>& m = pc.model<D>();
  const CaseSpec& c = pc.spec;
  const RunSettings& s = pc.settings;
  Json nodes = Json::array(), velocity = Json::array(), mass = Json::array();
  for (int i = 0; i < m.num_nodes(); ++i) {
    nodes.push_back(vec_json(m.ref.col(i)));
    velocity.push_back(vec_json(m.initial_velocity.template segment<D>(D * i)));
    mass.push_back(m.mass(D * i));
  }
  j["nodes"] = nodes;
  j["velocity"] = velocity;
  j["mass"] = mass;

  Json bodies = Json::array();
  const auto& meshes = pc.meshes<D>();
  for (std::size_t b = 0; b < m.bodies.size(); ++b) {
    const auto& info = m.bodies[b];
    const BodySpec& spec = c.bodies[b];
    Json body = Json::object();
    body["name"] = info.name;
    body["element"] = spec.element;
    Json cells = Json::object();
    if constexpr (D == 2) {
      body["thickness"] = info.thickness;
      if (!meshes[b].quads.empty()) cells["quad4"] = cells_json(meshes[b].quads, info.first_node);
      if (!meshes[b].tris.empty()) cells["tri3"] = cells_json(meshes[b].tris, info.first_node);
    } else {
      body["thickness"] = nullptr;
      if (!meshes[b].hexes.empty()) cells["hex8"] = cells_json(meshes[b].hexes, info.first_node);
      if (!meshes[b].tets.empty()) cells["tet4"] = cells_json(meshes[b].tets, info.first_node);
    }
    body["nodes"] = Json::array({info.first_node, info.num_nodes});
    body["cells"] = cells;
    body["material"] = material_json(spec.material);
    bodies.push_back(body);
  }
  j["bodies"] = bodies;
  j["gravity"] = vec_json(m.gravity);

  Json prescribed = Json::array();
  for (const PrescribedDof& p : s.prescribed) {
    Json q = Json::object();
    q["node"] = p.dof / D;
    q["component"] = p.dof % D;
    q["kind"] = p.kind == PrescribedDof::Kind::velocity ? "velocity" : "displacement";
    q["value"] = p.value;
    q["ramp"] = p.ramp;
    prescribed.push_back(q);
  }
  j["prescribed"] = prescribed;
  Json loads = Json::array();
  for (const NodalLoad& l : s.loads) {
    Json q = Json::object();
    q["node"] = l.dof / D;
    q["component"] = l.dof % D;
    q["force"] = l.value;
    q["start"] = l.start;
    q["ramp"] = l.ramp;
    loads.push_back(q);
  }
  j["loads"] = loads;

  const auto& obstacles = obstacles_of(s, m);
  Json obs = Json::array();
  for (const auto& ob : obstacles) obs.push_back(obstacle_json(ob));
  j["obstacles"] = obs;

  // The candidates and stiffnesses of ricochet's own penalty scheme (make_penalty_contact), so
  // that an adapter's penalty can be ricochet's, like for like.
  Json contact = Json::object();
  Json candidates = Json::array();
  if (!obstacles.empty() || !s.body_pairs.empty()) {
    const PenaltyContactT<D> p = make_penalty_contact(m, obstacles, s.friction, s.prescribed, s.penalty, s.body_pairs);
    const std::vector<double> area = boundary_areas(m);
    for (std::size_t k = 0; k < p.set.candidates.size(); ++k) {
      const ContactCandidate& cand = p.set.candidates[k];
      Json q = Json::object();
      q["node"] = cand.node;
      q["obstacle"] = cand.pair >= 0 ? -1 : cand.obstacle;
      q["friction"] = cand.friction_coeff;
      q["stiffness"] = p.stiffness[k];
      q["area"] = area[cand.node];
      candidates.push_back(q);
    }
  }
  contact["candidates"] = candidates;
  contact["penalty_scale_factor"] = s.penalty.scale_factor;
  Json pairs = Json::array();
  for (const BodyPair& bp : s.body_pairs) {
    Json q = Json::object();
    q["slave"] = m.bodies[bp.slave].name;
    q["master"] = m.bodies[bp.master].name;
    q["friction"] = bp.friction;
    pairs.push_back(q);
  }
  contact["body_pairs"] = pairs;
  j["contact"] = contact;

  Json time = Json::object();
  time["dt"] = s.dt;
  time["end"] = s.end_time;
  time["steps"] = static_cast<long>(std::ceil(s.end_time / s.dt - 1e-9));
  time["dt_auto"] = pc.dt_auto();
  time["critical_dt"] = m.critical_dt;
  j["time"] = time;
}

}  // namespace

Json external_case_json(const PreparedCase& pc) {
  const CaseSpec& c = pc.spec;
  Json j = Json::object();
  j["format"] = "ricochet-external-case";
  j["version"] = 1;
  j["case"] = c.name;
  std::error_code ec;
  const std::filesystem::path abs = std::filesystem::absolute(c.file, ec);
  j["case_file"] = ec ? c.file : abs.lexically_normal().string();
  j["scheme"] = c.external.name;
  j["dimension"] = c.dimension;
  j["plane"] = c.dimension == 2 ? Json(plane_name(c.plane)) : Json();
  if (c.dimension == 3)
    add_model<3>(j, pc);
  else
    add_model<2>(j, pc);
  Json output = Json::object();
  output["interval"] = pc.settings.sample_interval;
  output["stress_measure"] = stress_measure_name(pc.settings.stress_measure);
  output["probes"] = probes_json(pc);
  j["output"] = output;
  j["threads"] = resolve_threads(c.threads);
  j["options"] = parse_json(c.external.options_json);
  return j;
}

}  // namespace ricochet
