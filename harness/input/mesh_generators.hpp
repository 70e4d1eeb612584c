// Structured meshes built from a few parameters (case files name them instead of a mesh
// file). Lengths are in metres. Every generator checks its parameters and throws InputError
// with a one-line message naming the generator and the parameter, e.g.
// "rectangle: nx must be >= 1 (got 0)"; the caller prefixes the file and key.
#pragma once

#include <cstdint>

#include "solver/model/mesh.hpp"
#include "solver/core/types.hpp"

namespace ricochet {

// An axis-aligned rectangle [origin, origin + (width, height)] split into nx x ny Q4 cells.
// Nodes are numbered row by row from the bottom-left: node (i, j) has index j*(nx+1) + i.
// With `triangles`, each quad becomes two T3 cells instead; the diagonal alternates by
// column (even columns i run bottom-left to top-right, odd columns bottom-right to top-left),
// so no node gets the eight-triangle "union jack" star and, for even nx, the mesh is
// mirror-symmetric about x = origin.x + width/2.
// Node sets: left, right, bottom, top, boundary, all.
struct RectangleSpec {
  double width = 1, height = 1;  // [m], finite and > 0
  int nx = 1, ny = 1;            // cells across and up, >= 1
  Vec2 origin = Vec2::Zero();    // bottom-left corner [m], finite
  bool triangles = false;
};
Mesh make_rectangle(const RectangleSpec& spec);

// The Kim-Kwak oblique-impact plate: width L, flat top, and a bottom edge that is a circular
// arc of radius R through both bottom corners. The arc's lowest point is the origin, its
// centre is (0, R), the bottom corners are at (+-L/2, s) with sagitta s = R - sqrt(R^2 - L^2/4).
// The top edge is y = s + height (side height), or y = height if `height_is_overall`.
// Structured nx x ny Q4 mesh, node (i, j) at index j*(nx+1) + i: column i has
// x_i = -L/2 + i*L/nx, its bottom node on the arc, its top node on the top edge, and the nodes
// between graded geometrically so that (top row cell height)/(bottom row cell height) = bias
// (bias > 1 refines towards the arc). Node sets: bottom (the arc), top, left, right,
// boundary, all, top_left, top_right, lowest (the arc node at x = 0 for even nx, the two
// nearest x = 0 for odd nx). With `triangles`, each quad becomes two T3 cells, the diagonals
// alternating by column as for the rectangle (mirror-symmetric about x = 0 for even nx).
struct ArcPlateSpec {
  double width = 0.04, height = 0.08, radius = 0.101;  // [m], finite, > 0, radius > width/2
  int nx = 12, ny = 32;                                // cells across and up, >= 1
  bool height_is_overall = false;  // height measured from the arc's lowest point
  double bias = 1.0;               // [-], finite and > 0
  bool triangles = false;
};
Mesh make_arc_plate(const ArcPlateSpec& spec);

// A disk of radius R about `center`, all Q4, as an "O-grid" (butterfly): a central block of
// n x n cells and four ring blocks of n x nr cells, nr = ceil(n/2), one per side of the
// central block. n is the number of cells along a quarter of the rim (4n rim edges).
// - The rim nodes are centre + R (cos, sin) of the angles -pi/4 + k pi/(2n), k = 0 .. 4n-1,
//   computed per quarter with exact 90-degree swaps, so the mesh has the symmetries of the
//   square to round-off and the rim node at the bottom (even n) is exactly centre - (0, R).
// - The central block's sides bulge: each side point is 0.7 x the square of half-width
//   0.4 R plus 0.3 x the circle through its corners, at the same angle. This raises the block
//   corner angle from 90 to about 120 degrees, so the three cells at a block corner get
//   similar angles (cell angles within 61-126 degrees for n >= 3; n = 1 is a square block in
//   four trapezoids, 45-135). The block's interior nodes are the transfinite (Coons)
//   interpolation of its sides.
// - Ring nodes lie on the straight line from a block side node to its rim node, graded
//   geometrically as in a log-polar grid (radial size proportional to the local circumference),
//   so the ring cells are near square; nr = ceil(n/2) follows from ln(R/0.45 R)/(pi/(2n)).
// The polygon of rim nodes has area 2 n R^2 sin(pi/(2n)), which converges to pi R^2 at second
// order. Nodes: the central block's (n+1)^2 row by row, then the rings outwards, 4n nodes each,
// counter-clockwise from the angle -pi/4. Cells are counter-clockwise.
// Node sets: boundary (the rim), all, center (the node at the centre; even n only), lowest,
// highest, leftmost, rightmost (the rim node at the extreme for even n; the two rim nodes
// nearest it for odd n).
struct DiskSpec {
  double radius = 1.0;          // R [m], finite and > 0
  Vec2 center = Vec2::Zero();   // [m], finite
  int n = 8;                    // cells along a quarter of the rim, >= 1
};
Mesh make_disk(const DiskSpec& spec);

// The local element size h of every node [m]: the smallest length of the cell edges that meet
// at the node (+infinity for a node that no cell uses). A graded mesh thus has small h where its
// cells are small. Squared lengths are computed as std::fma(dx, dx, dy * dy) and the root by
// std::sqrt, both correctly rounded, so h is the same on every IEEE-754 machine.
std::vector<double> local_element_size(const Mesh& mesh);

// Moves every interior node (not in boundary_nodes(mesh), used by a cell) by a random vector
// whose components are each uniform in [-distort h, +distort h), h = local_element_size of
// that node in the undistorted mesh; boundary nodes are not moved, so node sets and boundary
// shapes stay exact. The random numbers are reproducible on every machine:
// - generator std::mt19937_64 constructed from `seed` (the standard fixes its sequence);
// - interior nodes in increasing node index, two draws per node, x first, then y;
// - a draw k (64 bits) becomes u = (k >> 11) * 2^-53, uniform in [0, 1) and exact, then
//   r = 2u - 1 in [-1, 1) (exact), and the coordinate x + (distort h) r is computed as
//   std::fma(distort * h, r, x) (correctly rounded, no compiler-dependent contraction).
// distort = 0 returns at once: the mesh is unchanged and no number is drawn. Afterwards every
// cell must have positive area and every Q4 a positive corner Jacobian (q4_corner_quality > 0,
// i.e. it is still convex); otherwise InputError "after distortion Q4 cell C (nodes ...) ...;
// lower distort (got d) or use another seed". A square cell cannot fold for distort < 0.25
// (its corner Jacobian is at least (1 - 2d)^2 - (2d)^2 = 1 - 4d of the undistorted one); above
// that some seeds fold a cell. The case reader allows [0, 0.5); here distort must be finite
// and >= 0.
void distort_mesh(Mesh& mesh, double distort, std::uint64_t seed);

}  // namespace ricochet
