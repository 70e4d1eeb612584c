// A 2D mesh as the solver receives it: reference coordinates, cells and named node sets.
#pragma once

#include <array>
#include <map>
#include <string>
#include <vector>

#include "solver/types.hpp"

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

}  // namespace ricochet
