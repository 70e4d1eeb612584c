// The 2D element blocks of a Model<2> (model.hpp): what a body asks for (BodyInput<2>), what the
// model keeps of it (BodyInfo<2>), and per formulation (Q4 with 2x2 points, Q4 with one point and
// hourglass control, T3) the reference geometry computed once (shape-function gradients,
// volumes, hourglass vectors) with its lane layout for the vectorized force kernels
// (forces/element_kernels2.hpp). The 3D counterparts: blocks3.hpp.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "solver/elements/hourglass.hpp"
#include "solver/materials/material.hpp"
#include "solver/model/mesh.hpp"

namespace ricochet {

template <int D>
struct BodyInput;
template <int D>
struct BodyInfo;
template <int D>
struct ModelBlocks;

enum class QuadElement { full_2x2, one_point_hourglass };
template <>
struct BodyInput<2> {
  std::string name;
  Mesh mesh;
  Material material;
  QuadElement quad_element = QuadElement::full_2x2;
  HourglassControl hourglass;
  double thickness = 1.0;               // [m]
  Vec2 initial_velocity = Vec2::Zero();  // [m/s]
};

using Grad4 = Eigen::Matrix<double, 4, 2>;  // rows = element nodes, cols = dN/dX, dN/dY [1/m]
using Grad3 = Eigen::Matrix<double, 3, 2>;

// Each geometry also lists its values as lane_value(k), 0 <= k < kLaneValues: the order in
// which ElementBlock::lane_geom stores them for the vectorized force kernels.
struct Q4FullGeom {
  std::array<Grad4, 4> dndx;  // at the 2x2 Gauss points
  std::array<double, 4> vol;  // Gauss weight * det J0 * thickness [m^3]
  // Per point q: dN/dX (I, J) at 9q + 2I + J, the volume at 9q + 8.
  static constexpr int kLaneValues = 36;
  double lane_value(int k) const { return k % 9 == 8 ? vol[k / 9] : dndx[k / 9](k % 9 / 2, k % 9 % 2); }
};
struct Q4HourglassGeom {
  Grad4 dndx;                  // mean (= centroid) gradients
  Eigen::Vector4d gamma;       // FB hourglass vector, orthogonal to linear fields [-]
  double vol = 0.0;            // A0 * thickness [m^3]
  double hourglass_coeff = 0.0;  // c of HourglassControl: [kg/s] viscous or [N/m] stiffness
  // dN/dX (I, J) at 2I + J, gamma_I at 8 + I, then the volume and c.
  static constexpr int kLaneValues = 14;
  double lane_value(int k) const {
    return k < 8 ? dndx(k / 2, k % 2) : k < 12 ? gamma(k - 8) : k == 12 ? vol : hourglass_coeff;
  }
};
struct T3Geom {
  Grad3 dndx;
  double vol = 0.0;  // A0 * thickness [m^3]
  // dN/dX (I, J) at 2I + J, then the volume.
  static constexpr int kLaneValues = 7;
  double lane_value(int k) const { return k < 6 ? dndx(k / 2, k % 2) : vol; }
};

// One body's cells of one formulation. `first_cell` is the index of the block's first cell in
// the global cell numbering (bodies in order; in each body its quads, then its triangles).
template <int N, class Geom>
struct ElementBlock {
  int body = 0;
  int first_cell = 0;
  Material material;
  std::vector<std::array<int, N>> conn;  // global node indices
  std::vector<Geom> geom;
  // The same cells in batches of kLanes, structure of arrays, for the vectorized force
  // kernels (element_kernels.hpp). Batch k covers cells k kLanes ... k kLanes + kLanes - 1;
  // the last batch is padded with copies of the last cell. In a batch's records
  // (batch_conn, batch_geom) node I of lane l is at I kLanes + l and geometry value j
  // (Geom::lane_value) of lane l at j kLanes + l. Made by pack_lanes().
  std::vector<int> lane_conn;
  std::vector<double> lane_geom;
  std::size_t num_batches() const { return (conn.size() + kLanes - 1) / kLanes; }
  const int* batch_conn(std::size_t k) const { return lane_conn.data() + k * N * kLanes; }
  const double* batch_geom(std::size_t k) const { return lane_geom.data() + k * Geom::kLaneValues * kLanes; }
};

using Q4FullBlock = ElementBlock<4, Q4FullGeom>;
struct Q4HourglassBlock : ElementBlock<4, Q4HourglassGeom> {
  HourglassForm form = HourglassForm::viscous;
};
inline bool viscous_hourglass(const Q4HourglassBlock& b) { return b.form == HourglassForm::viscous; }
using T3Block = ElementBlock<3, T3Geom>;

template <>
struct BodyInfo<2> {
  std::string name;
  int first_node = 0, num_nodes = 0;
  int first_cell = 0, num_cells = 0;
  double thickness = 0.0;
  QuadElement quad_element = QuadElement::full_2x2;
  Material material;
  std::vector<int> boundary_nodes;  // global indices of nodes on an edge used by one cell, sorted
  std::vector<BoundaryEdge> boundary_edges;  // boundary_edges() of the body's mesh, global indices
};

// The model's element blocks by formulation, in the order every force pass visits them (and
// so sums f_int): Q4 with hourglass control, Q4 2x2, T3.
enum class BlockKind { q4_hourglass, q4_full, t3 };
inline constexpr BlockKind kBlockKinds[] = {BlockKind::q4_hourglass, BlockKind::q4_full, BlockKind::t3};

template <>
struct ModelBlocks<2> {
  PlaneMode plane = PlaneMode::stress;
  std::vector<Q4FullBlock> q4_full;
  std::vector<Q4HourglassBlock> q4_hourglass;
  std::vector<T3Block> t3;

  using Kind = BlockKind;
  static constexpr const BlockKind (&kKinds)[3] = kBlockKinds;
  // fn(the blocks of `kind`), a vector of that formulation's block type.
  template <class Fn>
  void with_blocks(BlockKind kind, Fn&& fn) const {
    switch (kind) {
      case BlockKind::q4_hourglass: return fn(q4_hourglass);
      case BlockKind::q4_full: return fn(q4_full);
      case BlockKind::t3: return fn(t3);
    }
  }
};

// Critical-step estimates of one reference cell (docs/background.md, Critical time step): Q4 uses
// L_e = sqrt(2) A / sqrt(d13^2 + d24^2) (Flanagan-Belytschko bound, diagonals d13, d24);
// T3 uses the analogous bound of the lumped constant-strain triangle,
// L_e = sqrt(2/3) 2 A / sqrt(eig_max(sum over edges e e^T)) (a/sqrt(3) for an equilateral
// triangle of side a; the smallest altitude, 2 A / longest edge, overestimates the stable
// step by up to 27 %). [m]
double q4_characteristic_length(const Eigen::Matrix<double, 2, 4>& x);
double t3_characteristic_length(const Eigen::Matrix<double, 2, 3>& x);

}  // namespace ricochet
