// Tests of the 3D mesh (solver/model/mesh.hpp) and its generators (harness/input/
// mesh_generators3.hpp): volumes against closed forms and the divergence theorem, corner
// quality, the boundary-face finder against an independent count, the box (hexahedra and the
// 6-tetrahedra split), the extrusion of the 2D generators, node sets and rejected parameters.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <numeric>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "harness/input/input_error.hpp"
#include "harness/input/mesh_generators.hpp"
#include "harness/input/mesh_generators3.hpp"
#include "solver/model/mesh.hpp"

namespace ricochet {
namespace {

using Hex = std::array<int, 8>;
using Tet = std::array<int, 4>;

// The unit cube in the corner order of mesh.hpp.
Mesh3 unit_cube() {
  Mesh3 m;
  m.nodes.resize(3, 8);
  m.nodes << 0, 1, 1, 0, 0, 1, 1, 0,  //
      0, 0, 1, 1, 0, 0, 1, 1,         //
      0, 0, 0, 0, 1, 1, 1, 1;
  m.hexes = {{0, 1, 2, 3, 4, 5, 6, 7}};
  return m;
}

// Sum of signed cell volumes [m^3]; EXPECTs every cell positive (and hexahedra unfolded).
double checked_volume(const Mesh3& mesh) {
  double total = 0.0;
  for (const Hex& h : mesh.hexes) {
    const double v = signed_volume(mesh, h);
    EXPECT_GT(v, 0.0);
    EXPECT_GT(hex_corner_quality(mesh, h), 0.0);
    total += v;
  }
  for (const Tet& t : mesh.tets) {
    const double v = signed_volume(mesh, t);
    EXPECT_GT(v, 0.0);
    total += v;
  }
  return total;
}

void expect_sets_sorted_unique(const Mesh3& mesh) {
  for (const auto& [name, set] : mesh.node_sets) {
    EXPECT_TRUE(std::is_sorted(set.begin(), set.end())) << name;
    EXPECT_EQ(std::adjacent_find(set.begin(), set.end()), set.end()) << name;
    for (int n : set) EXPECT_TRUE(n >= 0 && n < mesh.num_nodes()) << name;
  }
}

std::string error_of(auto&& make) {
  try {
    make();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no InputError";
}

// The faces of every cell as (sorted corners, cyclic corner order), counted with a std::map: an
// implementation independent of boundary_faces' sort.
struct FaceUse {
  std::vector<std::vector<int>> oriented;  // each use's corners in cell order
};
std::map<std::vector<int>, FaceUse> face_uses(const Mesh3& mesh) {
  std::map<std::vector<int>, FaceUse> uses;
  auto add = [&](std::vector<int> corners) {
    std::vector<int> key = corners;
    std::sort(key.begin(), key.end());
    uses[key].oriented.push_back(corners);
  };
  for (const Hex& h : mesh.hexes)
    for (const auto& f : kHexFaces) add({h[f[0]], h[f[1]], h[f[2]], h[f[3]]});
  for (const Tet& t : mesh.tets)
    for (const auto& f : kTetFaces) add({t[f[0]], t[f[1]], t[f[2]]});
  return uses;
}

// `b` is `a` run backwards (same cycle, opposite orientation).
bool reversed_cycle(const std::vector<int>& a, const std::vector<int>& b) {
  if (a.size() != b.size()) return false;
  std::vector<int> r(a.rbegin(), a.rend());
  for (std::size_t s = 0; s < r.size(); ++s) {
    std::rotate(r.begin(), r.begin() + 1, r.end());
    if (r == b) return true;
  }
  return false;
}

// Checks boundary_faces(mesh) against face_uses: the faces used once, in cell order, nothing
// used by three cells, every interior face used by two cells in opposite orientations. Returns
// the number of interior faces.
std::size_t expect_faces_consistent(const Mesh3& mesh) {
  const std::vector<BoundaryFace> faces = boundary_faces(mesh);
  const auto uses = face_uses(mesh);
  std::size_t once = 0, interior = 0;
  for (const auto& [key, use] : uses) {
    EXPECT_LE(use.oriented.size(), 2u) << "a face used by 3 or more cells";
    if (use.oriented.size() == 1) ++once;
    if (use.oriented.size() == 2) {
      ++interior;
      EXPECT_TRUE(reversed_cycle(use.oriented[0], use.oriented[1])) << "interior face not matched exactly";
    }
  }
  EXPECT_EQ(faces.size(), once);
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const BoundaryFace& b = faces[f];
    std::vector<int> key(b.nodes.begin(), b.nodes.begin() + b.corners);
    std::sort(key.begin(), key.end());
    const auto it = uses.find(key);
    if (it == uses.end()) {
      ADD_FAILURE() << "boundary face " << f << " is no face of a cell";
      continue;
    }
    EXPECT_EQ(it->second.oriented.size(), 1u);
    if (b.corners == 3) {
      EXPECT_EQ(b.nodes[3], -1);
    }
    if (f > 0) {
      EXPECT_LT(std::tie(faces[f - 1].cell, faces[f - 1].local_face), std::tie(b.cell, b.local_face));
    }
    const bool hex = b.cell < static_cast<int>(mesh.hexes.size());
    EXPECT_EQ(b.corners, hex ? 4 : 3);
    // The face is the cell's face `local_face` and carries the cell's volume.
    for (int k = 0; k < b.corners; ++k) {
      const int node = hex ? mesh.hexes[b.cell][kHexFaces[b.local_face][k]]
                           : mesh.tets[b.cell - mesh.hexes.size()][kTetFaces[b.local_face][k]];
      EXPECT_EQ(b.nodes[k], node);
    }
    EXPECT_EQ(b.cell_volume, hex ? signed_volume(mesh, mesh.hexes[b.cell])
                                 : signed_volume(mesh, mesh.tets[b.cell - mesh.hexes.size()]));
  }
  EXPECT_EQ(face_nodes(faces), boundary_nodes(mesh));
  return interior;
}

Vec3 cell_centroid(const Mesh3& mesh, int cell) {
  Vec3 c = Vec3::Zero();
  if (cell < static_cast<int>(mesh.hexes.size())) {
    for (int n : mesh.hexes[cell]) c += mesh.nodes.col(n) / 8.0;
  } else {
    for (int n : mesh.tets[cell - mesh.hexes.size()]) c += mesh.nodes.col(n) / 4.0;
  }
  return c;
}

Vec3 face_centroid(const Mesh3& mesh, const BoundaryFace& f) {
  Vec3 c = Vec3::Zero();
  for (int k = 0; k < f.corners; ++k) c += mesh.nodes.col(f.nodes[k]) / f.corners;
  return c;
}

// The volume by the divergence theorem, V = 1/3 sum over the faces of the integral of x . n dA,
// each face the bilinear (or flat) surface through its corners, by 2 x 2 Gauss points (exact:
// the integrand is at most quadratic in each surface coordinate). Independent of signed_volume.
double divergence_volume(const Mesh3& mesh, const Hex& h) {
  const double g[2] = {0.5 - 0.5 / std::sqrt(3.0), 0.5 + 0.5 / std::sqrt(3.0)};
  double sum = 0.0;
  for (const auto& f : kHexFaces) {
    const Vec3 a = mesh.nodes.col(h[f[0]]), b = mesh.nodes.col(h[f[1]]), c = mesh.nodes.col(h[f[2]]),
               d = mesh.nodes.col(h[f[3]]);
    for (const double u : g)
      for (const double v : g) {
        const Vec3 x = (1 - u) * (1 - v) * a + u * (1 - v) * b + u * v * c + (1 - u) * v * d;
        const Vec3 xu = (1 - v) * (b - a) + v * (c - d);
        const Vec3 xv = (1 - u) * (d - a) + u * (c - b);
        sum += x.dot(xu.cross(xv)) / 4.0;
      }
  }
  return sum / 3.0;
}

// ---------------------------------------------------------------- cells

TEST(Mesh3, VolumesOfUnitCellsAndClosedForms) {
  Mesh3 m = unit_cube();
  EXPECT_EQ(signed_volume(m, m.hexes[0]), 1.0);
  EXPECT_EQ(hex_corner_quality(m, m.hexes[0]), 1.0);
  const Tet unit_tet = {0, 1, 3, 4};  // (0,0,0), (1,0,0), (0,1,0), (0,0,1)
  EXPECT_EQ(signed_volume(m, unit_tet), 1.0 / 6.0);
  EXPECT_EQ(signed_volume(m, Tet{0, 3, 1, 4}), -1.0 / 6.0);
  EXPECT_EQ(signed_volume(m, Hex{4, 5, 6, 7, 0, 1, 2, 3}), -1.0);  // faces swapped: inverted
  EXPECT_LT(hex_corner_quality(m, Hex{4, 5, 6, 7, 0, 1, 2, 3}), 0.0);

  // Corner 6 moved by d: x = x0 + xi eta zeta d, det J = 1 + d . (eta zeta, xi zeta, xi eta), so
  // V = 1 + (d_x + d_y + d_z)/4 (a warped hexahedron: its three faces at corner 6 are not flat);
  // under an affine map x -> A x + b the volume is det A times that.
  std::mt19937_64 random(3);
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  for (int trial = 0; trial < 200; ++trial) {
    Mesh3 w = unit_cube();
    const Vec3 d(u(random), u(random), u(random));
    w.nodes.col(6) += d;
    Mat3 A;
    for (int i = 0; i < 9; ++i) A(i / 3, i % 3) = (i % 4 == 0 ? 1.0 : 0.0) + u(random);
    if (A.determinant() < 0.0) A.col(0) *= -1.0;
    w.nodes = (A * w.nodes).colwise() + Vec3(1.5, -2.0, 0.25);
    const double expected = A.determinant() * (1.0 + d.sum() / 4.0);
    // Measured at most 6.7e-16 (signed_volume) and 1.3e-15 (divergence theorem).
    EXPECT_NEAR(signed_volume(w, w.hexes[0]), expected, 1e-14) << trial;
    EXPECT_NEAR(divergence_volume(w, w.hexes[0]), expected, 1e-14) << trial;
  }
  // Random hexahedra: the divergence theorem (faces of kHexFaces, outward) agrees.
  for (int trial = 0; trial < 200; ++trial) {
    Mesh3 w = unit_cube();
    for (int k = 0; k < 24; ++k) w.nodes(k % 3, k / 3) += 0.5 * u(random);
    EXPECT_NEAR(signed_volume(w, w.hexes[0]), divergence_volume(w, w.hexes[0]), 1e-14) << trial;  // measured 8.9e-16
  }
}

TEST(Mesh3, CornerQualityOfParallelepipedsAndFoldedHexahedra) {
  Mesh3 m = unit_cube();
  Mat3 shear;
  shear << 2, 0.5, 0.3, 0, 1, -0.4, 0, 0, 0.7;
  m.nodes = shear * m.nodes;
  EXPECT_NEAR(hex_corner_quality(m, m.hexes[0]), 1.0, 1e-15);  // every corner det = det(shear)
  // Corner 6 pulled to (p, p, p): det J = 1 + 3 (p - 1) at corner 6, V = 1 + 3 (p - 1)/4. At
  // p = 0.5 the volume is still positive (0.625) but corner 6 is folded (-0.5): quality
  // -0.5 / mean(1, 1, 1, 1, 0.5, 0.5, 0.5, -0.5) = -0.8.
  Mesh3 f = unit_cube();
  f.nodes.col(6) = Vec3(0.5, 0.5, 0.5);
  EXPECT_NEAR(signed_volume(f, f.hexes[0]), 0.625, 1e-15);
  EXPECT_NEAR(hex_corner_quality(f, f.hexes[0]), -0.8, 1e-15);
  f.nodes.col(6) = Vec3(0.7, 0.7, 0.7);  // 3p - 2 = 0.1 > 0: not folded
  EXPECT_GT(hex_corner_quality(f, f.hexes[0]), 0.0);
}

TEST(Mesh3, BoundaryFacesOfOneCellAreOutwardInTableOrder) {
  const Mesh3 cube = unit_cube();
  const std::vector<BoundaryFace> faces = boundary_faces(cube);
  ASSERT_EQ(faces.size(), 6u);
  const Vec3 normals[6] = {-Vec3::UnitX(), Vec3::UnitX(), -Vec3::UnitY(), Vec3::UnitY(), -Vec3::UnitZ(), Vec3::UnitZ()};
  for (int f = 0; f < 6; ++f) {
    EXPECT_EQ(faces[f].local_face, f);
    EXPECT_EQ(faces[f].corners, 4);
    EXPECT_EQ(faces[f].cell_volume, 1.0);
    EXPECT_EQ(face_area_vector(cube, faces[f]), normals[f]) << f;
  }
  Mesh3 tet;
  tet.nodes.resize(3, 4);
  tet.nodes << 0, 1, 0, 0,  //
      0, 0, 1, 0,           //
      0, 0, 0, 1;
  tet.tets = {{0, 1, 2, 3}};
  const std::vector<BoundaryFace> tf = boundary_faces(tet);
  ASSERT_EQ(tf.size(), 4u);
  const Vec3 tn[4] = {-0.5 * Vec3::UnitZ(), -0.5 * Vec3::UnitY(), Vec3(0.5, 0.5, 0.5), -0.5 * Vec3::UnitX()};
  for (int f = 0; f < 4; ++f) {
    EXPECT_EQ(tf[f].corners, 3);
    EXPECT_EQ(tf[f].nodes[3], -1);
    EXPECT_EQ(tf[f].cell_volume, 1.0 / 6.0);
    EXPECT_EQ(face_area_vector(tet, tf[f]), tn[f]) << f;
  }
  EXPECT_EQ(boundary_nodes(tet), (std::vector<int>{0, 1, 2, 3}));
}

// Two hexahedra sharing a face, and the same cube split into tetrahedra next to a hexahedron:
// a quadrilateral and two triangles on the same four nodes never match.
TEST(Mesh3, SharedFacesAreInteriorAndQuadrilateralsNeverMatchTriangles) {
  const Mesh3 two = make_box({.size = Vec3(2, 1, 1), .nx = 2});
  EXPECT_EQ(boundary_faces(two).size(), 10u);
  EXPECT_EQ(expect_faces_consistent(two), 1u);

  Mesh3 mixed = two;  // the second cube as 6 tetrahedra
  const Mesh3 split = make_box({.size = Vec3(2, 1, 1), .nx = 2, .tetrahedra = true});
  mixed.hexes.pop_back();
  mixed.tets.assign(split.tets.begin() + 6, split.tets.end());
  // 5 faces of the hexahedron, 2 x 5 triangles of the tetrahedra's outer faces, and the shared
  // square twice: once as the hexahedron's quadrilateral, once as two triangles.
  EXPECT_EQ(boundary_faces(mixed).size(), 5u + 10u + 1u + 2u);
  expect_faces_consistent(mixed);

  // A tetrahedron on three corners of the cube's +x face (its three lowest nodes, 1 2 5 of
  // the face 1 2 6 5) and a point beyond: the triangle matches no quadrilateral.
  Mesh3 glued = unit_cube();
  glued.nodes.conservativeResize(3, 9);
  glued.nodes.col(8) = Vec3(1.5, 0.5, 0.5);
  glued.tets = {{1, 2, 5, 8}};
  ASSERT_GT(signed_volume(glued, glued.tets[0]), 0.0);
  EXPECT_EQ(boundary_faces(glued).size(), 6u + 4u);
  EXPECT_EQ(expect_faces_consistent(glued), 0u);
}

// ---------------------------------------------------------------- box

TEST(Mesh3Box, CountsVolumeAndPositiveCells) {
  for (const bool tets : {false, true}) {
    SCOPED_TRACE(tets ? "tetrahedra" : "hexahedra");
    const Mesh3 m =
        make_box({.size = Vec3(2.0, 0.5, 0.75), .nx = 4, .ny = 3, .nz = 2, .origin = Vec3(1, -2, 0.5), .tetrahedra = tets});
    EXPECT_EQ(m.num_nodes(), 5 * 4 * 3);
    EXPECT_EQ(m.hexes.size(), tets ? 0u : 24u);
    EXPECT_EQ(m.tets.size(), tets ? 144u : 0u);
    EXPECT_EQ(m.num_cells(), tets ? 144 : 24);
    EXPECT_NEAR(checked_volume(m), 0.75, 4e-15);  // measured 1.1e-16 (hexahedra), 5.6e-16 (tetrahedra)
    EXPECT_EQ(m.nodes.row(0).minCoeff(), 1.0);
    EXPECT_EQ(m.nodes.row(0).maxCoeff(), 3.0);
    EXPECT_EQ(m.nodes.row(1).minCoeff(), -2.0);
    EXPECT_EQ(m.nodes.row(1).maxCoeff(), -1.5);
    EXPECT_EQ(m.nodes.row(2).minCoeff(), 0.5);
    EXPECT_EQ(m.nodes.row(2).maxCoeff(), 1.25);
    for (const Hex& h : m.hexes) EXPECT_NEAR(hex_corner_quality(m, h), 1.0, 1e-15);
    // Every tetrahedron has the volume of a sixth of its cell.
    for (const Tet& t : m.tets) EXPECT_NEAR(signed_volume(m, t), 0.75 / 144, 1e-17);
  }
}

TEST(Mesh3Box, BoundaryFacesCoverTheSurfaceOutwards) {
  const int nx = 4, ny = 3, nz = 2;
  const Vec3 size(2.0, 0.5, 0.75), origin(1, -2, 0.5);
  const Vec3 center = origin + size / 2;
  for (const bool tets : {false, true}) {
    SCOPED_TRACE(tets ? "tetrahedra" : "hexahedra");
    const Mesh3 m = make_box({.size = size, .nx = nx, .ny = ny, .nz = nz, .origin = origin, .tetrahedra = tets});
    const std::vector<BoundaryFace> faces = boundary_faces(m);
    EXPECT_EQ(faces.size(), (tets ? 4u : 2u) * (nx * ny + ny * nz + nz * nx));
    Vec3 sum = Vec3::Zero();
    double area = 0.0;
    std::map<int, double> side_area;  // by outward axis: 0..5 = -x, +x, -y, +y, -z, +z
    for (const BoundaryFace& f : faces) {
      const Vec3 a = face_area_vector(m, f);
      sum += a;
      area += a.norm();
      // Points away from the box's centroid and from its own cell's.
      EXPECT_GT((face_centroid(m, f) - center).dot(a), 0.0);
      EXPECT_GT((face_centroid(m, f) - cell_centroid(m, f.cell)).dot(a), 0.0);
      // Lies in one side of the box, with that side's outward normal exactly.
      int axis = 0;
      a.cwiseAbs().maxCoeff(&axis);
      EXPECT_EQ(a.norm(), std::abs(a(axis)));
      const int side = 2 * axis + (a(axis) > 0 ? 1 : 0);
      side_area[side] += a.norm();
      const double plane = a(axis) > 0 ? origin(axis) + size(axis) : origin(axis);
      for (int k = 0; k < f.corners; ++k) EXPECT_EQ(m.nodes(axis, f.nodes[k]), plane);
    }
    EXPECT_LT(sum.norm(), 1e-15);
    EXPECT_NEAR(area, 2 * (size.x() * size.y() + size.y() * size.z() + size.z() * size.x()), 1e-14);  // measured 1.8e-15
    for (int s = 0; s < 6; ++s) {
      const int a = s / 2;
      EXPECT_NEAR(side_area[s], size((a + 1) % 3) * size((a + 2) % 3), 1e-15) << "side " << s;
    }
    expect_faces_consistent(m);
  }
}

TEST(Mesh3Box, SixTetrahedraSplitIsConformingForAnyCounts) {
  const std::vector<std::tuple<int, int, int>> counts = {{1, 1, 1}, {2, 1, 1}, {1, 2, 1}, {1, 1, 2}, {3, 2, 2}, {2, 3, 4}};
  for (const auto& [nx, ny, nz] : counts) {
    SCOPED_TRACE(std::to_string(nx) + "x" + std::to_string(ny) + "x" + std::to_string(nz));
    const Mesh3 m = make_box({.nx = nx, .ny = ny, .nz = nz, .tetrahedra = true});
    const std::size_t cells = 6u * nx * ny * nz, outer = 4u * (nx * ny + ny * nz + nz * nx);
    // 4 faces per tetrahedron: the outer ones once, every other one exactly twice.
    EXPECT_EQ(expect_faces_consistent(m), (4 * cells - outer) / 2);
    EXPECT_EQ(boundary_faces(m).size(), outer);
    EXPECT_NEAR(checked_volume(m), 1.0, 1e-14);
  }
}

TEST(Mesh3Box, NodeSets) {
  const Mesh3 m = make_box({.size = Vec3(2, 3, 4), .nx = 2, .ny = 3, .nz = 4, .origin = Vec3(-1, 0, 1)});
  expect_sets_sorted_unique(m);
  const std::map<std::string, std::pair<int, double>> sides = {
      {"left", {0, -1.0}}, {"right", {0, 1.0}}, {"bottom", {1, 0.0}}, {"top", {1, 3.0}}, {"back", {2, 1.0}}, {"front", {2, 5.0}}};
  EXPECT_EQ(m.node_sets.size(), 8u);
  for (const auto& [name, where] : sides) {
    const auto& [axis, value] = where;
    const std::vector<int>& set = m.node_sets.at(name);
    std::vector<int> expected;
    for (int n = 0; n < m.num_nodes(); ++n)
      if (m.nodes(axis, n) == value) expected.push_back(n);
    EXPECT_EQ(set, expected) << name;
  }
  EXPECT_EQ(m.node_sets.at("left").size(), 4u * 5u);
  EXPECT_EQ(m.node_sets.at("bottom").size(), 3u * 5u);
  EXPECT_EQ(m.node_sets.at("front").size(), 3u * 4u);
  EXPECT_EQ(m.node_sets.at("boundary"), boundary_nodes(m));
  EXPECT_EQ(m.node_sets.at("boundary").size(), 60u - 1u * 2u * 3u);  // all but the 1 x 2 x 3 interior
  EXPECT_EQ(m.node_sets.at("all").size(), 60u);
  const Mesh3 t = make_box({.size = Vec3(2, 3, 4), .nx = 2, .ny = 3, .nz = 4, .origin = Vec3(-1, 0, 1), .tetrahedra = true});
  EXPECT_EQ(t.nodes, m.nodes);
  EXPECT_EQ(t.node_sets, m.node_sets);
  EXPECT_EQ(t.node_sets.at("boundary"), boundary_nodes(t));
}

TEST(Mesh3Box, RejectsBadParameters) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(error_of([] { make_box({.nx = 0}); }), "box: nx must be >= 1 (got 0)");
  EXPECT_EQ(error_of([] { make_box({.ny = -2}); }), "box: ny must be >= 1 (got -2)");
  EXPECT_EQ(error_of([] { make_box({.nz = 0}); }), "box: nz must be >= 1 (got 0)");
  EXPECT_EQ(error_of([] { make_box({.size = Vec3(0, 1, 1)}); }), "box: lx must be finite and > 0 (got 0)");
  EXPECT_EQ(error_of([&] { make_box({.size = Vec3(1, nan, 1)}); }), "box: ly must be finite and > 0 (got nan)");
  EXPECT_EQ(error_of([&] { make_box({.size = Vec3(1, 1, -inf)}); }), "box: lz must be finite and > 0 (got -inf)");
  EXPECT_EQ(error_of([&] { make_box({.origin = Vec3(0, 0, inf)}); }), "box: origin must be finite (got 0, 0, inf)");
  EXPECT_EQ(error_of([] { make_box({.nx = 1000, .ny = 1000, .nz = 1000}); }),
            "box: (nx+1)*(ny+1)*(nz+1) must be <= 100000000 nodes (got nx 1000, ny 1000, nz 1000)");
  EXPECT_NE(error_of([] { make_box({.nx = 1 << 30, .ny = 1 << 30, .nz = 1 << 30}); }).find("must be <= 100000000"),
            std::string::npos);  // no overflow of the count
}

// ---------------------------------------------------------------- ball

TEST(Mesh3Ball, CountsAndPositiveCellsOfGoodQuality) {
  // The header's promise: every hexahedron's corner quality above 0.28 for n = 1 .. 40, above
  // 0.45 for n >= 4, above 0.65 for n >= 8. Measured 0.286 (n = 2), 0.456 (n = 4), 0.659 (n = 8).
  double worst = 1.0, worst4 = 1.0, worst8 = 1.0;
  for (int n = 1; n <= 40; ++n) {
    SCOPED_TRACE("n = " + std::to_string(n));
    const Mesh3 m = make_ball({.radius = 0.03, .center = Vec3(0.1, -0.2, 0.3), .n = n});
    const int nr = (n + 1) / 2;
    ASSERT_EQ(m.num_nodes(), (n + 1) * (n + 1) * (n + 1) + nr * (6 * n * n + 2));
    ASSERT_EQ(m.hexes.size(), static_cast<std::size_t>(n * n * n + 6 * n * n * nr));
    EXPECT_TRUE(m.tets.empty());
    for (const Hex& h : m.hexes) {
      EXPECT_GT(signed_volume(m, h), 0.0);
      const double q = hex_corner_quality(m, h);
      worst = std::min(worst, q);
      if (n >= 4) worst4 = std::min(worst4, q);
      if (n >= 8) worst8 = std::min(worst8, q);
    }
  }
  EXPECT_GT(worst, 0.28);
  EXPECT_GT(worst4, 0.45);
  EXPECT_GT(worst8, 0.65);
}

TEST(Mesh3Ball, VolumeConvergesToTheSphereSecondOrder) {
  const double R = 0.03, exact = 4.0 / 3.0 * std::numbers::pi * R * R * R;
  double previous = 1.0;
  for (const int n : {4, 8, 16, 32}) {
    const Mesh3 m = make_ball({.radius = R, .center = Vec3(0.1, -0.2, 0.3), .n = n});
    const double error = (exact - checked_volume(m)) / exact;  // inscribed faces: the mesh is smaller
    EXPECT_GT(error, 0.0) << n;
    if (n > 4) {
      EXPECT_NEAR(previous / error, 4.0, 0.2) << n;  // halving the cells divides it by 4
    }
    previous = error;
  }
  EXPECT_LT(previous, 2e-3);
}

TEST(Mesh3Ball, SurfaceIsTheSphereClosedAndOutward) {
  const double R = 0.03;
  const Vec3 c(0.1, -0.2, 0.3);
  for (const int n : {1, 2, 5, 8}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    const Mesh3 m = make_ball({.radius = R, .center = c, .n = n});
    const std::vector<BoundaryFace> faces = boundary_faces(m);
    EXPECT_EQ(faces.size(), static_cast<std::size_t>(6 * n * n));
    EXPECT_EQ(m.node_sets.at("boundary"), boundary_nodes(m));
    EXPECT_EQ(m.node_sets.at("boundary").size(), static_cast<std::size_t>(6 * n * n + 2));
    // R to the round-off of adding the centre (|c| = 0.37 m: an ulp is 5.6e-17).
    for (const int p : m.node_sets.at("boundary")) EXPECT_NEAR((m.nodes.col(p) - c).norm(), R, 2e-16);
    Vec3 sum = Vec3::Zero();
    for (const BoundaryFace& f : faces) {
      const Vec3 a = face_area_vector(m, f);
      sum += a;
      EXPECT_GT((face_centroid(m, f) - c).dot(a), 0.0);
    }
    EXPECT_LT(sum.norm(), 1e-18);  // measured ~1e-19 against faces of ~1e-4 m^2
    expect_faces_consistent(m);
  }
}

TEST(Mesh3Ball, MirrorSymmetricAboutItsCentralPlanesExactly) {
  for (const int n : {3, 6}) {
    const Mesh3 m = make_ball({.radius = 1.0, .n = n});
    std::map<std::array<double, 3>, int> at;
    for (int p = 0; p < m.num_nodes(); ++p) at[{m.nodes(0, p), m.nodes(1, p), m.nodes(2, p)}] = p;
    EXPECT_EQ(at.size(), static_cast<std::size_t>(m.num_nodes()));  // no two nodes coincide
    for (int axis = 0; axis < 3; ++axis)
      for (int p = 0; p < m.num_nodes(); ++p) {
        std::array<double, 3> x = {m.nodes(0, p), m.nodes(1, p), m.nodes(2, p)};
        x[static_cast<std::size_t>(axis)] = -x[static_cast<std::size_t>(axis)];
        EXPECT_TRUE(at.count(x)) << "node " << p << " mirrored along axis " << axis;
      }
  }
}

TEST(Mesh3Ball, NodeSets) {
  const Vec3 c(1.0, 2.0, -3.0);
  const double R = 0.5;
  const std::map<std::string, std::pair<int, double>> extremes = {
      {"leftmost", {0, -1.0}}, {"rightmost", {0, 1.0}}, {"lowest", {1, -1.0}},
      {"highest", {1, 1.0}},   {"backmost", {2, -1.0}}, {"frontmost", {2, 1.0}}};
  for (const int n : {4, 5}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    const Mesh3 m = make_ball({.radius = R, .center = c, .n = n});
    expect_sets_sorted_unique(m);
    EXPECT_EQ(m.node_sets.at("all").size(), static_cast<std::size_t>(m.num_nodes()));
    EXPECT_EQ(m.node_sets.count("center"), n % 2 == 0 ? 1u : 0u);
    if (n % 2 == 0) {
      EXPECT_EQ(m.nodes.col(m.node_sets.at("center")[0]), c);
    }
    for (const auto& [name, where] : extremes) {
      const auto& [axis, sign] = where;
      const std::vector<int>& set = m.node_sets.at(name);
      ASSERT_EQ(set.size(), n % 2 == 0 ? 1u : 4u) << name;
      // The set's nodes are the sphere's nodes furthest along sign x axis.
      double best = -1.0;
      for (const int p : m.node_sets.at("boundary")) best = std::max(best, sign * (m.nodes(axis, p) - c(axis)));
      for (const int p : set) EXPECT_NEAR(sign * (m.nodes(axis, p) - c(axis)), best, 1e-15) << name;
      if (n % 2 == 0) {
        EXPECT_EQ(m.nodes(axis, set[0]), c(axis) + sign * R) << name;
      }
    }
  }
}

TEST(Mesh3Ball, RejectsBadParameters) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(error_of([] { make_ball({.n = 0}); }), "ball: n must be >= 1 (got 0)");
  EXPECT_EQ(error_of([] { make_ball({.radius = -1.0}); }), "ball: radius must be finite and > 0 (got -1)");
  EXPECT_EQ(error_of([&] { make_ball({.radius = nan}); }), "ball: radius must be finite and > 0 (got nan)");
  EXPECT_EQ(error_of([&] { make_ball({.center = Vec3(0, nan, 0)}); }), "ball: center must be finite (got 0, nan, 0)");
  EXPECT_EQ(error_of([] { make_ball({.n = 500}); }),
            "ball: (n+1)^3 + ceil(n/2) (6 n^2 + 2) must be <= 100000000 nodes (got n 500)");
  EXPECT_NE(error_of([] { make_ball({.n = 1 << 30}); }).find("must be <= 100000000"), std::string::npos);
}

// ---------------------------------------------------------------- extrude

TEST(Mesh3Extrude, RectangleIsTheBox) {
  const Mesh3 e = extrude(make_rectangle({.width = 2.0, .height = 0.5, .nx = 3, .ny = 2}), 0.3, 4);
  const Mesh3 b = make_box({.size = Vec3(2.0, 0.5, 0.3), .nx = 3, .ny = 2, .nz = 4});
  EXPECT_EQ(e.nodes, b.nodes);  // bit for bit
  EXPECT_EQ(e.hexes, b.hexes);
  EXPECT_TRUE(e.tets.empty());
  EXPECT_EQ(e.node_sets, b.node_sets);
}

// The arc plate's area (sum of its 2D cells) times the thickness; its boundary area.
TEST(Mesh3Extrude, ArcPlateVolumeIsAreaTimesThickness) {
  const double thickness = 0.01;
  const int layers = 3;
  for (const bool triangles : {false, true}) {
    SCOPED_TRACE(triangles ? "triangles" : "quadrilaterals");
    const Mesh plate = make_arc_plate({.nx = 6, .ny = 8, .bias = 2.0, .triangles = triangles});
    double area = 0.0, perimeter = 0.0;
    for (const auto& q : plate.quads) area += signed_area(plate, q.data(), 4);
    for (const auto& t : plate.tris) area += signed_area(plate, t.data(), 3);
    for (const BoundaryEdge& e : boundary_edges(plate)) perimeter += (plate.nodes.col(e.b) - plate.nodes.col(e.a)).norm();
    const Mesh3 m = extrude(plate, thickness, layers);
    EXPECT_EQ(m.num_nodes(), plate.num_nodes() * (layers + 1));
    EXPECT_EQ(m.hexes.size(), plate.quads.size() * layers);
    EXPECT_EQ(m.tets.size(), 3 * plate.tris.size() * layers);
    EXPECT_NEAR(checked_volume(m), area * thickness, 1e-14 * area * thickness);  // measured 2.1e-16
    const std::vector<BoundaryFace> faces = boundary_faces(m);
    const std::size_t edges = boundary_edges(plate).size(), cells = static_cast<std::size_t>(plate.num_cells());
    EXPECT_EQ(faces.size(), triangles ? 2 * cells + 2 * layers * edges : 2 * cells + layers * edges);
    double surface = 0.0;
    Vec3 sum = Vec3::Zero();
    for (const BoundaryFace& f : faces) {
      surface += face_area_vector(m, f).norm();
      sum += face_area_vector(m, f);
      EXPECT_GT((face_centroid(m, f) - cell_centroid(m, f.cell)).dot(face_area_vector(m, f)), 0.0);
    }
    // Measured: 2e-16 and 3.5e-16 of the surface.
    EXPECT_NEAR(surface, 2 * area + perimeter * thickness, 2e-15 * surface);
    EXPECT_LT(sum.norm(), 4e-15 * surface);
    expect_faces_consistent(m);
  }
}

// Triangles in any numbering: the prisms' cuts conform (every interior face twice, opposite),
// every tetrahedron is positive. The rectangle's triangles come in both orders of their sorted
// corners (a, b, c counter-clockwise and clockwise); a random renumbering mixes them further.
TEST(Mesh3Extrude, TrianglePrismsConformInAnyNumbering) {
  const Mesh flat = make_rectangle({.width = 1.0, .height = 0.8, .nx = 4, .ny = 3, .triangles = true});
  std::mt19937_64 random(11);
  for (int trial = 0; trial < 20; ++trial) {
    Mesh m = flat;
    if (trial > 0) {
      std::vector<int> perm(static_cast<std::size_t>(m.num_nodes()));
      std::iota(perm.begin(), perm.end(), 0);
      std::shuffle(perm.begin(), perm.end(), random);
      for (int n = 0; n < m.num_nodes(); ++n) m.nodes.col(perm[n]) = flat.nodes.col(n);
      for (auto& t : m.tris)
        for (int& n : t) n = perm[n];
      for (auto& [name, set] : m.node_sets) {
        for (int& n : set) n = perm[n];
        std::sort(set.begin(), set.end());
      }
    }
    const Mesh3 e = extrude(m, 0.2, 2);
    SCOPED_TRACE(trial);
    EXPECT_NEAR(checked_volume(e), 0.8 * 0.2, 1e-15);
    const std::size_t cells = e.tets.size(), outer = 2 * m.tris.size() + 2 * 2 * boundary_edges(m).size();
    EXPECT_EQ(boundary_faces(e).size(), outer);
    EXPECT_EQ(expect_faces_consistent(e), (4 * cells - outer) / 2);
  }
}

TEST(Mesh3Extrude, NodeSetsRunThroughTheThickness) {
  const int layers = 4;
  const double thickness = 0.02;
  const Mesh plate = make_arc_plate({.nx = 6, .ny = 4});
  const Mesh3 m = extrude(plate, thickness, layers);
  expect_sets_sorted_unique(m);
  const int n = plate.num_nodes();
  // "lowest" (the arc's node at x = 0) becomes its line along z.
  ASSERT_EQ(plate.node_sets.at("lowest").size(), 1u);
  const std::vector<int>& lowest = m.node_sets.at("lowest");
  ASSERT_EQ(lowest.size(), static_cast<std::size_t>(layers + 1));
  for (int l = 0; l <= layers; ++l) {
    EXPECT_EQ(lowest[l], l * n + plate.node_sets.at("lowest")[0]);
    EXPECT_EQ(m.nodes.col(lowest[l]), Vec3(0.0, 0.0, thickness * (static_cast<double>(l) / layers)));
  }
  for (const char* name : {"left", "right", "top", "bottom", "top_left", "top_right"})
    EXPECT_EQ(m.node_sets.at(name).size(), plate.node_sets.at(name).size() * (layers + 1)) << name;
  for (int p : m.node_sets.at("top")) EXPECT_EQ(m.nodes(1, p), plate.nodes(1, plate.node_sets.at("top")[0]));
  std::vector<int> back, front;
  for (int p = 0; p < m.num_nodes(); ++p) {
    if (m.nodes(2, p) == 0.0) back.push_back(p);
    if (m.nodes(2, p) == thickness) front.push_back(p);
  }
  EXPECT_EQ(m.node_sets.at("back"), back);
  EXPECT_EQ(m.node_sets.at("front"), front);
  EXPECT_EQ(m.node_sets.at("boundary"), boundary_nodes(m));
  EXPECT_EQ(m.node_sets.at("all").size(), static_cast<std::size_t>(m.num_nodes()));
  EXPECT_EQ(m.node_sets.size(), plate.node_sets.size() + 2);  // + back, front
}

TEST(Mesh3Extrude, RejectsBadInput) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Mesh quads = make_rectangle({});
  EXPECT_EQ(error_of([&] { extrude(quads, 0.0, 1); }), "extrude: thickness must be finite and > 0 (got 0)");
  EXPECT_EQ(error_of([&] { extrude(quads, nan, 1); }), "extrude: thickness must be finite and > 0 (got nan)");
  EXPECT_EQ(error_of([&] { extrude(quads, 1.0, 0); }), "extrude: layers must be >= 1 (got 0)");
  EXPECT_EQ(error_of([] { extrude(Mesh{}, 1.0, 1); }), "extrude: the 2D mesh has no cells");
  Mesh mixed = make_rectangle({.nx = 2, .triangles = true});
  mixed.tris.pop_back();
  mixed.tris.pop_back();
  mixed.quads.push_back({1, 2, 5, 4});
  EXPECT_EQ(error_of([&] { extrude(mixed, 1.0, 1); }),
            "extrude: the 2D mesh mixes quadrilaterals (1) and triangles (2); a hexahedron's side face cannot "
            "meet two tetrahedra's triangles: use one kind");
  Mesh clockwise = make_rectangle({.nx = 2});
  std::reverse(clockwise.quads[1].begin(), clockwise.quads[1].end());
  EXPECT_EQ(error_of([&] { extrude(clockwise, 1.0, 1); }), "extrude: 2D cell 1 is not counter-clockwise (area <= 0)");
  Mesh tri_cw = make_rectangle({.triangles = true});
  std::swap(tri_cw.tris[0][1], tri_cw.tris[0][2]);
  EXPECT_EQ(error_of([&] { extrude(tri_cw, 1.0, 1); }), "extrude: 2D cell 0 is not counter-clockwise (area <= 0)");
  EXPECT_EQ(error_of([] { extrude(make_rectangle({.nx = 100, .ny = 100}), 1.0, 20000); }),
            "extrude: nodes x (layers+1) must be <= 100000000 nodes (got 10201 nodes, layers 20000)");
}

}  // namespace
}  // namespace ricochet
