// The `ricochet run` command end to end: documented outputs on a good case; for each class of
// bad input a single-line error naming the file and the key or line, exit status 2, and no
// output folder.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace fs = std::filesystem;

namespace {

struct Outcome {
  int status = -1;
  std::string output;  // stdout and stderr
};

Outcome run(const std::string& args) {
  const std::string cmd = std::string(RICOCHET_BINARY) + " " + args + " 2>&1";
  Outcome o;
  FILE* p = popen(cmd.c_str(), "r");
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), p)) o.output += buf.data();
  const int raw = pclose(p);
  o.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  return o;
}

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("ricochet_cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  std::string out() const { return (dir_ / "out").string(); }

  // Runs a case expected to be rejected and checks the contract of a rejection.
  void expect_rejected(const std::string& case_text, const std::string& extra_args,
                       const std::vector<std::string>& must_contain) {
    const std::string file = write("case.toml", case_text);
    const Outcome o = run("run " + file + " --out " + out() + " " + extra_args);
    EXPECT_EQ(o.status, 2) << o.output;
    EXPECT_EQ(std::count(o.output.begin(), o.output.end(), '\n'), 1) << o.output;
    EXPECT_NE(o.output.find(file), std::string::npos) << "message must name the file: " << o.output;
    for (const auto& s : must_contain) EXPECT_NE(o.output.find(s), std::string::npos) << s << " in: " << o.output;
    EXPECT_FALSE(fs::exists(out())) << "nothing may be written on bad input";
  }

  fs::path dir_;
};

const std::string kGood = R"(name = "tiny"
mesh = "m"
[meshes.m]
generator = "rectangle"
width = 0.1
height = 0.05
nx = 4
ny = 2
[[bodies]]
name = "b"
velocity = [1.0, 0.0]
[bodies.material]
young = 1e6
poisson = 0.3
density = 1000.0
[time]
end = 1e-3
dt = 1e-5
[output]
interval = 1e-4
fields = [5e-4]
[[output.probes]]
name = "P"
point = [0.0, 0.0]
)";

// kGood with its generated mesh replaced by a mesh file.
std::string with_mesh_file(const std::string& file) {
  std::string s = kGood;
  const auto a = s.find("generator"), b = s.find("[[bodies]]");
  return s.replace(a, b - a, "file = \"" + file + "\"\n");
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  if (at == std::string::npos) throw std::logic_error("test setup: '" + from + "' not in case");
  return s.replace(at, from.size(), to);
}

}  // namespace

TEST_F(CliTest, GoodCaseWritesDocumentedOutputs) {
  const std::string file = write("case.toml", kGood);
  const Outcome o = run("run " + file + " --out " + out());
  ASSERT_EQ(o.status, 0) << o.output;
  EXPECT_NE(o.output.find("element-steps/s"), std::string::npos);
  ASSERT_TRUE(fs::exists(fs::path(out()) / "summary.json"));
  ASSERT_TRUE(fs::exists(fs::path(out()) / "fields" / "fields.pvd"));
  std::ifstream h(fs::path(out()) / "history.csv");
  std::string header;
  std::getline(h, header);
  for (const char* col : {"time", "kinetic_energy", "strain_energy", "total_energy", "friction_dissipation",
                          "energy_error", "penetration_max", "contact_nodes", "normal_force",
                          "tangential_force", "momentum_x", "momentum_y", "von_mises_max", "P_ux",
                          "P_uy", "P_vx", "P_vy"})
    EXPECT_NE(header.find(col), std::string::npos) << col;
  int rows = 0;
  for (std::string line; std::getline(h, line);) ++rows;
  EXPECT_EQ(rows, 11);  // t = 0, 1e-4, ..., 1e-3
  std::stringstream summary;
  summary << std::ifstream(fs::path(out()) / "summary.json").rdbuf();
  for (const char* key : {"\"status\": \"ok\"", "\"steps\": 100", "\"energy_error_max\"",
                          "\"penetration_max\"", "\"von_mises_max\"", "\"element_steps_per_second\"",
                          "\"ricochet_version\""})
    EXPECT_NE(summary.str().find(key), std::string::npos) << key;
}

TEST_F(CliTest, SetOverridesAKey) {
  const std::string file = write("case.toml", kGood);
  const Outcome o = run("run " + file + " --out " + out() + " --set time.dt=2e-5 --set bodies[0].velocity=[0,1]");
  ASSERT_EQ(o.status, 0) << o.output;
  std::stringstream summary;
  summary << std::ifstream(fs::path(out()) / "summary.json").rdbuf();
  EXPECT_NE(summary.str().find("\"steps\": 50"), std::string::npos) << summary.str();
}

TEST_F(CliTest, RejectsSyntaxError) { expect_rejected(kGood + "oops = \n", "", {":25:", "TOML"}); }

TEST_F(CliTest, RejectsUnknownKey) {
  expect_rejected(replace(kGood, "dt = 1e-5", "dt = 1e-5\ndtt = 2"), "", {"time.dtt", "unknown key", "allowed"});
}

TEST_F(CliTest, RejectsWrongType) {
  expect_rejected(replace(kGood, "young = 1e6", "young = \"stiff\""), "", {"bodies[0].material.young", "expected a number"});
}

TEST_F(CliTest, RejectsValueOutOfRange) {
  expect_rejected(replace(kGood, "poisson = 0.3", "poisson = 0.5"), "", {"poisson", "(-1, 0.5)"});
  expect_rejected(replace(kGood, "dt = 1e-5", "dt = -1e-5"), "", {"time.dt", "> 0"});
}

TEST_F(CliTest, RejectsMissingKey) { expect_rejected(replace(kGood, "density = 1000.0", ""), "", {"density", "missing"}); }

TEST_F(CliTest, RejectsMissingMeshFile) {
  expect_rejected(with_mesh_file("nowhere.msh"), "",
                  {"meshes.m", "nowhere.msh"});
}

TEST_F(CliTest, RejectsMalformedMeshFile) {
  write("bad.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n1 0 0 0\n2 1 zero 0\n");
  expect_rejected(with_mesh_file("bad.msh"), "", {"bad.msh:7"});
}

TEST_F(CliTest, RejectsInvertedElement) {
  // Two quads, the second one clockwise: mixed orientation is an inverted element.
  write("inv.msh",
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n6\n1 0 0 0\n2 1 0 0\n3 2 0 0\n4 0 1 0\n5 1 1 0\n6 2 1 0\n"
        "$EndNodes\n$Elements\n2\n1 3 2 1 1 1 2 5 4\n2 3 2 1 1 2 6 3 5\n$EndElements\n");
  expect_rejected(with_mesh_file("inv.msh"), "", {"inv.msh", "element 2"});
}

TEST_F(CliTest, RejectsDegenerateElement) {
  write("deg.msh",
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 2 0 0\n4 3 0 0\n"
        "$EndNodes\n$Elements\n1\n1 3 2 1 1 1 2 3 4\n$EndElements\n");
  expect_rejected(with_mesh_file("deg.msh"), "", {"deg.msh", "degenerate"});
}

TEST_F(CliTest, RejectsBadSet) {
  expect_rejected(kGood, "--set time.dt", {"--set time.dt", "KEY=VALUE"});
  expect_rejected(kGood, "--set time.dt=fast", {"--set time.dt", "expected a number"});
  expect_rejected(kGood, "--set time.nothing=1", {"time.nothing", "unknown key"});
  expect_rejected(kGood, "--set bodies[3].velocity=[0,0]", {"--set", "has 1 elements"});
}

TEST_F(CliTest, RejectsUnknownNodeSetAndMesh) {
  expect_rejected(kGood + "[[boundary]]\nnodes = \"nowhere\"\nx = 0.0\n", "", {"boundary[0].nodes", "nowhere", "available"});
  expect_rejected(replace(kGood, "mesh = \"m\"", "mesh = \"q\""), "", {"mesh", "no mesh named"});
}

TEST_F(CliTest, RejectsBadCommandLine) {
  const Outcome a = run("run");
  EXPECT_EQ(a.status, 2);
  const Outcome b = run("run " + write("case.toml", kGood) + " --bogus");
  EXPECT_EQ(b.status, 2);
  EXPECT_NE(b.output.find("--bogus"), std::string::npos);
  const Outcome c = run("run " + (dir_ / "absent.toml").string());
  EXPECT_EQ(c.status, 2);
  EXPECT_NE(c.output.find("absent.toml: cannot open"), std::string::npos);
}

TEST_F(CliTest, DivergedRunIsAResult) {
  // The left edge is held while the body moves: it deforms, and dt is far above the limit.
  const std::string file = write("case.toml", kGood + "[[boundary]]\nnodes = \"left\"\nx = 0.0\n");
  const Outcome o = run("run " + file + " --out " + out() + " --set time.dt=4e-3 --set time.end=0.4");
  EXPECT_EQ(o.status, 3) << o.output;
  std::stringstream summary;
  summary << std::ifstream(fs::path(out()) / "summary.json").rdbuf();
  EXPECT_NE(summary.str().find("\"status\": \"diverged\""), std::string::npos) << summary.str();
}

// Every command answers --help (and -h) on stdout with exit 0 and names each of its options;
// the top-level usage names every command. The option lists are what each command accepts
// (an option missing from its help would be a documentation defect).
TEST_F(CliTest, EveryCommandAnswersHelp) {
  const std::vector<std::pair<std::string, std::vector<std::string>>> commands = {
      {"run", {"--set", "--out", "--quiet"}},
      {"sweep", {"--out", "--jobs", "--repeat", "--check", "--force", "--quiet"}},
      {"check", {"--junit"}},
      {"stability", {"--set", "--out", "--tolerance", "--max-runs", "--end", "--energy-bound", "--quiet"}},
      {"report", {"--out", "--accuracy", "--stability", "--verification", "--no-discover"}},
      {"plot", {"--out"}},
  };
  const Outcome top = run("--help");
  EXPECT_EQ(top.status, 0) << top.output;
  for (const auto& [command, options] : commands) {
    EXPECT_NE(top.output.find("ricochet " + command + " "), std::string::npos) << command << " in: " << top.output;
    for (const char* flag : {"--help", "-h"}) {
      const Outcome o = run(command + " " + flag);
      EXPECT_EQ(o.status, 0) << command << " " << flag << ": " << o.output;
      EXPECT_NE(o.output.find("usage"), std::string::npos) << command << ": " << o.output;
      for (const auto& option : options)
        EXPECT_NE(o.output.find(option), std::string::npos) << command << " --help lacks " << option << ": " << o.output;
    }
  }
  // Top-level usage without a command goes to stderr with exit 2 (no command is bad input).
  EXPECT_EQ(run("").status, 2);
}
