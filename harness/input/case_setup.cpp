#include "harness/input/case_setup.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numbers>
#include <stdexcept>
#include <utility>

#include <Eigen/Geometry>

#include "harness/input/gmsh_reader.hpp"
#include "harness/input/input_error.hpp"
#include "harness/input/run_plan.hpp"
#include "solver/contact/body_contact3.hpp"
#include "solver/schemes/relaxation.hpp"
#include "solver/schemes/time_step.hpp"

namespace ricochet {
namespace {

// The 2D mesh of a 2D source (a 2D generator or Gmsh file) as generated or read, distorted.
Mesh build_planar_source(const CaseSpec& c, const MeshSpec& m) {
  Mesh mesh;
  try {
    if (const auto* r = std::get_if<RectangleSpec>(&m.source))
      mesh = make_rectangle(*r);
    else if (const auto* a = std::get_if<ArcPlateSpec>(&m.source))
      mesh = make_arc_plate(*a);
    else if (const auto* d = std::get_if<DiskSpec>(&m.source))
      mesh = make_disk(*d);
    else
      mesh = read_gmsh(std::get<GmshFile>(m.source).path);
  } catch (const InputError& e) {
    throw InputError(c.file + ": " + m.where + ": " + e.what());
  }
  // Distortion (generated meshes) moves interior nodes of the mesh as generated, before the
  // scale, rotation and offset below, so those transform the distorted mesh rigidly.
  try {
    distort_mesh(mesh, m.distort, m.seed);
  } catch (const InputError& e) {
    throw InputError(c.file + ": " + m.where + ".distort: " + e.what());
  }
  return mesh;
}

// Areas, volumes, masses and stiffnesses are squares and higher powers of lengths, which a
// double must hold: the span of a mesh is kept within [1e-100, 1e100] m.
template <class Nodes>
void check_span(const CaseSpec& c, const MeshSpec& m, const Nodes& nodes) {
  if (nodes.cols() == 0) return;
  const double size = (nodes.rowwise().maxCoeff() - nodes.rowwise().minCoeff()).maxCoeff();
  if (!(size >= 1e-100 && size <= 1e100)) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3g", size);
    throw InputError(c.file + ": " + m.where + (m.scale != 1.0 ? ".scale" : "") + ": the mesh spans " + buf +
                     " m; allowed: 1e-100 ... 1e100 m (a double must hold the squares of its lengths)");
  }
}

Mesh build_mesh(const CaseSpec& c, const MeshSpec& m) {
  Mesh mesh = build_planar_source(c, m);
  // x' = R (s x - c) + c + offset: scaled, rotated counterclockwise about c, translated.
  const Vec2 about = m.rotate_about.head<2>(), offset = m.offset.head<2>();
  mesh.nodes *= m.scale;
  if (m.rotate != 0.0) {
    const double a = m.rotate * std::numbers::pi / 180.0;
    Mat2 r;
    r << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
    mesh.nodes.colwise() -= about;
    mesh.nodes = (r * mesh.nodes).eval();
    mesh.nodes.colwise() += about;
  }
  mesh.nodes.colwise() += offset;
  check_span(c, m, mesh.nodes);
  return mesh;
}

// A 3D mesh: the box or ball generator, a 3D Gmsh file, or a 2D source extruded; then
// x' = R (s x - c) + c + offset with R the rotation by `rotate` degrees about rotate_axis
// (right-handed), c = rotate_about.
Mesh3 build_mesh3(const CaseSpec& c, const MeshSpec& m) {
  Mesh3 mesh;
  try {
    if (const auto* b = std::get_if<BoxSpec>(&m.source))
      mesh = make_box(*b);
    else if (const auto* ball = std::get_if<BallSpec>(&m.source))
      mesh = make_ball(*ball);
    else if (const auto* g = std::get_if<GmshFile>(&m.source); g && !m.extrude)
      mesh = read_gmsh3(g->path);
  } catch (const InputError& e) {
    throw InputError(c.file + ": " + m.where + ": " + e.what());
  }
  if (m.extrude) {
    const Mesh planar = build_planar_source(c, m);
    try {
      mesh = extrude(planar, m.extrude->thickness, m.extrude->layers);
    } catch (const InputError& e) {
      throw InputError(c.file + ": " + m.where + ".extrude: " + e.what());
    }
  }
  mesh.nodes *= m.scale;
  if (m.rotate != 0.0) {
    const Mat3 r = Eigen::AngleAxisd(m.rotate * std::numbers::pi / 180.0, m.rotate_axis).toRotationMatrix();
    mesh.nodes.colwise() -= m.rotate_about;
    mesh.nodes = (r * mesh.nodes).eval();
    mesh.nodes.colwise() += m.rotate_about;
  }
  mesh.nodes.colwise() += m.offset;
  check_span(c, m, mesh.nodes);
  return mesh;
}

Material make_material(const MaterialSpec& m, PlaneMode plane) {
  if (m.model == "neo_hookean") return NeoHookean::make(m.young, m.poisson, m.density, plane);
  if (m.model == "blatz_ko") return BlatzKo::make(m.shear_modulus, m.density, plane);
  if (m.model == "mooney_rivlin")
    return MooneyRivlin::make(m.c10, m.c01, m.bulk_modulus, m.density, plane);
  return StVenantKirchhoff::make(m.young, m.poisson, m.density, plane);
}

template <class MeshT>
std::string set_names(const MeshT& m) {
  std::string s;
  for (const auto& [name, nodes] : m.node_sets) s += (s.empty() ? "" : ", ") + name;
  return s.empty() ? "(none)" : s;
}

int body_index(const CaseSpec& c, const std::string& name, const std::string& where, const char* key) {
  for (std::size_t i = 0; i < c.bodies.size(); ++i)
    if (c.bodies[i].name == name) return static_cast<int>(i);
  throw InputError(c.file + ": " + where + "." + key + ": no body named \"" + name + "\"");
}

template <class MeshT>
const std::vector<int>& node_set(const CaseSpec& c, const MeshT& m, const std::string& name,
                                 const std::string& where, const char* key) {
  const auto it = m.node_sets.find(name);
  if (it == m.node_sets.end())
    throw InputError(c.file + ": " + where + "." + key + ": no node set \"" + name +
                     "\" in this body; available: " + set_names(m));
  return it->second;
}


// A node that starts inside an obstacle or inside another body of a contact pair is an input
// error, not a divergence at t = 0: the first line that names what, where and how deep.
// Tolerance: depth > 1e-9 of the body's size (the diagonal of its reference bounding box), so
// a node placed on a surface (a gap of 0 up to round-off) is not reported.
template <class M, class Body>
double body_size(const M& model, const Body& b) {
  const auto x = model.ref.middleCols(b.first_node, b.num_nodes);
  return (x.rowwise().maxCoeff() - x.rowwise().minCoeff()).norm();
}

// "(x, y)" or "(x, y, z)", each "%.6g".
template <class V>
std::string point_text(const V& x) {
  std::string s = "(";
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.6g", x[k]);
    s += (k ? ", " : "") + std::string(buf);
  }
  return s + ")";
}

std::string depth_text(double d) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.3g m", d);
  return buf;
}

// Whether a point lies inside a body and how deep: the even-odd rule over the body's boundary
// edges (which close every outline and hole) and the distance to the nearest edge. The edges are
// bucketed in a uniform grid over their bounding box, so that a query visits the edges of the
// cells between it and the grid's nearest side (the even-odd ray) and the edges in rings of
// cells around it (the distance), not every edge: checking every slave node of a contact pair costs about
// (slave nodes + master edges), not their product (two bars of 20000 x 1 cells in a contact
// pair took 21.5 s before the first step with the product; docs/reliability.md, Fuzzing).
// Only a point within rounding of the boundary can be judged otherwise than by a ray along +x
// over all edges, and its depth is then below the check's tolerance.
class BoundaryGrid {
 public:
  BoundaryGrid(const Model<2>& model, const BodyInfo<2>& body) : model_(model), edges_(body.boundary_edges) {
    if (edges_.empty()) return;
    lo_ = Vec2::Constant(std::numeric_limits<double>::infinity());
    hi_ = -lo_;
    double length = 0.0;
    for (const BoundaryEdge& e : edges_) {
      const Vec2 a = model.ref.col(e.a), b = model.ref.col(e.b);
      lo_ = lo_.cwiseMin(a).cwiseMin(b);
      hi_ = hi_.cwiseMax(a).cwiseMax(b);
      length += (b - a).norm();
    }
    const double n = static_cast<double>(edges_.size());
    const Vec2 span = hi_ - lo_;
    // Cells about the mean edge length; coarser while there would be more than about 4 cells
    // or 16 cell entries per edge (a few long edges across a fine grid).
    h_ = length / n;
    if (!(h_ > 0.0) || !std::isfinite(h_)) h_ = std::max(span.maxCoeff(), 1.0);
    for (;;) {
      const double nx = std::floor(span.x() / h_) + 1.0, ny = std::floor(span.y() / h_) + 1.0;
      double entries = 0.0;
      if (nx * ny <= 4.0 * n + 16.0) {
        for (const BoundaryEdge& e : edges_) {
          const auto [c0, r0, c1, r1] = cell_box(e, static_cast<int>(nx), static_cast<int>(ny));
          entries += double(c1 - c0 + 1) * double(r1 - r0 + 1);
        }
        if (entries <= 16.0 * n + 16.0) {
          nx_ = static_cast<int>(nx), ny_ = static_cast<int>(ny);
          break;
        }
      }
      h_ *= 2.0;
    }
    // Cell lists, compressed: first_[cell] .. first_[cell + 1] in items_.
    first_.assign(static_cast<std::size_t>(nx_) * ny_ + 1, 0);
    auto each_cell = [&](const BoundaryEdge& e, auto&& fn) {
      const auto [c0, r0, c1, r1] = cell_box(e, nx_, ny_);
      for (int r = r0; r <= r1; ++r)
        for (int c = c0; c <= c1; ++c) fn(static_cast<std::size_t>(r) * nx_ + c);
    };
    for (const BoundaryEdge& e : edges_) each_cell(e, [&](std::size_t k) { ++first_[k + 1]; });
    for (std::size_t k = 1; k < first_.size(); ++k) first_[k] += first_[k - 1];
    items_.resize(first_.back());
    std::vector<int> fill(first_.begin(), first_.end() - 1);
    for (int i = 0; i < static_cast<int>(edges_.size()); ++i)
      each_cell(edges_[i], [&](std::size_t k) { items_[fill[k]++] = i; });
    seen_.assign(edges_.size(), -1);
  }

  // The distance from x to the boundary if x is inside the body, else a negative number. A
  // distance found to be at most `beat` is returned as soon as it is found (the caller wants
  // only a deeper node than one it has).
  double depth_inside(const Vec2& x, double beat) {
    if (edges_.empty() || !(x.x() >= lo_.x() && x.x() <= hi_.x() && x.y() >= lo_.y() && x.y() <= hi_.y()))
      return -1.0;  // outside the bounding box of a closed outline: not inside
    const int cx = col(x.x()), cy = row(x.y());
    // The even-odd rule along the axis ray (+x, -x, +y or -y) that crosses the fewest cells to
    // the grid's edge: a long thin body is crossed across, not along. An edge that the ray
    // crosses spans x's other coordinate, so it has an entry in the ray's row (or column); its
    // crossing lies within its extent along the ray, so not behind x's cell (one cell more
    // behind for a crossing rounded past the extent's end).
    const int axis = std::min(nx_ - cx, cx + 1) <= std::min(ny_ - cy, cy + 1) ? 0 : 1;  // 0: along x
    const int along = axis == 0 ? cx : cy, count = axis == 0 ? nx_ : ny_;
    const bool forward = axis == 0 ? nx_ - cx <= cx + 1 : ny_ - cy <= cy + 1;
    const int other = 1 - axis;
    bool inside = false;
    ++query_;
    const int from = forward ? std::max(along - 1, 0) : 0;
    const int to = forward ? count - 1 : std::min(along + 1, count - 1);
    for (int k = from; k <= to; ++k) {
      const std::size_t c = axis == 0 ? cell(k, cy) : cell(cx, k);
      for (int j = first_[c]; j < first_[c + 1]; ++j) {
        const int i = items_[j];
        if (seen_[i] == query_) continue;
        seen_[i] = query_;
        const Vec2 a = model_.ref.col(edges_[i].a), b = model_.ref.col(edges_[i].b);
        if ((a[other] > x[other]) != (b[other] > x[other])) {
          const double cross = a[axis] + (x[other] - a[other]) * (b[axis] - a[axis]) / (b[other] - a[other]);
          if (forward ? x[axis] < cross : x[axis] > cross) inside = !inside;
        }
      }
    }
    if (!inside) return -1.0;
    // The nearest edge: rings of cells at Chebyshev distance 0, 1, 2, ... from x's cell. An
    // edge not met up to ring k lies in cells of ring k + 1 or beyond, at least k h from x.
    ++query_;
    double dist = std::numeric_limits<double>::infinity();
    for (int ring = 0; ring <= std::max(nx_, ny_); ++ring) {
      for (int r = cy - ring; r <= cy + ring; ++r) {
        if (r < 0 || r >= ny_) continue;
        const bool edge_row = r == cy - ring || r == cy + ring;
        for (int c = cx - ring; c <= cx + ring; c += (edge_row || ring == 0) ? 1 : 2 * ring) {
          if (c < 0 || c >= nx_) continue;
          for (int k = first_[cell(c, r)]; k < first_[cell(c, r) + 1]; ++k) {
            const int i = items_[k];
            if (seen_[i] == query_) continue;
            seen_[i] = query_;
            const Vec2 a = model_.ref.col(edges_[i].a), b = model_.ref.col(edges_[i].b);
            const Vec2 ab = b - a;
            const double t = std::clamp((x - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
            dist = std::min(dist, (a + t * ab - x).norm());
          }
        }
      }
      if (dist <= ring * h_ || dist <= beat) break;
    }
    return dist;
  }

 private:
  int col(double x) const { return std::clamp(static_cast<int>(std::min((x - lo_.x()) / h_, 1e9)), 0, nx_ - 1); }
  int row(double y) const { return std::clamp(static_cast<int>(std::min((y - lo_.y()) / h_, 1e9)), 0, ny_ - 1); }
  std::size_t cell(int c, int r) const { return static_cast<std::size_t>(r) * nx_ + c; }
  // The cells (c0, r0) .. (c1, r1) that an edge's bounding box covers in an nx x ny grid.
  std::array<int, 4> cell_box(const BoundaryEdge& e, int nx, int ny) const {
    const Vec2 a = model_.ref.col(e.a), b = model_.ref.col(e.b);
    auto at = [&](double v, double lo, int n) {
      return std::clamp(static_cast<int>(std::min((v - lo) / h_, 1e9)), 0, n - 1);
    };
    return {at(std::min(a.x(), b.x()), lo_.x(), nx), at(std::min(a.y(), b.y()), lo_.y(), ny),
            at(std::max(a.x(), b.x()), lo_.x(), nx), at(std::max(a.y(), b.y()), lo_.y(), ny)};
  }

  const Model<2>& model_;
  const std::vector<BoundaryEdge>& edges_;
  Vec2 lo_ = Vec2::Zero(), hi_ = Vec2::Zero();
  double h_ = 1.0;  // cell size [m]
  int nx_ = 1, ny_ = 1;
  std::vector<int> first_, items_;
  std::vector<int> seen_;  // the last query that tested each edge
  int query_ = 0;
};

// Nodes inside a rigid obstacle, in either dimension.
template <class M>
void check_obstacle_penetration(const CaseSpec& c, const M& model, const std::vector<ObstacleOf<M>>& obstacles) {
  for (std::size_t bi = 0; bi < model.bodies.size(); ++bi) {
    const auto& b = model.bodies[bi];
    const double tol = 1e-9 * body_size(model, b);
    for (std::size_t o = 0; o < obstacles.size(); ++o) {
      int worst = -1;
      double depth = tol;
      for (int node : b.boundary_nodes) {
        const double d = -closest(obstacles[o], model.ref.col(node)).gap;
        if (d > depth) depth = d, worst = node;
      }
      if (worst >= 0)
        throw InputError(c.file + ": " + c.bodies[bi].where + " (\"" + b.name + "\") node " +
                         std::to_string(worst - b.first_node) + " at " + point_text(model.ref.col(worst)) +
                         " starts inside " + c.obstacles[o].where + " (\"" + c.obstacles[o].name + "\"), " +
                         depth_text(depth) + " deep (the deepest node); move the body or the obstacle");
    }
  }
}

// The error of a contact pair whose slave node `worst` (a global index) starts `depth` inside
// the master body, in either dimension.
template <class M, class Body>
InputError slave_inside_master(const CaseSpec& c, const M& model, const Body& slave, const Body& master, int worst,
                               double depth) {
  return InputError(c.file + ": body \"" + slave.name + "\" node " + std::to_string(worst - slave.first_node) +
                    " at " + point_text(model.ref.col(worst)) + " starts inside body \"" + master.name +
                    "\" of a contact pair, " + depth_text(depth) + " deep (the deepest node); move one of the bodies");
}

void check_initial_penetration(const CaseSpec& c, const Model<2>& model, const RunSettings& s) {
  check_obstacle_penetration(c, model, obstacles_of(s, model));
  for (std::size_t k = 0; k < s.body_pairs.size(); ++k) {
    const BodyInfo<2>& slave = model.bodies[s.body_pairs[k].slave];
    const BodyInfo<2>& master = model.bodies[s.body_pairs[k].master];
    const double tol = 1e-9 * std::max(body_size(model, slave), body_size(model, master));
    int worst = -1;
    double depth = tol;
    BoundaryGrid grid(model, master);
    for (int node : slave.boundary_nodes) {
      const double d = grid.depth_inside(model.ref.col(node), depth);
      if (d > depth) depth = d, worst = node;
    }
    if (worst >= 0) throw slave_inside_master(c, model, slave, master, worst, depth);
  }
}

// 3D: nodes inside a rigid obstacle, and slave nodes inside their pair's master body (the
// signed distance to its boundary faces, body_contact3.hpp; nodes outside the master's
// bounding box are skipped).
void check_initial_penetration(const CaseSpec& c, const Model<3>& model, const RunSettings& s) {
  check_obstacle_penetration(c, model, obstacles_of(s, model));
  const Eigen::VectorXd u0 = Eigen::VectorXd::Zero(model.num_dofs());
  auto ref = [&](int j) -> Vec3 { return model.ref.col(j); };
  for (std::size_t k = 0; k < s.body_pairs.size(); ++k) {
    const BodyInfo<3>& slave = model.bodies[s.body_pairs[k].slave];
    const BodyInfo<3>& master = model.bodies[s.body_pairs[k].master];
    const double tol = 1e-9 * std::max(body_size(model, slave), body_size(model, master));
    const Surface3 surf = make_surface3(model, s.body_pairs[k].master);
    const BoxD<3> box = surface_box(surf, ref, 0.0);
    int worst = -1;
    double depth = tol;
    for (int node : slave.boundary_nodes) {
      if (!box.contains(model.ref.col(node))) continue;
      const double d = depth_inside(model, surf, u0, model.ref.col(node));
      if (d > depth) depth = d, worst = node;
    }
    if (worst >= 0) throw slave_inside_master(c, model, slave, master, worst, depth);
  }
}

Material3 make_material3(const MaterialSpec& m) {
  if (m.model == "neo_hookean") return NeoHookean3::make(m.young, m.poisson, m.density);
  if (m.model == "blatz_ko") return BlatzKo3::make(m.shear_modulus, m.density);
  if (m.model == "mooney_rivlin") return MooneyRivlin3::make(m.c10, m.c01, m.bulk_modulus, m.density);
  return StVenantKirchhoff3::make(m.young, m.poisson, m.density);
}

// The body's `[[bodies.node_sets]]`: the nodes inside or on each box, in either dimension.
template <class MeshT>
void add_box_node_sets(const CaseSpec& c, const BodySpec& b, MeshT& mesh) {
  const int d = static_cast<int>(mesh.nodes.rows());
  for (const BoxNodeSet& s : b.node_sets) {
    std::vector<int> nodes;
    for (int i = 0; i < mesh.num_nodes(); ++i) {
      bool in = true;
      for (int k = 0; k < d; ++k) in = in && mesh.nodes(k, i) >= s.lo[k] && mesh.nodes(k, i) <= s.hi[k];
      if (in) nodes.push_back(i);
    }
    if (nodes.empty())
      throw InputError(c.file + ": " + b.where + ".node_sets: box of \"" + s.name + "\" selects no node");
    mesh.node_sets[s.name] = std::move(nodes);
  }
}

// The case's meshes and the model of its bodies, in 2D or 3D.
void build_bodies(const CaseSpec& c, CaseBodies<2>& p) {
  std::vector<BodyInput<2>> inputs;
  for (const BodySpec& b : c.bodies) {
    Mesh mesh = build_mesh(c, c.meshes.at(b.mesh));
    add_box_node_sets(c, b, mesh);
    BodyInput<2> in;
    in.name = b.name;
    in.material = make_material(b.material, c.plane);
    in.quad_element = b.element == "q4" ? QuadElement::full_2x2 : QuadElement::one_point_hourglass;
    in.hourglass = b.hourglass;
    in.thickness = b.thickness;
    in.initial_velocity = b.velocity.head<2>();
    in.mesh = mesh;
    p.meshes.push_back(std::move(mesh));
    inputs.push_back(std::move(in));
  }
  try {
    p.model = build_model(inputs, c.plane, c.gravity.head<2>());
  } catch (const std::invalid_argument& e) {
    throw InputError(c.file + ": bodies: " + e.what());
  }
}

void build_bodies(const CaseSpec& c, CaseBodies<3>& p) {
  std::vector<BodyInput<3>> inputs;
  for (const BodySpec& b : c.bodies) {
    Mesh3 mesh = build_mesh3(c, c.meshes.at(b.mesh));
    add_box_node_sets(c, b, mesh);
    if (c.scene_rotation) mesh.nodes = (*c.scene_rotation * mesh.nodes).eval();
    BodyInput<3> in;
    in.name = b.name;
    in.material = make_material3(b.material);
    in.hex_element = b.element == "hex8" ? HexElement::full_2x2x2 : HexElement::one_point_hourglass;
    in.hourglass = b.hourglass;
    in.initial_velocity = c.turned(b.velocity);
    in.mesh = mesh;
    p.meshes.push_back(std::move(mesh));
    inputs.push_back(std::move(in));
  }
  try {
    p.model = build_model(inputs, c.turned(c.gravity));
  } catch (const std::invalid_argument& e) {
    throw InputError(c.file + ": bodies: " + e.what());
  }
}

const std::vector<Mesh>& meshes_of(const PreparedCase& p, const Model<2>&) { return p.meshes<2>(); }
const std::vector<Mesh3>& meshes_of(const PreparedCase& p, const Model<3>&) { return p.meshes<3>(); }
const Obstacle& shape_of(const ObstacleSpec& o, const Model<2>&) { return o.shape; }
const Obstacle3& shape_of(const ObstacleSpec& o, const Model<3>&) { return o.shape3; }
// An obstacle turned by the case's scene rotation (3D).
const Obstacle& turned(const CaseSpec&, const Obstacle& o) { return o; }
Obstacle3 turned(const CaseSpec& c, const Obstacle3& o) {
  if (!c.scene_rotation) return o;
  const Mat3& r = *c.scene_rotation;
  Obstacle3 t = o;
  t.point = r * o.point;
  t.normal = r * o.normal;
  t.center = r * o.center;
  t.axes = r * o.axes;
  t.axis = r * o.axis;
  return t;
}

// Everything after the bodies, in either dimension D = M::kDim: initial velocities, prescribed
// DOFs, loads, obstacles, contact, the time step, relaxation, probes.
template <class M>
void prepare_run(PreparedCase& p, M& model) {
  constexpr int D = M::kDim;
  using Vec = Eigen::Matrix<double, D, 1>;
  const CaseSpec& c = p.spec;
  const auto& meshes = meshes_of(p, model);
  // A spinning start: v = velocity + omega x (x - c) at every node of the body, c the given
  // centre or the body's centre of mass (lumped masses), so its linear momentum stays m v.
  for (std::size_t bi = 0; bi < c.bodies.size(); ++bi) {
    const Vec3 omega = c.turned(c.bodies[bi].angular_velocity);
    if (omega == Vec3::Zero()) continue;
    const auto& b = model.bodies[bi];
    Vec centre = Vec::Zero();
    if (c.bodies[bi].rotation_center) {
      centre = c.turned(*c.bodies[bi].rotation_center).template head<D>();
    } else {
      double mass = 0.0;
      for (int i = b.first_node; i < b.first_node + b.num_nodes; ++i) {
        centre += model.mass(D * i) * model.ref.col(i);
        mass += model.mass(D * i);
      }
      centre /= mass;
    }
    for (int i = b.first_node; i < b.first_node + b.num_nodes; ++i) {
      const Vec r = model.ref.col(i) - centre;
      if constexpr (D == 2)
        model.initial_velocity.template segment<2>(2 * i) += omega.z() * Vec2(-r.y(), r.x());
      else
        model.initial_velocity.template segment<3>(3 * i) += omega.cross(r);
    }
  }
  // [[initial_velocity]]: a node set's own velocity, in file order (a later one wins).
  for (const InitialVelocitySpec& iv : c.initial_velocities) {
    const int bi = body_index(c, iv.body, iv.where, "body");
    const int node0 = model.bodies[bi].first_node;
    for (int local : node_set(c, meshes[bi], iv.nodes, iv.where, "nodes"))
      model.initial_velocity.template segment<D>(D * (node0 + local)) = c.turned(iv.velocity).template head<D>();
  }

  RunSettings& s = p.settings;
  s.end_time = c.end_time;
  s.sample_interval = c.sample_interval;
  s.field_times = c.field_times;
  s.stress_measure = c.stress_measure;
  s.stress_every_step = c.stress_every_step;
  s.energy_growth_limit = c.energy_growth_limit;
  s.monitor_every = c.monitor_every;
  s.threads = c.threads;
  s.adapt_threads = c.adapt_threads;

  std::map<int, std::string> prescribed_by;  // dof -> boundary key, to reject conflicts
  for (const BoundarySpec& b : c.boundaries) {
    const int bi = body_index(c, b.body, b.where, "body");
    const int node0 = model.bodies[bi].first_node;
    for (int local : node_set(c, meshes[bi], b.nodes, b.where, "nodes")) {
      for (int k = 0; k < D; ++k) {
        const std::optional<double>& value = k == 0 ? b.x : k == 1 ? b.y : b.z;
        if (!value) continue;
        const int dof = D * (node0 + local) + k;
        const auto [it, fresh] = prescribed_by.emplace(dof, b.where);
        if (!fresh)
          throw InputError(c.file + ": " + b.where + ": node " + std::to_string(local) + " direction " +
                           ("xyz"[k] + std::string()) + " is already prescribed by " + it->second);
        s.prescribed.push_back({dof, b.kind, *value, b.ramp});
      }
    }
  }

  // [[loads]]: the total force shared over the set's nodes by lumped mass (m_i / sum m) or
  // equally, one NodalLoad per loaded DOF.
  for (const LoadSpec& l : c.loads) {
    const int bi = body_index(c, l.body, l.where, "body");
    const int node0 = model.bodies[bi].first_node;
    const std::vector<int>& nodes = node_set(c, meshes[bi], l.nodes, l.where, "nodes");
    const Vec3 force = c.turned(l.force);
    double total = 0.0;
    for (int local : nodes) total += l.by_mass ? model.mass[D * (node0 + local)] : 1.0;
    for (int local : nodes) {
      const double share = (l.by_mass ? model.mass[D * (node0 + local)] : 1.0) / total;
      for (int k = 0; k < D; ++k)
        if (force[k] != 0.0) s.loads.push_back({D * (node0 + local) + k, force[k] * share, l.start, l.ramp});
    }
  }

  for (const ObstacleSpec& o : c.obstacles) obstacles_in(s, model).push_back(turned(c, shape_of(o, model)));
  s.friction.assign(c.bodies.size(), std::vector<double>(c.obstacles.size(), 0.0));
  for (std::size_t b = 0; b < c.bodies.size(); ++b)
    for (std::size_t o = 0; o < c.obstacles.size(); ++o) {
      const auto it = c.obstacles[o].friction_by_body.find(c.bodies[b].name);
      s.friction[b][o] = it != c.obstacles[o].friction_by_body.end() ? it->second : c.obstacles[o].friction;
    }
  for (const ContactPairSpec& cp : c.contact_pairs) {
    const int slave = body_index(c, cp.slave, cp.where, "slave"), master = body_index(c, cp.master, cp.where, "master");
    s.body_pairs.push_back({slave, master, cp.friction, cp.name});
    if (cp.two_pass) s.body_pairs.push_back({master, slave, cp.friction, cp.name});
  }
  check_initial_penetration(c, model, s);
  s.contact = c.contact;
  s.penalty = c.penalty;
  s.contact_method = c.scheme == Scheme::explicit_penalty ? RunSettings::ContactMethod::penalty
                                                    : RunSettings::ContactMethod::bipotential;
  // The soft constraint's springs k1 = soft_scale m / (2 dt^2) use the step the run would have
  // without them: the elements' automatic step, or the fixed time.dt (LS-DYNA: the initial step).
  if (s.penalty.soft_scale > 0.0) s.penalty.soft_dt = p.dt_auto() ? c.dt_safety * model.critical_dt : *c.dt;
  // The automatic step: safety x the solver's critical step, which with penalty contact is the
  // combined limit of elements and springs (min(dt_e, dt_p) alone is not stable when the two
  // are close: tests/solver/contact/test_penalty_contact.cpp).
  // It also gives the springs' own limit, which the summary reports for fixed steps too.
  const double critical = critical_time_step(model, s, &p.penalty_critical_dt);
  s.dt = p.dt_auto() ? c.dt_safety * critical : *c.dt;
  // [relaxation]: the explicit schemes relax at half the run's step, the implicit scheme with
  // the semi-explicit loop at half the automatic explicit step (safety x the elements' critical
  // step) (solver/schemes/relaxation.hpp, kRelaxationStepFactor).
  s.relaxation.enabled = c.relaxation.enabled;
  s.relaxation.tolerance = c.relaxation.tolerance;
  s.relaxation.max_steps = c.relaxation.max_steps;
  s.relaxation.dt = kRelaxationStepFactor * (c.scheme == Scheme::implicit ? c.dt_safety * model.critical_dt : s.dt);
  // The variable step (explicit schemes, time.dt = "auto"): the same rule on the current
  // configuration every dt_update_interval steps (StepControl, solver/schemes/time_step.hpp).
  s.dt_update_interval = c.dt_update_interval;
  s.dt_safety = c.dt_safety;
  s.dt_min_ratio = c.dt_min_ratio;

  for (const ProbeSpec& pr : c.probes) {
    const int bi = body_index(c, pr.body, pr.where, "body");
    const auto& m = meshes[bi];
    ProbeInfo info{pr.name, pr.body, 0, Vec3::Zero(), 0.0};
    int local = 0;
    if (pr.point) {
      double best = 1e300;
      for (int i = 0; i < m.num_nodes(); ++i) {
        const double d = (m.nodes.col(i) - c.turned(*pr.point).template head<D>()).norm();
        if (d < best) best = d, local = i;
      }
      info.distance = best;
    } else {
      local = node_set(c, m, pr.node_set, pr.where, "node_set").front();
    }
    info.node = model.bodies[bi].first_node + local;
    info.position.template head<D>() = m.nodes.col(local);
    p.probes.push_back(info);
    s.probes.push_back({pr.name, info.node});
  }
}

}  // namespace

PreparedCase prepare_case(const CaseSpec& spec) {
  PreparedCase p;
  p.spec = spec;
  check_mesh_plan(p.spec);  // before a mesh is built: the generated meshes' memory
  if (p.spec.dimension == 3)
    build_bodies(p.spec, p.bodies.emplace<CaseBodies<3>>());
  else
    build_bodies(p.spec, p.bodies.emplace<CaseBodies<2>>());
  std::visit([&](auto& bodies) { prepare_run(p, bodies.model); }, p.bodies);
  check_run_plan(p);  // steps, history rows, memory, the automatic step against time.end
  return p;
}

RunResult run_case(const PreparedCase& pc, const ProgressFn& progress) {
  if (pc.spec.scheme == Scheme::external)
    throw std::logic_error("run_case: an external scheme runs through run_external (harness/external/external_run.hpp)");
  return with_model(pc, [&](const auto& model) {
    return pc.spec.scheme == Scheme::implicit ? run_implicit(model, pc.settings, pc.spec.implicit, progress)
                                              : run_explicit(model, pc.settings, progress);
  });
}

}  // namespace ricochet
