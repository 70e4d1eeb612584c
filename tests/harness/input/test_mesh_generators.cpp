// Tests of the structured mesh generators (harness/input/mesh_generators.hpp): counts, exact areas
// and their convergence, orientation, cell quality, node sets, grading, and rejected
// parameters.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>
#include <string>
#include <utility>

#include "harness/input/input_error.hpp"
#include "harness/input/mesh_generators.hpp"
#include "solver/model/model.hpp"

namespace ricochet {
namespace {

// Sum of signed cell areas [m^2]; EXPECTs every cell counter-clockwise (and quads convex).
double checked_area(const Mesh& mesh) {
  double total = 0.0;
  for (const auto& q : mesh.quads) {
    const double a = signed_area(mesh, q.data(), 4);
    EXPECT_GT(a, 0.0);
    EXPECT_GT(q4_corner_quality(mesh, q), 0.0);
    total += a;
  }
  for (const auto& t : mesh.tris) {
    const double a = signed_area(mesh, t.data(), 3);
    EXPECT_GT(a, 0.0);
    total += a;
  }
  return total;
}

void expect_sets_sorted_unique(const Mesh& mesh) {
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

TEST(Rectangle, CountsCoordinatesAreaAndSets) {
  const Mesh m =
      make_rectangle({.width = 2.0, .height = 0.5, .nx = 3, .ny = 2, .origin = Vec2(1, -2)});
  EXPECT_EQ(m.num_nodes(), 12);
  EXPECT_EQ(m.quads.size(), 6u);
  EXPECT_TRUE(m.tris.empty());
  EXPECT_NEAR(checked_area(m), 1.0, 1e-14);
  expect_sets_sorted_unique(m);
  EXPECT_EQ(m.node_sets.at("left").size(), 3u);
  EXPECT_EQ(m.node_sets.at("right").size(), 3u);
  EXPECT_EQ(m.node_sets.at("bottom").size(), 4u);
  EXPECT_EQ(m.node_sets.at("top").size(), 4u);
  EXPECT_EQ(m.node_sets.at("boundary").size(), 10u);
  EXPECT_EQ(m.node_sets.at("all").size(), 12u);
  for (int n : m.node_sets.at("left")) EXPECT_EQ(m.nodes(0, n), 1.0);
  for (int n : m.node_sets.at("right")) EXPECT_EQ(m.nodes(0, n), 3.0);
  for (int n : m.node_sets.at("bottom")) EXPECT_EQ(m.nodes(1, n), -2.0);
  for (int n : m.node_sets.at("top")) EXPECT_EQ(m.nodes(1, n), -1.5);
  EXPECT_EQ(m.node_sets.at("boundary"), (std::vector<int>{0, 1, 2, 3, 4, 7, 8, 9, 10, 11}));
}

TEST(Rectangle, TrianglesAlternateByColumnAndAreMirrorSymmetric) {
  const int nx = 4, ny = 3;
  const Mesh m =
      make_rectangle({.width = 4.0, .height = 3.0, .nx = nx, .ny = ny, .triangles = true});
  EXPECT_EQ(m.num_nodes(), 20);
  EXPECT_TRUE(m.quads.empty());
  ASSERT_EQ(m.tris.size(), 24u);
  EXPECT_NEAR(checked_area(m), 12.0, 1e-13);
  expect_sets_sorted_unique(m);

  // Mirror about x = 2 maps node (i, j) to (nx - i, j); the set of triangles is unchanged.
  const auto key = [](std::array<int, 3> t) {
    std::sort(t.begin(), t.end());
    return t;
  };
  std::set<std::array<int, 3>> tris;
  for (const auto& t : m.tris) tris.insert(key(t));
  for (const auto& t : m.tris) {
    std::array<int, 3> mirrored{};
    for (int k = 0; k < 3; ++k) mirrored[k] = (t[k] / (nx + 1)) * (nx + 1) + nx - t[k] % (nx + 1);
    EXPECT_TRUE(tris.count(key(mirrored)));
  }
  // No union-jack star: no node is shared by eight triangles.
  std::vector<int> valence(20, 0);
  for (const auto& t : m.tris)
    for (int n : t) ++valence[n];
  EXPECT_LE(*std::max_element(valence.begin(), valence.end()), 6);
}

TEST(Rectangle, RejectsBadParameters) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(error_of([] { make_rectangle({.nx = 0}); }), "rectangle: nx must be >= 1 (got 0)");
  EXPECT_EQ(error_of([] { make_rectangle({.ny = -3}); }), "rectangle: ny must be >= 1 (got -3)");
  EXPECT_EQ(error_of([] { make_rectangle({.width = 0}); }),
            "rectangle: width must be finite and > 0 (got 0)");
  EXPECT_NE(error_of([&] { make_rectangle({.width = nan}); }).find("rectangle: width"),
            std::string::npos);
  EXPECT_NE(error_of([&] { make_rectangle({.height = -1}); }).find("rectangle: height"),
            std::string::npos);
  EXPECT_NE(error_of([&] { make_rectangle({.height = inf}); }).find("rectangle: height"),
            std::string::npos);
  EXPECT_NE(error_of([&] { make_rectangle({.origin = Vec2(nan, 0)}); }).find("rectangle: origin"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              make_rectangle({.nx = 1 << 20, .ny = 1 << 20});
            }).find("rectangle: (nx+1)*(ny+1)"),
            std::string::npos);
}

constexpr double L = 0.04, H = 0.08, R = 0.101;

double arc_plate_area(double side_height) {
  const double s = R - std::sqrt(R * R - L * L / 4);
  return L * side_height + R * R * std::asin(L / (2 * R)) - (L / 2) * (R - s);
}

TEST(ArcPlate, DefaultCountsAreaAndOrientation) {
  const Mesh m = make_arc_plate({});
  EXPECT_EQ(m.num_nodes(), 13 * 33);
  EXPECT_EQ(m.quads.size(), 12u * 32u);
  EXPECT_TRUE(m.tris.empty());
  EXPECT_NEAR(arc_plate_area(H), 3.2534e-3, 5e-8);
  // The polygon inscribed in the arc misses nx chord segments of about c^3/(12 R) each,
  // chord c ~ L/nx (longer near the corners, where the arc is steeper: a few per cent).
  const double deficit = arc_plate_area(H) - checked_area(m);
  EXPECT_NEAR(deficit, L * L * L / (12 * R * 12 * 12), 0.05 * deficit);
  expect_sets_sorted_unique(m);
}

TEST(ArcPlate, TrianglesSplitEveryQuadWithTheSameNodesAndArea) {
  const Mesh q = make_arc_plate({});
  const Mesh t = make_arc_plate({.triangles = true});
  EXPECT_TRUE(t.quads.empty());
  ASSERT_EQ(t.tris.size(), 2 * q.quads.size());
  EXPECT_EQ(t.nodes, q.nodes);  // the same nodes, bit for bit
  EXPECT_EQ(t.node_sets, q.node_sets);
  EXPECT_NEAR(checked_area(t), checked_area(q), 1e-15);  // every triangle counter-clockwise
  // Each pair of triangles (2k, 2k+1) covers quad k: together they use its four corners.
  for (std::size_t k = 0; k < q.quads.size(); ++k) {
    std::set<int> corners(q.quads[k].begin(), q.quads[k].end());
    std::set<int> used(t.tris[2 * k].begin(), t.tris[2 * k].end());
    used.insert(t.tris[2 * k + 1].begin(), t.tris[2 * k + 1].end());
    EXPECT_EQ(used, corners) << "quad " << k;
  }
}

TEST(ArcPlate, AreaConvergesAtSecondOrder) {
  double error[3];
  for (int k = 0; k < 3; ++k) {
    const Mesh m = make_arc_plate({.nx = 12 << k, .ny = 4});
    error[k] = arc_plate_area(H) - checked_area(m);
    EXPECT_GT(error[k], 0.0);
  }
  EXPECT_NEAR(error[0] / error[1], 4.0, 0.1);
  EXPECT_NEAR(error[1] / error[2], 4.0, 0.1);
}

TEST(ArcPlate, GeometryAndNodeSets) {
  const double s = R - std::sqrt(R * R - L * L / 4);
  const Mesh m = make_arc_plate({.nx = 12, .ny = 8});
  const auto& sets = m.node_sets;
  ASSERT_EQ(sets.at("bottom").size(), 13u);
  for (int n : sets.at("bottom")) {
    const double dist = std::hypot(m.nodes(0, n), m.nodes(1, n) - R);
    EXPECT_LE(std::abs(dist - R), 1e-15 * R) << n;
    EXPECT_GE(m.nodes(1, n), 0.0);
  }
  // The generator computes the sagitta R - sqrt(R^2 - x^2) at x = L/2 itself, so s here
  // equals it only to rounding: whether R^2 - x^2 is fused into one multiply-add depends on
  // the optimisation level (g++ contracts from -O2 on; the sanitizer build is -O1) and on
  // where the compiler folds the constants. One rounding of R^2 moves the square root by about
  // eps R / 2 (R^2 / (2 sqrt(R^2 - L^2/4)) ~ 0.51 R): a few eps R bounds it. The x
  // coordinates (-L/2, L/2, 0) are products by exact fractions and equal to the bit; all top
  // nodes share one y (the generator's y_top), to the bit.
  const double ulps_of_r = 4 * std::numeric_limits<double>::epsilon() * R;
  const double y_top = m.nodes(1, sets.at("top_left")[0]);
  EXPECT_NEAR(y_top, s + H, ulps_of_r);
  for (int n : sets.at("top")) EXPECT_EQ(m.nodes(1, n), y_top);
  for (int n : sets.at("left")) EXPECT_EQ(m.nodes(0, n), -L / 2);
  for (int n : sets.at("right")) EXPECT_EQ(m.nodes(0, n), L / 2);
  EXPECT_EQ(sets.at("top").size(), 13u);
  EXPECT_EQ(sets.at("left").size(), 9u);
  EXPECT_EQ(sets.at("boundary").size(), 2u * 13 + 2 * 9 - 4);
  EXPECT_EQ(sets.at("all").size(), 13u * 9);
  ASSERT_EQ(sets.at("lowest").size(), 1u);
  EXPECT_EQ(m.nodes.col(sets.at("lowest")[0]), Vec2(0, 0));
  ASSERT_EQ(sets.at("top_left").size(), 1u);
  ASSERT_EQ(sets.at("top_right").size(), 1u);
  EXPECT_EQ(m.nodes.col(sets.at("top_left")[0]), Vec2(-L / 2, y_top));
  EXPECT_EQ(m.nodes.col(sets.at("top_right")[0]), Vec2(L / 2, y_top));
  // The bottom corners on the arc, at the generator's sagitta (mirror images: equal y).
  EXPECT_EQ(m.nodes(0, 0), -L / 2);
  EXPECT_NEAR(m.nodes(1, 0), s, ulps_of_r);
  EXPECT_EQ(m.nodes(0, 12), L / 2);
  EXPECT_EQ(m.nodes(1, 12), m.nodes(1, 0));
}

TEST(ArcPlate, OddNxHasTwoLowestNodesAndOverallHeight) {
  const Mesh m = make_arc_plate({.nx = 5, .ny = 3, .height_is_overall = true});
  const std::vector<int>& lowest = m.node_sets.at("lowest");
  ASSERT_EQ(lowest.size(), 2u);
  EXPECT_EQ(m.nodes(0, lowest[0]), -m.nodes(0, lowest[1]));
  EXPECT_NEAR(m.nodes(0, lowest[1]), L / 10, 1e-18);
  EXPECT_EQ(m.nodes(1, lowest[0]), m.nodes(1, lowest[1]));
  for (int n : m.node_sets.at("bottom")) EXPECT_GE(m.nodes(1, n), m.nodes(1, lowest[0]));
  for (int n : m.node_sets.at("top")) EXPECT_EQ(m.nodes(1, n), H);
  EXPECT_NEAR(checked_area(m), arc_plate_area(H) - L * (R - std::sqrt(R * R - L * L / 4)), 5e-6);
}

TEST(ArcPlate, BiasGradesRowsTowardsTheArc) {
  const int nx = 4, ny = 6;
  const Mesh uniform = make_arc_plate({.nx = nx, .ny = ny});
  const Mesh graded = make_arc_plate({.nx = nx, .ny = ny, .bias = 4.0});
  EXPECT_NEAR(checked_area(graded), checked_area(uniform), 1e-15);
  const auto y = [nx](const Mesh& m, int i, int j) { return m.nodes(1, j * (nx + 1) + i); };
  for (int i = 0; i <= nx; ++i) {
    const double bottom = y(graded, i, 1) - y(graded, i, 0);
    const double top = y(graded, i, ny) - y(graded, i, ny - 1);
    EXPECT_NEAR(top / bottom, 4.0, 1e-12);
    EXPECT_LT(bottom, y(uniform, i, 1) - y(uniform, i, 0));
    for (int j = 1; j < ny; ++j) {
      EXPECT_NEAR(y(uniform, i, j + 1) - y(uniform, i, j), y(uniform, i, 1) - y(uniform, i, 0),
                  1e-15);
      const double ratio =
          (y(graded, i, j + 1) - y(graded, i, j)) / (y(graded, i, j) - y(graded, i, j - 1));
      EXPECT_NEAR(ratio, std::pow(4.0, 1.0 / (ny - 1)), 1e-12);
    }
  }
  const Mesh coarse = make_arc_plate({.nx = 3, .ny = 6, .bias = 0.25});  // finer at the top
  EXPECT_NEAR(checked_area(coarse), checked_area(make_arc_plate({.nx = 3, .ny = 1, .bias = 7})),
              1e-15);
}

TEST(ArcPlate, RejectsBadParameters) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(error_of([] { make_arc_plate({.radius = 0.01}); }),
            "arc_plate: radius must be > width/2 (got 0.01, width 0.04)");
  EXPECT_NE(error_of([] { make_arc_plate({.radius = 0.02}); }).find("radius must be > width/2"),
            std::string::npos);
  EXPECT_EQ(error_of([] { make_arc_plate({.nx = 0}); }), "arc_plate: nx must be >= 1 (got 0)");
  EXPECT_EQ(error_of([] { make_arc_plate({.ny = 0}); }), "arc_plate: ny must be >= 1 (got 0)");
  EXPECT_EQ(error_of([] { make_arc_plate({.bias = 0}); }),
            "arc_plate: bias must be finite and > 0 (got 0)");
  EXPECT_NE(error_of([&] { make_arc_plate({.bias = nan}); }).find("arc_plate: bias"),
            std::string::npos);
  EXPECT_NE(error_of([&] { make_arc_plate({.width = nan}); }).find("arc_plate: width"),
            std::string::npos);
  EXPECT_NE(error_of([&] { make_arc_plate({.height = -0.1}); }).find("arc_plate: height"),
            std::string::npos);
  EXPECT_NE(error_of([&] { make_arc_plate({.radius = -1}); }).find("arc_plate: radius"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              make_arc_plate({.height = 0.001, .height_is_overall = true});
            }).find("arc_plate: height must be > the arc's sagitta"),
            std::string::npos);
}

// ---- disk ----

// Nodes (n+1)^2 + 4 n nr and cells n^2 + 4 n nr of the O-grid, nr = ceil(n/2).
int disk_rings(int n) { return (n + 1) / 2; }

// Smallest and largest interior angle over the cells [degrees].
std::pair<double, double> angle_range(const Mesh& m) {
  double lo = 180.0, hi = 0.0;
  for (const auto& q : m.quads) {
    for (int k = 0; k < 4; ++k) {
      const Vec2 p = m.nodes.col(q[k]);
      const Vec2 e1 = m.nodes.col(q[(k + 1) % 4]) - p, e2 = m.nodes.col(q[(k + 3) % 4]) - p;
      const double deg = std::atan2(e1.x() * e2.y() - e1.y() * e2.x(), e1.dot(e2)) * 180.0 / M_PI;
      lo = std::min(lo, deg);
      hi = std::max(hi, deg);
    }
  }
  return {lo, hi};
}

TEST(Disk, CountsAndNodeSets) {
  const Vec2 c(0.3, -0.1);
  const double radius = 0.05;
  for (int n : {1, 2, 3, 4, 5, 8, 13}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    const Mesh m = make_disk({.radius = radius, .center = c, .n = n});
    const int nr = disk_rings(n);
    EXPECT_EQ(m.num_nodes(), (n + 1) * (n + 1) + 4 * n * nr);
    EXPECT_EQ(m.quads.size(), static_cast<std::size_t>(n * n + 4 * n * nr));
    EXPECT_TRUE(m.tris.empty());
    expect_sets_sorted_unique(m);
    const auto& sets = m.node_sets;
    EXPECT_EQ(sets.at("all").size(), static_cast<std::size_t>(m.num_nodes()));
    // `boundary` is the rim, and the rim is exactly the topological boundary (the nodes on an
    // edge used by one cell: the contact candidates of every scheme).
    EXPECT_EQ(sets.at("boundary").size(), static_cast<std::size_t>(4 * n));
    EXPECT_EQ(sets.at("boundary"), boundary_nodes(m));
    // Every node belongs to a cell.
    std::vector<int> used(static_cast<std::size_t>(m.num_nodes()), 0);
    for (const auto& q : m.quads)
      for (int k : q) ++used[static_cast<std::size_t>(k)];
    EXPECT_EQ(std::count(used.begin(), used.end(), 0), 0);

    // Extreme rim nodes: exactly at the extreme point for even n, else the two nodes around it,
    // mirror images of each other.
    const struct {
      const char* name;
      Vec2 dir;
    } extremes[] = {{"rightmost", Vec2(1, 0)}, {"highest", Vec2(0, 1)}, {"leftmost", Vec2(-1, 0)},
                    {"lowest", Vec2(0, -1)}};
    for (const auto& e : extremes) {
      const std::vector<int>& set = sets.at(e.name);
      ASSERT_EQ(set.size(), n % 2 == 0 ? 1u : 2u) << e.name;
      double best = -1e300;
      for (int k : sets.at("boundary")) best = std::max(best, e.dir.dot(m.nodes.col(k) - c));
      for (int k : set) EXPECT_NEAR(e.dir.dot(m.nodes.col(k) - c), best, 1e-15) << e.name;
      if (n % 2 == 0) {
        EXPECT_NEAR((m.nodes.col(set[0]) - (c + radius * e.dir)).norm(), 0.0, 1e-15) << e.name;
      } else {
        const Vec2 mid = 0.5 * (m.nodes.col(set[0]) + m.nodes.col(set[1])) - c;
        EXPECT_NEAR(mid.normalized().dot(e.dir), 1.0, 1e-15) << e.name;
      }
    }
    if (n % 2 == 0) {
      ASSERT_EQ(sets.at("center").size(), 1u);
      EXPECT_EQ(m.nodes.col(sets.at("center")[0]), c);
    } else {
      EXPECT_FALSE(sets.count("center"));
    }
  }
}

TEST(Disk, RimOnTheCircleAndCellsWellShaped) {
  // Every rim node is at distance R from the centre (to round-off), and every cell is
  // counter-clockwise and convex. Quality (smallest corner Jacobian / mean, and the angles),
  // measured: n = 1 is a square block with four trapezoids (45-135 degrees, quality 0.72);
  // n = 2 has quality 0.52 and angles 67.5-127.9; from n = 3 on, quality >= 0.659 rising to
  // 0.94 at n = 32, angles within 61.1-125.5 degrees. Bounds a little outside those values.
  const double radius = 2.5;
  const Vec2 c(-1.0, 4.0);
  for (int n : {1, 2, 3, 4, 5, 6, 8, 11, 16, 32}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    const Mesh m = make_disk({.radius = radius, .center = c, .n = n});
    for (int k : m.node_sets.at("boundary"))
      EXPECT_NEAR((m.nodes.col(k) - c).norm(), radius, 4e-16 * (radius + c.norm())) << k;
    double quality = 1.0;
    for (const auto& q : m.quads) quality = std::min(quality, q4_corner_quality(m, q));
    const auto [lo, hi] = angle_range(m);
    EXPECT_GE(quality, n >= 3 ? 0.65 : 0.5);
    EXPECT_GE(lo, n >= 3 ? 60.0 : 44.9);
    EXPECT_LE(hi, n >= 3 ? 126.0 : 135.1);
    // Interior nodes are strictly inside.
    std::vector<bool> rim(static_cast<std::size_t>(m.num_nodes()), false);
    for (int k : m.node_sets.at("boundary")) rim[static_cast<std::size_t>(k)] = true;
    for (int k = 0; k < m.num_nodes(); ++k) {
      if (!rim[static_cast<std::size_t>(k)]) {
        EXPECT_LT((m.nodes.col(k) - c).norm(), radius * (1 - 1e-3)) << k;
      }
    }
    std::printf("[disk] n %2d: %5d nodes, %5d cells, corner quality >= %.3f, angles %.1f-%.1f deg\n", n,
                m.num_nodes(), m.num_cells(), quality, lo, hi);
  }
}

TEST(Disk, AreaIsTheRimPolygonAndConvergesToPiR2AtSecondOrder) {
  // The cells tile the polygon of the 4n rim nodes exactly (positive areas summing to its
  // area 2 n R^2 sin(pi/(2n)): no gap, no overlap). That polygon misses pi R^2 by
  // pi^3 R^2/(24 n^2) + O(n^-4): second order. Measured order log2(e_n/e_2n): 1.998, 1.9995,
  // 1.9999 (n = 8 -> 16 -> 32 -> 64).
  const double radius = 0.03;
  double error[4];
  for (int k = 0; k < 4; ++k) {
    const int n = 8 << k;
    const Mesh m = make_disk({.radius = radius, .n = n});
    const double area = checked_area(m);
    const double polygon = 2.0 * n * radius * radius * std::sin(M_PI / (2.0 * n));
    EXPECT_NEAR(area, polygon, 1e-14 * polygon);
    error[k] = M_PI * radius * radius - area;
    EXPECT_GT(error[k], 0.0);
    EXPECT_NEAR(error[k], std::pow(M_PI, 3) * radius * radius / (24.0 * n * n), 0.01 * error[k]);
  }
  for (int k = 0; k < 3; ++k) {
    const double order = std::log2(error[k] / error[k + 1]);
    EXPECT_NEAR(order, 2.0, 0.01);
    std::printf("[disk] area error n %d -> %d: %.3e -> %.3e, order %.4f\n", 8 << k, 16 << k, error[k],
                error[k + 1], order);
  }
}

TEST(Disk, HasTheSymmetriesOfTheSquare) {
  // Mirror images about both axes and the diagonals, and quarter turns, map the node cloud onto
  // itself (the generator builds the quarters with exact coordinate swaps), so a symmetric
  // load gives a symmetric response, e.g. no spin for a frictionless normal impact.
  for (int n : {4, 5}) {
    const Mesh m = make_disk({.radius = 1.0, .n = n});
    std::set<std::pair<double, double>> cloud;
    const auto key = [](double x, double y) {  // rounded to 1e-13 so that round-off does not split keys
      return std::make_pair(std::round(x * 1e13) / 1e13 + 0.0, std::round(y * 1e13) / 1e13 + 0.0);
    };
    for (int k = 0; k < m.num_nodes(); ++k) cloud.insert(key(m.nodes(0, k), m.nodes(1, k)));
    EXPECT_EQ(cloud.size(), static_cast<std::size_t>(m.num_nodes()));
    for (int k = 0; k < m.num_nodes(); ++k) {
      const double x = m.nodes(0, k), y = m.nodes(1, k);
      EXPECT_TRUE(cloud.count(key(-x, y))) << k;
      EXPECT_TRUE(cloud.count(key(x, -y))) << k;
      EXPECT_TRUE(cloud.count(key(y, x))) << k;
      EXPECT_TRUE(cloud.count(key(-y, x))) << k;
    }
  }
}

TEST(Disk, RejectsBadParameters) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(error_of([] { make_disk({.radius = 0}); }), "disk: radius must be finite and > 0 (got 0)");
  EXPECT_EQ(error_of([] { make_disk({.radius = -0.1}); }),
            "disk: radius must be finite and > 0 (got -0.1)");
  EXPECT_NE(error_of([&] { make_disk({.radius = nan}); }).find("disk: radius"), std::string::npos);
  EXPECT_NE(error_of([&] { make_disk({.radius = inf}); }).find("disk: radius"), std::string::npos);
  EXPECT_EQ(error_of([] { make_disk({.n = 0}); }), "disk: n must be >= 1 (got 0)");
  EXPECT_EQ(error_of([] { make_disk({.n = -4}); }), "disk: n must be >= 1 (got -4)");
  EXPECT_NE(error_of([&] { make_disk({.center = Vec2(0, nan)}); }).find("disk: center must be finite"),
            std::string::npos);
  EXPECT_NE(error_of([&] { make_disk({.center = Vec2(inf, 0)}); }).find("disk: center must be finite"),
            std::string::npos);
  EXPECT_EQ(error_of([] { make_disk({.n = 6000}); }),
            "disk: (n+1)^2 + 4 n ceil(n/2) must be <= 100000000 nodes (got n 6000)");
}

}  // namespace
}  // namespace ricochet
