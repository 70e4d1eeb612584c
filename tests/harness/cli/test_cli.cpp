// The `ricochet` program end to end: `run`'s documented outputs on a good case; for each class of
// bad input a single-line error naming the file and the key or line, exit status 2, and no
// output folder; the command line of every command (help, unknown options, every option shown);
// `--out` values that name no folder; outputs that are written completely or not at all.
#include <gtest/gtest.h>

#include <omp.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "tests/support/run_program.hpp"
#include "tests/support/temp_dir.hpp"

namespace fs = std::filesystem;

namespace {

using Outcome = ricochet::test_support::ProgramOutcome;

// `ricochet ARGS` through /bin/sh, after the shell commands `prefix` (e.g. "cd DIR &&").
Outcome run(const std::string& args, const std::string& prefix = "") {
  return ricochet::test_support::run_ricochet(args, prefix);
}

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = ricochet::test_support::fresh_test_dir("ricochet_cli_");
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& text) {
    return ricochet::test_support::write_text(dir_ / name, text);
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
                          "\"ricochet_version\"", "\"threads\""})
    EXPECT_NE(summary.str().find(key), std::string::npos) << key;
}

// A variable step (time.dt = "auto", time.dt_update_interval): the history's `dt` column, the
// summary's range, the run ending on time.end (docs/outputs.md).
TEST_F(CliTest, VariableStepWritesItsColumnAndRange) {
  const std::string file = write("case.toml", replace(kGood, "dt = 1e-5", "dt = \"auto\"\ndt_update_interval = 10"));
  const Outcome o = run("run " + file + " --out " + out());
  ASSERT_EQ(o.status, 0) << o.output;
  EXPECT_NE(o.output.find("(variable: "), std::string::npos) << o.output;
  std::ifstream h(fs::path(out()) / "history.csv");
  std::string header;
  std::getline(h, header);
  EXPECT_EQ(header.rfind("time,dt,kinetic_energy,", 0), 0u) << header;
  std::string last;
  for (std::string line; std::getline(h, line);) last = line;
  EXPECT_EQ(last.rfind("0.001,", 0), 0u) << "the last row is at time.end: " << last;
  std::stringstream summary;
  summary << std::ifstream(fs::path(out()) / "summary.json").rdbuf();
  for (const char* key : {"\"dt_update_interval\": 10", "\"dt_min\"", "\"dt_max\"", "\"dt_updates\"",
                          "\"dt_floor\"", "\"time_reached\": 0.001,", "\"dt_mode\": \"auto\""})
    EXPECT_NE(summary.str().find(key), std::string::npos) << key << " in " << summary.str();
}

// The variable step's keys: an integer >= 0, only with time.dt = "auto", not with the implicit
// scheme; the floor's ratio in (0, 1].
TEST_F(CliTest, RejectsBadVariableStep) {
  const std::string autodt = replace(kGood, "dt = 1e-5", "dt = \"auto\"");
  expect_rejected(replace(autodt, "[time]", "[time]\ndt_update_interval = -1"), "",
                  {"time.dt_update_interval", "expected an integer in [0, 1000000000]; got -1"});
  expect_rejected(replace(autodt, "[time]", "[time]\ndt_update_interval = 2.5"), "",
                  {"time.dt_update_interval", "expected an integer"});
  expect_rejected(autodt, "--set time.dt_update_interval=-3", {"--set time.dt_update_interval", "got -3"});
  expect_rejected(replace(kGood, "[time]", "[time]\ndt_update_interval = 5"), "",
                  {"time.dt_update_interval", "needs time.dt = \"auto\"", "1e-05 s"});
  expect_rejected("scheme = \"implicit\"\n" + replace(autodt, "[time]", "[time]\ndt_update_interval = 5"), "",
                  {"time.dt_update_interval", "implicit scheme takes a fixed step"});
  expect_rejected(replace(autodt, "[time]", "[time]\ndt_min_ratio = 0.0"), "", {"time.dt_min_ratio", "in (0, 1]"});
  expect_rejected(autodt, "--set time.dt_min_ratio=1.5", {"time.dt_min_ratio", "in (0, 1]"});
}

// output.field_format and output.field_compression: bad values are one-line input errors naming
// the file and key; the default is binary with zlib, and every encoding holds the same arrays.
TEST_F(CliTest, FieldFormatKeys) {
  const std::string in_output = "fields = [5e-4]";
  expect_rejected(replace(kGood, in_output, in_output + "\nfield_format = \"hdf5\""), "",
                  {"output.field_format", "got \"hdf5\"", "\"ascii\", \"binary\", \"base64\""});
  expect_rejected(replace(kGood, in_output, in_output + "\nfield_compression = \"gzip\""), "",
                  {"output.field_compression", "got \"gzip\"", "\"none\", \"zlib\""});
  expect_rejected(replace(kGood, in_output, in_output + "\nfield_format = \"ascii\"\nfield_compression = \"zlib\""),
                  "", {"output.field_compression", "needs field_format \"binary\" or \"base64\""});
  expect_rejected(kGood, "--set output.field_format=ascii --set output.field_compression=zlib",
                  {"--set output.field_compression", "needs field_format"});
  expect_rejected(kGood, "--set output.field_format=1", {"output.field_format"});
  expect_rejected(replace(kGood, in_output, in_output + "\nfield_formats = \"ascii\""), "",
                  {"field_formats", "did you mean", "field_format"});

  const std::string file = write("case.toml", kGood);
  struct Expect {
    std::string args, format, compressor;
  };
  for (const Expect& e : std::vector<Expect>{
           {"", "appended", "vtkZLibDataCompressor"},
           {"--set output.field_compression=none", "appended", ""},
           {"--set output.field_format=base64", "binary", "vtkZLibDataCompressor"},
           {"--set output.field_format=base64 --set output.field_compression=none", "binary", ""},
           {"--set output.field_format=ascii", "ascii", ""}}) {
    fs::remove_all(out());
    const Outcome o = run("run " + file + " --out " + out() + " --quiet " + e.args);
    ASSERT_EQ(o.status, 0) << e.args << ": " << o.output;
    std::ifstream vtu(fs::path(out()) / "fields" / "tiny_00000050.vtu", std::ios::binary);
    std::stringstream text;
    text << vtu.rdbuf();
    const std::string doc = text.str();
    ASSERT_FALSE(doc.empty()) << e.args;
    for (const char* name : {"displacement", "velocity", "contact_force", "contact_gap", "contact_status", "von_mises",
                             "cauchy_stress", "green_lagrange_strain", "body"})
      EXPECT_NE(doc.find(std::string("Name=\"") + name + "\""), std::string::npos) << e.args << ": " << name;
    EXPECT_NE(doc.find("Name=\"connectivity\" format=\"" + e.format + "\""), std::string::npos) << e.args;
    EXPECT_EQ(doc.find("compressor=\"vtkZLibDataCompressor\"") != std::string::npos, !e.compressor.empty()) << e.args;
  }
}

TEST_F(CliTest, SetOverridesAKey) {
  const std::string file = write("case.toml", kGood);
  const Outcome o = run("run " + file + " --out " + out() + " --set time.dt=2e-5 --set bodies[0].velocity=[0,1]");
  ASSERT_EQ(o.status, 0) << o.output;
  std::stringstream summary;
  summary << std::ifstream(fs::path(out()) / "summary.json").rdbuf();
  EXPECT_NE(summary.str().find("\"steps\": 50"), std::string::npos) << summary.str();
}

// --set meshes.m.distort works like any key: the same seed writes the same fields byte for byte,
// no distortion other fields.
TEST_F(CliTest, SetDistortsAGeneratedMesh) {
  const std::string file = write("case.toml", kGood);
  auto fields = [&](const std::string& name, const std::string& args) {
    const fs::path dir = dir_ / name;
    const Outcome o = run("run " + file + " --quiet --out " + dir.string() + " " + args);
    EXPECT_EQ(o.status, 0) << o.output;
    std::stringstream s;
    for (const auto& e : fs::directory_iterator(dir / "fields"))
      if (e.path().extension() == ".vtu") s << std::ifstream(e.path(), std::ios::binary).rdbuf();
    return s.str();
  };
  const std::string plain = fields("plain", "");
  const std::string a = fields("a", "--set meshes.m.distort=0.2 --set meshes.m.seed=3");
  const std::string b = fields("b", "--set meshes.m.distort=0.2 --set meshes.m.seed=3");
  const std::string c = fields("c", "--set meshes.m.distort=0.2 --set meshes.m.seed=4");
  ASSERT_FALSE(plain.empty());
  EXPECT_EQ(a, b);
  EXPECT_NE(a, plain);
  EXPECT_NE(a, c);
  EXPECT_EQ(fields("zero", "--set meshes.m.distort=0.0 --set meshes.m.seed=3"), plain);
}

// distort and seed: one line naming the key and the range, exit 2, in the file or through --set;
// a mesh file cannot be distorted.
TEST_F(CliTest, RejectsBadDistortion) {
  const std::string mesh = "generator = \"rectangle\"\n";
  expect_rejected(replace(kGood, mesh, mesh + "distort = 0.5\n"), "", {"meshes.m.distort", "[0, 0.5)", "got 0.5"});
  expect_rejected(replace(kGood, mesh, mesh + "distort = -0.1\n"), "", {"meshes.m.distort", "[0, 0.5)", "got -0.1"});
  expect_rejected(replace(kGood, mesh, mesh + "seed = -1\n"), "", {"meshes.m.seed", "an integer in [0, ", "got -1"});
  expect_rejected(replace(kGood, mesh, mesh + "seed = 2.5\n"), "", {"meshes.m.seed", "an integer"});
  expect_rejected(kGood, "--set meshes.m.distort=0.5", {"meshes.m.distort", "[0, 0.5)"});
  expect_rejected(kGood, "--set meshes.m.seed=-1", {"meshes.m.seed", "got -1"});
  // In range but folding a cell of this mesh (seed 25 does at 0.45): the key and what to do.
  expect_rejected(kGood, "--set meshes.m.distort=0.45 --set meshes.m.seed=25",
                  {"meshes.m.distort: after distortion Q4 cell 1 (nodes 1 2 7 6) is not convex",
                   "lower distort (got 0.45) or use another seed"});
  write("two.msh",
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n6\n1 0 0 0\n2 1 0 0\n3 2 0 0\n4 0 1 0\n5 1 1 0\n6 2 1 0\n"
        "$EndNodes\n$Elements\n2\n1 3 2 1 1 1 2 5 4\n2 3 2 1 1 2 3 6 5\n$EndElements\n");
  const std::string file = with_mesh_file("two.msh");
  expect_rejected(replace(file, "file = ", "distort = 0.1\nfile = "), "", {"meshes.m.distort", "generated meshes only", "not to a mesh file"});
  expect_rejected(replace(file, "file = ", "seed = 3\nfile = "), "", {"meshes.m.seed", "generated meshes only"});
  expect_rejected(file, "--set meshes.m.distort=0.2", {"meshes.m.distort", "generated meshes only"});
}

namespace {

// The `threads` of a run's summary.json; -1 if absent.
int summary_threads(const fs::path& dir) {
  std::stringstream s;
  s << std::ifstream(dir / "summary.json").rdbuf();
  const std::string text = s.str(), key = "\"threads\": ";
  const auto at = text.find(key);
  return at == std::string::npos ? -1 : std::stoi(text.substr(at + key.size()));
}

}  // namespace

// The threads a run uses: all cores by default, else the case key (file or --set), else --threads,
// which wins over both; summary.json records the count used.
TEST_F(CliTest, ThreadsComeFromTheCaseKeyAndTheOption) {
  const std::string file = write("case.toml", kGood);
  const std::string threaded = write("threaded.toml", "threads = 2\n" + kGood);
  struct Case {
    std::string args;
    int threads;
  };
  for (const Case& c : std::vector<Case>{{file, omp_get_num_procs()},
                                         {threaded, 2},
                                         {file + " --set threads=1", 1},
                                         {file + " --threads 3", 3},
                                         {threaded + " --threads=1", 1},
                                         {threaded + " --set threads=3 --threads 1", 1},
                                         {threaded + " --threads 0", omp_get_num_procs()}}) {
    fs::remove_all(out());
    const Outcome o = run("run " + c.args + " --out " + out() + " --quiet");
    ASSERT_EQ(o.status, 0) << c.args << ": " << o.output;
    EXPECT_EQ(summary_threads(out()), c.threads) << c.args;
  }
}

TEST_F(CliTest, RejectsBadThreads) {
  for (const std::string value : {"-1", "1.5", "\"two\"", "257", "true"})
    expect_rejected("threads = " + value + "\n" + kGood, "", {":1:", "threads", "expected an integer in [0, 256]"});
  expect_rejected(kGood, "--set threads=-2", {"--set threads", "expected an integer in [0, 256]", "got -2"});
  expect_rejected(kGood, "--set threads=2.0", {"--set threads", "expected an integer in [0, 256]"});
  // --threads: one line naming the command and the option, exit 2, nothing written.
  const std::string file = write("case.toml", kGood);
  for (const std::string command : {"run", "stability", "sweep"})
    for (const std::string value : {"-1", "two", "1.5", "257", ""}) {
      const Outcome o = run(command + " " + file + " --out " + out() + " --threads '" + value + "'");
      EXPECT_EQ(o.status, 2) << command << " " << value << ": " << o.output;
      EXPECT_EQ(std::count(o.output.begin(), o.output.end(), '\n'), 1) << command << " " << value << ": " << o.output;
      EXPECT_NE(o.output.find("ricochet " + command + ": --threads: expected an integer in [0, 256]; got '" + value + "'"),
                std::string::npos)
          << o.output;
      EXPECT_FALSE(fs::exists(out())) << command << " " << value;
    }
}

TEST_F(CliTest, RejectsSyntaxError) { expect_rejected(kGood + "oops = \n", "", {":25:", "TOML"}); }

TEST_F(CliTest, RejectsUnknownKey) {
  expect_rejected(replace(kGood, "dt = 1e-5", "dt = 1e-5\ndtt = 2"), "", {"time.dtt", "unknown key", "allowed"});
}

// A misspelt key or mesh name is answered with the likely one; a name close to nothing is not.
TEST_F(CliTest, UnknownNamesSuggestTheLikelyOne) {
  expect_rejected(replace(kGood, "dt = 1e-5", "dt = 1e-5\ndtt = 2"), "",
                  {"time.dtt: unknown key (did you mean \"dt\"?); allowed here:"});
  expect_rejected(replace(kGood, "young = 1e6", "yuong = 1e6"), "", {"bodies[0].material.yuong: unknown key (did you mean \"young\"? it is required here and missing)"});
  expect_rejected(kGood, "--set time.ennd=1e-3", {"time.ennd", "did you mean \"end\"?"});
  expect_rejected(replace(kGood, "dt = 1e-5", "dt = 1e-5\nzzzzzz = 2"), "", {"time.zzzzzz: unknown key; allowed here:"});
  expect_rejected(replace(kGood + "[meshes.fine]\ngenerator = \"rectangle\"\nwidth = 0.1\nheight = 0.05\nnx = 8\nny = 4\n",
                          "mesh = \"m\"", "mesh = \"fin\""),
                  "", {"no mesh named \"fin\" in [meshes] (did you mean \"fine\"?); defined: fine, m"});
  expect_rejected(replace(kGood, "mesh = \"m\"", "mesh = \"q\""), "", {"no mesh named \"q\" in [meshes] (did you mean \"m\"?); defined: m"});
}

// A node that starts inside an obstacle or inside the other body of a contact pair is bad
// input, named with its depth, not a divergence at t = 0; a body resting on a surface is not.
TEST_F(CliTest, RejectsInitialPenetration) {
  // The rectangle spans y in [0, 0.05]; a ground at y = 0.002 holds its bottom row 2 mm deep.
  const std::string contact = "scheme = \"semi_explicit\"\n" + kGood;
  const std::string ground = "[[obstacles]]\nname = \"floor\"\npoint = [0.0, 0.002]\nnormal = [0.0, 1.0]\n";
  expect_rejected(contact + ground, "",
                  {"bodies[0] (\"b\") node 0 at (0, 0) starts inside obstacles[0] (\"floor\"), 0.002 m deep"});
  // Resting on it (gap 0) runs.
  const std::string resting = "[[obstacles]]\nname = \"floor\"\npoint = [0.0, 0.0]\nnormal = [0.0, 1.0]\n";
  const Outcome o = run("run " + write("case.toml", contact + resting) + " --out " + out() + " --quiet");
  EXPECT_EQ(o.status, 0) << o.output;
  fs::remove_all(out());
  // Two bodies of a contact pair that overlap by 5 mm.
  const std::string pair = replace(contact, "[[bodies]]", "[meshes.m2]\ngenerator = \"rectangle\"\nwidth = 0.1\nheight = 0.05\n"
                                                        "nx = 4\nny = 2\norigin = [0.095, 0.0]\n[[bodies]]") +
                           "[[bodies]]\nname = \"c\"\nmesh = \"m2\"\n[bodies.material]\nyoung = 1e6\npoisson = 0.3\ndensity = 1000.0\n"
                           "[[contact_pairs]]\nslave = \"b\"\nmaster = \"c\"\n";
  expect_rejected(pair, "", {"body \"b\" node 9 at (0.1, 0.025) starts inside body \"c\" of a contact pair, 0.005 m deep"});
}

TEST_F(CliTest, InterfaceNamesNameHistoryColumns) {
  // Obstacles and contact pairs name their history columns (<name>_normal_force, ...): one
  // name each, of letters, digits and '_'.
  const std::string contact = "scheme = \"semi_explicit\"\n" + kGood;
  const std::string floor = "[[obstacles]]\nname = \"floor\"\npoint = [0.0, 0.0]\nnormal = [0.0, 1.0]\n";
  const std::string wall = "[[obstacles]]\nname = \"floor\"\npoint = [-0.01, 0.0]\nnormal = [1.0, 0.0]\n";
  expect_rejected(contact + floor + wall, "", {"obstacles[1].name", "\"floor\" already names another obstacle"});
  expect_rejected(contact + replace(floor, "\"floor\"", "\"the floor\""), "",
                  {"obstacles[0].name", "letters, digits and '_'"});
  // The history has the obstacle's columns beside the summed ones.
  const Outcome o = run("run " + write("case.toml", contact + floor) + " --out " + out() + " --quiet");
  ASSERT_EQ(o.status, 0) << o.output;
  std::ifstream in(out() + "/history.csv");
  std::string header;
  std::getline(in, header);
  for (const char* c : {",normal_force,", ",floor_normal_force,", ",floor_tangential_force,", ",floor_contact_nodes,",
                        ",floor_contact_work,", ",floor_friction_dissipation"})
    EXPECT_NE(header.find(c), std::string::npos) << c << " in " << header;
  fs::remove_all(out());
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

// [relaxation] and [[loads]]: each bad value is one line naming the file, the key and what is
// allowed, exit 2, nothing written.
TEST_F(CliTest, RejectsBadRelaxationAndLoads) {
  expect_rejected(kGood + "[relaxation]\ntolerance = 0.0\n", "", {":26:", "relaxation.tolerance", "in (0, 0.1]"});
  expect_rejected(kGood + "[relaxation]\ntolerance = 0.5\n", "", {"relaxation.tolerance", "in (0, 0.1]"});
  expect_rejected(kGood + "[relaxation]\nmax_steps = 0\n", "", {"relaxation.max_steps", "expected an integer in [1, 100000000]"});
  expect_rejected(kGood + "[relaxation]\nmax_steps = 2.5\n", "", {"relaxation.max_steps", "expected an integer"});
  expect_rejected(kGood + "[relaxation]\nenabled = \"yes\"\n", "", {"relaxation.enabled", "expected true or false"});
  expect_rejected(kGood + "[relaxation]\ntolerence = 1e-6\n", "",
                  {"relaxation.tolerence: unknown key (did you mean \"tolerance\"?); allowed here:", "max_steps"});
  expect_rejected(kGood, "--set relaxation.tolerance=-1", {"--set relaxation.tolerance", "in (0, 0.1]"});
  expect_rejected(kGood, "--set relaxation=true", {"relaxation", "expected a table"});
  const std::string load = "[[loads]]\nnodes = \"left\"\n";
  expect_rejected(kGood + load, "", {"loads[0].force", "missing required key"});
  expect_rejected(kGood + load + "force = [1.0]\n", "", {"loads[0].force", "expected an array of two numbers [x, y]"});
  expect_rejected(kGood + load + "force = [1.0, \"x\"]\n", "", {"loads[0].force", "expected an array of two numbers"});
  expect_rejected(kGood + load + "force = [1.0, 0.0]\ndistribution = \"area\"\n", "",
                  {"loads[0].distribution", "\"mass\"", "\"equal\""});
  expect_rejected(kGood + load + "force = [1.0, 0.0]\nramp = -1.0\n", "", {"loads[0].ramp", ">= 0"});
  expect_rejected(kGood + load + "force = [1.0, 0.0]\nstart = -0.1\n", "", {"loads[0].start", ">= 0"});
  expect_rejected(kGood + load + "force = [1.0, 0.0]\nstrat = 0.1\n", "", {"loads[0].strat: unknown key (did you mean \"start\"?)"});
  expect_rejected(kGood + "[[loads]]\nforce = [1.0, 0.0]\n", "", {"loads[0].nodes", "missing required key"});
  expect_rejected(kGood + "[[loads]]\nnodes = \"nowhere\"\nforce = [1.0, 0.0]\n", "",
                  {"loads[0].nodes", "no node set \"nowhere\"", "available"});
  expect_rejected(kGood + "[[loads]]\nbody = \"q\"\nnodes = \"left\"\nforce = [1.0, 0.0]\n", "",
                  {"loads[0].body", "no body named \"q\""});
  expect_rejected(kGood, "--set loads=1", {"loads", "expected an array of tables"});
}

// A relaxed run reports its relaxation in summary.json; a relaxation that does not converge is
// a result (exit 3, status diverged with the reason, outputs written), not a crash. kGood's
// body is free: without loads it is at rest and in equilibrium at once; under gravity it falls
// and cannot converge.
TEST_F(CliTest, RelaxationIsReported) {
  const std::string file = write("case.toml", kGood + "[relaxation]\n");
  const Outcome o = run("run " + file + " --out " + out() + " --quiet");
  ASSERT_EQ(o.status, 0) << o.output;
  std::stringstream summary;
  summary << std::ifstream(fs::path(out()) / "summary.json").rdbuf();
  for (const char* key : {"\"relaxation\": {", "\"converged\": true", "\"steps\": 0", "\"velocity_resets\"",
                          "\"residual\"", "\"kinetic_ratio\"", "\"settlement\"", "\"drift\": {", "\"displacement_max\""})
    EXPECT_NE(summary.str().find(key), std::string::npos) << key << " in " << summary.str();
  fs::remove_all(out());
  const std::string falling = write("falling.toml", "gravity = [0.0, -9.81]\n" + kGood + "[relaxation]\nmax_steps = 100\n");
  const Outcome f = run("run " + falling + " --out " + out());
  EXPECT_EQ(f.status, 3) << f.output;
  EXPECT_NE(f.output.find("relaxation: did not converge in 100 steps"), std::string::npos) << f.output;
  std::stringstream diverged;
  diverged << std::ifstream(fs::path(out()) / "summary.json").rdbuf();
  for (const char* key : {"\"status\": \"diverged\"", "\"converged\": false", "\"reason\": \"relaxation: did not converge"})
    EXPECT_NE(diverged.str().find(key), std::string::npos) << key << " in " << diverged.str();
  // Without the table, or with enabled = false, summary.json says null.
  for (const std::string extra : {"", "[relaxation]\nenabled = false\n"}) {
    fs::remove_all(out());
    const Outcome n = run("run " + write("plain.toml", kGood + extra) + " --out " + out() + " --quiet");
    ASSERT_EQ(n.status, 0) << n.output;
    std::stringstream plain;
    plain << std::ifstream(fs::path(out()) / "summary.json").rdbuf();
    EXPECT_NE(plain.str().find("\"relaxation\": null"), std::string::npos) << plain.str();
  }
}

// Every command answers --help (and -h) on stdout with exit 0 and names each of its options;
// the top-level usage names every command. The option lists are what each command accepts
// (an option missing from its help would be a documentation defect).
TEST_F(CliTest, EveryCommandAnswersHelp) {
  const std::vector<std::pair<std::string, std::vector<std::string>>> commands = {
      {"run", {"--set", "--threads", "--out", "--quiet"}},
      {"sweep",
       {"--out", "--jobs", "--threads", "--repeat", "--check", "--force", "--quiet", "--shard", "--merge", "--slurm", "--shards",
        "--slurm-option", "--dry-run"}},
      {"check", {"--junit"}},
      {"stability", {"--set", "--threads", "--out", "--tolerance", "--max-runs", "--end", "--energy-bound", "--quiet"}},
      {"report", {"DIR", "--out"}},
      {"plot", {"--out"}},
      {"reproduce", {"--tier", "--out", "--studies", "--force", "--quiet", "--no-report"}},
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
  // No command is bad usage: one line on stderr, exit 2.
  EXPECT_EQ(run("").status, 2);
}

namespace {

const std::vector<std::string> kCommands = {"run", "sweep", "check", "stability", "report", "plot", "reproduce"};

// The positional arguments of each command, as files that do not exist (under `dir`).
std::string absent_files(const std::string& command, const fs::path& dir) {
  if (command == "check") return (dir / "absent.csv").string() + " " + (dir / "absent.toml").string();
  if (command == "report" || command == "plot") return (dir / "absent_dir").string();
  return (dir / "absent.toml").string();
}

// An option as a --help text shows it: its names ("-j", "--jobs") and its value ("N"; empty for
// a switch). Both ricochet's help and the report scripts' (argparse) put each option at the start
// of a line, "  -j, --jobs N   help text".
struct HelpOption {
  std::vector<std::string> names;
  std::string value;
};

std::vector<HelpOption> options_in(const std::string& help) {
  std::vector<HelpOption> out;
  std::istringstream lines(help);
  for (std::string line; std::getline(lines, line);) {
    const auto start = line.find_first_not_of(' ');
    if (start == std::string::npos || start == 0 || line[start] != '-') continue;
    std::string label = line.substr(start, line.find("  ", start) - start);
    HelpOption o;
    std::istringstream forms(label);
    for (std::string form; std::getline(forms, form, ',');) {
      form.erase(0, form.find_first_not_of(' '));
      const auto space = form.find(' ');
      o.names.push_back(form.substr(0, space));
      if (space != std::string::npos) o.value = form.substr(space + 1);
    }
    out.push_back(o);
  }
  return out;
}

// A value that the option accepts, by the name of its value.
std::string sample_value(const std::string& value, const fs::path& dir) {
  if (value == "N" || value == "K") return "2";
  if (value == "K/N") return "1/2";
  if (value == "REL") return "0.01";
  if (value == "TIME") return "0.001";
  if (value == "E") return "0.1";
  if (value == "TIER") return "fast";
  if (value == "KEY=VALUE") return "time.dt=1e-5";
  return (dir / "value").string();
}

}  // namespace

// An unknown option is bad usage: one line naming it, exit 2, for every command.
TEST_F(CliTest, UnknownOptionOfEveryCommandIsOneLineAndExitTwo) {
  for (const auto& command : kCommands) {
    const Outcome o = run(command + " " + absent_files(command, dir_) + " --no-such-option");
    EXPECT_EQ(o.status, 2) << command << ": " << o.output;
    EXPECT_EQ(std::count(o.output.begin(), o.output.end(), '\n'), 1) << command << ": " << o.output;
    EXPECT_NE(o.output.find("--no-such-option"), std::string::npos) << command << ": " << o.output;
  }
  for (const std::string args : {"--no-such-option", "no-such-command", ""}) {
    const Outcome o = run(args);
    EXPECT_EQ(o.status, 2) << args << ": " << o.output;
    EXPECT_EQ(std::count(o.output.begin(), o.output.end(), '\n'), 1) << args << ": " << o.output;
    EXPECT_NE(o.output.find("allowed: run, sweep, check, stability, report, plot"), std::string::npos) << o.output;
  }
  // A missing value, an extra file: one line, exit 2 too.
  for (const std::string& args : std::vector<std::string>{"run " + absent_files("run", dir_) + " --out", "sweep a.toml b.toml",
                                   "check " + absent_files("check", dir_) + " --junit", "stability"}) {
    const Outcome o = run(args);
    EXPECT_EQ(o.status, 2) << args << ": " << o.output;
    EXPECT_EQ(std::count(o.output.begin(), o.output.end(), '\n'), 1) << args << ": " << o.output;
  }
}

// Every option that a command's --help shows is accepted, in each of its forms and with a value
// where it takes one: the command goes on to read its (absent) input file and names it, rather
// than rejecting the command line.
TEST_F(CliTest, EveryOptionInTheHelpIsAccepted) {
  for (const auto& command : kCommands) {
    const Outcome help = run(command + " --help");
    ASSERT_EQ(help.status, 0) << command << ": " << help.output;
    const std::vector<HelpOption> options = options_in(help.output);
    EXPECT_GE(options.size(), 2u) << command << ": " << help.output;
    const std::string files = absent_files(command, dir_);
    for (const HelpOption& option : options) {
      for (const std::string& name : option.names) {
        if (name == "-h" || name == "--help") continue;
        std::string value;
        if (!option.value.empty()) value.append(" ").append(sample_value(option.value, dir_));
        const Outcome o = run(command + " " + files + " " + name + value);
        EXPECT_EQ(o.status, 2) << command << " " << name << ": " << o.output;
        EXPECT_EQ(std::count(o.output.begin(), o.output.end(), '\n'), 1) << command << " " << name << ": " << o.output;
        EXPECT_NE(o.output.find((dir_ / "absent").string()), std::string::npos)
            << command << " " << name << value << " was not accepted: " << o.output;
      }
    }
  }
}

// `ricochet --help` is the complete usage: every command with every option its own --help shows
// (for report and plot, the options of their scripts, which the scripts' own --help lists).
TEST_F(CliTest, TopLevelHelpListsEveryCommandsOptions) {
  const Outcome top = run("--help");
  ASSERT_EQ(top.status, 0) << top.output;
  EXPECT_NE(top.output.find("--version"), std::string::npos);
  for (const auto& command : kCommands) {
    const auto at = top.output.find("\n" + command + ": ");
    ASSERT_NE(at, std::string::npos) << command << " has no section in: " << top.output;
    const auto end = top.output.find("\n\n", at + 1);
    const std::string section = top.output.substr(at, end == std::string::npos ? std::string::npos : end - at);
    std::set<std::string> listed, own;
    for (const HelpOption& o : options_in(section)) listed.insert(o.names.begin(), o.names.end());
    for (const HelpOption& o : options_in(run(command + " --help").output)) own.insert(o.names.begin(), o.names.end());
    EXPECT_EQ(listed, own) << command;
  }
  EXPECT_EQ(run("--version").output, std::string("ricochet ") + RICOCHET_VERSION + "\n");
}

// `--out` must name a folder: an empty value (which used to fall back on results/<name>) and a
// path that is, or is inside, an existing file are bad input of run, sweep and stability: one
// line naming the option, exit 2, nothing written.
TEST_F(CliTest, OutMustNameAFolder) {
  const std::string c = write("case.toml", kGood);
  const std::string s = write("sweep.toml", "base = \"case.toml\"\n[[group]]\n");
  const std::string file = write("file.txt", "not a folder\n");
  const fs::path work = dir_ / "work";
  fs::create_directories(work);
  for (const std::string& command : {"run " + c, "sweep " + s, "stability " + c}) {
    for (const std::string& out : {std::string("''"), std::string("--out=")}) {
      const std::string args = command + (out == "''" ? " --out ''" : " --out=");
      const Outcome o = run(args, "cd '" + work.string() + "' &&");
      EXPECT_EQ(o.status, 2) << args << ": " << o.output;
      EXPECT_EQ(std::count(o.output.begin(), o.output.end(), '\n'), 1) << o.output;
      EXPECT_NE(o.output.find("--out"), std::string::npos) << o.output;
      EXPECT_TRUE(fs::is_empty(work)) << args << " wrote into the working folder";
      fs::remove_all(work);
      fs::create_directories(work);
    }
    for (const std::string& out : {file, file + "/sub"}) {
      const std::string args = command + " --out " + out;
      const Outcome o = run(args);
      EXPECT_EQ(o.status, 2) << args << ": " << o.output;
      EXPECT_EQ(std::count(o.output.begin(), o.output.end(), '\n'), 1) << o.output;
      EXPECT_NE(o.output.find("--out"), std::string::npos) << o.output;
      EXPECT_NE(o.output.find(file), std::string::npos) << o.output;
      EXPECT_TRUE(fs::is_regular_file(file));
    }
  }
}

namespace {

// What a reader of an output folder may see: every output of a run or none of them.
void expect_all_or_nothing(const fs::path& out, const Outcome& o) {
  const bool summary = fs::is_regular_file(out / "summary.json");
  EXPECT_EQ(fs::exists(out / "history.csv"), summary) << o.output;
  EXPECT_EQ(fs::exists(out / "fields"), summary) << o.output;
  EXPECT_EQ(o.status == 0, summary) << o.output;
  if (o.status != 0) {
    EXPECT_EQ(o.status, 1) << o.output;
    EXPECT_EQ(std::count(o.output.begin(), o.output.end(), '\n'), 1) << o.output;
    EXPECT_EQ(o.output.rfind("ricochet: error: cannot write '" + out.string(), 0), 0u) << o.output;
  }
  if (fs::is_directory(out))
    for (const auto& e : fs::directory_iterator(out)) {
      const std::string name = e.path().filename().string();
      EXPECT_NE(name.rfind(".staging", 0), 0u) << name << " left behind";
    }
}

}  // namespace

// A run whose outputs cannot all be written leaves none of them (a reader never sees
// history.csv or fields/ without their summary.json) and says why in one line, exit 1.
TEST_F(CliTest, RunOutputsAreAllOrNothing) {
  const std::string c = write("case.toml", kGood);
  const fs::path o = out();
  // summary.json's temporary name taken by a folder.
  fs::create_directories(o / "summary.json.tmp");
  expect_all_or_nothing(o, run("run " + c + " --out " + o.string() + " --quiet"));
  fs::remove_all(o);
  // summary.json itself a folder that cannot be replaced.
  fs::create_directories(o / "summary.json" / "x");
  const Outcome s = run("run " + c + " --out " + o.string() + " --quiet");
  EXPECT_EQ(s.status, 1) << s.output;
  expect_all_or_nothing(o, s);
  EXPECT_NE(s.output.find("summary.json"), std::string::npos) << s.output;
  fs::remove_all(o);
  // A full disk, as a file size limit of 20 kB: history.csv fits, the field file does not. An
  // earlier run's complete outputs in the folder are not mixed with the new ones.
  ASSERT_EQ(run("run " + c + " --out " + o.string() + " --quiet").status, 0);
  const Outcome f = run("run " + c + " --out " + o.string() + " --quiet --set meshes.m.nx=40 --set meshes.m.ny=20",
                        "trap '' XFSZ; ulimit -f 40;");
  EXPECT_EQ(f.status, 1) << f.output;
  EXPECT_NE(f.output.find("File too large"), std::string::npos) << f.output;
  expect_all_or_nothing(o, f);
}
