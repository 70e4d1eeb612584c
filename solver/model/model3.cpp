#include "solver/model/model3.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace ricochet {
namespace {

[[noreturn]] void bad_cell(const std::string& body, int cell, const char* what) {
  throw std::invalid_argument("body '" + body + "' cell " + std::to_string(cell) + ": " + what);
}

template <int N>
Nodes3<N> corners(const Mesh3& m, const std::array<int, N>& c) {
  Nodes3<N> x;
  for (int a = 0; a < N; ++a) x.col(a) = m.nodes.col(c[a]);
  return x;
}

// Fills b.lane_conn and b.lane_geom (the layout of ElementBlock3) from b.conn and the cells'
// values (values[e * kValues + j]).
template <int N, class Layout>
void pack_lanes3(ElementBlock3<N, Layout>& b, const std::vector<double>& values) {
  const std::size_t batches = b.num_batches();
  b.lane_conn.assign(batches * N * kLanes, 0);
  b.lane_geom.assign(batches * Layout::kValues * kLanes, 0.0);
  for (std::size_t k = 0; k < batches; ++k)
    for (int l = 0; l < kLanes; ++l) {
      const std::size_t e = std::min(k * kLanes + l, b.conn.size() - 1);
      for (int i = 0; i < N; ++i) b.lane_conn[(k * N + i) * kLanes + l] = b.conn[e][i];
      for (int j = 0; j < Layout::kValues; ++j)
        b.lane_geom[(k * Layout::kValues + j) * kLanes + l] = values[e * Layout::kValues + j];
    }
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

Hex8Geom cell_geometry(const Model3& model, const Hex8Block& b, std::size_t e) {
  Hex8Geom g;
  hex8_geometry(cell_corners(model, b, e), g);
  return g;
}

Hex8OnePointGeom cell_geometry(const Model3& model, const Hex8OnePointBlock& b, std::size_t e) {
  Hex8OnePointGeom g;
  hex8_one_point_geometry(cell_corners(model, b, e), b.material, b.hourglass, g);
  return g;
}

Tet4Geom cell_geometry(const Model3& model, const Tet4Block& b, std::size_t e) {
  Tet4Geom g;
  tet4_geometry(cell_corners(model, b, e), g);
  return g;
}

Model3 build_model3(const std::vector<BodyInput3>& inputs, const Vec3& gravity) {
  Model3 model;
  model.gravity = gravity;
  int total_nodes = 0, total_cells = 0;
  for (const auto& b : inputs) {
    total_nodes += b.mesh.num_nodes();
    total_cells += b.mesh.num_cells();
  }
  model.ref.resize(3, total_nodes);
  model.mass = Eigen::VectorXd::Zero(3 * total_nodes);
  model.initial_velocity.resize(3 * total_nodes);
  model.cell_dt.assign(total_cells, 0.0);

  int node0 = 0, cell0 = 0;
  for (int bi = 0; bi < static_cast<int>(inputs.size()); ++bi) {
    const BodyInput3& in = inputs[bi];
    const Mesh3& m = in.mesh;
    const double rho = material_density(in.material);
    const double cp = material_wave_speed(in.material);
    if (!(rho > 0.0)) throw std::invalid_argument("body '" + in.name + "': density must be > 0");
    if (!(cp > 0.0)) throw std::invalid_argument("body '" + in.name + "': wave speed must be > 0");
    std::vector<BoundaryFace> faces = boundary_faces(m);
    for (BoundaryFace& f : faces) {
      for (int k = 0; k < f.corners; ++k) f.nodes[k] += node0;
      f.cell += cell0;
    }
    std::vector<int> face_node_list = face_nodes(faces);
    model.bodies.push_back({in.name, node0, m.num_nodes(), cell0, m.num_cells(), in.hex_element, in.material,
                            std::move(face_node_list), std::move(faces)});
    model.ref.middleCols(node0, m.num_nodes()) = m.nodes;
    for (int i = 0; i < m.num_nodes(); ++i) model.initial_velocity.segment<3>(3 * (node0 + i)) = in.initial_velocity;

    auto add_masses = [&](const auto& c, const auto& masses) {
      for (int a = 0; a < static_cast<int>(c.size()); ++a)
        for (int k = 0; k < 3; ++k) model.mass(3 * (node0 + c[a]) + k) += masses(a);
    };

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
      add_masses(c, hex8_lumped_masses(x, rho));
      model.cell_dt[cell0 + e] = hex8_characteristic_length(x) / cp;
    }
    if (!full.conn.empty()) {
      pack_lanes3(full, values);
      model.hex8_full.push_back(std::move(full));
    }
    if (!hg.conn.empty()) {
      pack_lanes3(hg, values);
      model.hex8_hourglass.push_back(std::move(hg));
    }

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
      add_masses(c, tet4_lumped_masses(x, rho));
      model.cell_dt[tet.first_cell + k] = tet4_characteristic_length(x) / cp;
    }
    if (!tet.conn.empty()) {
      pack_lanes3(tet, values);
      model.tet4.push_back(std::move(tet));
    }

    node0 += m.num_nodes();
    cell0 += m.num_cells();
  }
  for (int i = 0; i < model.num_dofs(); ++i)
    if (!(model.mass(i) > 0.0))
      throw std::invalid_argument("node " + std::to_string(i / 3) + " belongs to no cell (zero mass)");
  model.inv_mass = model.mass.cwiseInverse();
  model.critical_dt = 1e300;
  for (int c = 0; c < total_cells; ++c)
    if (model.cell_dt[c] < model.critical_dt) {
      model.critical_dt = model.cell_dt[c];
      model.critical_cell = c;
    }
  return model;
}

}  // namespace ricochet
