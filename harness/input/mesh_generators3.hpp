// Structured 3D meshes built from a few parameters (docs/three-dimensions.md, Meshes in 3D): a
// box, a ball, and the extrusion of a 2D mesh through its thickness. Lengths are in metres. As in 2D
// (mesh_generators.hpp), every generator checks its parameters and throws InputError with a
// one-line message naming the generator and the parameter, e.g. "box: nz must be >= 1 (got 0)".
//
// Axes: x and y are the 2D plane's (y up, as in every 2D case), z is the thickness. The side
// names follow: left/right are x = min/max, bottom/top y = min/max, back/front z = min/max (front
// is the +z side, towards a viewer of the x-y plane in a right-handed frame).
#pragma once

#include "solver/model/mesh.hpp"
#include "solver/core/types.hpp"

namespace ricochet {

// An axis-aligned box [origin, origin + size] split into nx x ny x nz hexahedra. Node (i, j, k)
// has index (k (ny+1) + j) (nx+1) + i, so each layer k is make_rectangle's numbering; cells are
// in the order k, j, i, hexahedron (i, j, k) with corners (i,j,k), (i+1,j,k), (i+1,j+1,k),
// (i,j+1,k) and the same at k+1 (the VTK/Gmsh order of mesh.hpp, positive volume).
// With `tetrahedra`, each hexahedron becomes 6 tetrahedra around its main diagonal from corner 0
// (i,j,k) to corner 6 (i+1,j+1,k+1), one per path along three edges from 0 to 6 (the Kuhn or
// Freudenthal split): corners (0,1,2,6), (0,2,3,6), (0,3,7,6), (0,7,4,6), (0,4,5,6), (0,5,1,6),
// each positive. Every cell is split the same way, and the split cuts each face of the cube
// along its diagonal in the direction (+1, +1) of the face's two axes, the same on opposite faces,
// so neighbouring cells cut their shared face along the same diagonal: the mesh is conforming for
// any nx, ny, nz (the 5-tetrahedra split needs mirrored cells alternating like a chessboard).
// Node sets: left, right, bottom, top, back, front, boundary, all.
struct BoxSpec {
  Vec3 size = Vec3::Ones();      // (lx, ly, lz) [m], finite and > 0
  int nx = 1, ny = 1, nz = 1;    // cells along x, y, z, >= 1
  Vec3 origin = Vec3::Zero();    // the corner of smallest x, y, z [m], finite
  bool tetrahedra = false;       // 6 tetrahedra per cell instead of the hexahedron
};
Mesh3 make_box(const BoxSpec& spec);

// A ball of radius R about `center`, in hexahedra: the 3D counterpart of the 2D disk (make_disk),
// a "cubed sphere". A cube-shaped core of n x n x n cells is wrapped by six blocks, one on each
// face of the cube, of n x n x nr cells with nr = ceil(n/2) layers out to the sphere, so the
// sphere is divided like a cube's faces: n cells along each quarter of a great circle through
// two face centres, 6 n^2 faces in all. Nodes: (n+1)^3 + nr (6 n^2 + 2); cells: n^3 + 6 n^2 nr.
// Geometry, with xi in [-1, 1]^3 the core's lattice ((2i - n)/n, (2j - n)/n, (2k - n)/n), m its
// max norm and d(q) = unit vector along (tan(pi q_x / 4), tan(pi q_y / 4), tan(pi q_z / 4)) the
// equiangular direction of a point q of the cube's surface (equal angles between the rays of
// neighbouring nodes along a face's midlines):
// - the core's surface is the cube of half-width a = 0.4 R bulged towards the sphere of radius
//   a sqrt(3) through its corners: B(q) = a ((1 - 0.3) q + 0.3 sqrt(3) d(q));
// - a core node is x = m B(xi / m) (the surface scaled down: nested bulged cubes; the centre is
//   at 0);
// - block node of layer l = 1 .. nr above the core surface point q: B(q) + t_l (R d(q) - B(q)),
//   t_l spaced geometrically as the disk's rings (the growth of a log-polar grid from the core's
//   face centre to R), and the last layer exactly R d(q).
// Every coordinate is an odd function of the lattice index about its middle, so the ball is
// mirror-symmetric about its three central planes to the last bit. The core's size and bulge
// (those of the disk) keep every hexahedron's corner quality (hex_corner_quality) above 0.28 for
// n = 1 .. 40 (the worst at n = 2, whose blocks have one layer), above 0.45 for n >= 4 and above
// 0.65 for n >= 8 (tests/solver/model/test_mesh3.cpp). Hexahedra only: the 6-tetrahedra split of the box needs a mesh whose
// cells cut shared faces alike, which the blocks' turned grids do not give.
// Node sets: "boundary" (the sphere's nodes), "all", "center" (n even), and the sphere's extreme
// nodes "leftmost", "rightmost", "lowest", "highest", "backmost", "frontmost" (x, y, z min and max:
// one node for n even, the four nearest for n odd).
struct BallSpec {
  double radius = 1.0;         // R [m], finite and > 0
  Vec3 center = Vec3::Zero();  // [m], finite
  int n = 8;                   // cells along a cube edge = along a quarter of a great circle, >= 1
};
Mesh3 make_ball(const BallSpec& spec);

// The 2D mesh (a generator's or a Gmsh file's) extruded through z in [0, thickness] in `layers`
// equal layers: node n of the 2D mesh at layer l (z = thickness l / layers) has index
// l num_nodes + n; cells layer by layer. z starts at 0 as the box's does with origin z = 0, so the
// extruded rectangle is the box (same nodes, cells and node sets: tests/solver/model/test_mesh3.cpp).
// - A quadrilateral becomes a hexahedron: (a, b, c, d) at layer l, then at l + 1.
// - A triangle's prism becomes 3 tetrahedra (no wedge elements): with its 2D node indices sorted
//   a < b < c, each side face is cut along the diagonal from the lower index's node at z_l to the
//   higher one's at z_(l+1); the cut depends on the edge only, so neighbouring prisms cut their
//   shared face alike (conforming), and the three diagonals never close a cycle, which makes the
//   prism (a, b, c, c'), (a, b', b, c'), (a, a', b', c') (primes at z_(l+1); two corners swapped
//   where (a, b, c) is clockwise, so every volume is positive).
// - A mesh of quadrilaterals and triangles is rejected: a hexahedron's side face would meet two
//   tetrahedra's triangles (a pyramid would be needed).
// Node sets: each 2D set extended through the thickness (its nodes at every layer, e.g. the arc
// plate's "lowest" becomes its line of nodes along z), then "back" (z = 0), "front"
// (z = thickness) and "boundary" (every node on the 3D boundary, boundary_nodes()) set anew,
// replacing 2D sets of those names. Checks: thickness finite and > 0, layers >= 1, a mesh with
// cells, every cell counter-clockwise (positive area), and the node count.
Mesh3 extrude(const Mesh& mesh, double thickness, int layers);

}  // namespace ricochet
