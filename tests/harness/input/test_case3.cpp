// 3D cases (docs/case-format.md, 3D cases): the dimension from the meshes, the 3D keys and their
// errors, the prepared Model<3>, the scene rotation, and a run's outputs (history columns,
// summary keys, VTU hexahedra) through the program.
#include <gtest/gtest.h>

#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "harness/input/case_setup.hpp"
#include "harness/input/input_error.hpp"
#include "harness/outputs/json_io.hpp"
#include "harness/outputs/run_outputs.hpp"

namespace fs = std::filesystem;
using namespace ricochet;

namespace {

// A 2 x 1 x 1 cm block of 4 x 2 x 2 hexahedra, 1 mm above the plane y = 0, falling at 2 m/s.
const std::string kBlock = R"(name = "block3"
scheme = "semi_explicit"
mesh = "m"
[meshes.m]
generator = "box"
size = [0.02, 0.01, 0.01]
nx = 4
ny = 2
nz = 2
origin = [0.0, 0.001, 0.0]
[[bodies]]
name = "b"
velocity = [1.0, -2.0, 0.5]
[bodies.material]
model = "neo_hookean"
young = 1e6
poisson = 0.3
density = 1000.0
[[obstacles]]
name = "ground"
type = "plane"
normal = [0.0, 1.0, 0.0]
friction = 0.2
[time]
end = 2e-3
[output]
interval = 1e-4
fields = [1e-3]
[[output.probes]]
name = "corner"
point = [0.0, 0.001, 0.0]
)";

fs::path temp_file(const std::string& tag) {
  return fs::temp_directory_path() / ("ricochet_case3_" + tag + "_" + std::to_string(getpid()) + ".toml");
}

CaseSpec read(const std::string& text, const std::vector<std::string>& overrides = {}) {
  const fs::path file = temp_file("read");
  std::ofstream(file) << text;
  try {
    CaseSpec c = read_case(file.string(), overrides);
    fs::remove(file);
    return c;
  } catch (...) {
    fs::remove(file);
    throw;
  }
}

// The message of the InputError that reading and preparing the case throws ("" if none).
std::string error_of(const std::string& text, const std::vector<std::string>& overrides = {}) {
  try {
    prepare_case(read(text, overrides));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Case3, DimensionComesFromTheMeshes) {
  const CaseSpec box = read(kBlock);
  EXPECT_EQ(box.dimension, 3);
  const PreparedCase pc = prepare_case(box);
  EXPECT_EQ(pc.dimension(), 3);
  EXPECT_EQ(pc.model<3>().num_cells(), 16);
  EXPECT_EQ(pc.model<3>().num_nodes(), 45);
  EXPECT_TRUE(std::holds_alternative<CaseBodies<3>>(pc.bodies));  // no 2D model beside it
  EXPECT_EQ(obstacles_of(pc.settings, pc.model<3>()).size(), 1u);
  EXPECT_TRUE(std::holds_alternative<std::vector<Obstacle3>>(pc.settings.obstacles));
  // The body's velocity on every node, in three components.
  for (int i = 0; i < pc.model<3>().num_nodes(); ++i)
    EXPECT_EQ(Vec3(pc.model<3>().initial_velocity.segment<3>(3 * i)), Vec3(1.0, -2.0, 0.5));
  EXPECT_NEAR(pc.model<3>().mass.sum() / 3.0, 1000.0 * 0.02 * 0.01 * 0.01, 1e-15);

  // A 2D generator with extrude: 3D, the rectangle's cells through 3 layers, the box's nodes.
  CaseSpec ex = read(kBlock, {"meshes.m={generator = \"rectangle\", width = 0.02, height = 0.01, nx = 4, ny = 2, "
                              "origin = [0.0, 0.001], extrude = {thickness = 0.01, layers = 2}}"});
  EXPECT_EQ(ex.dimension, 3);
  const PreparedCase pe = prepare_case(ex);
  EXPECT_EQ(pe.model<3>().num_cells(), 16);
  EXPECT_EQ(pe.model<3>().ref, pc.model<3>().ref);  // the extruded rectangle is the box, bit for bit

  // A 3D Gmsh file (one tetrahedron) is 3D; the same case with a 2D one would be 2D.
  const fs::path msh = fs::temp_directory_path() / ("ricochet_case3_tet_" + std::to_string(getpid()) + ".msh");
  std::ofstream(msh) << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0.001 0\n2 0.01 0.001 0\n"
                        "3 0 0.011 0\n4 0 0.001 0.01\n$EndNodes\n$Elements\n1\n1 4 0 1 2 3 4\n$EndElements\n";
  const CaseSpec g = read(kBlock, {"meshes.m={file = \"" + msh.string() + "\"}"});
  EXPECT_EQ(g.dimension, 3);
  EXPECT_EQ(prepare_case(g).model<3>().num_cells(), 1);
  fs::remove(msh);
}

TEST(Case3, TwoDKeysAndLimitsAreNamed) {
  struct Bad {
    std::vector<std::string> set;
    std::vector<std::string> expect;  // substrings of the message
  };
  const std::vector<Bad> bad = {
      {{"plane=\"strain\""}, {"plane", "applies to 2D cases"}},
      {{"bodies[0].thickness=0.01"}, {"bodies[0].thickness", "applies to 2D bodies"}},
      {{"bodies[0].element=\"q4\""}, {"bodies[0].element", "hex8"}},
      {{"bodies[0].velocity=[1.0, 2.0]"}, {"bodies[0].velocity", "three numbers [x, y, z]"}},
      {{"gravity=[0.0, -9.81]"}, {"gravity", "three numbers"}},
      {{"obstacles[0].type=\"line\""}, {"obstacles[0].type", "plane"}},
      {{"obstacles[0].normal=[0.0, 0.0, 0.0]"}, {"obstacles[0].normal", "non-zero"}},
      {{"obstacles[0].radius=1.0"}, {"obstacles[0].radius", "unknown key for type = \"plane\""}},
      {{"obstacles[0].type=\"sphere\"", "obstacles[0].normal=[]"}, {"obstacles[0]"}},
      {{"meshes.m.size=[0.02, -0.01, 0.01]"}, {"meshes.m.size", "> 0"}},
      {{"meshes.m.distort=0.1"}, {"meshes.m.distort", "allowed for \"box\": none"}},
      {{"meshes.m.extrude={thickness = 0.01}"}, {"meshes.m.extrude", "3D already"}},
      {{"meshes.n={generator = \"rectangle\", width = 1.0, height = 1.0}"}, {"meshes.n", "2D mesh", "3D throughout"}},
      {{"contact_pairs=[{slave = \"b\", master = \"b\"}]"}, {"contact_pairs[0].master", "must differ from slave"}},
      {{"bodies[0].node_sets=[{name = \"s\", box = [0.0, 0.0, 1.0, 1.0]}]"}, {"node_sets[0].box", "zmin"}},
      {{"scene_rotation={axis = [0.0, 0.0, 0.0], angle = 10.0}"}, {"scene_rotation.axis", "non-zero"}},
      {{"obstacles[0].point=[0.0, 0.005, 0.0]"}, {"starts inside", "ground"}},
  };
  for (const Bad& b : bad) {
    const std::string e = error_of(kBlock, b.set);
    SCOPED_TRACE(b.set.front());
    EXPECT_FALSE(e.empty());
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;  // one line
    for (const std::string& s : b.expect) EXPECT_NE(e.find(s), std::string::npos) << e;
  }
  // A 2D case still reads [x, y] and rejects the 3D keys.
  const std::string two_d = R"(mesh = "m"
[meshes.m]
generator = "rectangle"
width = 0.1
height = 0.1
[[bodies]]
[bodies.material]
young = 1e6
poisson = 0.3
density = 1000.0
[time]
end = 1e-4
)";
  EXPECT_EQ(read(two_d).dimension, 2);
  EXPECT_NE(error_of(two_d, {"scene_rotation={axis = [0.0, 0.0, 1.0], angle = 10.0}"}).find("applies to 3D cases"),
            std::string::npos);
  EXPECT_NE(error_of(two_d, {"meshes.m.rotate_axis=[1.0, 0.0, 0.0]"}).find("applies to 3D meshes"), std::string::npos);
  EXPECT_NE(error_of(two_d, {"bodies[0].velocity=[1.0, 0.0, 0.0]"}).find("two numbers [x, y]"), std::string::npos);
}

// The 3D set-up of the keys the 2D code had: a mesh turned about rotate_axis, a spin vector,
// [[initial_velocity]], [[boundary]] with z, [[loads]] with a z force, gravity in z.
TEST(Case3, ThreeDimensionalSetUp) {
  // A quarter turn about x through the origin: (x, y, z) -> (x, -z, y); the box is lifted by
  // 0.03 m so that it stays above the plane y = 0.
  const PreparedCase turned =
      prepare_case(read(kBlock, {"meshes.m.rotate=90.0", "meshes.m.rotate_axis=[2.0, 0.0, 0.0]",
                                 "meshes.m.offset=[0.0, 0.03, 0.0]"}));
  const PreparedCase plain = prepare_case(read(kBlock));
  for (int i = 0; i < plain.model<3>().num_nodes(); ++i) {
    const Vec3 x = plain.model<3>().ref.col(i);
    EXPECT_LT((Vec3(turned.model<3>().ref.col(i)) - Vec3(x.x(), -x.z() + 0.03, x.y())).norm(), 1e-15) << i;
  }
  // v = velocity + omega x (x - c), c the centre of mass (here the box's centre).
  const Vec3 w(10.0, -20.0, 30.0), c(0.01, 0.006, 0.005);
  const PreparedCase spin = prepare_case(read(kBlock, {"bodies[0].angular_velocity=[10.0, -20.0, 30.0]"}));
  for (int i = 0; i < spin.model<3>().num_nodes(); ++i) {
    const Vec3 expected = Vec3(1.0, -2.0, 0.5) + w.cross(Vec3(spin.model<3>().ref.col(i)) - c);
    EXPECT_LT((Vec3(spin.model<3>().initial_velocity.segment<3>(3 * i)) - expected).norm(), 1e-14) << i;
  }
  // Node sets of the box: left (x = 0, 9 nodes), back (z = 0, 15 nodes).
  const PreparedCase set = prepare_case(
      read(kBlock, {"initial_velocity=[{nodes = \"left\", velocity = [0.0, 0.0, 3.0]}]",
                    "boundary=[{nodes = \"back\", z = 0.0}]",
                    "loads=[{nodes = \"left\", force = [0.0, 0.0, 9.0], distribution = \"equal\"}]",
                    "gravity=[0.0, 0.0, -9.81]"}));
  const std::vector<int>& left = set.meshes<3>()[0].node_sets.at("left");
  const std::vector<int>& back = set.meshes<3>()[0].node_sets.at("back");
  ASSERT_EQ(left.size(), 9u);
  ASSERT_EQ(back.size(), 15u);
  for (int i : left) EXPECT_EQ(Vec3(set.model<3>().initial_velocity.segment<3>(3 * i)), Vec3(0.0, 0.0, 3.0));
  ASSERT_EQ(set.settings.prescribed.size(), back.size());  // z only
  for (std::size_t k = 0; k < back.size(); ++k) EXPECT_EQ(set.settings.prescribed[k].dof, 3 * back[k] + 2);
  ASSERT_EQ(set.settings.loads.size(), left.size());  // z only, 1 N each
  for (std::size_t k = 0; k < left.size(); ++k) {
    EXPECT_EQ(set.settings.loads[k].dof, 3 * left[k] + 2);
    EXPECT_DOUBLE_EQ(set.settings.loads[k].value, 1.0);
  }
  EXPECT_EQ(set.model<3>().gravity, Vec3(0.0, 0.0, -9.81));
}

// A slave node that starts inside its contact pair's master body is an input error naming the
// file, both bodies, the deepest node, where it is and how deep (the 2D message); touching is not.
TEST(Case3, SlaveNodeInsideTheMasterBodyIsNamed) {
  // Two 2 x 1 x 1 cm boxes. The slave's left face x = 0.016 lies 4 mm inside the master
  // (x in [0, 0.02]); of its nodes only the middle one, (0.016, 0.005, 0.005), is away from the
  // master's faces y = 0, 0.01 and z = 0, 0.01: node (i, j, k) = (0, 1, 1) of the 2 x 2 x 2 box,
  // index (k (ny + 1) + j)(nx + 1) + i = 12, 0.004 m from the master's face x = 0.02.
  const std::string two_boxes = R"(name = "pair3"
scheme = "semi_explicit"
[meshes.master]
generator = "box"
size = [0.02, 0.01, 0.01]
nx = 2
ny = 1
nz = 1
[meshes.slave]
generator = "box"
size = [0.02, 0.01, 0.01]
nx = 2
ny = 2
nz = 2
origin = [0.016, 0.0, 0.0]
[[bodies]]
name = "target"
mesh = "master"
[bodies.material]
young = 1e6
poisson = 0.3
density = 1000.0
[[bodies]]
name = "striker"
mesh = "slave"
velocity = [-1.0, 0.0, 0.0]
[bodies.material]
young = 1e6
poisson = 0.3
density = 1000.0
[[contact_pairs]]
slave = "striker"
master = "target"
[time]
end = 1e-4
)";
  const std::string e = error_of(two_boxes);
  EXPECT_EQ(e, temp_file("read").string() +
                   ": body \"striker\" node 12 at (0.016, 0.005, 0.005) starts inside body \"target\" of a contact "
                   "pair, 0.004 m deep (the deepest node); move one of the bodies");
  // Touching (the slave's left face on the master's right face) is not an error.
  EXPECT_EQ(error_of(two_boxes, {"meshes.slave.origin=[0.02, 0.0, 0.0]"}), "");
}

// Every 3D obstacle type reads into the checked shape.
TEST(Case3, ObstacleTypes) {
  const CaseSpec s = read(kBlock, {"obstacles=[{type = \"sphere\", center = [0.0, -1.0, 0.0], radius = 0.5}]"});
  EXPECT_EQ(s.obstacles[0].shape3.kind, ObstacleKind3::sphere);
  EXPECT_EQ(s.obstacles[0].shape3.radius, 0.5);
  const CaseSpec b = read(kBlock, {"obstacles=[{type = \"box\", center = [0.0, -1.0, 0.0], "
                                   "half_extents = [1.0, 1.0, 1.0], axes = [[1.0, 1.0, 0.0], [0.0, 1.0, 0.0]]}]"});
  EXPECT_EQ(b.obstacles[0].shape3.kind, ObstacleKind3::box);
  EXPECT_NEAR(b.obstacles[0].shape3.axes(0, 0), std::sqrt(0.5), 1e-15);
  const CaseSpec c = read(kBlock, {"obstacles=[{type = \"cylinder\", center = [0.0, -1.0, 0.0], "
                                   "axis = [0.0, 0.0, 2.0], radius = 1.0, half_length = 0.5, inside = false}]"});
  EXPECT_EQ(c.obstacles[0].shape3.kind, ObstacleKind3::cylinder);
  EXPECT_EQ(c.obstacles[0].shape3.axis, Vec3::UnitZ());
  EXPECT_EQ(c.obstacles[0].shape3.half_length, 0.5);
  const std::string parallel = error_of(kBlock, {"obstacles=[{type = \"box\", center = [0.0, -1.0, 0.0], "
                                                 "half_extents = [1.0, 1.0, 1.0], axes = [[1.0, 0.0, 0.0], [2.0, 0.0, 0.0]]}]"});
  EXPECT_NE(parallel.find("obstacles[0].type"), std::string::npos) << parallel;
  EXPECT_NE(parallel.find("parallel"), std::string::npos) << parallel;
}

// [scene_rotation]: positions, velocities, gravity and obstacles turned by R; node-set boxes
// select before it.
TEST(Case3, SceneRotationTurnsEverything) {
  const std::vector<std::string> turn = {"scene_rotation={axis = [1.0, 2.0, -1.5], angle = 50.0}",
                                         "gravity=[0.0, -9.81, 0.0]",
                                         "bodies[0].node_sets=[{name = \"low\", box = [0.0, 0.0, 0.0, 1.0, 0.0011, 1.0]}]",
                                         "bodies[0].angular_velocity=[0.0, 0.0, 30.0]"};
  std::vector<std::string> plain_set(turn.begin() + 1, turn.end());
  const PreparedCase plain = prepare_case(read(kBlock, plain_set));
  const PreparedCase turned = prepare_case(read(kBlock, turn));
  const Mat3 r = Eigen::AngleAxisd(50.0 * std::numbers::pi / 180.0, Vec3(1.0, 2.0, -1.5).normalized()).toRotationMatrix();
  EXPECT_LT((turned.model<3>().ref - r * plain.model<3>().ref).cwiseAbs().maxCoeff(), 1e-17);
  for (int i = 0; i < plain.model<3>().num_nodes(); ++i)
    EXPECT_LT((Vec3(turned.model<3>().initial_velocity.segment<3>(3 * i)) -
               r * Vec3(plain.model<3>().initial_velocity.segment<3>(3 * i))).norm(),
              1e-14);
  EXPECT_LT((turned.model<3>().gravity - r * plain.model<3>().gravity).norm(), 1e-14);
  EXPECT_LT((obstacles_of(turned.settings, turned.model<3>())[0].normal - r * Vec3::UnitY()).norm(), 1e-15);
  EXPECT_EQ(turned.meshes<3>()[0].node_sets.at("low"), plain.meshes<3>()[0].node_sets.at("low"));
  EXPECT_EQ(turned.meshes<3>()[0].node_sets.at("low").size(), 15u);  // the bottom layer y = 0.001
  EXPECT_EQ(turned.probes[0].node, plain.probes[0].node);
  EXPECT_NE(error_of(kBlock, {turn[0], "boundary=[{nodes = \"left\", x = 0.0}]"}).find("cannot be turned"),
            std::string::npos);
}

// `ricochet run` on a 3D case: the 3D history columns, summary keys and a VTU of hexahedra.
TEST(Case3, RunWritesThreeDimensionalOutputs) {
  const fs::path file = temp_file("run");
  const fs::path out = fs::temp_directory_path() / ("ricochet_case3_out_" + std::to_string(getpid()));
  std::ofstream(file) << kBlock;
  const std::string cmd = std::string(RICOCHET_BINARY) + " run " + file.string() + " --out " + out.string() + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream h(out / "history.csv");
  std::string header;
  std::getline(h, header);
  for (const char* col : {",momentum_z,", ",angular_momentum_x,", ",angular_momentum_z,", ",corner_uz,", ",corner_vz",
                          ",ground_normal_force,"})
    EXPECT_NE(header.find(col), std::string::npos) << col;
  EXPECT_EQ(header.find(",angular_momentum,"), std::string::npos);
  const Json s = Json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(s["dimension"], 3);
  EXPECT_TRUE(s["plane"].is_null());
  EXPECT_EQ(s["elements"], 16);
  EXPECT_EQ(s["status"], "ok");
  EXPECT_TRUE(s["final"].contains("angular_momentum_z"));
  EXPECT_TRUE(s.contains("rebound_velocity_z"));
  EXPECT_TRUE(s["probes"][0].contains("z"));
  EXPECT_GT(s["contact_iterations"]["steps_with_contact"].get<long>(), 0);
  EXPECT_GT(s["friction_dissipation"].get<double>(), 0.0);
  EXPECT_LE(s["penetration_max"].get<double>(), 1e-12);
  EXPECT_GT(s["contact_force_mean"].get<double>(), 0.0);
  // contact_force_max is the largest normal_force of the history.
  {
    std::ifstream hist(out / "history.csv");
    std::string line;
    std::getline(hist, line);
    std::vector<std::string> names;
    std::stringstream hs(line);
    for (std::string cell; std::getline(hs, cell, ',');) names.push_back(cell);
    const auto col = std::find(names.begin(), names.end(), "normal_force") - names.begin();
    double largest = 0.0;
    while (std::getline(hist, line)) {
      std::stringstream ls(line);
      std::string cell;
      for (long k = 0; k <= col; ++k) std::getline(ls, cell, ',');
      largest = std::max(largest, std::stod(cell));
    }
    EXPECT_GT(largest, 0.0);
    EXPECT_EQ(s["contact_force_max"].get<double>(), largest);
  }
  // One field file: 45 points, 16 hexahedra (VTK type 12), the 3D arrays.
  std::vector<fs::path> vtu;
  for (const auto& e : fs::directory_iterator(out / "fields"))
    if (e.path().extension() == ".vtu") vtu.push_back(e.path());
  ASSERT_EQ(vtu.size(), 1u);
  std::stringstream text;
  text << std::ifstream(vtu[0]).rdbuf();
  EXPECT_NE(text.str().find("NumberOfPoints=\"45\" NumberOfCells=\"16\""), std::string::npos);
  for (const char* name : {"\"displacement\"", "\"contact_force\"", "\"cauchy_stress\"", "\"von_mises\""})
    EXPECT_NE(text.str().find(name), std::string::npos) << name;
  fs::remove(file);
  fs::remove_all(out);
}

}  // namespace
