#include "solver/model/model.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace ricochet {
namespace {

// What building a model of either dimension does alike: the arrays sized for all bodies, per
// body its range, its nodes and initial velocity after the previous bodies', its cells
// (cells(model, body index, input, first node, first cell, rho, c_p): the dimension's element
// blocks, lumped masses and cell_dt), and at the end the inverse masses and the critical cell.

[[noreturn]] void bad_cell(const std::string& body, int cell, const char* what) {
  throw std::invalid_argument("body '" + body + "' cell " + std::to_string(cell) + ": " + what);
}

// The reference corners of cell c of mesh m, D x N.
template <int N, class MeshT>
auto corners(const MeshT& m, const std::array<int, N>& c) {
  Eigen::Matrix<double, decltype(MeshT::nodes)::RowsAtCompileTime, N> x;
  for (int a = 0; a < N; ++a) x.col(a) = m.nodes.col(c[a]);
  return x;
}

// Adds `value` to each of node i's D DOF masses.
template <int D>
void add_node_mass(Model<D>& model, int node, double value) {
  for (int k = 0; k < D; ++k) model.mass(D * node + k) += value;
}

// Adds masses(a) to corner a of cell c (mesh numbering, the body's first node node0).
template <int D, class Cell, class Masses>
void add_cell_masses(Model<D>& model, int node0, const Cell& c, const Masses& masses) {
  for (int a = 0; a < static_cast<int>(c.size()); ++a) add_node_mass(model, node0 + c[a], masses(a));
}

// A body's range and boundary in global numbering.
BodyInfo<2> body_info(const BodyInput<2>& in, int node0, int cell0) {
  const Mesh& m = in.mesh;
  if (!(in.thickness > 0.0)) throw std::invalid_argument("body '" + in.name + "': thickness must be > 0");
  std::vector<BoundaryEdge> edges = boundary_edges(m);
  for (BoundaryEdge& e : edges) {
    e.a += node0;
    e.b += node0;
  }
  return {in.name, node0, m.num_nodes(), cell0, m.num_cells(), in.thickness,
          in.quad_element, in.material, edge_nodes(edges), std::move(edges)};
}

BodyInfo<3> body_info(const BodyInput<3>& in, int node0, int cell0) {
  const Mesh3& m = in.mesh;
  std::vector<BoundaryFace> faces = boundary_faces(m);
  for (BoundaryFace& f : faces) {
    for (int k = 0; k < f.corners; ++k) f.nodes[k] += node0;
    f.cell += cell0;
  }
  std::vector<int> face_node_list = face_nodes(faces);
  return {in.name, node0, m.num_nodes(), cell0, m.num_cells(), in.hex_element, in.material,
          std::move(face_node_list), std::move(faces)};
}

template <int D, class Cells>
void assemble(Model<D>& model, const std::vector<BodyInput<D>>& inputs, Cells&& cells) {
  int total_nodes = 0, total_cells = 0;
  for (const auto& b : inputs) {
    total_nodes += b.mesh.num_nodes();
    total_cells += b.mesh.num_cells();
  }
  model.ref.resize(D, total_nodes);
  model.mass = Eigen::VectorXd::Zero(D * total_nodes);
  model.initial_velocity.resize(D * total_nodes);
  model.cell_dt.assign(total_cells, 0.0);

  int node0 = 0, cell0 = 0;
  for (int bi = 0; bi < static_cast<int>(inputs.size()); ++bi) {
    const BodyInput<D>& in = inputs[bi];
    const auto& m = in.mesh;
    model.bodies.push_back(body_info(in, node0, cell0));
    const double rho = material_density(in.material);
    const double cp = material_wave_speed(in.material);
    if (!(rho > 0.0)) throw std::invalid_argument("body '" + in.name + "': density must be > 0");
    if (!(cp > 0.0)) throw std::invalid_argument("body '" + in.name + "': wave speed must be > 0");
    model.ref.middleCols(node0, m.num_nodes()) = m.nodes;
    for (int i = 0; i < m.num_nodes(); ++i)
      model.initial_velocity.template segment<D>(D * (node0 + i)) = in.initial_velocity;
    cells(bi, in, node0, cell0, rho, cp);
    node0 += m.num_nodes();
    cell0 += m.num_cells();
  }
  for (int i = 0; i < model.num_dofs(); ++i)
    if (!(model.mass(i) > 0.0))
      throw std::invalid_argument("node " + std::to_string(i / D) + " belongs to no cell (zero mass)");
  model.inv_mass = model.mass.cwiseInverse();
  model.critical_dt = 1e300;
  for (int c = 0; c < total_cells; ++c)
    if (model.cell_dt[c] < model.critical_dt) {
      model.critical_dt = model.cell_dt[c];
      model.critical_cell = c;
    }
}

// Reference derivatives dN/dxi of the bilinear Q4 at (xi, eta); node order (-1,-1), (1,-1),
// (1,1), (-1,1). Rows = nodes.
Grad4 q4_dn_dxi(double xi, double eta) {
  Grad4 d;
  d << -(1 - eta), -(1 - xi), (1 - eta), -(1 + xi), (1 + eta), (1 + xi), -(1 + eta), (1 - xi);
  return 0.25 * d;
}

Eigen::Vector4d q4_shape(double xi, double eta) {
  return 0.25 * Eigen::Vector4d((1 - xi) * (1 - eta), (1 + xi) * (1 - eta), (1 + xi) * (1 + eta),
                                (1 - xi) * (1 + eta));
}


// Appends block b, unless it has no cell, to `blocks` with its lane layout (blocks2.hpp,
// blocks3.hpp): b.lane_conn and b.lane_geom from b.conn and value(e, j), the j-th of the n lane
// values of cell e (a batch's missing lanes repeat its last cell).
template <class Block, class Value>
void add_block(std::vector<Block>& blocks, Block& b, int n, const Value& value) {
  if (b.conn.empty()) return;
  constexpr int N = std::tuple_size_v<typename decltype(b.conn)::value_type>;
  const std::size_t batches = b.num_batches();
  b.lane_conn.assign(batches * N * kLanes, 0);
  b.lane_geom.assign(batches * n * kLanes, 0.0);
  for (std::size_t k = 0; k < batches; ++k)
    for (int l = 0; l < kLanes; ++l) {
      const std::size_t e = std::min(k * kLanes + l, b.conn.size() - 1);
      for (int i = 0; i < N; ++i) b.lane_conn[(k * N + i) * kLanes + l] = b.conn[e][i];
      for (int j = 0; j < n; ++j) b.lane_geom[(k * n + j) * kLanes + l] = value(e, j);
    }
  blocks.push_back(std::move(b));
}
// The 2D blocks' lane values: Geom::lane_value of each cell's geometry.
template <class Block>
void add_block(std::vector<Block>& blocks, Block& b) {
  using Geom = typename decltype(b.geom)::value_type;
  add_block(blocks, b, Geom::kLaneValues, [&b](std::size_t e, int j) { return b.geom[e].lane_value(j); });
}
// The 3D blocks' lane values: kValues per cell in `values`, cell after cell.
template <class Block>
void add_block(std::vector<Block>& blocks, Block& b, const std::vector<double>& values) {
  constexpr int n = Block::Lanes::kValues;
  add_block(blocks, b, n, [&values](std::size_t e, int j) { return values[e * n + j]; });
}

// The Walsh-Hadamard coefficients sum_a s_am x_a of 8 corner values for the monomials m = 0..7
// of kHexMonomialSigns (plain sums; the model's geometry only, computed once).
std::array<double, 8> hex_coefficients(const Eigen::Matrix<double, 8, 1>& x) {
  std::array<double, 8> c{};
  for (int m = 0; m < 8; ++m)
    for (int a = 0; a < 8; ++a) c[m] += kHexMonomialSigns[a][m] * x(a);
  return c;
}

}  // namespace

double q4_characteristic_length(const Eigen::Matrix<double, 2, 4>& x) {
  const double area = 0.5 * ((x(0, 2) - x(0, 0)) * (x(1, 3) - x(1, 1)) -
                             (x(0, 3) - x(0, 1)) * (x(1, 2) - x(1, 0)));
  const double d13 = (x.col(2) - x.col(0)).squaredNorm();
  const double d24 = (x.col(3) - x.col(1)).squaredNorm();
  return std::sqrt(2.0) * area / std::sqrt(d13 + d24);
}

double t3_characteristic_length(const Eigen::Matrix<double, 2, 3>& x) {
  // Lumped CST (m = rho A t / 3 per node, K = A t G^T D G with G u = grad u): omega_max^2 <=
  // (3 / rho) |D| s_max, |D| = 2 (lambda + mu) <= 2 rho c_p^2, s_max the largest eigenvalue of
  // S = sum_I B_I B_I^T = (sum_k e_k e_k^T) / (4 A^2) over the edge vectors e_k. So
  // 2 / omega_max >= L_e / c_p with L_e = sqrt(2/3) 2A / sqrt(eig_max(sum_k e_k e_k^T)).
  const Vec2 e1 = x.col(1) - x.col(0), e2 = x.col(2) - x.col(0), e3 = x.col(2) - x.col(1);
  const double area = 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());
  const Mat2 s = e1 * e1.transpose() + e2 * e2.transpose() + e3 * e3.transpose();
  const double half_diff = 0.5 * (s(0, 0) - s(1, 1));
  const double s_max = 0.5 * s.trace() + std::sqrt(half_diff * half_diff + s(0, 1) * s(0, 1));
  return std::sqrt(2.0 / 3.0) * 2.0 * area / std::sqrt(s_max);
}


Hex8Geom cell_geometry(const Model<3>& model, const Hex8Block& b, std::size_t e) {
  Hex8Geom g;
  hex8_geometry(cell_corners(model, b, e), g);
  return g;
}

Hex8OnePointGeom cell_geometry(const Model<3>& model, const Hex8OnePointBlock& b, std::size_t e) {
  Hex8OnePointGeom g;
  hex8_one_point_geometry(cell_corners(model, b, e), b.material, b.hourglass, g);
  return g;
}

Tet4Geom cell_geometry(const Model<3>& model, const Tet4Block& b, std::size_t e) {
  Tet4Geom g;
  tet4_geometry(cell_corners(model, b, e), g);
  return g;
}

Model<2> build_model(const std::vector<BodyInput<2>>& inputs, PlaneMode plane, const Vec2& gravity) {
  Model<2> model;
  model.plane = plane;
  model.gravity = gravity;
  assemble(model, inputs, [&](int bi, const BodyInput<2>& in, int node0, int cell0, double rho, double cp) {
    const Mesh& m = in.mesh;
    const double t = in.thickness;
  // Quads: geometry at 2x2 Gauss points (mass lumping by row sums uses it for both
  // formulations), then the formulation's own data.
  Q4FullBlock full;
  Q4HourglassBlock hg;
  full.body = hg.body = bi;
  full.first_cell = hg.first_cell = cell0;
  full.material = hg.material = in.material;
  hg.form = in.hourglass.form;
  const double g = 1.0 / std::sqrt(3.0);
  const double gp[4][2] = {{-g, -g}, {g, -g}, {g, g}, {-g, g}};
  for (int q = 0; q < static_cast<int>(m.quads.size()); ++q) {
    const auto& c = m.quads[q];
    const Eigen::Matrix<double, 2, 4> x = corners<4>(m, c);
    if (q4_corner_quality(m, c) <= 0.0) bad_cell(in.name, q, "non-convex or inverted quadrilateral");
    Q4FullGeom fg;
    for (int k = 0; k < 4; ++k) {
      const Grad4 dxi = q4_dn_dxi(gp[k][0], gp[k][1]);
      const Mat2 jac = x * dxi;  // dX/dxi
      const double det = jac.determinant();
      if (!(det > 0.0)) bad_cell(in.name, q, "non-positive Jacobian");
      fg.dndx[k] = dxi * jac.inverse();
      fg.vol[k] = det * t;
      const Eigen::Vector4d n = q4_shape(gp[k][0], gp[k][1]);
      for (int a = 0; a < 4; ++a) add_node_mass(model, node0 + c[a], rho * fg.vol[k] * n(a));
    }
    const std::array<int, 4> gc = {c[0] + node0, c[1] + node0, c[2] + node0, c[3] + node0};
    const double area = signed_area(m, c.data(), 4);
    if (in.quad_element == QuadElement::full_2x2) {
      full.conn.push_back(gc);
      full.geom.push_back(fg);
    } else {
      Q4HourglassGeom hgg;
      // Mean gradients B_I = b_I / A, b_I = (y_{I+1} - y_{I-1}, x_{I-1} - x_{I+1}) / 2.
      for (int a = 0; a < 4; ++a) {
        const Vec2 nxt = x.col((a + 1) % 4), prv = x.col((a + 3) % 4);
        hgg.dndx(a, 0) = 0.5 * (nxt.y() - prv.y()) / area;
        hgg.dndx(a, 1) = 0.5 * (prv.x() - nxt.x()) / area;
      }
      // gamma = (h - (h . x_i) B_i) / 4, h = (1, -1, 1, -1).
      const Eigen::Vector4d h(1.0, -1.0, 1.0, -1.0);
      const Vec2 hx = x * h;
      hgg.gamma = 0.25 * (h - hgg.dndx * hx);
      hgg.vol = area * t;
      const double bb = hgg.dndx.squaredNorm();
      hgg.hourglass_coeff =
          in.hourglass.form == HourglassForm::viscous
              ? in.hourglass.coeff * rho * cp * t * std::sqrt(area)
              : in.hourglass.coeff * rho * cp * cp * t * area * bb / 2.0;
      hg.conn.push_back(gc);
      hg.geom.push_back(hgg);
    }
    model.cell_dt[cell0 + q] = q4_characteristic_length(x) / cp;
  }
  add_block(model.q4_full, full);
  add_block(model.q4_hourglass, hg);

  T3Block tri;
  tri.body = bi;
  tri.first_cell = cell0 + static_cast<int>(m.quads.size());
  tri.material = in.material;
  for (int k = 0; k < static_cast<int>(m.tris.size()); ++k) {
    const auto& c = m.tris[k];
    const Eigen::Matrix<double, 2, 3> x = corners<3>(m, c);
    const double area = signed_area(m, c.data(), 3);
    if (!(area > 0.0)) bad_cell(in.name, static_cast<int>(m.quads.size()) + k, "non-positive area");
    T3Geom tg;
    for (int a = 0; a < 3; ++a) {
      const Vec2 nxt = x.col((a + 1) % 3), prv = x.col((a + 2) % 3);
      tg.dndx(a, 0) = 0.5 * (nxt.y() - prv.y()) / area;
      tg.dndx(a, 1) = 0.5 * (prv.x() - nxt.x()) / area;
      add_node_mass(model, node0 + c[a], rho * area * t / 3.0);
    }
    tg.vol = area * t;
    tri.conn.push_back({c[0] + node0, c[1] + node0, c[2] + node0});
    tri.geom.push_back(tg);
    model.cell_dt[tri.first_cell + k] = t3_characteristic_length(x) / cp;
  }
  add_block(model.t3, tri);

  });
  return model;
}

Model<3> build_model(const std::vector<BodyInput<3>>& inputs, const Vec3& gravity) {
  Model<3> model;
  model.gravity = gravity;
  assemble(model, inputs, [&](int bi, const BodyInput<3>& in, int node0, int cell0, double rho, double cp) {
    const Mesh3& m = in.mesh;
  // Hexahedra: one block of the body's formulation.
  const bool one_point = in.hex_element == HexElement::one_point_hourglass;
  Hex8Block full;
  Hex8OnePointBlock hg;
  full.body = hg.body = bi;
  full.first_cell = hg.first_cell = cell0;
  full.material = hg.material = in.material;
  hg.hourglass = in.hourglass;
  std::vector<double> values;
  values.reserve(m.hexes.size() * (one_point ? Hex8OnePointLanes::kValues : Hex8Lanes::kValues));
  for (int e = 0; e < static_cast<int>(m.hexes.size()); ++e) {
    const auto& c = m.hexes[e];
    const Hex8Nodes x = corners<8>(m, c);
    if (!(hex_corner_quality(m, c) > 0.0)) bad_cell(in.name, e, "folded or inverted hexahedron (corner quality <= 0)");
    const std::array<int, 8> gc = {c[0] + node0, c[1] + node0, c[2] + node0, c[3] + node0,
                                   c[4] + node0, c[5] + node0, c[6] + node0, c[7] + node0};
    if (!one_point) {
      Hex8Geom g;
      if (!hex8_geometry(x, g)) bad_cell(in.name, e, "non-positive Jacobian at a Gauss point");
      for (int q = 0; q < 8; ++q) {
        const Mat3 k = hex8_jacobian(x, q).inverse() / 8.0;
        for (int r = 0; r < 3; ++r)
          for (int s = 0; s < 3; ++s) values.push_back(k(r, s));
        values.push_back(g.vol[q]);
      }
      full.conn.push_back(gc);
    } else {
      Hex8OnePointGeom g;
      if (!hex8_one_point_geometry(x, in.material, in.hourglass, g))
        bad_cell(in.name, e, "non-positive Jacobian at a Gauss point");
      std::array<std::array<double, 8>, 3> bh, xh;
      for (int j = 0; j < 3; ++j) {
        bh[j] = hex_coefficients(g.dndx.col(j));
        xh[j] = hex_coefficients(x.row(j).transpose());
      }
      for (int mo = 1; mo < 8; ++mo)
        for (int j = 0; j < 3; ++j) values.push_back(bh[j][mo] / 8.0);
      for (int alpha = 0; alpha < 4; ++alpha)
        for (int j = 0; j < 3; ++j) values.push_back(xh[j][4 + alpha]);
      values.push_back(g.vol);
      values.push_back(g.hourglass_coeff / 64.0);
      hg.conn.push_back(gc);
    }
    add_cell_masses(model, node0, c, hex8_lumped_masses(x, rho));
    model.cell_dt[cell0 + e] = hex8_characteristic_length(x) / cp;
  }
  add_block(model.hex8_full, full, values);
  add_block(model.hex8_hourglass, hg, values);

  // Tetrahedra.
  Tet4Block tet;
  tet.body = bi;
  tet.first_cell = cell0 + static_cast<int>(m.hexes.size());
  tet.material = in.material;
  values.clear();
  for (int k = 0; k < static_cast<int>(m.tets.size()); ++k) {
    const auto& c = m.tets[k];
    const Tet4Nodes x = corners<4>(m, c);
    Tet4Geom g;
    if (!tet4_geometry(x, g)) bad_cell(in.name, static_cast<int>(m.hexes.size()) + k, "non-positive volume");
    for (int a = 0; a < 4; ++a)
      for (int j = 0; j < 3; ++j) values.push_back(g.dndx(a, j));
    values.push_back(g.vol);
    tet.conn.push_back({c[0] + node0, c[1] + node0, c[2] + node0, c[3] + node0});
    add_cell_masses(model, node0, c, tet4_lumped_masses(x, rho));
    model.cell_dt[tet.first_cell + k] = tet4_characteristic_length(x) / cp;
  }
  add_block(model.tet4, tet, values);

  });
  return model;
}

}  // namespace ricochet
