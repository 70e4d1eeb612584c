// A mesh as the solver receives it: reference coordinates, cells and named node sets; Mesh in
// 2D (quadrilaterals and triangles), Mesh3 in 3D (hexahedra and tetrahedra; docs/three-dimensions.md,
// Meshes in 3D), each with its boundary finder (edges in 2D, faces in 3D).
#pragma once

#include <array>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Geometry>  // cross()

#include "solver/core/types.hpp"

namespace ricochet {

// ------------------------------------------------------------------------------------------ 2D

// Cells are counter-clockwise in the reference configuration (positive area).
struct Mesh {
  Eigen::Matrix2Xd nodes;                          // 2 x n, reference coordinates [m]
  std::vector<std::array<int, 4>> quads;           // Q4 cells, node indices
  std::vector<std::array<int, 3>> tris;            // T3 cells, node indices
  std::map<std::string, std::vector<int>> node_sets;  // sorted, unique node indices

  int num_nodes() const { return static_cast<int>(nodes.cols()); }
  int num_cells() const { return static_cast<int>(quads.size() + tris.size()); }
};

// Signed area of a polygon given by its corner coordinates (shoelace formula) [m^2].
double signed_area(const Mesh& mesh, const int* corners, int count);

// Smallest Jacobian determinant at the corners of a Q4 cell, divided by its mean value; a
// convex counter-clockwise quadrilateral has a positive value, a non-convex or bow-tie
// one does not. [-]
double q4_corner_quality(const Mesh& mesh, const std::array<int, 4>& q);

// An edge used by exactly one cell, oriented as that cell runs: counter-clockwise, so the body
// lies on its left and its outward normal is (e_y, -e_x)/|e| for e = x_b - x_a.
struct BoundaryEdge {
  int a = 0, b = 0;        // node indices (of the mesh, or global ones in a Model<2>)
  double cell_area = 0.0;  // reference area of the one cell that uses it [m^2]
};

// The one boundary-edge finder: every edge used by one cell only, in the order of the cells
// (quads, then triangles) and of each cell's edges. The contact surfaces between bodies, the
// penalty springs' stiffness and the boundary node sets are all built from it.
std::vector<BoundaryEdge> boundary_edges(const Mesh& mesh);

// The ends of the given edges, sorted and unique.
std::vector<int> edge_nodes(const std::vector<BoundaryEdge>& edges);

// Nodes on the mesh boundary: edge_nodes(boundary_edges(mesh)).
inline std::vector<int> boundary_nodes(const Mesh& mesh) { return edge_nodes(boundary_edges(mesh)); }

// ------------------------------------------------------------------------------------------ 3D

// Corner orders are VTK's, which are Gmsh's (VTK_HEXAHEDRON = Gmsh type 5, VTK_TETRA = type 4):
//
//   hexahedron            7-------6       corners 0 1 2 3: one face, counter-clockwise when
//                        /|      /|       seen from the opposite face 4 5 6 7 (i.e. from inside
//                       4-------5 |       the cell: (x1 - x0) x (x3 - x0) points into it);
//                       | 3-----|-2       corner k + 4 is joined to corner k by an edge. The unit
//                       |/      |/        cube: 0 (0,0,0), 1 (1,0,0), 2 (1,1,0), 3 (0,1,0),
//                       0-------1         4 (0,0,1), 5 (1,0,1), 6 (1,1,1), 7 (0,1,1).
//
//   tetrahedron           corners 0 1 2 counter-clockwise seen from corner 3:
//                         (x1 - x0) x (x2 - x0) . (x3 - x0) > 0; the unit tetrahedron is
//                         0 (0,0,0), 1 (1,0,0), 2 (0,1,0), 3 (0,0,1).
//
// Every cell of a Mesh3 has positive volume in that order (the readers and generators check it).
struct Mesh3 {
  Eigen::Matrix3Xd nodes;                          // 3 x n, reference coordinates [m]
  std::vector<std::array<int, 8>> hexes;           // 8-node hexahedra (trilinear), node indices
  std::vector<std::array<int, 4>> tets;            // 4-node tetrahedra (linear), node indices
  std::map<std::string, std::vector<int>> node_sets;  // sorted, unique node indices

  int num_nodes() const { return static_cast<int>(nodes.cols()); }
  // Cells are numbered hexes first, then tetrahedra.
  int num_cells() const { return static_cast<int>(hexes.size() + tets.size()); }
};

// Signed volume of a cell [m^3]. A tetrahedron: det[x1 - x0, x2 - x0, x3 - x0] / 6. A hexahedron:
// the integral of det J of its trilinear map, by 2 x 2 x 2 Gauss points, which is exact (det J is
// at most quadratic in each reference coordinate), so it holds for warped faces too; for an
// axis-aligned box it is the product of the side lengths, without round-off from the points.
double signed_volume(const Mesh3& mesh, const std::array<int, 4>& tet);
double signed_volume(const Mesh3& mesh, const std::array<int, 8>& hex);

// Smallest Jacobian determinant at the corners of a hexahedron, divided by its mean over the
// eight corners (the 3D q4_corner_quality). The corner Jacobian of corner k is the determinant of
// the three edges leaving it in right-handed order; it is 1 at every corner of a parallelepiped,
// and a value <= 0 means the trilinear map folds (an inverted or badly twisted cell). [-]
double hex_corner_quality(const Mesh3& mesh, const std::array<int, 8>& hex);

// The faces of each cell, their corners as cell-local indices, counter-clockwise seen from
// outside the cell: the right-hand rule gives the outward normal.
// Hexahedron, in the order -x, +x, -y, +y, -z, +z of the unit cube (VTK's face order):
inline constexpr std::array<std::array<int, 4>, 6> kHexFaces = {
    {{0, 4, 7, 3}, {1, 2, 6, 5}, {0, 1, 5, 4}, {3, 7, 6, 2}, {0, 3, 2, 1}, {4, 5, 6, 7}}};
// Tetrahedron: the face opposite corner 3, 2, 0, 1 in that order.
inline constexpr std::array<std::array<int, 3>, 4> kTetFaces = {{{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}}};

// A face used by exactly one cell, its corners counter-clockwise seen from outside the body: its
// outward normal is by the right-hand rule (face_area_vector).
struct BoundaryFace {
  std::array<int, 4> nodes{};  // node indices; nodes[3] = -1 for a triangle
  int corners = 0;             // 4 (a hexahedron's quadrilateral) or 3 (a tetrahedron's triangle)
  int cell = 0;                // the one cell that uses it: hexes first, then tets (Mesh3::num_cells)
  int local_face = 0;          // its index in kHexFaces or kTetFaces
  double cell_volume = 0.0;    // reference volume of that cell [m^3]
};

// The one boundary-face finder: every face used by one cell only, in the order of the cells
// (hexes, then tets) and of each cell's faces (kHexFaces, kTetFaces). Faces are matched by their
// sorted node tuples (one sort of all faces, O(F log F)); a quadrilateral and a triangle never
// match. A face shared by two cells is interior. A mesh that joins a hexahedron's face to two
// tetrahedra's triangles (which needs a pyramid, not supported) is not conforming there: those
// faces come out as boundary faces.
std::vector<BoundaryFace> boundary_faces(const Mesh3& mesh);

// The vector area of a face [m^2]: its area times its outward unit normal for a planar face.
// Triangle: (x1 - x0) x (x2 - x0) / 2. Quadrilateral: (x2 - x0) x (x3 - x1) / 2, the vector area
// of the bilinear surface through its corners (exact for warped faces too: a vector area depends
// on the boundary curve only), so the faces of a closed surface sum to zero.
Vec3 face_area_vector(const Mesh3& mesh, const BoundaryFace& face);

// The corners of the given faces, sorted and unique.
std::vector<int> face_nodes(const std::vector<BoundaryFace>& faces);

// Nodes on the mesh boundary: face_nodes(boundary_faces(mesh)).
inline std::vector<int> boundary_nodes(const Mesh3& mesh) { return face_nodes(boundary_faces(mesh)); }

}  // namespace ricochet
