// A 2D mesh as the solver receives it: reference coordinates, cells and named node sets.
#pragma once

#include <array>
#include <map>
#include <string>
#include <vector>

#include "solver/core/types.hpp"

namespace ricochet {

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

}  // namespace ricochet
