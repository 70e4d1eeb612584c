// Tests of the 3D Gmsh reader (read_gmsh3 / parse_gmsh3, harness/input/gmsh_reader.hpp): small
// hand-written 2.2 and 4.1 files (the same mesh in both), round trips of generated boxes through
// .msh text written here, one-line errors naming file and line, and no crash on truncated or
// corrupted files.
#include <gtest/gtest.h>

#include <charconv>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "harness/input/gmsh_reader.hpp"
#include "harness/input/input_error.hpp"
#include "harness/input/mesh_generators3.hpp"
#include "solver/model/mesh.hpp"

namespace ricochet {
namespace {

namespace fs = std::filesystem;

// Two unit cubes side by side along x ([0, 2] x [0, 1] x [0, 1]), as Gmsh writes them with
// physical groups: a point "probe" (on node 2, and on node 13, which no cell uses), an unnamed
// line (physical 6), a quadrangle "left" (x = 0), two triangles "right" (x = 2), and the volume
// in physical groups "body" and 9 (unnamed). 2.2 repeats each hexahedron once per physical group.
const std::string two_hexes_22 = R"($MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
4
0 5 "probe"
2 1 "left"
2 3 "right"
3 2 "body"
$EndPhysicalNames
$Nodes
13
1 0 0 0
2 1 0 0
3 2 0 0
4 0 1 0
5 1 1 0
6 2 1 0
7 0 0 1
8 1 0 1
9 2 0 1
10 0 1 1
11 1 1 1
12 2 1 1
13 5 5 5
$EndNodes
$Elements
10
1 15 2 5 1 2
2 15 2 5 2 13
3 1 2 6 1 1 2
4 3 2 1 1 1 7 10 4
5 2 2 3 2 3 6 12
6 2 2 3 2 3 12 9
7 5 2 2 1 1 2 5 4 7 8 11 10
8 5 2 2 1 2 3 6 5 8 9 12 11
9 5 2 9 1 1 2 5 4 7 8 11 10
10 5 2 9 1 2 3 6 5 8 9 12 11
$EndElements
)";

// The same mesh in 4.1: physical groups through $Entities, nodes in entity blocks.
const std::string two_hexes_41 = R"($MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
4
0 5 "probe"
2 1 "left"
2 3 "right"
3 2 "body"
$EndPhysicalNames
$Entities
2 1 2 1
1 1 0 0 1 5
2 5 5 5 1 5
1 0 0 0 1 0 0 1 6 2 1 -2
1 0 0 0 0 1 1 1 1 0
2 2 0 0 2 1 1 1 3 0
1 0 0 0 2 1 1 2 2 9 2 1 2
$EndEntities
$Nodes
3 13 1 13
0 1 0 1
2
1 0 0
0 2 0 1
13
5 5 5
3 1 0 11
1
3
4
5
6
7
8
9
10
11
12
0 0 0
2 0 0
0 1 0
1 1 0
2 1 0
0 0 1
1 0 1
2 0 1
0 1 1
1 1 1
2 1 1
$EndNodes
$Elements
6 8 1 8
0 1 15 1
1 2
0 2 15 1
2 13
1 1 1 1
3 1 2
2 1 3 1
4 1 7 10 4
2 2 2 2
5 3 6 12
6 3 12 9
3 1 5 2
7 1 2 5 4 7 8 11 10
8 2 3 6 5 8 9 12 11
$EndElements
)";

void expect_same(const Mesh3& a, const Mesh3& b) {
  EXPECT_EQ(a.nodes, b.nodes);
  EXPECT_EQ(a.hexes, b.hexes);
  EXPECT_EQ(a.tets, b.tets);
  EXPECT_EQ(a.node_sets, b.node_sets);
}

std::string number(double v) {
  char buffer[32];
  return std::string(buffer, std::to_chars(buffer, buffer + sizeof buffer, v).ptr);
}

// A Mesh3 as .msh text (written here from the format's description, not by the reader's code):
// node tag = index + 1, element tag = cell + 1 (hexahedra, then tetrahedra), every cell in the
// physical volume 1 named "all".
std::string to_msh22(const Mesh3& m) {
  std::string s = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n3 1 \"all\"\n$EndPhysicalNames\n";
  s += "$Nodes\n" + std::to_string(m.num_nodes()) + "\n";
  for (int n = 0; n < m.num_nodes(); ++n)
    s += std::to_string(n + 1) + " " + number(m.nodes(0, n)) + " " + number(m.nodes(1, n)) + " " +
         number(m.nodes(2, n)) + "\n";
  s += "$EndNodes\n$Elements\n" + std::to_string(m.num_cells()) + "\n";
  int tag = 1;
  auto cell = [&](int type, const auto& corners) {
    s += std::to_string(tag++) + " " + std::to_string(type) + " 2 1 1";
    for (int c : corners) {
      s += ' ';  // not " " + to_string(): g++ 12 warns falsely on it (-Wrestrict)
      s += std::to_string(c + 1);
    }
    s += "\n";
  };
  for (const auto& h : m.hexes) cell(5, h);
  for (const auto& t : m.tets) cell(4, t);
  return s + "$EndElements\n";
}

std::string to_msh41(const Mesh3& m) {
  std::string s = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n3 1 \"all\"\n$EndPhysicalNames\n";
  s += "$Entities\n0 0 0 1\n1 0 0 0 1 1 1 1 1 0\n$EndEntities\n";
  const std::string n = std::to_string(m.num_nodes());
  s += "$Nodes\n1 " + n + " 1 " + n + "\n3 1 0 " + n + "\n";
  for (int k = 0; k < m.num_nodes(); ++k) s += std::to_string(k + 1) + "\n";
  for (int k = 0; k < m.num_nodes(); ++k)
    s += number(m.nodes(0, k)) + " " + number(m.nodes(1, k)) + " " + number(m.nodes(2, k)) + "\n";
  const int blocks = (m.hexes.empty() ? 0 : 1) + (m.tets.empty() ? 0 : 1);
  s += "$EndNodes\n$Elements\n" + std::to_string(blocks) + " " + std::to_string(m.num_cells()) + " 1 " +
       std::to_string(m.num_cells()) + "\n";
  int tag = 1;
  auto block = [&](int type, const auto& cells) {
    if (cells.empty()) return;
    s += "3 1 " + std::to_string(type) + " " + std::to_string(cells.size()) + "\n";
    for (const auto& c : cells) {
      s += std::to_string(tag++);
      for (int k : c) {
        s += ' ';
        s += std::to_string(k + 1);
      }
      s += "\n";
    }
  };
  block(5, m.hexes);
  block(4, m.tets);
  return s + "$EndElements\n";
}

// The InputError message of parse_gmsh3(text, "m.msh"), or a marker if it did not throw one.
std::string error_of(const std::string& text) {
  try {
    parse_gmsh3(text, "m.msh");
  } catch (const InputError& e) {
    return e.what();
  }
  return "no InputError";
}

// Expects parse_gmsh3 to reject `text` with exactly "m.msh:LINE: what", one line.
void expect_error(const std::string& text, int line, const std::string& what) {
  EXPECT_EQ(error_of(text), "m.msh:" + std::to_string(line) + ": " + what);
}

// A 2.2 file of the unit cube's 8 nodes (in the corner order of mesh.hpp) with these element
// lines from line 17 on; `node7` replaces the coordinates of node 7, (1, 1, 1).
std::string cube22(const std::string& elements, int count, const std::string& node7 = "1 1 1") {
  return "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n8\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n"
         "5 0 0 1\n6 1 0 1\n7 " + node7 + "\n8 0 1 1\n$EndNodes\n$Elements\n" + std::to_string(count) + "\n" +
         elements + "$EndElements\n";
}

TEST(Gmsh3, ReadsHexahedraWithPhysicalGroups) {
  const Mesh3 m = parse_gmsh3(two_hexes_22, "two_hexes_22.msh");
  ASSERT_EQ(m.num_nodes(), 12);  // node 13 (a point only) is dropped
  Eigen::Matrix3Xd nodes(3, 12);
  nodes << 0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1, 2,  //
      0, 0, 0, 1, 1, 1, 0, 0, 0, 1, 1, 1,       //
      0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1;
  EXPECT_EQ(m.nodes, nodes);
  EXPECT_EQ(m.hexes, (std::vector<std::array<int, 8>>{{0, 1, 4, 3, 6, 7, 10, 9}, {1, 2, 5, 4, 7, 8, 11, 10}}));
  EXPECT_TRUE(m.tets.empty());
  for (const auto& h : m.hexes) EXPECT_EQ(signed_volume(m, h), 1.0);
  const std::map<std::string, std::vector<int>> sets = {{"body", {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}},
                                                        {"left", {0, 3, 6, 9}},
                                                        {"physical_6", {0, 1}},
                                                        {"physical_9", {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}},
                                                        {"probe", {1}},
                                                        {"right", {2, 5, 8, 11}}};
  EXPECT_EQ(m.node_sets, sets);
  EXPECT_EQ(boundary_faces(m).size(), 10u);
}

TEST(Gmsh3, Versions22And41GiveTheSameMesh) {
  expect_same(parse_gmsh3(two_hexes_22, "a.msh"), parse_gmsh3(two_hexes_41, "b.msh"));
  // And the generated boxes, hexahedra and tetrahedra, through both versions.
  for (const bool tets : {false, true}) {
    SCOPED_TRACE(tets ? "tetrahedra" : "hexahedra");
    Mesh3 box = make_box({.size = Vec3(0.3, 0.2, 0.1), .nx = 3, .ny = 2, .nz = 2, .origin = Vec3(-0.1, 1e-3, 7), .tetrahedra = tets});
    box.node_sets = {{"all", box.node_sets.at("all")}};
    expect_same(parse_gmsh3(to_msh22(box), "box22.msh"), box);
    expect_same(parse_gmsh3(to_msh41(box), "box41.msh"), box);
  }
}

TEST(Gmsh3, ReadsHexahedraAndTetrahedraTogether) {
  // Hexahedra and tetrahedra in one file, in element-tag order of each kind.
  Mesh3 mixed = make_box({.nx = 2});
  const Mesh3 split = make_box({.nx = 2, .tetrahedra = true});
  mixed.hexes.pop_back();
  mixed.tets.assign(split.tets.begin() + 6, split.tets.end());
  mixed.node_sets = {{"all", mixed.node_sets.at("all")}};
  const Mesh3 m = parse_gmsh3(to_msh41(mixed), "mixed.msh");
  expect_same(m, mixed);
  double volume = 0.0;
  for (const auto& h : m.hexes) volume += signed_volume(m, h);
  for (const auto& t : m.tets) volume += signed_volume(m, t);
  EXPECT_NEAR(volume, 1.0, 1e-15);
}

TEST(Gmsh3, ReadsFilesAndRejectsMissingOnes) {
  const fs::path file = fs::path(testing::TempDir()) / ("ricochet_gmsh3_" + std::to_string(std::random_device{}()) + ".msh");
  std::ofstream(file, std::ios::binary) << two_hexes_41;
  expect_same(read_gmsh3(file), parse_gmsh3(two_hexes_41, "x"));
  fs::remove(file);
  try {
    read_gmsh3(file);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), file.string() + ": cannot open");
  }
}

TEST(Gmsh3, RejectsBadCells) {
  expect_error(cube22("1 5 2 0 1 5 6 7 8 1 2 3 4\n", 1), 17,
               "inverted element 1 (volume -1 < 0); allowed: cells of positive volume in Gmsh's corner order");
  expect_error(cube22("1 4 2 0 1 1 2 4 5\n2 4 2 0 1 1 4 2 5\n", 2), 18,
               "inverted element 2 (volume -0.166667 < 0); allowed: cells of positive volume in Gmsh's corner order");
  expect_error(cube22("1 4 2 0 1 1 2 3 4\n", 1), 17, "degenerate element 1 (zero volume)");
  expect_error(cube22("1 5 2 0 1 1 2 3 4 1 2 3 4\n", 1), 17, "degenerate element 1 (zero volume)");
  // Corner 7 at the centre: volume 0.625 > 0, but the corner is folded (mesh.hpp).
  expect_error(cube22("1 5 2 0 1 1 2 3 4 5 6 7 8\n", 1, "0.5 0.5 0.5"), 17,
               "degenerate element 1 (a corner Jacobian is <= 0: folded hexahedron)");
  EXPECT_EQ(parse_gmsh3(cube22("1 5 2 0 1 1 2 3 4 5 6 7 8\n", 1, "0.7 0.7 0.7"), "m.msh").hexes.size(), 1u);
  expect_error(cube22("1 6 2 0 1 1 2 4 5 6 8\n", 1), 17,
               "unsupported element type 6 (6-node prism); allowed: 4 (4-node tetrahedron), 5 (8-node hexahedron), "
               "and 1/2/3/15 for node sets");
  expect_error(cube22("1 11 2 0 1 1 2 4 5 1 2 3 4 5 6\n", 1), 17,
               "unsupported element type 11 (10-node tetrahedron); allowed: 4 (4-node tetrahedron), 5 (8-node "
               "hexahedron), and 1/2/3/15 for node sets");
  expect_error(cube22("1 3 2 0 1 1 2 3 4\n", 1), 15,
               "no cells: the mesh needs elements of type 4 (4-node tetrahedron) or 5 (8-node hexahedron)");
  expect_error(cube22("1 4 2 0 1 1 2 4 44\n", 1), 17, "element 1 refers to node 44, which is not in $Nodes");
  expect_error(cube22("1 5 2 0 1 1 2 3 4 5 6 7\n", 1), 18,
               "expected node tag (an integer), got '$EndElements' (section shorter than its counts say?)");
  expect_error(cube22("1 4 2 0 1 1 2 4 5\n", 1, "1 inf 1"), 12, "expected y (a finite number), got 'inf'");
  // The 2D reader keeps its own rule and message for the same file.
  try {
    parse_gmsh(cube22("1 5 2 0 1 1 2 3 4 5 6 7 8\n", 1), "m.msh");
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "m.msh:17: unsupported element type 5 (8-node hexahedron); allowed: 2 (3-node triangle), 3 (4-node "
              "quadrangle), and 1/15 for node sets");
  }
}

TEST(Gmsh3, RejectsBadVersion41Blocks) {
  const std::string head = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
  const std::string nodes =  // lines 4-15
      "$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n";
  EXPECT_EQ(parse_gmsh3(head + nodes + "$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n", "m.msh").tets.size(), 1u);
  expect_error(head + nodes + "$Elements\n1 1 1 1\n2 1 4 1\n1 1 2 3 4\n$EndElements\n", 18,
               "element type 4 in a block of entity dimension 2");
  expect_error(head + nodes + "$Elements\n1 2 1 2\n3 1 4 1\n1 1 2 3 4\n$EndElements\n", 16,
               "$Elements says 2 elements, its blocks hold 1");
  expect_error(head + "$Entities\n0 0 0 1\n1 0 0 0 1 1 1 0 0\n$EndEntities\n" + nodes +
                   "$Elements\n1 1 1 1\n3 7 4 1\n1 1 2 3 4\n$EndElements\n",
               23, "element 1 belongs to entity (dimension 3, tag 7), which is not in $Entities");
}

// Every prefix of the valid files (read only if it ends after $EndElements), and every token
// replaced by something wrong, is either read or rejected with InputError: no other exception, no
// crash, no endless loop.
TEST(Gmsh3, SurvivesTruncationAndCorruption) {
  for (const std::string* text : {&two_hexes_22, &two_hexes_41}) {
    const Mesh3 full = parse_gmsh3(*text, "full.msh");
    const std::size_t complete = text->rfind("$EndElements") + std::string("$EndElements").size();
    for (std::size_t n = 0; n < text->size(); ++n) {
      if (n < complete)
        EXPECT_NE(error_of(text->substr(0, n)), "no InputError") << "cut at " << n;
      else
        expect_same(parse_gmsh3(text->substr(0, n), "cut.msh"), full);
    }
    for (std::size_t begin = 0; begin < text->size();) {
      const std::size_t end = std::min(text->find_first_of(" \n", begin), text->size());
      for (const char* bad : {"-1", "0", "x", "99999999999999999999", "1e308", "3", "4", "5"}) {
        const std::string corrupted = text->substr(0, begin) + bad + text->substr(end);
        const std::string message = error_of(corrupted);
        EXPECT_EQ(message.find('\n'), std::string::npos) << message;
        if (message != "no InputError") {
          EXPECT_EQ(message.rfind("m.msh:", 0), 0u) << message;
        }
      }
      begin = end + 1;
    }
  }
}

}  // namespace
}  // namespace ricochet
