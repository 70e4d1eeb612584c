// Tests of the Gmsh .msh reader (harness/input/gmsh_reader.hpp) on the files in tests/data and on
// malformed files written to a temporary directory: every rejection names file and line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>

#include "harness/input/gmsh_reader.hpp"
#include "harness/input/input_error.hpp"

namespace ricochet {
namespace {

namespace fs = std::filesystem;

fs::path data(const std::string& name) {
  return fs::path(RICOCHET_SOURCE_DIR) / "tests" / "data" / name;
}

std::string slurp(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

// Writes `text` to <temporary directory>/ricochet_gmsh_<run>_<slot>.msh and returns its path;
// <run> is random per process, as CTest runs tests in parallel processes. Each call without a
// slot gets a fresh file; all of them are removed when the program ends.
fs::path write_temp(const std::string& text, int slot = -1) {
  struct Files {
    std::set<fs::path> paths;
    ~Files() {
      std::error_code ec;
      for (const fs::path& p : paths) fs::remove(p, ec);
    }
  };
  static Files files;
  static const std::string run = std::to_string(std::random_device{}());
  static int counter = 1000;
  const fs::path file =
      fs::path(testing::TempDir()) /
      ("ricochet_gmsh_" + run + "_" + std::to_string(slot >= 0 ? slot : counter++) + ".msh");
  std::ofstream(file, std::ios::binary) << text;
  files.paths.insert(file);
  return file;
}

// The InputError message of read_gmsh(file), or a marker if it did not throw one.
std::string error_of(const fs::path& file) {
  try {
    read_gmsh(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "no InputError";
}

// Expects read_gmsh to reject `text` with a message "FILE:LINE: ..." containing `what`.
void expect_error(const std::string& text, int line, const std::string& what) {
  const fs::path file = write_temp(text);
  const std::string message = error_of(file);
  EXPECT_EQ(message.rfind(file.string() + ":" + std::to_string(line) + ": ", 0), 0u) << message;
  EXPECT_NE(message.find(what), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
}

double total_area(const Mesh& m) {
  double a = 0.0;
  for (const auto& q : m.quads) a += signed_area(m, q.data(), 4);
  for (const auto& t : m.tris) a += signed_area(m, t.data(), 3);
  return a;
}

void expect_same(const Mesh& a, const Mesh& b) {
  EXPECT_EQ(a.nodes, b.nodes);
  EXPECT_EQ(a.quads, b.quads);
  EXPECT_EQ(a.tris, b.tris);
  EXPECT_EQ(a.node_sets, b.node_sets);
}

const std::string header22 = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";
const std::string nodes22 =  // lines 4-12
    "$Nodes\n6\n1 0 0 0\n2 1 0 0\n3 2 0 0\n4 0 1 0\n5 1 1 0\n6 2 1 0\n$EndNodes\n";

// A 2.2 file with the nodes above and these element lines (line 15 onwards).
std::string file22(const std::string& elements, int count) {
  return header22 + nodes22 + "$Elements\n" + std::to_string(count) + "\n" + elements +
         "$EndElements\n";
}

TEST(GmshReader, ReadsQuadMeshWithPhysicalGroups) {
  const Mesh m = read_gmsh(data("gmsh_quad_2x1_v22.msh"));
  ASSERT_EQ(m.num_nodes(), 6);  // the point-only node 7 is dropped
  Eigen::Matrix2Xd expected(2, 6);
  expected << 0, 1, 2, 0, 1, 2, 0, 0, 0, 1, 1, 1;
  EXPECT_EQ(m.nodes, expected);
  EXPECT_EQ(m.quads,
            (std::vector<std::array<int, 4>>{{0, 1, 4, 3}, {1, 2, 5, 4}}));  // duplicates merged
  EXPECT_TRUE(m.tris.empty());
  EXPECT_EQ(total_area(m), 2.0);
  const std::map<std::string, std::vector<int>> sets = {{"bottom", {0, 1, 2}},
                                                        {"physical_7", {0, 3}},
                                                        {"physical_9", {0, 1, 2, 3, 4, 5}},
                                                        {"probe", {}},
                                                        {"steel plate", {0, 1, 2, 3, 4, 5}}};
  EXPECT_EQ(m.node_sets, sets);
}

TEST(GmshReader, Versions22And41GiveTheSameMesh) {
  expect_same(read_gmsh(data("gmsh_quad_2x1_v22.msh")), read_gmsh(data("gmsh_quad_2x1_v41.msh")));
}

TEST(GmshReader, ReadsMixedTrianglesAndQuads) {
  const Mesh m = read_gmsh(data("gmsh_mixed_v41.msh"));
  EXPECT_EQ(m.num_nodes(), 6);
  EXPECT_EQ(m.quads, (std::vector<std::array<int, 4>>{{0, 1, 4, 3}}));
  EXPECT_EQ(m.tris, (std::vector<std::array<int, 3>>{{1, 2, 5}, {1, 5, 4}}));
  EXPECT_EQ(total_area(m), 2.0);
  EXPECT_TRUE(m.node_sets.empty());
}

TEST(GmshReader, FlipsAnAllClockwiseMesh) {
  const Mesh m = read_gmsh(data("gmsh_mixed_clockwise_v22.msh"));
  expect_same(m, read_gmsh(data("gmsh_mixed_v41.msh")));
  EXPECT_EQ(total_area(m), 2.0);
}

TEST(GmshReader, RejectsMixedOrientation) {
  const fs::path file = data("gmsh_mixed_orientation_v22.msh");
  EXPECT_EQ(error_of(file),
            file.string() +
                ":17: inverted (clockwise) element 57; all cells must have the same orientation");
}

TEST(GmshReader, RejectsBadFiles) {
  const fs::path missing = data("no_such_file.msh");
  EXPECT_EQ(error_of(missing), missing.string() + ": cannot open");
  EXPECT_EQ(error_of(data("")), data("").string() + ": cannot open: not a regular file");  // a directory
  // A device is never read (it could be endless: /dev/zero, /dev/stdin).
  for (const char* device : {"/dev/zero", "/dev/null"}) {
    if (fs::exists(device)) {
      EXPECT_EQ(error_of(device), std::string(device) + ": cannot open: not a regular file");
    }
  }
  const fs::path binary = data("gmsh_binary_header.msh");
  EXPECT_EQ(error_of(binary), binary.string() + ":2: binary .msh is not supported; save as ASCII");
  const fs::path truncated = data("gmsh_truncated_v41.msh");
  EXPECT_EQ(error_of(truncated),
            truncated.string() + ":21: unexpected end of file in $Entities (truncated?)");

  expect_error("", 1, "empty file");
  expect_error("$Nodes\n", 1, "expected $MeshFormat");
  expect_error("$MeshFormat\n3.0 0 8\n$EndMeshFormat\n", 2,
               "unsupported .msh version '3.0'; supported: 2.2 and 4.1");
  expect_error("$MeshFormat\n2.2 2 8\n$EndMeshFormat\n", 2,
               "file-type (0 = ASCII) must be in [0, 1] (got 2)");
  expect_error(header22 + "$Nodes\n6\n1 0 0 0\n2 1 0", 7, "unexpected end of file in $Nodes");
  expect_error(header22 + "$Nodes\n1\n1 0 0 0\n", 6, "unexpected end of file in $Nodes");
  expect_error(header22 + "$Nodes\n2\n1 0 0 0\n$EndNodes\n", 7,
               "expected node tag (an integer), got '$EndNodes'");
  expect_error(header22 + "$Nodes\n1\n1 0 zero 0\n$EndNodes\n", 6,
               "expected y (a finite number), got 'zero'");
  expect_error(header22 + "$Nodes\n1\n1 0 nan 0\n$EndNodes\n", 6,
               "expected y (a finite number), got 'nan'");
  expect_error(header22 + "$Nodes\n2\n1 0 0 0\n1 1 0 0\n$EndNodes\n", 7, "duplicate node tag 1");
  expect_error(header22 + "$Nodes\n1.5\n", 5, "expected number of nodes (an integer), got '1.5'");
  expect_error(header22 + "$PhysicalNames\n1\n1 2 \"bottom\n$EndPhysicalNames\n", 6,
               "unterminated quoted string");
  expect_error(header22 + "$Comments\nanything\n", 5, "unexpected end of file in $Comments");
  const fs::path no_nodes = write_temp(header22 + "$Elements\n0\n$EndElements\n");
  EXPECT_EQ(error_of(no_nodes), no_nodes.string() + ": no $Nodes section");
  const fs::path no_elements = write_temp(header22 + nodes22);
  EXPECT_EQ(error_of(no_elements), no_elements.string() + ": no $Elements section");
}

TEST(GmshReader, RejectsBadElements) {
  expect_error(file22("1 3 2 0 1 1 2 5 4\n2 10 2 0 1 1 2 3 4 5 6 7 8 9\n", 2), 16,
               "unsupported element type 10 (9-node quadrangle); allowed: 2 (3-node triangle), "
               "3 (4-node quadrangle), and 1/15 for node sets");
  expect_error(file22("1 4 2 0 1 1 2 3 4\n", 1), 15,
               "unsupported element type 4 (4-node tetrahedron)");
  expect_error(file22("1 3 2 0 1 1 2 5 44\n", 1), 15,
               "element 1 refers to node 44, which is not in $Nodes");
  expect_error(file22("1 1 2 0 1 1 2\n", 1), 13, "no cells");
  expect_error(file22("1 3 2 0 1 1 2 5 4\n1 2 2 0 1 2 3 6\n", 2), 16, "duplicate element tag 1");
  expect_error(file22("1 3 2 0 1 1 2 5 4\n12 2 2 0 1 1 2 3\n", 2), 16,
               "degenerate element 12 (zero area)");
  expect_error(file22("12 3 2 0 1 1 2 2 4\n", 1), 15,
               "degenerate element 12 (non-convex quadrangle)");
  expect_error(file22("8 3 2 0 1 1 5 2 4\n", 1), 15, "degenerate element 8");  // bow-tie
  expect_error(file22("1 3 2 0 1 1 2 5 4\n", 3), 16,
               "expected element tag (an integer), got '$EndElements'");
  expect_error(file22("1 3 2 0 1 1 2 5\n", 1), 16,
               "expected node tag (an integer), got '$EndElements'");
  expect_error(file22("1 3 2 0 1 1 2 5 4 9\n", 1), 15, "expected $EndElements, got '9'");
  expect_error(header22 + "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 1 1 1e-3\n4 0 1 0\n$EndNodes\n" +
                   "$Elements\n1\n1 3 2 0 1 1 2 3 4\n$EndElements\n",
               8, "not a planar mesh in z = 0 (node 3 has z = 0.001)");
}

TEST(GmshReader, RejectsBadVersion41Blocks) {
  const std::string head = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
  const std::string nodes =
      "$Nodes\n1 3 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n";  // 4-13
  expect_error(head + "$Nodes\n1 4 1 3\n2 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n", 5,
               "$Nodes says 4 nodes, its blocks hold 3");
  expect_error(head + nodes + "$Elements\n1 1 1 1\n2 1 1 1\n1 1 2\n$EndElements\n", 16,
               "element type 1 in a block of entity dimension 2");
  expect_error(head + nodes + "$Elements\n1 2 1 2\n2 1 2 1\n1 1 2 3\n$EndElements\n", 14,
               "$Elements says 2 elements, its blocks hold 1");
  expect_error(head + nodes + "$Elements\n1 1 1 1\n2 1 16 1\n1 1 2 3 1 2 3 1 2\n$EndElements\n", 16,
               "unsupported element type 16 (8-node quadrangle)");
  expect_error(head + "$Entities\n0 0 1 0\n1 0 0 0 1 1 0 0 0\n$EndEntities\n" + nodes +
                   "$Elements\n1 1 1 1\n2 7 2 1\n1 1 2 3\n$EndElements\n",
               21, "element 1 belongs to entity (dimension 2, tag 7), which is not in $Entities");
  expect_error(head + nodes + "$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 3\n$EndElements\n$Nodes\n", 19,
               "duplicate section $Nodes");
}

// Every prefix of the valid files (read only if it ends after $EndElements), and every token
// replaced by something wrong, is either read or rejected with InputError: no other exception, no
// crash, no endless loop.
TEST(GmshReader, SurvivesTruncationAndCorruption) {
  for (const char* name :
       {"gmsh_quad_2x1_v22.msh", "gmsh_quad_2x1_v41.msh", "gmsh_mixed_v41.msh"}) {
    const std::string text = slurp(data(name));
    ASSERT_FALSE(text.empty());
    const Mesh full = read_gmsh(data(name));
    const std::size_t complete = text.rfind("$EndElements") + std::string("$EndElements").size();
    for (std::size_t n = 0; n < text.size(); ++n) {
      const fs::path cut = write_temp(text.substr(0, n), 0);
      if (n < complete)
        EXPECT_NE(error_of(cut), "no InputError") << name << " cut at " << n;
      else
        expect_same(read_gmsh(cut), full);
    }
    for (std::size_t begin = 0; begin < text.size();) {
      const std::size_t end = std::min(text.find_first_of(" \n", begin), text.size());
      for (const char* bad : {"-1", "0", "x", "99999999999999999999", "1e308", "3"}) {
        const std::string corrupted = text.substr(0, begin) + bad + text.substr(end);
        try {
          read_gmsh(write_temp(corrupted, 0));
        } catch (const InputError&) {
        }
      }
      begin = end + 1;
    }
  }
}

}  // namespace
}  // namespace ricochet
