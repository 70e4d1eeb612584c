// Tests of the structured mesh generators (harness/mesh_generators.hpp): counts, exact areas
// and their convergence, orientation, node sets, grading, and rejected parameters.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>

#include "harness/input_error.hpp"
#include "harness/mesh_generators.hpp"

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
  for (int n : sets.at("top")) EXPECT_EQ(m.nodes(1, n), s + H);
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
  EXPECT_EQ(m.nodes.col(sets.at("top_left")[0]), Vec2(-L / 2, s + H));
  EXPECT_EQ(m.nodes.col(sets.at("top_right")[0]), Vec2(L / 2, s + H));
  EXPECT_EQ(m.nodes.col(0), Vec2(-L / 2, s));  // bottom-left corner on the arc
  EXPECT_EQ(m.nodes.col(12), Vec2(L / 2, s));  // bottom-right corner on the arc
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

}  // namespace
}  // namespace ricochet
