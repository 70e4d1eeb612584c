// The assembled model of either dimension, Model<D>: global node arrays, lumped masses, the
// bodies' ranges and the element blocks whose reference geometry is computed once. What is the
// same in 2D and 3D is written here once; the element blocks, which differ (the formulations,
// their geometry and its lane layout), are the dimension's ModelBlocks<D>: blocks2.hpp (Q4, T3)
// and blocks3.hpp (hexahedra, tetrahedra). DOFs are interleaved, DOF D i + k for component k of
// node i.
#pragma once

#include <cstddef>
#include <type_traits>
#include <variant>
#include <vector>

#include "solver/model/blocks2.hpp"
#include "solver/model/blocks3.hpp"

namespace ricochet {

template <int D>
struct Model : ModelBlocks<D> {
  static constexpr int kDim = D;                   // coordinates per node
  Eigen::Matrix<double, D, Eigen::Dynamic> ref;    // D x n reference coordinates, all bodies [m]
  Eigen::VectorXd mass;                            // lumped mass per DOF (D n, a node's equal) [kg]
  Eigen::VectorXd inv_mass;                        // 1/mass per DOF [1/kg]
  Eigen::VectorXd initial_velocity;                // per DOF [m/s]
  Eigen::Matrix<double, D, 1> gravity = Eigen::Matrix<double, D, 1>::Zero();  // body acceleration [m/s^2]
  std::vector<BodyInfo<D>> bodies;
  std::vector<double> cell_dt;  // per global cell: L_e / c_p, the critical-step estimate [s]
  double critical_dt = 0.0;     // min of cell_dt [s]
  int critical_cell = -1;

  int num_nodes() const { return static_cast<int>(ref.cols()); }
  int num_dofs() const { return D * num_nodes(); }
  int num_cells() const { return static_cast<int>(cell_dt.size()); }
  std::size_t num_blocks(typename ModelBlocks<D>::Kind kind) const {
    std::size_t n = 0;
    this->with_blocks(kind, [&](const auto& blocks) { n = blocks.size(); });
    return n;
  }
};

// Calls fn(block, material, std::bool_constant<viscous hourglass control>) for block k of
// `kind`, with its material's own type (one std::visit per block). The constant is false for
// the formulations without hourglass control (no viscous_hourglass() for their block type).
template <int D, class Fn>
void visit_block(const Model<D>& model, typename ModelBlocks<D>::Kind kind, std::size_t k, Fn&& fn) {
  model.with_blocks(kind, [&](const auto& blocks) {
    const auto& b = blocks[k];
    std::visit(
        [&](const auto& mat) {
          if constexpr (requires { viscous_hourglass(b); }) {
            if (viscous_hourglass(b))
              fn(b, mat, std::true_type{});
            else
              fn(b, mat, std::false_type{});
          } else {
            fn(b, mat, std::false_type{});
          }
        },
        b.material);
  });
}

// fn(block) for every element block (conn, first_cell, body), whatever its formulation, in the
// order of ModelBlocks<D>::kKinds.
template <int D, class Fn>
void for_each_cell_block(const Model<D>& model, Fn&& fn) {
  for (const auto kind : ModelBlocks<D>::kKinds)
    model.with_blocks(kind, [&](const auto& blocks) {
      for (const auto& b : blocks) fn(b);
    });
}

// visit_block for every element block, in the order every pass sums f_int (ModelBlocks<D>::kKinds).
template <int D, class Fn>
void for_each_block(const Model<D>& model, Fn&& fn) {
  for (const auto kind : ModelBlocks<D>::kKinds)
    for (std::size_t k = 0; k < model.num_blocks(kind); ++k) visit_block(model, kind, k, fn);
}

// Builds a 2D model: per body its nodes (after the previous bodies'), a block of its
// quadrilaterals (2x2 points or one point, BodyInput<2>::quad_element) and one of its triangles,
// the row-sum lumped masses and cell_dt = L_e / c_p of each cell. Throws std::invalid_argument
// for a cell with non-positive area or a non-convex quadrilateral (naming the body and cell), or
// non-positive thickness/density; naming the node for a node of no cell (zero mass).
Model<2> build_model(const std::vector<BodyInput<2>>& bodies, PlaneMode plane, const Vec2& gravity);

// Builds a 3D model: per body its nodes, a block of its hexahedra (2x2x2 or one point,
// BodyInput<3>::hex_element) and one of its tetrahedra, the row-sum lumped masses
// (hex8_lumped_masses, tet4_lumped_masses), cell_dt = L_e / c_p of each cell
// (hex8_characteristic_length, tet4_characteristic_length: the bound of docs/three-dimensions.md,
// Elements in 3D). Throws std::invalid_argument naming the body and the cell (its index in the
// body's mesh, Mesh3 numbering) for a hexahedron of corner quality <= 0 (hex_corner_quality(),
// folded or inverted) or with det J <= 0 at a Gauss point, a tetrahedron of volume <= 0, and
// naming the body for a density or wave speed that is not > 0; naming the node for a node of no
// cell (zero mass).
Model<3> build_model(const std::vector<BodyInput<3>>& bodies, const Vec3& gravity);

// The reference corners of cell e of a 3D block [m], 3 x N (column a = corner a).
template <int N, class Layout>
Nodes3<N> cell_corners(const Model<3>& model, const ElementBlock3<N, Layout>& b, std::size_t e) {
  Nodes3<N> x;
  for (int a = 0; a < N; ++a) x.col(a) = model.ref.col(b.conn[e][a]);
  return x;
}

// element3d.hpp's geometry of cell e, rebuilt by its builders from the reference corners (the
// same bits the model was built from; a 3D block stores the lane form only). For the element
// matrices of the implicit scheme and for tests.
Hex8Geom cell_geometry(const Model<3>& model, const Hex8Block& b, std::size_t e);
Hex8OnePointGeom cell_geometry(const Model<3>& model, const Hex8OnePointBlock& b, std::size_t e);
Tet4Geom cell_geometry(const Model<3>& model, const Tet4Block& b, std::size_t e);

}  // namespace ricochet
