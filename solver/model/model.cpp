#include "solver/model/model.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace ricochet {
namespace {

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

[[noreturn]] void bad_cell(const std::string& body, int cell, const char* what) {
  throw std::invalid_argument("body '" + body + "' cell " + std::to_string(cell) + ": " + what);
}

template <int N>
Eigen::Matrix<double, 2, N> corners(const Mesh& m, const std::array<int, N>& c) {
  Eigen::Matrix<double, 2, N> x;
  for (int i = 0; i < N; ++i) x.col(i) = m.nodes.col(c[i]);
  return x;
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

Model build_model(const std::vector<BodyInput>& inputs, PlaneMode plane, const Vec2& gravity) {
  Model model;
  model.plane = plane;
  model.gravity = gravity;
  int total_nodes = 0, total_cells = 0;
  for (const auto& b : inputs) {
    total_nodes += b.mesh.num_nodes();
    total_cells += b.mesh.num_cells();
  }
  model.ref.resize(2, total_nodes);
  model.mass = Eigen::VectorXd::Zero(2 * total_nodes);
  model.initial_velocity.resize(2 * total_nodes);
  model.cell_dt.assign(total_cells, 0.0);

  int node0 = 0, cell0 = 0;
  for (int bi = 0; bi < static_cast<int>(inputs.size()); ++bi) {
    const BodyInput& in = inputs[bi];
    const Mesh& m = in.mesh;
    const double rho = material_density(in.material);
    const double cp = material_wave_speed(in.material);
    const double t = in.thickness;
    if (!(t > 0.0)) throw std::invalid_argument("body '" + in.name + "': thickness must be > 0");
    if (!(rho > 0.0)) throw std::invalid_argument("body '" + in.name + "': density must be > 0");
    std::vector<BoundaryEdge> edges = boundary_edges(m);
    for (BoundaryEdge& e : edges) {
      e.a += node0;
      e.b += node0;
    }
    model.bodies.push_back({in.name, node0, m.num_nodes(), cell0, m.num_cells(), t,
                            in.quad_element, in.material, edge_nodes(edges), std::move(edges)});
    model.ref.middleCols(node0, m.num_nodes()) = m.nodes;
    for (int i = 0; i < m.num_nodes(); ++i)
      model.initial_velocity.segment<2>(2 * (node0 + i)) = in.initial_velocity;

    auto add_mass = [&](int local_node, double value) {
      model.mass(2 * (node0 + local_node)) += value;
      model.mass(2 * (node0 + local_node) + 1) += value;
    };

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
        for (int a = 0; a < 4; ++a) add_mass(c[a], rho * fg.vol[k] * n(a));
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
    if (!full.conn.empty()) {
      pack_lanes(full);
      model.q4_full.push_back(std::move(full));
    }
    if (!hg.conn.empty()) {
      pack_lanes(hg);
      model.q4_hourglass.push_back(std::move(hg));
    }

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
        add_mass(c[a], rho * area * t / 3.0);
      }
      tg.vol = area * t;
      tri.conn.push_back({c[0] + node0, c[1] + node0, c[2] + node0});
      tri.geom.push_back(tg);
      model.cell_dt[tri.first_cell + k] = t3_characteristic_length(x) / cp;
    }
    if (!tri.conn.empty()) {
      pack_lanes(tri);
      model.t3.push_back(std::move(tri));
    }

    node0 += m.num_nodes();
    cell0 += m.num_cells();
  }
  for (int i = 0; i < model.num_dofs(); ++i)
    if (!(model.mass(i) > 0.0))
      throw std::invalid_argument("node " + std::to_string(i / 2) + " belongs to no cell (zero mass)");
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
