// Tests of the 3D model (solver/model/model3.hpp): its shape and numbering (bodies, blocks,
// global nodes and cells, boundary faces, the lane layout), the lumped masses against the cells'
// volumes, the critical-step lengths against element3d.hpp's, the stored geometry against the
// builders', and the cells it rejects. Every measured error is printed ("[model3] ...").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "solver/model/model.hpp"
#include "tests/support/meshes3.hpp"

namespace ricochet {
namespace {

using namespace test3;

constexpr double kEps = std::numeric_limits<double>::epsilon();

// Three bodies: one-point hexahedra, tetrahedra, 2x2x2 hexahedra.
std::vector<BodyInput<3>> three_bodies() {
  const std::vector<Law> laws = all_laws();
  std::vector<BodyInput<3>> in;
  in.push_back(body_of(Kind::hex8_viscous, distorted_box(3, 2, 2, false, 0.1, 1), laws[0].m, "a"));
  in.push_back(body_of(Kind::tet4, distorted_box(2, 1, 2, true, 0.1, 2), laws[1].m, "b"));
  in.push_back(body_of(Kind::hex8, distorted_box(2, 2, 3, false, 0.1, 3), laws[3].m, "c"));
  in[0].initial_velocity = Vec3(1.0, -2.0, 3.0);
  in[1].initial_velocity = Vec3(-0.5, 0.0, 0.25);
  for (BodyInput<3>& b : in) b.mesh.nodes.row(0).array() += 3.0 * (&b - in.data());  // bodies apart
  return in;
}

TEST(Model3, ShapeAndNumbering) {
  static_assert(Model<3>::kDim == 3 && Model<2>::kDim == 2);
  const std::vector<BodyInput<3>> in = three_bodies();
  const Vec3 gravity(0.0, -9.81, 1.0);
  const Model<3> model = build_model(in, gravity);
  int nodes = 0, cells = 0;
  for (const BodyInput<3>& b : in) {
    nodes += b.mesh.num_nodes();
    cells += b.mesh.num_cells();
  }
  EXPECT_EQ(model.num_nodes(), nodes);
  EXPECT_EQ(model.num_dofs(), 3 * nodes);
  EXPECT_EQ(model.num_cells(), cells);
  EXPECT_EQ(model.mass.size(), 3 * nodes);
  EXPECT_EQ(model.inv_mass.size(), 3 * nodes);
  EXPECT_EQ(model.gravity, gravity);
  ASSERT_EQ(model.bodies.size(), 3u);
  ASSERT_EQ(model.num_blocks(BlockKind3::hex8_hourglass), 1u);
  ASSERT_EQ(model.num_blocks(BlockKind3::tet4), 1u);
  ASSERT_EQ(model.num_blocks(BlockKind3::hex8_full), 1u);

  int node0 = 0, cell0 = 0;
  for (std::size_t bi = 0; bi < in.size(); ++bi) {
    const Mesh3& m = in[bi].mesh;
    const BodyInfo<3>& info = model.bodies[bi];
    SCOPED_TRACE(info.name);
    EXPECT_EQ(info.name, in[bi].name);
    EXPECT_EQ(info.first_node, node0);
    EXPECT_EQ(info.num_nodes, m.num_nodes());
    EXPECT_EQ(info.first_cell, cell0);
    EXPECT_EQ(info.num_cells, m.num_cells());
    EXPECT_EQ(info.hex_element, in[bi].hex_element);
    EXPECT_EQ(model.ref.middleCols(node0, m.num_nodes()), m.nodes);
    for (int p = 0; p < m.num_nodes(); ++p)
      EXPECT_EQ(model.initial_velocity.segment<3>(3 * (node0 + p)), in[bi].initial_velocity);
    // Boundary nodes and faces: the mesh's own, renumbered.
    std::vector<int> expected_nodes = boundary_nodes(m);
    for (int& p : expected_nodes) p += node0;
    EXPECT_EQ(info.boundary_nodes, expected_nodes);
    EXPECT_TRUE(std::is_sorted(info.boundary_nodes.begin(), info.boundary_nodes.end()));
    const std::vector<BoundaryFace> faces = boundary_faces(m);
    ASSERT_EQ(info.boundary_faces.size(), faces.size());
    for (std::size_t f = 0; f < faces.size(); ++f) {
      const BoundaryFace& g = info.boundary_faces[f];
      EXPECT_EQ(g.corners, faces[f].corners);
      EXPECT_EQ(g.cell, faces[f].cell + cell0);
      EXPECT_EQ(g.local_face, faces[f].local_face);
      EXPECT_EQ(g.cell_volume, faces[f].cell_volume);
      for (int k = 0; k < 4; ++k) EXPECT_EQ(g.nodes[k], k < faces[f].corners ? faces[f].nodes[k] + node0 : -1);
    }
    node0 += m.num_nodes();
    cell0 += m.num_cells();
  }

  // Blocks: body, first cell, global connectivity, and the lane copy (the padding lanes repeat
  // the last cell).
  auto check_block = [&](const auto& b, int body, int first_cell, const auto& mesh_cells) {
    SCOPED_TRACE("block of body " + std::to_string(body));
    EXPECT_EQ(b.body, body);
    EXPECT_EQ(b.first_cell, first_cell);
    ASSERT_EQ(b.conn.size(), mesh_cells.size());
    for (std::size_t e = 0; e < b.conn.size(); ++e)
      for (std::size_t a = 0; a < b.conn[e].size(); ++a)
        EXPECT_EQ(b.conn[e][a], mesh_cells[e][a] + model.bodies[body].first_node);
    ASSERT_EQ(b.lane_conn.size(), b.num_batches() * b.conn[0].size() * kLanes);
    for (std::size_t k = 0; k < b.num_batches(); ++k)
      for (int l = 0; l < kLanes; ++l) {
        const std::size_t e = std::min(k * kLanes + l, b.conn.size() - 1);
        for (std::size_t a = 0; a < b.conn[e].size(); ++a) EXPECT_EQ(b.batch_conn(k)[a * kLanes + l], b.conn[e][a]);
      }
  };
  check_block(model.hex8_hourglass[0], 0, model.bodies[0].first_cell, in[0].mesh.hexes);
  check_block(model.tet4[0], 1, model.bodies[1].first_cell, in[1].mesh.tets);  // a body of tetrahedra only
  check_block(model.hex8_full[0], 2, model.bodies[2].first_cell, in[2].mesh.hexes);
  EXPECT_EQ(model.hex8_hourglass[0].hourglass.form, HourglassForm::viscous);
  EXPECT_EQ(model.hex8_hourglass[0].conn.size() % kLanes, 4u);  // 12 cells: a partial last batch
}

// The lumped masses: the row sums of element3d.hpp assembled in cell order (the same numbers,
// so exactly), equal in x, y and z, and summing to rho V with V from mesh.hpp's volumes.
TEST(Model3, MassesSumToDensityTimesVolume) {
  double worst = 0.0;
  for (const Kind kind : kAllKinds)
    for (const Law& law : all_laws()) {
      SCOPED_TRACE(std::string(kind_name(kind)) + ", " + law.name);
      const Mesh3 mesh = distorted_box(3, 3, 2, is_tet(kind), 0.15, 11);
      const Model<3> model = build_model({body_of(kind, mesh, law.m)}, Vec3::Zero());
      const double rho = material_density(law.m);
      Eigen::VectorXd expected = Eigen::VectorXd::Zero(model.num_nodes());
      double volume = 0.0;
      for (const auto& h : mesh.hexes) {
        Hex8Nodes x;
        for (int a = 0; a < 8; ++a) x.col(a) = mesh.nodes.col(h[a]);
        const Eigen::Matrix<double, 8, 1> m = hex8_lumped_masses(x, rho);
        for (int a = 0; a < 8; ++a) expected(h[a]) += m(a);
        volume += signed_volume(mesh, h);
      }
      for (const auto& t : mesh.tets) {
        Tet4Nodes x;
        for (int a = 0; a < 4; ++a) x.col(a) = mesh.nodes.col(t[a]);
        const Eigen::Vector4d m = tet4_lumped_masses(x, rho);
        for (int a = 0; a < 4; ++a) expected(t[a]) += m(a);
        volume += signed_volume(mesh, t);
      }
      double total = 0.0;
      for (int p = 0; p < model.num_nodes(); ++p) {
        for (int k = 0; k < 3; ++k) {
          EXPECT_EQ(model.mass(3 * p + k), expected(p));
          EXPECT_EQ(model.inv_mass(3 * p + k), 1.0 / expected(p));
        }
        EXPECT_GT(model.mass(3 * p), 0.0);
        total += model.mass(3 * p);
      }
      // Bound: the cell masses are exact to a few ulps (element3d.hpp's row sums, measured to
      // 8e-16 in tests/solver/elements/test_elements3d.cpp) and the sums over 18 to 108 cells add at most
      // cells x 8 x eps; 1e-13 is above both.
      const double err = std::abs(total - rho * volume) / (rho * volume);
      worst = std::max(worst, err);
      EXPECT_LE(err, 1e-13);
    }
  std::printf("[model3] masses: |sum m - rho V| / (rho V) <= %.2e\n", worst);
}

// cell_dt = L_e / c_p with element3d.hpp's lengths of the cells' reference corners (the same
// call, so the same bits); critical_dt and critical_cell their minimum.
TEST(Model3, CellDtIsTheKernelsCriticalLength) {
  for (const Kind kind : kAllKinds)
    for (const Law& law : all_laws()) {
      SCOPED_TRACE(std::string(kind_name(kind)) + ", " + law.name);
      const Mesh3 mesh = distorted_box(2, 3, 2, is_tet(kind), 0.15, 5);
      const Model<3> model = build_model({body_of(kind, mesh, law.m)}, Vec3::Zero());
      const double cp = material_wave_speed(law.m);
      ASSERT_EQ(model.num_cells(), mesh.num_cells());
      int c = 0;
      for (const auto& h : mesh.hexes) {
        Hex8Nodes x;
        for (int a = 0; a < 8; ++a) x.col(a) = mesh.nodes.col(h[a]);
        EXPECT_EQ(model.cell_dt[c++], hex8_characteristic_length(x) / cp);
      }
      for (const auto& t : mesh.tets) {
        Tet4Nodes x;
        for (int a = 0; a < 4; ++a) x.col(a) = mesh.nodes.col(t[a]);
        EXPECT_EQ(model.cell_dt[c++], tet4_characteristic_length(x) / cp);
      }
      const auto it = std::min_element(model.cell_dt.begin(), model.cell_dt.end());
      EXPECT_EQ(model.critical_dt, *it);
      EXPECT_EQ(model.critical_cell, static_cast<int>(it - model.cell_dt.begin()));
      EXPECT_GT(model.critical_dt, 0.0);
    }
}

// The lane copy holds the builders' numbers: K_q = J_q^-1 / 8 and vol_q of hex8_jacobian() and
// hex8_geometry() exactly; for one point the volume and c / 64 exactly, and the mean gradients
// back from their Walsh-Hadamard coefficients to round-off; the tetrahedron's gradients and volume
// exactly. cell_geometry() rebuilds the builders' geometry bit for bit.
TEST(Model3, LaneGeometryIsTheBuildersGeometry) {
  const Law law = all_laws()[0];
  double worst_b = 0.0;
  for (const Kind kind : kAllKinds) {
    SCOPED_TRACE(kind_name(kind));
    const Mesh3 mesh = distorted_box(3, 2, 2, is_tet(kind), 0.15, 9);
    const Model<3> model = build_model({body_of(kind, mesh, law.m)}, Vec3::Zero());
    if (kind == Kind::hex8) {
      const Hex8Block& b = model.hex8_full[0];
      for (std::size_t e = 0; e < b.conn.size(); ++e) {
        const Hex8Nodes x = cell_corners(model, b, e);
        Hex8Geom g;
        ASSERT_TRUE(hex8_geometry(x, g));
        const Hex8Geom r = cell_geometry(model, b, e);
        for (int q = 0; q < 8; ++q) {
          EXPECT_EQ(r.vol[q], g.vol[q]);
          EXPECT_EQ(r.dndx[q], g.dndx[q]);
          EXPECT_EQ(b.geom(e, Hex8Lanes::vol(q)), g.vol[q]);
          const Mat3 jinv = hex8_jacobian(x, q).inverse();
          for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) EXPECT_EQ(8.0 * b.geom(e, Hex8Lanes::k(q, i, j)), jinv(i, j));
        }
      }
    } else if (kind == Kind::tet4) {
      const Tet4Block& b = model.tet4[0];
      for (std::size_t e = 0; e < b.conn.size(); ++e) {
        Tet4Geom g;
        ASSERT_TRUE(tet4_geometry(cell_corners(model, b, e), g));
        const Tet4Geom r = cell_geometry(model, b, e);
        EXPECT_EQ(r.dndx, g.dndx);
        EXPECT_EQ(r.vol, g.vol);
        EXPECT_EQ(b.geom(e, Tet4Lanes::kVol), g.vol);
        for (int a = 0; a < 4; ++a)
          for (int j = 0; j < 3; ++j) EXPECT_EQ(b.geom(e, Tet4Lanes::dndx(a, j)), g.dndx(a, j));
      }
    } else {
      const Hex8OnePointBlock& b = model.hex8_hourglass[0];
      for (std::size_t e = 0; e < b.conn.size(); ++e) {
        const Hex8Nodes x = cell_corners(model, b, e);
        Hex8OnePointGeom g;
        HourglassControl hc;
        hc.form = kind == Kind::hex8_stiffness ? HourglassForm::stiffness : HourglassForm::viscous;
        ASSERT_TRUE(hex8_one_point_geometry(x, law.m, hc, g));
        const Hex8OnePointGeom r = cell_geometry(model, b, e);
        EXPECT_EQ(r.dndx, g.dndx);
        EXPECT_EQ(r.gamma, g.gamma);
        EXPECT_EQ(r.vol, g.vol);
        EXPECT_EQ(r.hourglass_coeff, g.hourglass_coeff);
        EXPECT_EQ(r.form, hc.form);
        EXPECT_EQ(b.geom(e, Hex8OnePointLanes::kVol), g.vol);
        EXPECT_EQ(64.0 * b.geom(e, Hex8OnePointLanes::kCoeff64), g.hourglass_coeff);
        // B_a = sum_m s_am Bh_m (m = 1..7; sum_a B_a = 0).
        const double scale = g.dndx.cwiseAbs().maxCoeff();
        for (int a = 0; a < 8; ++a)
          for (int j = 0; j < 3; ++j) {
            double s = 0.0;
            for (int m = 1; m < 8; ++m) s += kHexMonomialSigns[a][m] * b.geom(e, Hex8OnePointLanes::bh(m, j));
            worst_b = std::max(worst_b, std::abs(s - g.dndx(a, j)) / scale);
          }
        // xh_alpha = X h_alpha, the hourglass base vectors of element3d.hpp.
        const Hex8Hourglass h = hex8_hourglass_base();
        for (int al = 0; al < 4; ++al) {
          const Vec3 xh = x * h.col(al);
          for (int j = 0; j < 3; ++j)
            EXPECT_NEAR(b.geom(e, Hex8OnePointLanes::xh(al, j)), xh(j), 8 * kEps * x.cwiseAbs().maxCoeff());
        }
      }
    }
  }
  // Bound: B_a from its coefficients is a sum of 7 terms, each an exact 1/8 of a sum of 8, so a
  // few ulps of max |B|: 1e-15.
  std::printf("[model3] mean gradients from their coefficients: %.2e of max |B|\n", worst_b);
  EXPECT_LE(worst_b, 1e-15);
}

// The cells build_model rejects: the message names the body and the cell (its index in the
// body's mesh, hexahedra then tetrahedra).
TEST(Model3, BadCellsAreRejectedNamingBodyAndCell) {
  const Law law = all_laws()[0];
  auto message = [&](const std::vector<BodyInput<3>>& in) -> std::string {
    try {
      build_model(in, Vec3::Zero());
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "(accepted)";
  };
  for (const Kind kind : {Kind::hex8, Kind::hex8_viscous}) {
    SCOPED_TRACE(kind_name(kind));
    // The second body's cell 3 turned inside out (its two layers swapped).
    std::vector<BodyInput<3>> in = {body_of(kind, distorted_box(2, 2, 1, false, 0.1, 1), law.m, "first"),
                                  body_of(kind, distorted_box(2, 2, 2, false, 0.1, 2), law.m, "second")};
    auto& h = in[1].mesh.hexes[3];
    std::swap_ranges(h.begin(), h.begin() + 4, h.begin() + 4);
    std::string what = message(in);
    EXPECT_NE(what.find("body 'second' cell 3"), std::string::npos) << what;
    EXPECT_NE(what.find("corner quality"), std::string::npos) << what;
    // A hexahedron folded at one corner (hex_corner_quality() <= 0).
    BodyInput<3> folded = body_of(kind, Mesh3{}, law.m, "folded");
    folded.mesh.nodes.resize(3, 8);
    folded.mesh.nodes << 0, 1, 1, 0, 0, 1, 1, 0,  //
        0, 0, 1, 1, 0, 0, 1, 1,                   //
        0, 0, 0, 0, 1, 1, 1, 1;
    folded.mesh.nodes.col(6) = Vec3(0.45, 0.45, 0.45);  // corner 6 pushed through to the middle
    folded.mesh.hexes = {{0, 1, 2, 3, 4, 5, 6, 7}};
    ASSERT_LE(hex_corner_quality(folded.mesh, folded.mesh.hexes[0]), 0.0);
    what = message({folded});
    EXPECT_NE(what.find("body 'folded' cell 0"), std::string::npos) << what;
  }
  // A tetrahedron with two corners swapped: cell index after the body's hexahedra (none here, 6
  // tetrahedra a box cell: cell 7 is the second cell's second tetrahedron).
  std::vector<BodyInput<3>> in = {body_of(Kind::tet4, distorted_box(2, 1, 1, true, 0.1, 4), law.m, "tets")};
  std::swap(in[0].mesh.tets[7][0], in[0].mesh.tets[7][1]);
  std::string what = message(in);
  EXPECT_NE(what.find("body 'tets' cell 7"), std::string::npos) << what;
  EXPECT_NE(what.find("volume"), std::string::npos) << what;
  // Density, and a node of no cell.
  BodyInput<3> light = body_of(Kind::hex8, distorted_box(1, 1, 1, false, 0.0), StVenantKirchhoff3::make(1e6, 0.3, 0.0),
                             "light");
  what = message({light});
  EXPECT_NE(what.find("body 'light'"), std::string::npos) << what;
  EXPECT_NE(what.find("density"), std::string::npos) << what;
  BodyInput<3> extra = body_of(Kind::hex8, distorted_box(1, 1, 1, false, 0.0), law.m, "extra");
  extra.mesh.nodes.conservativeResize(3, 9);
  extra.mesh.nodes.col(8) = Vec3(5.0, 5.0, 5.0);
  what = message({extra});
  EXPECT_NE(what.find("node 8 belongs to no cell"), std::string::npos) << what;
}

}  // namespace
}  // namespace ricochet
