// Contact between deformable bodies in 3D, the node-to-face geometry (solver/contact/
// body_contact3.hpp): the surface of a body's boundary faces, the projection onto triangles and
// bilinear quadrilaterals (against hand values and a brute-force minimization), the stencil, the
// face choice (walking, ties, edges and vertices), the signed distance and frame invariance.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "harness/input/mesh_generators3.hpp"
#include "tests/support/meshes3.hpp"
#include "solver/contact/body_contact3.hpp"
#include "solver/contact/contact_set.hpp"
// Last: it declares the C allocation functions that Eigen's headers declare differently.
#include "tests/support/alloc_counter.hpp"

namespace ricochet {
namespace {

using Points = std::vector<Vec3>;

Model<3> model_of(Mesh3 mesh) {
  BodyInput<3> b;
  b.name = "master";
  b.mesh = std::move(mesh);
  b.material = StVenantKirchhoff3::make(1e6, 0.3, 1000.0);
  return build_model({b}, Vec3::Zero());
}

Mesh3 box_mesh(Vec3 size, int nx, int ny, int nz, bool tets, Vec3 origin = Vec3::Zero()) {
  BoxSpec s;
  s.size = size;
  s.nx = nx;
  s.ny = ny;
  s.nz = nz;
  s.tetrahedra = tets;
  s.origin = origin;
  return make_box(s);
}

// Unit cubes at the given integer corners, sharing nodes: an L-shaped body has a concave edge.
// With `tets` each cube is split as make_box splits it (6 tetrahedra around its diagonal from
// corner 0 to corner 6), which is conforming between cubes.
Mesh3 cubes(const std::vector<std::array<int, 3>>& cells, bool tets = false) {
  Mesh3 m;
  std::map<std::array<int, 3>, int> index;
  std::vector<Vec3> nodes;
  auto node = [&](int i, int j, int k) {
    const auto [it, added] = index.try_emplace({i, j, k}, static_cast<int>(nodes.size()));
    if (added) nodes.emplace_back(i, j, k);
    return it->second;
  };
  for (const auto& c : cells) {
    const int i = c[0], j = c[1], k = c[2];
    m.hexes.push_back({node(i, j, k), node(i + 1, j, k), node(i + 1, j + 1, k), node(i, j + 1, k),
                       node(i, j, k + 1), node(i + 1, j, k + 1), node(i + 1, j + 1, k + 1), node(i, j + 1, k + 1)});
  }
  m.nodes.resize(3, static_cast<long>(nodes.size()));
  for (std::size_t p = 0; p < nodes.size(); ++p) m.nodes.col(static_cast<long>(p)) = nodes[p];
  if (!tets) return m;
  constexpr std::array<std::array<int, 4>, 6> kKuhn = {
      {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6}, {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}}};
  for (const auto& h : m.hexes)
    for (const auto& t : kKuhn) m.tets.push_back({h[t[0]], h[t[1]], h[t[2]], h[t[3]]});
  m.hexes.clear();
  return m;
}

// The model's reference positions with one more point at the end: the slave node.
Points positions_with_slave(const Model<3>& model) {
  Points x(model.num_nodes() + 1);
  for (int j = 0; j < model.num_nodes(); ++j) x[j] = model.ref.col(j);
  return x;
}

Vec3 face_point(const Surface3& s, const Points& x, int fi, double xi, double eta) {
  const SurfaceFace& f = s.faces[fi];
  const std::array<double, 4> w = face_weights(f.count, xi, eta);
  Vec3 p = Vec3::Zero();
  for (int a = 0; a < f.count; ++a) p += w[a] * x[f.node[a]];
  return p;
}

Vec3 face_centre(const Surface3& s, const Points& x, int fi) {
  return s.faces[fi].count == 3 ? face_point(s, x, fi, 1.0 / 3.0, 1.0 / 3.0) : face_point(s, x, fi, 0.5, 0.5);
}

// sum_j coef_j x_j over a stencil (x - p for a face contact).
Vec3 stencil_sum(const StencilN<5>& st, const Points& x) {
  Vec3 r = Vec3::Zero();
  for (int j = 0; j < st.count; ++j) r += st.coef[j] * x[st.node[j]];
  return r;
}
double coef_sum(const StencilN<5>& st) {
  double r = 0.0;
  for (int j = 0; j < st.count; ++j) r += st.coef[j];
  return r;
}

// The three test bodies of a box [0, 1] x [0, 0.8] x [0, 0.6]: hexahedra, tetrahedra, and
// distorted hexahedra (warped faces).
std::vector<Mesh3> test_meshes() {
  return {box_mesh(Vec3(1.0, 0.8, 0.6), 3, 2, 2, false), box_mesh(Vec3(1.0, 0.8, 0.6), 2, 2, 1, true),
          test3::distorted_box(3, 2, 2, false, 0.12), test3::distorted_box(2, 2, 2, true, 0.12)};
}

TEST(BodyContact3, SurfaceIsClosedAndOutward) {
  for (Mesh3& mesh : test_meshes()) {
    const bool tets = !mesh.tets.empty();
    const Model<3> model = model_of(mesh);
    const Surface3 s = make_surface3(model, 0);
    const Points x = positions_with_slave(model);
    ASSERT_EQ(s.faces.size(), model.bodies[0].boundary_faces.size());
    EXPECT_EQ(s.nodes, model.bodies[0].boundary_nodes);
    double longest = 0.0;
    for (int fi = 0; fi < static_cast<int>(s.faces.size()); ++fi) {
      const SurfaceFace& f = s.faces[fi];
      ASSERT_EQ(f.count, tets ? 3 : 4);
      for (int k = 0; k < f.count; ++k) {
        const int a = f.node[k], b = f.node[(k + 1) % f.count];
        longest = std::max(longest, (x[b] - x[a]).norm());
        // Closed and consistently oriented: the neighbour runs the edge the other way and
        // points back.
        const int g = f.neighbour[k], j = f.neighbour_edge[k];
        ASSERT_GE(g, 0);
        const SurfaceFace& fg = s.faces[g];
        EXPECT_EQ(fg.node[j], b);
        EXPECT_EQ(fg.node[(j + 1) % fg.count], a);
        EXPECT_EQ(fg.neighbour[j], fi);
        EXPECT_EQ(fg.neighbour_edge[j], k);
        // The face is listed at its corner.
        EXPECT_EQ(s.nodes[f.vertex[k]], a);
        const auto first = s.vertex_faces.begin() + s.vertex_faces_begin[f.vertex[k]];
        const auto last = s.vertex_faces.begin() + s.vertex_faces_begin[f.vertex[k] + 1];
        EXPECT_NE(std::find(first, last, fi), last);
      }
    }
    EXPECT_DOUBLE_EQ(s.max_length, longest);
    EXPECT_EQ(s.vertex_faces.size(), s.faces.size() * (tets ? 3u : 4u));
    // Outward: the divergence theorem, V = (1/3) sum over the faces of the integral of x . n dA,
    // with n dA = x_xi x x_eta dxi deta from the faces' corner order (exact by 2 x 2 Gauss points
    // for a bilinear face: the integrand is at most quadratic in each coordinate). A face turned
    // inwards changes the sum by twice its share.
    double volume = 0.0;
    for (const auto& h : mesh.hexes) volume += signed_volume(mesh, h);
    for (const auto& t : mesh.tets) volume += signed_volume(mesh, t);
    double flux = 0.0;
    const double gauss[2] = {0.5 - 0.5 / std::sqrt(3.0), 0.5 + 0.5 / std::sqrt(3.0)};
    for (int fi = 0; fi < static_cast<int>(s.faces.size()); ++fi) {
      const SurfaceFace& f = s.faces[fi];
      if (f.count == 3) {
        flux += face_centre(s, x, fi).dot(0.5 * (x[f.node[1]] - x[f.node[0]]).cross(x[f.node[2]] - x[f.node[0]]));
        continue;
      }
      const Vec3 a = x[f.node[1]] - x[f.node[0]], b = x[f.node[3]] - x[f.node[0]];
      const Vec3 c = (x[f.node[2]] - x[f.node[3]]) - a;
      for (double xi : gauss)
        for (double eta : gauss) flux += 0.25 * face_point(s, x, fi, xi, eta).dot((a + eta * c).cross(b + xi * c));
    }
    EXPECT_NEAR(flux / 3.0, volume, 1e-13 * volume);
    // And the normal at each face centre points away from the body's centre (every test body is
    // convex enough for that).
    Vec3 centre = Vec3::Zero();
    for (int j : s.nodes) centre += x[j];
    centre /= static_cast<double>(s.nodes.size());
    for (int fi = 0; fi < static_cast<int>(s.faces.size()); ++fi) {
      const Vec3 c = face_centre(s, x, fi);
      const FaceProjection p = project_on_face(s.faces[fi], [&](int j) { return x[j]; }, c);
      EXPECT_GT(p.normal.dot(c - centre), 0.0) << "face " << fi;
    }
  }
}

TEST(BodyContact3, ProjectionOntoFlatFacesByHand) {
  // The unit square in z = 0: (xi, eta) are (x, y), unclamped outside.
  const Vec3 q0(0, 0, 0), q1(1, 0, 0), q2(1, 1, 0), q3(0, 1, 0);
  FaceProjection p = project_on_quad(q0, q1, q2, q3, Vec3(0.3, 0.6, 0.25));
  EXPECT_TRUE(p.converged);
  EXPECT_NEAR(p.xi, 0.3, 1e-15);
  EXPECT_NEAR(p.eta, 0.6, 1e-15);
  EXPECT_NEAR(p.gap, 0.25, 1e-15);
  EXPECT_TRUE(p.normal.isApprox(Vec3::UnitZ(), 1e-15));
  EXPECT_TRUE(p.point.isApprox(Vec3(0.3, 0.6, 0.0), 1e-15));
  const std::array<double, 4> w = {0.7 * 0.4, 0.3 * 0.4, 0.3 * 0.6, 0.7 * 0.6};
  for (int a = 0; a < 4; ++a) EXPECT_NEAR(p.weight[a], w[a], 1e-15);
  p = project_on_quad(q0, q1, q2, q3, Vec3(1.5, -0.2, -0.1));
  EXPECT_TRUE(p.converged);
  EXPECT_NEAR(p.xi, 1.5, 1e-14);
  EXPECT_NEAR(p.eta, -0.2, 1e-14);
  EXPECT_NEAR(p.gap, -0.1, 1e-15);
  // A trapezoid (c = x2 - x3 - x1 + x0 = (-1, 0, 0): the map is bilinear, not affine):
  // x(0.25, 0.5) = (0.625, 0.5, 0) by hand.
  const Vec3 t0(0, 0, 0), t1(2, 0, 0), t2(1.5, 1, 0), t3(0.5, 1, 0);
  p = project_on_quad(t0, t1, t2, t3, Vec3(0.625, 0.5, -0.2));
  EXPECT_TRUE(p.converged);
  EXPECT_NEAR(p.xi, 0.25, 1e-14);
  EXPECT_NEAR(p.eta, 0.5, 1e-14);
  EXPECT_NEAR(p.gap, -0.2, 1e-15);
  EXPECT_TRUE(p.normal.isApprox(Vec3::UnitZ(), 1e-15));
  // Triangles: a right triangle in z = 0 and the tilted one through the unit points, whose
  // normal is (1, 1, 1)/sqrt(3) and whose centroid is the projection of (1, 1, 1).
  p = project_on_triangle(Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(0, 1, 0), Vec3(0.5, 0.25, 0.7));
  EXPECT_NEAR(p.xi, 0.25, 1e-15);
  EXPECT_NEAR(p.eta, 0.25, 1e-15);
  EXPECT_NEAR(p.gap, 0.7, 1e-15);
  EXPECT_NEAR(p.weight[0], 0.5, 1e-15);
  EXPECT_NEAR(p.weight[1], 0.25, 1e-15);
  EXPECT_NEAR(p.weight[2], 0.25, 1e-15);
  EXPECT_EQ(p.weight[3], 0.0);
  EXPECT_TRUE(p.normal.isApprox(Vec3::UnitZ(), 1e-15));
  p = project_on_triangle(Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1), Vec3(1, 1, 1));
  EXPECT_NEAR(p.xi, 1.0 / 3.0, 1e-15);
  EXPECT_NEAR(p.eta, 1.0 / 3.0, 1e-15);
  EXPECT_NEAR(p.gap, 2.0 / std::sqrt(3.0), 1e-15);
  EXPECT_TRUE(p.normal.isApprox(Vec3(1, 1, 1).normalized(), 1e-15));
  EXPECT_TRUE(p.point.isApprox(Vec3::Constant(1.0 / 3.0), 1e-15));
  // Outside across the hypotenuse: xi + eta > 1, unclamped.
  p = project_on_triangle(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0.8, 0.7, -0.3));
  EXPECT_NEAR(p.xi, 0.8, 1e-15);
  EXPECT_NEAR(p.eta, 0.7, 1e-15);
  EXPECT_NEAR(p.gap, -0.3, 1e-15);
  EXPECT_FALSE(inside_face(3, p.xi, p.eta));
  EXPECT_GT(edge_excess(3, 1, p.xi, p.eta), 0.0);
}

// Brute-force nearest point of the quadrilateral's bilinear patch over [0, 1]^2: a 101 x 101 grid,
// then 30 zooms of a 21 x 21 grid on 4 spacings around the best, each 5 times finer.
std::array<double, 3> brute_force_quad(const std::array<Vec3, 4>& c, const Vec3& x) {
  auto dist = [&](double xi, double eta) {
    const std::array<double, 4> w = face_weights(4, xi, eta);
    return (w[0] * c[0] + w[1] * c[1] + w[2] * c[2] + w[3] * c[3] - x).norm();
  };
  double bx = 0.5, be = 0.5, bd = dist(bx, be), h = 0.01;
  for (int i = 0; i <= 100; ++i)
    for (int j = 0; j <= 100; ++j)
      if (const double d = dist(0.01 * i, 0.01 * j); d < bd) bd = d, bx = 0.01 * i, be = 0.01 * j;
  for (int zoom = 0; zoom < 30; ++zoom) {
    const double cx = bx, ce = be;
    for (int i = -10; i <= 10; ++i)
      for (int j = -10; j <= 10; ++j) {
        const double xi = std::clamp(cx + 0.2 * h * i, 0.0, 1.0), eta = std::clamp(ce + 0.2 * h * j, 0.0, 1.0);
        if (const double d = dist(xi, eta); d < bd) bd = d, bx = xi, be = eta;
      }
    h *= 0.2;
  }
  return {bx, be, bd};
}

TEST(BodyContact3, WarpedQuadAgainstBruteForce) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int compared = 0;
  double worst_param = 0.0, worst_dist = 0.0;
  for (int q = 0; q < 12; ++q) {
    // A unit square, its corners moved in plane by up to 0.2 and warped out of it by up to 0.35.
    std::array<Vec3, 4> c = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)};
    for (Vec3& p : c) p += Vec3(0.2 * u(rng), 0.2 * u(rng), 0.35 * u(rng));
    for (int k = 0; k < 10; ++k) {
      // A point off the patch along its normal at an interior (xi, eta), on either side.
      const double xi = 0.5 + 0.4 * u(rng), eta = 0.5 + 0.4 * u(rng), h = 0.3 * u(rng);
      const std::array<double, 4> w = face_weights(4, xi, eta);
      const Vec3 a = c[1] - c[0], b = c[3] - c[0], cc = (c[2] - c[3]) - a;
      const Vec3 n = (a + eta * cc).cross(b + xi * cc).normalized();
      const Vec3 x = w[0] * c[0] + w[1] * c[1] + w[2] * c[2] + w[3] * c[3] + h * n;
      const FaceProjection p = project_on_quad(c[0], c[1], c[2], c[3], x);
      ASSERT_TRUE(p.converged);
      EXPECT_LE(p.iterations, 10);
      const std::array<double, 3> ref = brute_force_quad(c, x);
      // Only where the nearest point is inside the patch (the projection is a stationary point).
      if (std::min({ref[0], ref[1], 1.0 - ref[0], 1.0 - ref[1]}) < 1e-3) continue;
      ++compared;
      worst_param = std::max({worst_param, std::abs(p.xi - ref[0]), std::abs(p.eta - ref[1])});
      worst_dist = std::max(worst_dist, std::abs(std::abs(p.gap) - ref[2]));
      EXPECT_NEAR(p.xi, ref[0], 1e-8);
      EXPECT_NEAR(p.eta, ref[1], 1e-8);
      EXPECT_NEAR(std::abs(p.gap), ref[2], 1e-12);
      // The gap's sign is the side of the normal, and x - p lies along n.
      EXPECT_NEAR(p.gap, (x - p.point).dot(p.normal), 1e-15);
      EXPECT_LT((x - p.point - p.gap * p.normal).norm(), 1e-12);
    }
  }
  EXPECT_GE(compared, 100);
  std::printf("warped quadrilaterals: %d points, |d(xi, eta)| <= %.2g, |d gap| <= %.2g\n", compared, worst_param,
              worst_dist);
  // Far points and a strongly warped face (one corner lifted by its side): the iteration still
  // converges within its cap, to a stationary point of the distance over the extended patch.
  const std::array<Vec3, 4> c = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 1), Vec3(0, 1, 0)};
  for (int k = 0; k < 200; ++k) {
    const Vec3 x = 3.0 * Vec3(u(rng), u(rng), u(rng));
    const FaceProjection p = project_on_quad(c[0], c[1], c[2], c[3], x);
    ASSERT_TRUE(p.converged) << x.transpose();
    const Vec3 a = c[1] - c[0], b = c[3] - c[0], cc = (c[2] - c[3]) - a;
    const Vec3 r = p.point - x;
    EXPECT_LT(std::abs(r.dot(a + p.eta * cc)), 1e-12 * (1.0 + r.norm()));
    EXPECT_LT(std::abs(r.dot(b + p.xi * cc)), 1e-12 * (1.0 + r.norm()));
  }
}

TEST(BodyContact3, FaceStencilSumsToZeroAndGivesTheClosestPoint) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.05, 0.95), h(-0.005, 0.005);
  for (Mesh3& mesh : test_meshes()) {
    const Model<3> model = model_of(mesh);
    const Surface3 s = make_surface3(model, 0);
    Points x = positions_with_slave(model);
    const Points v(x.size(), Vec3::Zero());
    const int slave = model.num_nodes();
    auto pos = [&](int j) { return x[j]; };
    auto vel = [&](int j) { return v[j]; };
    for (int fi = 0; fi < static_cast<int>(s.faces.size()); ++fi) {
      double xi = u(rng), eta = u(rng);
      while (s.faces[fi].count == 3 && xi + eta > 0.95) xi = u(rng), eta = u(rng);
      const Vec3 p = face_point(s, x, fi, xi, eta);
      x[slave] = p + h(rng) * face_normal(s.faces[fi], pos, xi, eta);
      const NodeFace r = find_face(s, slave, fi, pos, pos, vel);
      ASSERT_EQ(r.face, fi);
      ASSERT_EQ(r.kind, FaceContactKind::face);
      ASSERT_EQ(r.stencil.count, 1 + s.faces[fi].count);
      EXPECT_EQ(r.stencil.node[0], slave);
      EXPECT_EQ(r.stencil.coef[0], 1.0);
      EXPECT_LT(std::abs(coef_sum(r.stencil)), 1e-15);
      // sum_j coef_j x_j = x_s - p: the face nodes' part is the closest point, and its component
      // along n is the gap.
      const Vec3 d = stencil_sum(r.stencil, x);
      EXPECT_LT((x[slave] - d - p).norm(), 1e-12);
      EXPECT_NEAR(r.normal.dot(d), r.gap, 1e-15);
      EXPECT_NEAR(r.xi, xi, 1e-9);
      EXPECT_NEAR(r.eta, eta, 1e-9);
      // Untracked, the search finds the same face.
      const NodeFace g = find_face(s, slave, -1, pos, pos, vel);
      EXPECT_EQ(g.face, fi);
      EXPECT_NEAR(g.gap, r.gap, 1e-15);
    }
  }
}

// A box [0, 3] x [0, 1] x [0, 2] of 3 x 2 x 2 hexahedra or tetrahedra: its top y = 1 is 3 x 2
// faces (12 triangles). A point slides just below the top along x, then across the vertex at
// x = 1, z = 1 diagonally, then over the convex edge at x = 3 and down the side.
TEST(BodyContact3, WalkingAcrossFacesEdgesAndVertices) {
  for (const bool tets : {false, true}) {
    const Model<3> model = model_of(box_mesh(Vec3(3.0, 1.0, 2.0), 3, 2, 2, tets));
    const Surface3 s = make_surface3(model, 0);
    Points x0 = positions_with_slave(model);
    Points x1 = x0;
    const Points v(x0.size(), Vec3::Zero());
    const int slave = model.num_nodes();
    auto start = [&](int j) { return x0[j]; };
    auto eval = [&](int j) { return x1[j]; };
    auto vel = [&](int j) { return v[j]; };
    // One step from a to b with the tracked face.
    int tracked = -1, changes = 0;
    auto step = [&](Vec3 a, Vec3 b) {
      x0[slave] = a;
      x1[slave] = b;
      const NodeFace r = find_face(s, slave, tracked, start, eval, vel);
      if (tracked >= 0 && r.face >= 0 && r.face != tracked) ++changes;
      tracked = r.face;
      return r;
    };
    const double depth = 1e-4;
    Vec3 at(0.2, 1.0 - depth, 0.3);
    for (int i = 0; i < 26; ++i) {
      const Vec3 next = at + Vec3(0.1, 0.0, 0.0);
      const NodeFace r = step(at, next);
      ASSERT_GE(r.face, 0);
      EXPECT_EQ(r.kind, FaceContactKind::face);
      EXPECT_TRUE(r.normal.isApprox(Vec3::UnitY(), 1e-14));
      EXPECT_NEAR(r.gap, -depth, 1e-15);
      at = next;
    }
    // Across the faces at x = 1 and 2, and for the triangles also their diagonals at x = 0.3,
    // 1.3 and 2.3 (the split cuts the top from (i, k) to (i + 1, k + 1)).
    EXPECT_EQ(changes, tets ? 5 : 2);
    // Diagonally over the vertex at (1, 1, 1) of four quadrilaterals (a crossing of no edge
    // neighbour): from the face x, z < 1 to the face x, z > 1 in one step.
    tracked = -1;
    NodeFace r = step(Vec3(0.9, 1.0 - depth, 0.9), Vec3(0.9, 1.0 - depth, 0.9));
    const int before = r.face;
    r = step(Vec3(0.9, 1.0 - depth, 0.9), Vec3(1.1, 1.0 - depth, 1.1));
    ASSERT_GE(r.face, 0);
    EXPECT_NE(r.face, before);
    EXPECT_EQ(r.kind, FaceContactKind::face);
    EXPECT_NEAR(r.gap, -depth, 1e-15);
    const Vec3 c = face_centre(s, x1, r.face);
    EXPECT_GT(c.x(), 1.0);
    EXPECT_GT(c.z(), 1.0);
    // Over the convex edge x = 3, y = 1: past the top's last face the point is in the edge's
    // region: an edge contact, the normal from the edge to the point, the gap its distance.
    tracked = -1;
    step(Vec3(2.9, 1.0 + 1e-3, 0.5), Vec3(2.9, 1.0 + 1e-3, 0.5));
    const int top = tracked;
    r = step(Vec3(2.9, 1.0 + 1e-3, 0.5), Vec3(3.0 + 4e-3, 1.0 + 3e-3, 0.5));
    ASSERT_GE(r.face, 0);
    EXPECT_EQ(r.face, top);
    EXPECT_EQ(r.kind, FaceContactKind::edge);
    EXPECT_TRUE(r.normal.isApprox(Vec3(0.8, 0.6, 0.0), 1e-12));
    EXPECT_NEAR(r.gap, 5e-3, 1e-15);
    EXPECT_EQ(r.stencil.count, 3);
    EXPECT_LT(std::abs(coef_sum(r.stencil)), 1e-15);
    EXPECT_LT((stencil_sum(r.stencil, x1) - Vec3(4e-3, 3e-3, 0.0)).norm(), 1e-15);
    // A step that ends beyond the side's face next to the edge (outside the body, x > 3) is in
    // no region of the top's edge: no contact with it, where the edge's pseudo-normal would give
    // a gap of -0.5.
    {
      const int keep = tracked;
      const NodeFace far = step(Vec3(2.9, 1.0 + 1e-3, 0.5), Vec3(3.0 + 1e-3, 0.3, 0.5));
      EXPECT_TRUE(far.face < 0 || far.gap > 0.0) << far.gap;
      tracked = keep;
    }
    // Back below the edge: the projection leaves the top across it into the side face x = 3.
    r = step(Vec3(3.0 + 4e-3, 1.0 + 3e-3, 0.5), Vec3(3.0 + 1e-3, 1.0 - 1e-3, 0.5));
    ASSERT_GE(r.face, 0);
    EXPECT_EQ(r.kind, FaceContactKind::face);
    EXPECT_TRUE(r.normal.isApprox(Vec3::UnitX(), 1e-14));
    EXPECT_NEAR(r.gap, 1e-3, 1e-15);
    // Down and along the side, into the side's upper face z > 1.
    r = step(Vec3(3.0 + 1e-3, 1.0 - 1e-3, 0.5), Vec3(3.0 - 2e-4, 0.9, 1.8));
    ASSERT_GE(r.face, 0);
    EXPECT_EQ(r.kind, FaceContactKind::face);
    EXPECT_TRUE(r.normal.isApprox(Vec3::UnitX(), 1e-14));
    EXPECT_NEAR(r.gap, -2e-4, 1e-15);
    EXPECT_GT(face_centre(s, x1, r.face).z(), 1.0);
    // And out past the corner (3, 1, 2): a vertex contact, 2-3-6-7.
    r = step(Vec3(3.0 - 2e-4, 0.9, 1.8), Vec3(3.0 + 2e-3, 1.0 + 3e-3, 2.0 + 6e-3));
    ASSERT_GE(r.face, 0);
    EXPECT_EQ(r.kind, FaceContactKind::vertex);
    EXPECT_TRUE(r.normal.isApprox(Vec3(2, 3, 6).normalized(), 1e-12));
    EXPECT_NEAR(r.gap, 7e-3, 1e-15);
    EXPECT_EQ(r.stencil.count, 2);
    EXPECT_TRUE(x1[r.stencil.node[1]].isApprox(Vec3(3, 1, 2), 1e-15));
    EXPECT_EQ(r.stencil.coef[1], -1.0);
  }
}

TEST(BodyContact3, EdgeAndVertexContactFromTheStartOfTheStep) {
  for (const bool tets : {false, true}) {
    const Model<3> model = model_of(box_mesh(Vec3(1.0, 1.0, 1.0), 2, 2, 2, tets));
    const Surface3 s = make_surface3(model, 0);
    Points x0 = positions_with_slave(model);
    Points x1 = x0;
    const Points v(x0.size(), Vec3::Zero());
    const int slave = model.num_nodes();
    auto start = [&](int j) { return x0[j]; };
    auto eval = [&](int j) { return x1[j]; };
    auto vel = [&](int j) { return v[j]; };
    auto find = [&](Vec3 a, Vec3 b) {
      x0[slave] = a;
      x1[slave] = b;
      return find_face(s, slave, -1, start, eval, vel);
    };
    // Outside the edge x = y = 1: the edge, 3-4-5.
    NodeFace r = find(Vec3(1.03, 1.04, 0.3), Vec3(1.03, 1.04, 0.3));
    ASSERT_GE(r.face, 0);
    EXPECT_EQ(r.kind, FaceContactKind::edge);
    EXPECT_TRUE(r.normal.isApprox(Vec3(0.6, 0.8, 0.0), 1e-12));
    EXPECT_NEAR(r.gap, 0.05, 1e-15);
    EXPECT_LT((x1[slave] - stencil_sum(r.stencil, x1) - Vec3(1, 1, 0.3)).norm(), 1e-15);
    // Outside the corner (1, 1, 1): the vertex, 2-3-6-7.
    r = find(Vec3(1.02, 1.03, 1.06), Vec3(1.02, 1.03, 1.06));
    ASSERT_GE(r.face, 0);
    EXPECT_EQ(r.kind, FaceContactKind::vertex);
    EXPECT_TRUE(r.normal.isApprox(Vec3(2, 3, 6).normalized(), 1e-12));
    EXPECT_NEAR(r.gap, 0.07, 1e-15);
    // A node that starts outside the corner and is predicted inside the body: the frame of the
    // start (the direction from the corner to it), a negative gap at the prediction.
    r = find(Vec3(1.02, 1.03, 1.06), Vec3(0.98, 0.99, 0.97));
    ASSERT_GE(r.face, 0);
    EXPECT_EQ(r.kind, FaceContactKind::vertex);
    EXPECT_TRUE(r.normal.isApprox(Vec3(2, 3, 6).normalized(), 1e-12));
    EXPECT_NEAR(r.gap, Vec3(2, 3, 6).normalized().dot(Vec3(-0.02, -0.01, -0.03)), 1e-15);
    // Farther than the longest edge (0.5; 0.71 for the triangles' diagonals): nothing.
    EXPECT_LT(find(Vec3(1.6, 1.6, 0.5), Vec3(1.6, 1.6, 0.5)).face, 0);
    // On the edge x = y = 1, the tie of the top and the side face goes to the face approached.
    x0[slave] = x1[slave] = Vec3(1.0, 1.0, 0.3);
    Points w = v;
    w[slave] = Vec3(-1.0, 0.0, 0.0);
    auto with_w = [&](int j) { return w[j]; };
    r = find_face(s, slave, -1, start, eval, with_w);
    EXPECT_TRUE(r.normal.isApprox(Vec3::UnitX(), 1e-14));
    w[slave] = Vec3(0.0, -1.0, 0.0);
    r = find_face(s, slave, -1, start, eval, with_w);
    EXPECT_TRUE(r.normal.isApprox(Vec3::UnitY(), 1e-14));
  }
}

TEST(BodyContact3, ConcaveEdgeInsideUsesTheBisector) {
  // An L: cubes (0,0,0), (1,0,0), (0,1,0). The edge x = y = 1 (z in [0, 1]) is concave: a node
  // pressed in near it, at (0.9, 0.9, 0.5), projects into neither of its faces (x = 1 for y > 1,
  // y = 1 for x > 1) and is nearer to it than to any other face.
  const Model<3> model = model_of(cubes({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}));
  const Surface3 s = make_surface3(model, 0);
  Points x = positions_with_slave(model);
  const Points v(x.size(), Vec3::Zero());
  const int slave = model.num_nodes();
  auto pos = [&](int j) { return x[j]; };
  auto vel = [&](int j) { return v[j]; };
  x[slave] = Vec3(0.9, 0.95, 0.5);
  const NodeFace r = find_face(s, slave, -1, pos, pos, vel);
  ASSERT_GE(r.face, 0);
  EXPECT_EQ(r.kind, FaceContactKind::edge);
  EXPECT_TRUE(r.normal.isApprox(Vec3(1, 1, 0).normalized(), 1e-14));
  EXPECT_NEAR(r.gap, -0.15 / std::sqrt(2.0), 1e-15);
  // The body's signed distance there: the distance to the edge, inside.
  EXPECT_NEAR(surface_signed_distance(s, pos, x[slave]), -std::hypot(0.1, 0.05), 1e-15);
  // Outside near the concave edge the node projects into both faces: the nearer one.
  x[slave] = Vec3(1.2, 1.1, 0.5);
  const NodeFace o = find_face(s, slave, -1, pos, pos, vel);
  EXPECT_EQ(o.kind, FaceContactKind::face);
  EXPECT_TRUE(o.normal.isApprox(Vec3::UnitY(), 1e-14));
  EXPECT_NEAR(o.gap, 0.1, 1e-15);
}

TEST(BodyContact3, ConcaveVertexInsideUsesTheAngleWeightedPseudoNormal) {
  // Two by two by two cubes less the one at (1, 0, 1): (1, 1, 1) is a concave vertex of three
  // faces, normals +x, -y, +z. Split into tetrahedra, the face of normal -y is two triangles
  // there (the split's diagonal runs through the vertex) and the other two one each, so only the
  // angle weights (90 degrees per face) give the symmetric (1, -1, 1)/sqrt(3).
  std::vector<std::array<int, 3>> cells;
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k)
        if (!(i == 1 && j == 0 && k == 1)) cells.push_back({i, j, k});
  for (const bool tets : {false, true}) {
    const Model<3> model = model_of(cubes(cells, tets));
    const Surface3 s = make_surface3(model, 0);
    Points x = positions_with_slave(model);
    const Points v(x.size(), Vec3::Zero());
    const int slave = model.num_nodes();
    auto pos = [&](int j) { return x[j]; };
    auto vel = [&](int j) { return v[j]; };
    // Pressed in near the vertex: it projects into none of the three faces.
    x[slave] = Vec3(0.95, 1.05, 0.95);
    const NodeFace r = find_face(s, slave, -1, pos, pos, vel);
    ASSERT_GE(r.face, 0);
    EXPECT_EQ(r.kind, FaceContactKind::vertex);
    EXPECT_TRUE(r.normal.isApprox(Vec3(1, -1, 1).normalized(), 1e-14)) << r.normal.transpose();
    EXPECT_NEAR(r.gap, -0.15 / std::sqrt(3.0), 1e-15);
    EXPECT_TRUE(x[r.stencil.node[1]].isApprox(Vec3(1, 1, 1), 1e-15));
    EXPECT_NEAR(surface_signed_distance(s, pos, x[slave]), -0.05 * std::sqrt(3.0), 1e-15);
  }
}

// The signed distance to a box a x b x c, positions X + u with u a rigid motion (rotation R,
// translation t): the exact value in the box's axes.
double box_signed_distance(const Vec3& size, const Vec3& y) {
  const Vec3 half = 0.5 * size, q = (y - half).cwiseAbs() - half;
  const double outside = q.cwiseMax(0.0).norm();
  return outside > 0.0 ? outside : q.maxCoeff();
}

TEST(BodyContact3, SignedDistanceAndDepthInsideABox) {
  const Vec3 size(1.0, 0.8, 0.6);
  const Mat3 rot = Eigen::AngleAxisd(0.9, Vec3(0.3, -1.0, 0.4).normalized()).toRotationMatrix();
  const Vec3 shift(0.4, -0.3, 1.2);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.3, 1.3);
  for (const bool tets : {false, true}) {
    const Model<3> model = model_of(box_mesh(size, 3, 2, 2, tets));
    const Surface3 s = make_surface3(model, 0);
    Eigen::VectorXd disp(model.num_dofs());
    for (int j = 0; j < model.num_nodes(); ++j)
      disp.segment<3>(3 * j) = rot * model.ref.col(j) + shift - model.ref.col(j);
    int inside = 0, outside = 0;
    for (int k = 0; k < 3000; ++k) {
      const Vec3 y(u(rng) * size.x(), u(rng) * size.y(), u(rng) * size.z());
      const double ref = box_signed_distance(size, y);
      if (std::abs(ref) < 1e-6) continue;
      const Vec3 x = rot * y + shift;
      const double d = signed_distance(model, s, disp, x);
      ASSERT_NEAR(d, ref, 1e-12) << y.transpose();
      EXPECT_EQ(depth_inside(model, s, disp, x), ref < 0.0 ? -d : 0.0);
      ++(ref < 0.0 ? inside : outside);
    }
    EXPECT_GT(inside, 300);
    EXPECT_GT(outside, 1500);
    // Points on the faces' diagonal planes through the edges and corners, inside and outside.
    for (const Vec3& y : {Vec3(0.05, 0.05, 0.3), Vec3(-0.05, -0.05, 0.3), Vec3(0.1, 0.1, 0.1), Vec3(-0.1, -0.1, -0.1),
                          Vec3(1.1, 0.9, 0.7), Vec3(0.95, 0.75, 0.55)}) {
      EXPECT_NEAR(signed_distance(model, s, disp, rot * y + shift), box_signed_distance(size, y), 1e-12);
    }
  }
}

TEST(BodyContact3, FrameInvariance) {
  // Rotating and translating everything rotates the normal and keeps the gap and the
  // parametric coordinates.
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const Mat3 rot = Eigen::AngleAxisd(3.0 * u(rng), Vec3(u(rng), u(rng), u(rng)).normalized()).toRotationMatrix();
    const Vec3 shift(u(rng), u(rng), u(rng));
    auto move = [&](const Vec3& p) -> Vec3 { return rot * p + shift; };
    std::array<Vec3, 4> c = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0)};
    for (Vec3& p : c) p += Vec3(0.2 * u(rng), 0.2 * u(rng), 0.35 * u(rng));
    const Vec3 x(0.5 + 0.6 * u(rng), 0.5 + 0.6 * u(rng), 0.4 * u(rng));
    const FaceProjection p = project_on_quad(c[0], c[1], c[2], c[3], x);
    const FaceProjection q = project_on_quad(move(c[0]), move(c[1]), move(c[2]), move(c[3]), move(x));
    EXPECT_NEAR(q.xi, p.xi, 1e-12);
    EXPECT_NEAR(q.eta, p.eta, 1e-12);
    EXPECT_NEAR(q.gap, p.gap, 1e-12);
    EXPECT_LT((q.normal - rot * p.normal).norm(), 1e-12);
    EXPECT_LT((q.point - move(p.point)).norm(), 1e-12);
    const FaceProjection pt = project_on_triangle(c[0], c[1], c[2], x);
    const FaceProjection qt = project_on_triangle(move(c[0]), move(c[1]), move(c[2]), move(x));
    EXPECT_NEAR(qt.xi, pt.xi, 1e-12);
    EXPECT_NEAR(qt.eta, pt.eta, 1e-12);
    EXPECT_NEAR(qt.gap, pt.gap, 1e-12);
    EXPECT_LT((qt.normal - rot * pt.normal).norm(), 1e-12);
  }
  // The face choice on the distorted bodies, faces, edges and vertices alike.
  for (Mesh3& mesh : test_meshes()) {
    const Model<3> model = model_of(mesh);
    const Surface3 s = make_surface3(model, 0);
    const Mat3 rot = Eigen::AngleAxisd(2.1, Vec3(1.0, 0.5, -0.7).normalized()).toRotationMatrix();
    const Vec3 shift(3.0, -1.0, 0.5);
    Points x0 = positions_with_slave(model), x1 = x0, y0 = x0, y1 = x0;
    Points v(x0.size(), Vec3::Zero()), w = v;
    const int slave = model.num_nodes();
    Vec3 lo = x0[0], hi = x0[0];
    for (const Vec3& p : x0) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    int kinds[3] = {0, 0, 0};
    for (int k = 0; k < 1500; ++k) {
      x0[slave] = lo + (Vec3::Constant(0.5) + 0.65 * Vec3(u(rng), u(rng), u(rng))).cwiseProduct(hi - lo);
      x1[slave] = x0[slave] + 0.02 * Vec3(u(rng), u(rng), u(rng));
      v[slave] = Vec3(u(rng), u(rng), u(rng));
      for (std::size_t j = 0; j < x0.size(); ++j) {
        y0[j] = rot * x0[j] + shift;
        y1[j] = rot * x1[j] + shift;
        w[j] = rot * v[j];
      }
      auto f = [&](const Points& p0, const Points& p1, const Points& vv) {
        return find_face(s, slave, -1, [&](int j) { return p0[j]; }, [&](int j) { return p1[j]; },
                         [&](int j) { return vv[j]; });
      };
      const NodeFace a = f(x0, x1, v), b = f(y0, y1, w);
      ASSERT_EQ(a.face, b.face);
      if (a.face < 0) continue;
      ++kinds[static_cast<int>(a.kind)];
      EXPECT_EQ(a.kind, b.kind);
      EXPECT_NEAR(a.gap, b.gap, 1e-12);
      EXPECT_LT((b.normal - rot * a.normal).norm(), 1e-12);
      EXPECT_NEAR(a.xi, b.xi, 1e-12);
      EXPECT_NEAR(a.eta, b.eta, 1e-12);
      ASSERT_EQ(a.stencil.count, b.stencil.count);
      for (int j = 0; j < a.stencil.count; ++j) {
        EXPECT_EQ(a.stencil.node[j], b.stencil.node[j]);
        EXPECT_NEAR(a.stencil.coef[j], b.stencil.coef[j], 1e-12);
      }
      EXPECT_NEAR(surface_signed_distance(s, [&](int j) { return x1[j]; }, x1[slave]),
                  surface_signed_distance(s, [&](int j) { return y1[j]; }, y1[slave]), 1e-12);
    }
    std::printf("%zu faces: %d face, %d edge, %d vertex contacts\n", s.faces.size(), kinds[0], kinds[1], kinds[2]);
    // Every kind was seen.
    EXPECT_GT(kinds[0], 100);
    EXPECT_GT(kinds[1], 20);
    EXPECT_GT(kinds[2], 5);
  }
}

TEST(BodyContact3, SurfaceCompletesTheContactSpace) {
  // The contact module's 3D space holds this surface, and its bounding box reads its nodes.
  static_assert(std::is_same_v<Space<3>::Surface, Surface3>);
  static_assert(std::is_same_v<Space<3>::Stencil, StencilN<5>>);
  const Model<3> model = model_of(box_mesh(Vec3(1.0, 0.8, 0.6), 2, 2, 2, false));
  const Surface3 s = make_surface3(model, 0);
  const auto box = surface_box(s, [&](int j) -> Vec3 { return model.ref.col(j); }, s.max_length);
  EXPECT_TRUE(box.lo.isApprox(Vec3::Constant(-0.5)));
  EXPECT_TRUE(box.hi.isApprox(Vec3(1.5, 1.3, 1.1)));
}

TEST(BodyContact3, QueriesDoNotAllocate) {
  long before = g_allocations.load();
  {
    std::vector<double> probe(64, 1.0);
    asm volatile("" : : "g"(probe.data()) : "memory");
  }
  ASSERT_GE(g_allocations.load() - before, 1) << "the counter counts";
  const Model<3> model = model_of(test3::distorted_box(3, 2, 2, false, 0.12));
  const Surface3 s = make_surface3(model, 0);
  Points x0 = positions_with_slave(model), x1 = x0;
  const Points v(x0.size(), Vec3::Ones());
  const int slave = model.num_nodes();
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-0.5, 1.5);
  Points xs(300);
  for (Vec3& p : xs) p = Vec3(u(rng), u(rng), u(rng));
  auto start = [&](int j) { return x0[j]; };
  auto eval = [&](int j) { return x1[j]; };
  auto vel = [&](int j) { return v[j]; };
  double sink = 0.0;
  int tracked = -1;
  before = g_allocations.load();
  for (std::size_t k = 0; k + 1 < xs.size(); ++k) {
    x0[slave] = xs[k];
    x1[slave] = xs[k] + 0.01 * (xs[k + 1] - xs[k]);
    const NodeFace r = find_face(s, slave, tracked, start, eval, vel);
    tracked = r.face;
    sink += r.gap + surface_signed_distance(s, eval, xs[k]);
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
}  // namespace ricochet
