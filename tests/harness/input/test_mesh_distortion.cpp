// Tests of mesh distortion (distort_mesh, local_element_size in harness/input/mesh_generators.hpp
// and the `distort` and `seed` keys of generated meshes): boundary nodes fixed exactly, interior
// displacements bounded by distort x h per component, the documented random-number recipe,
// reproducibility, distort = 0 as no change at all, valid cells, rejection of a distortion that
// inverts a cell, and the keys applied before scale through the case reader.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "harness/input/case_setup.hpp"
#include "harness/input/input_error.hpp"
#include "harness/input/mesh_generators.hpp"

namespace fs = std::filesystem;

namespace ricochet {
namespace {

bool bit_identical(const Mesh& a, const Mesh& b) {
  return a.nodes.cols() == b.nodes.cols() &&
         std::memcmp(a.nodes.data(), b.nodes.data(), sizeof(double) * a.nodes.size()) == 0;
}

Mesh distorted(Mesh m, double distort, std::uint64_t seed) {
  distort_mesh(m, distort, seed);
  return m;
}

struct Named {
  const char* name;
  Mesh mesh;
};

// One mesh of each generator, including a graded one and triangles.
std::vector<Named> sample_meshes() {
  return {
      {"rectangle quad", make_rectangle({.width = 2.0, .height = 1.0, .nx = 8, .ny = 5})},
      {"rectangle tri", make_rectangle({.width = 1.0, .height = 1.0, .nx = 6, .ny = 6, .triangles = true})},
      {"arc_plate bias 4", make_arc_plate({.nx = 8, .ny = 16, .bias = 4.0})},
      {"disk n 6", make_disk({.radius = 0.5, .center = Vec2(1.0, 2.0), .n = 6})},
  };
}

// h is the smallest edge length at a node: a 2 x 1 rectangle in 2 x 4 cells has edges 1 (across)
// and 0.25 (up), so every node has h = 0.25; an unused node has h = +infinity.
TEST(LocalElementSize, IsTheShortestAdjacentEdge) {
  Mesh m = make_rectangle({.width = 2.0, .height = 1.0, .nx = 2, .ny = 4});
  for (double h : local_element_size(m)) EXPECT_EQ(h, 0.25);
  // Graded: on a 1 x 1 plate with bias 4 the bottom row is the shortest, the top row the longest.
  const Mesh a = make_arc_plate({.width = 0.04, .height = 0.08, .radius = 0.101, .nx = 2, .ny = 4, .bias = 4.0});
  const std::vector<double> h = local_element_size(a);
  EXPECT_LT(h[0], h[4 * 3]);  // node (0, 0) on the arc vs node (0, 4) on the top edge
  m.nodes.conservativeResize(2, m.num_nodes() + 1);
  m.nodes.col(m.num_nodes() - 1) = Vec2(5.0, 5.0);
  EXPECT_TRUE(std::isinf(local_element_size(m).back()));
}

TEST(Distort, MovesInteriorNodesOnlyWithinDistortTimesH) {
  const double distort = 0.3;
  for (const auto& [name, mesh] : sample_meshes()) {
    SCOPED_TRACE(name);
    const Mesh d = distorted(mesh, distort, 5);
    const std::vector<double> h = local_element_size(mesh);
    std::vector<char> boundary(mesh.num_nodes(), 0);
    for (int n : boundary_nodes(mesh)) boundary[n] = 1;
    int interior = 0, moved = 0;
    double largest = 0.0;  // largest |component| / (distort h)
    for (int i = 0; i < mesh.num_nodes(); ++i) {
      const Vec2 u = d.nodes.col(i) - mesh.nodes.col(i);
      if (boundary[i]) {
        EXPECT_EQ(d.nodes(0, i), mesh.nodes(0, i)) << "boundary node " << i;
        EXPECT_EQ(d.nodes(1, i), mesh.nodes(1, i)) << "boundary node " << i;
        continue;
      }
      ++interior;
      // Round-off of x + u: allow a few ulps of the coordinate beyond the bound.
      const double tol = distort * h[i] + 4e-16 * mesh.nodes.col(i).cwiseAbs().maxCoeff();
      EXPECT_LE(std::abs(u.x()), tol) << "node " << i;
      EXPECT_LE(std::abs(u.y()), tol) << "node " << i;
      if (u.x() != 0.0 && u.y() != 0.0) ++moved;
      largest = std::max(largest, u.cwiseAbs().maxCoeff() / (distort * h[i]));
    }
    EXPECT_GT(interior, 10);
    EXPECT_EQ(moved, interior);  // every interior node moves in both x and y
    EXPECT_GT(largest, 0.8);     // the draws span the range, not a fraction of it
    // Cells stay counter-clockwise and Q4 cells convex.
    for (const auto& q : d.quads) {
      EXPECT_GT(signed_area(d, q.data(), 4), 0.0);
      EXPECT_GT(q4_corner_quality(d, q), 0.0);
    }
    for (const auto& t : d.tris) EXPECT_GT(signed_area(d, t.data(), 3), 0.0);
    EXPECT_EQ(d.quads, mesh.quads);
    EXPECT_EQ(d.tris, mesh.tris);
    EXPECT_EQ(d.node_sets, mesh.node_sets);
  }
}

// The graded arc plate is distorted relative to its own cells: near the arc, where cells are
// small, the displacements are small.
TEST(Distort, GradedMeshIsDistortedRelativeToItsCells) {
  const Mesh m = make_arc_plate({.nx = 8, .ny = 16, .bias = 4.0});
  const Mesh d = distorted(m, 0.4, 3);
  const std::vector<double> h = local_element_size(m);
  const int row = 9;  // nodes per row
  // Row 1 (next to the arc) vs row 15 (next to the top): bound by their own h, which differ.
  EXPECT_LT(1.5 * h[1 * row + 4], h[15 * row + 4]);
  for (int i = 1; i < 8; ++i) {
    EXPECT_LE((d.nodes.col(row + i) - m.nodes.col(row + i)).cwiseAbs().maxCoeff(), 0.4 * h[row + i] * (1 + 1e-12));
  }
}

TEST(Distort, FollowsTheDocumentedRecipe) {
  // The standard fixes mt19937_64: the 10000th number of a default-constructed one.
  std::mt19937_64 check;
  check.discard(9999);
  EXPECT_EQ(check(), 9981545732273789042ull);
  // A 2 x 2 rectangle has one interior node, 4, at (0.5, 0.5), h = 0.5.
  const Mesh m = make_rectangle({.width = 1.0, .height = 1.0, .nx = 2, .ny = 2});
  const std::uint64_t seed = 42;
  const Mesh d = distorted(m, 0.25, seed);
  std::mt19937_64 random(seed);
  const double rx = 2.0 * (static_cast<double>(random() >> 11) * 0x1p-53) - 1.0;
  const double ry = 2.0 * (static_cast<double>(random() >> 11) * 0x1p-53) - 1.0;
  EXPECT_EQ(d.nodes(0, 4), std::fma(0.25 * 0.5, rx, 0.5));
  EXPECT_EQ(d.nodes(1, 4), std::fma(0.25 * 0.5, ry, 0.5));
  for (int i = 0; i < 9; ++i) {
    if (i == 4) continue;
    EXPECT_EQ(d.nodes.col(i), m.nodes.col(i));
  }
  // And pinned as values, so that a change of recipe or platform shows.
  EXPECT_EQ(d.nodes(0, 4), 0x1.20a8efbeb772fp-1);
  EXPECT_EQ(d.nodes(1, 4), 0x1.11cbc7dcdc928p-1);
}

TEST(Distort, SameSeedSameMeshOtherSeedOtherMesh) {
  for (const auto& [name, mesh] : sample_meshes()) {
    SCOPED_TRACE(name);
    const Mesh a = distorted(mesh, 0.2, 1), b = distorted(mesh, 0.2, 1), c = distorted(mesh, 0.2, 2);
    EXPECT_TRUE(bit_identical(a, b));
    EXPECT_FALSE(bit_identical(a, c));
    EXPECT_FALSE(bit_identical(a, mesh));
    // Seed 0 is a seed like any other.
    EXPECT_FALSE(bit_identical(distorted(mesh, 0.2, 0), a));
  }
}

TEST(Distort, ZeroIsNoChangeAtAll) {
  for (const auto& [name, mesh] : sample_meshes()) {
    SCOPED_TRACE(name);
    EXPECT_TRUE(bit_identical(distorted(mesh, 0.0, 1), mesh));
    EXPECT_TRUE(bit_identical(distorted(mesh, 0.0, 12345), mesh));
  }
}

TEST(Distort, AnInvertedCellIsAnErrorThatSaysLowerDistort) {
  // Far beyond the reader's range (< 0.5): cells fold over.
  const Mesh m = make_rectangle({.width = 1.0, .height = 1.0, .nx = 4, .ny = 4});
  try {
    distorted(m, 3.0, 1);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("after distortion Q4 cell "), std::string::npos) << what;
    EXPECT_NE(what.find("lower distort (got 3)"), std::string::npos) << what;
  }
  const Mesh t = make_rectangle({.width = 1.0, .height = 1.0, .nx = 4, .ny = 4, .triangles = true});
  try {
    distorted(t, 3.0, 1);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("after distortion T3 cell "), std::string::npos) << what;
    EXPECT_NE(what.find("has no positive area; lower distort"), std::string::npos) << what;
  }
  Mesh copy = m;
  EXPECT_THROW(distort_mesh(copy, -0.1, 1), InputError);
  EXPECT_THROW(distort_mesh(copy, std::nan(""), 1), InputError);
}

const std::string kCase = R"(name = "rect"
mesh = "m"
[meshes.m]
generator = "rectangle"
width = 0.2
height = 0.1
nx = 4
ny = 2
[[bodies]]
name = "b"
[bodies.material]
young = 1e6
poisson = 0.3
density = 1000.0
[time]
end = 1e-4
dt = 1e-5
[output]
interval = 1e-5
)";

PreparedCase prepare(const std::vector<std::string>& overrides) {
  const fs::path file = fs::temp_directory_path() / ("ricochet_distortion_" + std::to_string(getpid()) + ".toml");
  std::ofstream(file) << kCase;
  PreparedCase pc = prepare_case(read_case(file.string(), overrides));
  fs::remove(file);
  return pc;
}

// The keys reach distort_mesh, which runs before scale and offset; defaults are distort = 0
// (no change) and seed = 1.
TEST(Distort, CaseKeysApplyBeforeScaleAndOffset) {
  const Mesh plain = make_rectangle({.width = 0.2, .height = 0.1, .nx = 4, .ny = 2});
  const PreparedCase none = prepare({});
  EXPECT_EQ(none.spec.meshes.at("m").distort, 0.0);
  EXPECT_EQ(none.spec.meshes.at("m").seed, 1u);
  EXPECT_TRUE(bit_identical(none.meshes<2>()[0], plain));
  const PreparedCase zero = prepare({"meshes.m.distort=0.0", "meshes.m.seed=9"});
  EXPECT_TRUE(bit_identical(zero.meshes<2>()[0], plain));

  const PreparedCase seed1 = prepare({"meshes.m.distort=0.2"});
  EXPECT_TRUE(bit_identical(seed1.meshes<2>()[0], distorted(plain, 0.2, 1)));
  const PreparedCase moved =
      prepare({"meshes.m.distort=0.2", "meshes.m.seed=7", "meshes.m.scale=2.0", "meshes.m.offset=[1.0, -1.0]"});
  Mesh expected = distorted(plain, 0.2, 7);
  expected.nodes *= 2.0;
  expected.nodes.colwise() += Vec2(1.0, -1.0);
  EXPECT_TRUE(bit_identical(moved.meshes<2>()[0], expected));
  EXPECT_FALSE(bit_identical(moved.meshes<2>()[0], seed1.meshes<2>()[0]));
}

}  // namespace
}  // namespace ricochet
