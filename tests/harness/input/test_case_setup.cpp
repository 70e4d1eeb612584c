// Scene set-up from a case file (harness/input/case_setup.cpp): mesh transforms and initial
// velocity fields, checked on the prepared model.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "harness/input/case_setup.hpp"
#include "harness/input/input_error.hpp"

namespace fs = std::filesystem;
using namespace ricochet;

namespace {

const std::string kRect = R"(name = "rect"
mesh = "m"
[meshes.m]
generator = "rectangle"
width = 0.2
height = 0.1
nx = 4
ny = 2
[[bodies]]
name = "b"
velocity = [1.0, -2.0]
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

PreparedCase prepare(const std::string& text, const std::vector<std::string>& overrides = {}) {
  const fs::path file = fs::temp_directory_path() / ("ricochet_case_setup_" + std::to_string(getpid()) + ".toml");
  std::ofstream(file) << text;
  PreparedCase pc = prepare_case(read_case(file.string(), overrides));
  fs::remove(file);
  return pc;
}

}  // namespace

// x' = R(theta) (s x - c) + c + offset, counterclockwise in degrees; rotate = 0 is no transform.
TEST(CaseSetup, GeneratedMeshesRotateAboutAPoint) {
  const PreparedCase plain = prepare(kRect);
  const PreparedCase turned = prepare(kRect, {"meshes.m.rotate=90", "meshes.m.rotate_about=[0.1, 0.0]",
                                              "meshes.m.offset=[1.0, 0.0]", "meshes.m.scale=2.0"});
  const PreparedCase zero = prepare(kRect, {"meshes.m.rotate=0", "meshes.m.rotate_about=[5.0, 5.0]"});
  ASSERT_EQ(plain.model<2>().num_nodes(), turned.model<2>().num_nodes());
  const Vec2 c(0.1, 0.0), o(1.0, 0.0);
  for (int i = 0; i < plain.model<2>().num_nodes(); ++i) {
    const Vec2 x = 2.0 * plain.model<2>().ref.col(i);
    const Vec2 expected = Vec2(-(x - c).y(), (x - c).x()) + c + o;
    EXPECT_NEAR((turned.model<2>().ref.col(i) - expected).norm(), 0.0, 1e-15) << "node " << i;
  }
  EXPECT_EQ(0, std::memcmp(plain.model<2>().ref.data(), zero.model<2>().ref.data(), sizeof(double) * plain.model<2>().ref.size()));
  // A rotation keeps every cell's area, so the mass (scaled by 2^2) is the same.
  EXPECT_NEAR(turned.model<2>().mass.sum(), 4.0 * plain.model<2>().mass.sum(), 1e-12 * plain.model<2>().mass.sum());
  // A tilted rectangle's critical step is that of the plain one scaled by 2.
  EXPECT_NEAR(turned.model<2>().critical_dt, 2.0 * plain.model<2>().critical_dt, 1e-12 * plain.model<2>().critical_dt);
}

// angular_velocity spins a body about its centre of mass (or rotation_center): linear momentum
// stays m v, the angular momentum about the centre of mass is omega sum m |r|^2.
TEST(CaseSetup, BodiesStartSpinning) {
  const double omega = 30.0;
  const PreparedCase still = prepare(kRect);
  const PreparedCase spin = prepare(kRect, {"bodies[0].angular_velocity=30.0"});
  const Model<2>& m = spin.model<2>();
  Vec2 centre = Vec2::Zero(), p = Vec2::Zero();
  double mass = 0.0;
  for (int i = 0; i < m.num_nodes(); ++i) {
    centre += m.mass(2 * i) * m.ref.col(i);
    mass += m.mass(2 * i);
    p += m.mass(2 * i) * m.initial_velocity.segment<2>(2 * i);
  }
  centre /= mass;
  EXPECT_NEAR((p - mass * Vec2(1.0, -2.0)).norm(), 0.0, 1e-12 * mass);
  double l = 0.0, inertia = 0.0;
  for (int i = 0; i < m.num_nodes(); ++i) {
    const Vec2 r = m.ref.col(i) - centre, v = m.initial_velocity.segment<2>(2 * i);
    l += m.mass(2 * i) * (r.x() * v.y() - r.y() * v.x());
    inertia += m.mass(2 * i) * r.squaredNorm();
  }
  EXPECT_NEAR(l, omega * inertia, 1e-12 * omega * inertia);
  EXPECT_GT(inertia, 0.0);
  // About a given point: v = v0 + omega x (x - c).
  const PreparedCase about = prepare(kRect, {"bodies[0].angular_velocity=30.0", "bodies[0].rotation_center=[0.0, 0.0]"});
  for (int i = 0; i < m.num_nodes(); ++i) {
    const Vec2 x = about.model<2>().ref.col(i);
    const Vec2 expected = Vec2(1.0, -2.0) + omega * Vec2(-x.y(), x.x());
    EXPECT_NEAR((about.model<2>().initial_velocity.segment<2>(2 * i) - expected).norm(), 0.0, 1e-13) << "node " << i;
  }
  // Without the key nothing changes.
  for (int i = 0; i < m.num_nodes(); ++i)
    EXPECT_EQ(still.model<2>().initial_velocity.segment<2>(2 * i), Vec2(1.0, -2.0));
  // A free spinning body keeps its angular momentum (the run's own history column).
  const RunResult r = run_case(spin);
  ASSERT_EQ(r.status, RunStatus::ok) << r.reason;
  const std::size_t col = r.history.column("angular_momentum");
  EXPECT_NEAR(r.history.at(0, col), omega * inertia, 1e-9 * omega * inertia);
  EXPECT_NEAR(r.history.at(r.history.rows() - 1, col), omega * inertia, 1e-6 * omega * inertia);
}

// [[initial_velocity]] gives a node set its own velocity (here the generator's "top" edge),
// after the body's velocity and spin; a later entry wins; an unknown set is an input error.
TEST(CaseSetup, NodeSetsGetTheirOwnInitialVelocity) {
  const std::string text = kRect + R"(
[[initial_velocity]]
nodes = "top"
velocity = [0.5, 0.0]
[[initial_velocity]]
body = "b"
nodes = "left"
velocity = [0.0, 3.0]
)";
  const PreparedCase pc = prepare(text);
  const Model<2>& m = pc.model<2>();
  const Mesh& mesh = pc.meshes<2>()[0];
  std::vector<int> kind(m.num_nodes(), 0);
  for (int i : mesh.node_sets.at("top")) kind[i] = 1;
  for (int i : mesh.node_sets.at("left")) kind[i] = 2;
  int top = 0, left = 0;
  for (int i = 0; i < m.num_nodes(); ++i) {
    const Vec2 v = m.initial_velocity.segment<2>(2 * i);
    const Vec2 expected = kind[i] == 2 ? Vec2(0.0, 3.0) : kind[i] == 1 ? Vec2(0.5, 0.0) : Vec2(1.0, -2.0);
    EXPECT_EQ(v, expected) << "node " << i;
    top += kind[i] == 1;
    left += kind[i] == 2;
  }
  EXPECT_GT(top, 0);
  EXPECT_GT(left, 0);
  EXPECT_THROW(prepare(kRect + "[[initial_velocity]]\nnodes = \"nowhere\"\nvelocity = [1.0, 0.0]\n"), InputError);
  EXPECT_THROW(prepare(kRect + "[[initial_velocity]]\nnodes = \"top\"\n"), InputError);
}

// output.field_interval: a snapshot at t = 0, interval, 2 interval ... up to the end, merged with
// the listed times; too many snapshots is an input error.
TEST(CaseSetup, FieldIntervalAddsEvenlySpacedSnapshots) {
  const PreparedCase pc = prepare(kRect, {"output.field_interval=2e-5", "output.fields=[3e-5, 4e-5]"});
  const RunResult r = run_case(pc);
  ASSERT_EQ(r.status, RunStatus::ok) << r.reason;
  std::vector<double> times;
  for (const FieldSnapshot& f : r.fields) times.push_back(f.time);
  const std::vector<double> expected = {0.0, 2e-5, 3e-5, 4e-5, 6e-5, 8e-5, 1e-4};
  ASSERT_EQ(times.size(), expected.size());
  for (std::size_t k = 0; k < times.size(); ++k) EXPECT_NEAR(times[k], expected[k], 1e-15) << k;
  EXPECT_THROW(prepare(kRect, {"output.field_interval=1e-9"}), InputError);
}

// A diverged run ends with a snapshot of the state it stopped in (finite values only), so that
// there is something to inspect; without field times it is the only one.
TEST(CaseSetup, DivergedRunKeepsItsLastState) {
  // The top edge starts moving against the rest (a deforming body), far above the stable
  // step (about 13 x): the explicit run blows up within a few steps.
  const PreparedCase pc = prepare(kRect + "[[initial_velocity]]\nnodes = \"top\"\nvelocity = [3.0, 0.0]\n",
                                  {"time.dt=1e-2", "time.end=1.0"});
  const RunResult r = run_case(pc);
  ASSERT_EQ(r.status, RunStatus::diverged);
  ASSERT_EQ(r.fields.size(), 1u) << r.reason;
  const FieldSnapshot& f = r.fields.back();
  EXPECT_EQ(f.step, r.diverged_step);
  EXPECT_EQ(f.time, r.diverged_time);
  EXPECT_TRUE(f.u.allFinite());
  EXPECT_TRUE(f.v.allFinite());
  ASSERT_EQ(f.von_mises.size(), static_cast<std::size_t>(pc.model<2>().num_cells()));
  EXPECT_GT(*std::max_element(f.von_mises.begin(), f.von_mises.end()), 0.0);
}
