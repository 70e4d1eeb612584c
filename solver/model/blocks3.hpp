// The 3D element blocks of a Model<3> (model.hpp; docs/three-dimensions.md, "The 3D model and
// force pass"): what a body asks for (BodyInput<3>), what the model keeps of it (BodyInfo<3>),
// and per formulation (hexahedra with 2x2x2 points, one-point hexahedra with hourglass control,
// tetrahedra) the lane layout of the reference geometry for the vectorized force kernels
// (forces/element_kernels3.hpp). DOFs are interleaved, (x0, y0, z0, x1, ...), DOF 3 i + k.
//
// The element kernels of one cell are element3d.hpp's. A block keeps its geometry in the lane
// copy only (a Hex8Geom is 1.6 kB a cell, its lane form 640 B): the geometry of element3d.hpp
// for one cell, e.g. for an element matrix, is rebuilt from the reference coordinates by
// cell_geometry() (model.hpp), with the builders' own arithmetic, so bit for bit what the model
// was built from. The 2D counterparts: blocks2.hpp.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "solver/elements/element3d.hpp"
#include "solver/elements/hourglass.hpp"
#include "solver/materials/material3d.hpp"
#include "solver/model/mesh.hpp"

namespace ricochet {

template <int D>
struct BodyInput;
template <int D>
struct BodyInfo;
template <int D>
struct ModelBlocks;

enum class HexElement { full_2x2x2, one_point_hourglass };

template <>
struct BodyInput<3> {
  std::string name;
  Mesh3 mesh;
  Material3 material;
  HexElement hex_element = HexElement::full_2x2x2;
  HourglassControl hourglass;            // one-point hexahedra (element3d.hpp: the 3D coefficients)
  Vec3 initial_velocity = Vec3::Zero();  // [m/s]
};

template <>
struct BodyInfo<3> {
  std::string name;
  int first_node = 0, num_nodes = 0;
  int first_cell = 0, num_cells = 0;
  HexElement hex_element = HexElement::full_2x2x2;
  Material3 material;
  std::vector<int> boundary_nodes;           // global indices of nodes on a boundary face, sorted
  std::vector<BoundaryFace> boundary_faces;  // boundary_faces() of the body's mesh, global node
                                             // and cell indices
};

// The lane layouts of the blocks' geometry (lane_geom): value j of a cell, per cell. The force
// pass's arithmetic that uses them is in element_kernels3.hpp.
//
// Hexahedron, 2x2x2 points: per point q (next to corner q, element3d.hpp), K_q = J_q^-1 / 8
// (J = dX/dxi, hex8_jacobian(); /8 is exact) by rows at 10 q + 3 r + c, and vol_q = det J_q
// (Gauss weight 1) at 10 q + 9 [m^3]. K, not dN/dX: F = I + (u dN/dxi) J^-1 at the points takes
// u dN/dxi from u's Walsh-Hadamard coefficients (element_kernels3.hpp), and 10 values a point
// instead of 25.
struct Hex8Lanes {
  static constexpr int kValues = 80;
  static constexpr int k(int q, int r, int c) { return 10 * q + 3 * r + c; }
  static constexpr int vol(int q) { return 10 * q + 9; }
};
// One-point hexahedron: the mean gradients B (element3d.hpp's Hex8OnePointGeom::dndx) as their
// Walsh-Hadamard coefficients Bh_m = 1/8 sum_a s_am B_a for the monomials m = 1..7 of
// kHexMonomials (B_a = sum_m s_am Bh_m; the constant one is 0: sum_a B_a = 0), component J at
// 3 (m - 1) + J [1/m]; the hourglass coordinates xh_alpha = X h_alpha (h_alpha the base vectors
// of hex8_hourglass_base(), X the 3 x 8 reference corners) at 21 + 3 alpha + J [m]; the volume at
// 33 [m^3]; c / 64 at 34 (c = Hex8OnePointGeom::hourglass_coeff, [kg/s] or [N/m]; /64 exact).
struct Hex8OnePointLanes {
  static constexpr int kValues = 35;
  static constexpr int bh(int m, int j) { return 3 * (m - 1) + j; }
  static constexpr int xh(int alpha, int j) { return 21 + 3 * alpha + j; }
  static constexpr int kVol = 33;
  static constexpr int kCoeff64 = 34;
};
// Tetrahedron: dN_a/dX_J (element3d.hpp's Tet4Geom::dndx) at 3 a + J [1/m], the volume at 12.
struct Tet4Lanes {
  static constexpr int kValues = 13;
  static constexpr int dndx(int a, int j) { return 3 * a + j; }
  static constexpr int kVol = 12;
};

// One body's cells of one formulation. `first_cell` is the index of the block's first cell in
// the global cell numbering (bodies in order; in each body its hexahedra, then its tetrahedra,
// as Mesh3 numbers them). The cells in batches of kLanes, structure of arrays, as the 2D
// ElementBlock: batch k covers cells k kLanes ... k kLanes + kLanes - 1, the last batch padded
// with copies of the last cell; in a batch's records node I of lane l is at I kLanes + l and
// geometry value j (Layout) of lane l at j kLanes + l.
template <int N, class Layout>
struct ElementBlock3 {
  static constexpr int kNodes = N;
  using Lanes = Layout;
  int body = 0;
  int first_cell = 0;
  Material3 material;
  std::vector<std::array<int, N>> conn;  // global node indices, VTK corner order
  std::vector<int> lane_conn;
  std::vector<double> lane_geom;
  std::size_t num_batches() const { return (conn.size() + kLanes - 1) / kLanes; }
  const int* batch_conn(std::size_t k) const { return lane_conn.data() + k * N * kLanes; }
  const double* batch_geom(std::size_t k) const { return lane_geom.data() + k * Layout::kValues * kLanes; }
  // Geometry value j of cell e.
  double geom(std::size_t e, int j) const { return batch_geom(e / kLanes)[j * kLanes + e % kLanes]; }
};
using Hex8Block = ElementBlock3<8, Hex8Lanes>;
struct Hex8OnePointBlock : ElementBlock3<8, Hex8OnePointLanes> {
  HourglassControl hourglass;  // the form decides the kernel: viscous (v) or stiffness (u)
};
inline bool viscous_hourglass(const Hex8OnePointBlock& b) { return b.hourglass.form == HourglassForm::viscous; }
using Tet4Block = ElementBlock3<4, Tet4Lanes>;

// The model's element blocks by formulation, in the order every force pass visits them (and so
// sums f_int): one-point hexahedra, 2x2x2 hexahedra, tetrahedra (the 2D order: BlockKind).
enum class BlockKind3 { hex8_hourglass, hex8_full, tet4 };
inline constexpr BlockKind3 kBlockKinds3[] = {BlockKind3::hex8_hourglass, BlockKind3::hex8_full, BlockKind3::tet4};


template <>
struct ModelBlocks<3> {
  std::vector<Hex8OnePointBlock> hex8_hourglass;
  std::vector<Hex8Block> hex8_full;
  std::vector<Tet4Block> tet4;

  using Kind = BlockKind3;
  static constexpr const BlockKind3 (&kKinds)[3] = kBlockKinds3;
  // fn(the blocks of `kind`), a vector of that formulation's block type.
  template <class Fn>
  void with_blocks(BlockKind3 kind, Fn&& fn) const {
    switch (kind) {
      case BlockKind3::hex8_hourglass: return fn(hex8_hourglass);
      case BlockKind3::hex8_full: return fn(hex8_full);
      case BlockKind3::tet4: return fn(tet4);
    }
  }
};

// The monomials of the trilinear hexahedron's Walsh-Hadamard coefficients (element_kernels3.hpp):
// m = 0..7 is 1, xi, eta, zeta, eta zeta, xi zeta, xi eta, xi eta zeta (4 + alpha: the hourglass
// base vector h_alpha of hex8_hourglass_base()); s_am, the monomial at corner a's signs
// (kHexCornerSigns), is kHexMonomialSigns[a][m].
inline constexpr std::array<std::array<int, 8>, 8> kHexMonomialSigns = [] {
  std::array<std::array<int, 8>, 8> s{};
  for (int a = 0; a < 8; ++a) {
    const int x = kHexCornerSigns[a][0], y = kHexCornerSigns[a][1], z = kHexCornerSigns[a][2];
    s[a] = {1, x, y, z, y * z, x * z, x * y, x * y * z};
  }
  return s;
}();

}  // namespace ricochet
