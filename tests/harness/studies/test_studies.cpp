// Studies (docs/studies.md): study.toml's validation (one line naming the file and the key), the
// discovery and order of a folder's studies, and `ricochet reproduce` end to end on a tiny study:
// its study.json, the reuse of unchanged runs, and the reruns after an edit of the case or of a
// mesh file it reads; the report is drawn only when something it shows changed.
#include <gtest/gtest.h>

#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "harness/input/input_error.hpp"
#include "harness/outputs/json_io.hpp"
#include "harness/studies/study_spec.hpp"
#include "harness/sweeps/run_identity.hpp"
#include "tests/support/run_program.hpp"
#include "tests/support/temp_dir.hpp"

namespace fs = std::filesystem;
using namespace ricochet;

namespace {

// A 4 x 2-cell block moving down and sideways onto a rigid line: 200 steps, contact, friction.
// It also defines (and so reads) the Gmsh mesh plate.msh, which no body uses.
const std::string kCase = R"(name = "tiny"
mesh = "m"
scheme = "semi_explicit"
[meshes.m]
generator = "rectangle"
width = 0.1
height = 0.05
nx = 4
ny = 2
[meshes.g]
file = "plate.msh"
[[bodies]]
name = "b"
velocity = [0.5, -1.0]
[bodies.material]
young = 1e6
poisson = 0.3
density = 1000.0
[[obstacles]]
name = "ground"
type = "line"
point = [0.0, -0.0005]
normal = [0.0, 1.0]
friction = 0.2
[time]
end = 2e-3
dt = 1e-5
[output]
interval = 1e-4
fields = []
)";

const std::string kMesh = R"($MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
6
1 0 0 0
2 1 0 0
3 2 0 0
4 0 1 0
5 1 1 0
6 2 1 0
$EndNodes
$Elements
2
1 3 2 1 1 1 2 5 4
2 3 2 1 1 2 3 6 5
$EndElements
)";

const std::string kSweep = R"(name = "runs"
base = "case.toml"
[[group]]
name = "g"
cross = { "obstacles[0].friction" = [0.0, 0.3], scheme = ["semi_explicit", "implicit"] }
)";

const std::string kGates = R"([[gate]]
name = "no failed runs"
kind = "count"
where = { status = "failed" }
max = 0
)";

const std::string kStudy = R"(title = "Tiny"
summary = "A block on a line, two frictions, two schemes."
order = 5

[[sweep]]
name = "runs"
file = "sweep.toml"
gates = "gates.toml"
)";

using Outcome = test_support::ProgramOutcome;

Outcome shell(const std::string& cmd) { return test_support::run_shell(cmd + " 2>&1"); }

class StudyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test_support::fresh_test_dir("ricochet_study_");
    fs::create_directories(dir_ / "studies" / "tiny");
    write("case.toml", kCase);
    write("plate.msh", kMesh);
    write("sweep.toml", kSweep);
    write("gates.toml", kGates);
    write("study.toml", kStudy);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path study() const { return dir_ / "studies" / "tiny"; }
  void write(const std::string& name, const std::string& text) const { std::ofstream(study() / name) << text; }
  void append(const std::string& name, const std::string& text) const {
    std::ofstream(study() / name, std::ios::app) << text;
  }

  // Expects read_study to reject study.toml with `text`: one line naming the file and each of `parts`.
  void expect_rejected(const std::string& text, const std::vector<std::string>& parts) {
    write("study.toml", text);
    try {
      read_study(study());
      ADD_FAILURE() << "accepted: " << text;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
      EXPECT_NE(msg.find((study() / "study.toml").string()), std::string::npos) << "names the file: " << msg;
      for (const std::string& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << p << " in: " << msg;
    }
  }

  Outcome reproduce(const std::string& args, const std::string& env = "") const {
    return shell("cd '" + dir_.string() + "' && " + env + " '" + RICOCHET_BINARY + "' reproduce " + args);
  }

  Json study_json() const { return read_json_file(dir_ / "out" / "tiny" / "study.json"); }

  fs::path dir_;
};

TEST_F(StudyTest, ReadsAValidStudy) {
  const StudySpec s = read_study(study());
  EXPECT_EQ(s.name, "tiny");
  EXPECT_EQ(s.title, "Tiny");
  ASSERT_EQ(s.sweeps.size(), 1u);
  EXPECT_EQ(s.sweeps[0].file, study() / "sweep.toml");
  EXPECT_EQ(s.sweeps[0].tiers, (std::vector<std::string>{"fast", "full"}));
  EXPECT_EQ(s.sweeps[0].threads, 1);
  EXPECT_EQ(s.sweeps[0].jobs, 1);
  EXPECT_EQ(s.order, 5);
}

TEST_F(StudyTest, RejectsBadStudyFilesInOneLineNamingTheKey) {
  expect_rejected(kStudy + "titel = \"x\"\n", {"titel", "unknown key"});
  expect_rejected("summary = \"s\"\n[[sweep]]\nname = \"a\"\nfile = \"sweep.toml\"\n", {"title", "missing"});
  expect_rejected(kStudy + "[[sweep]]\nname = \"runs\"\nfile = \"sweep.toml\"\ntier = [\"full\"]\n",
                  {"sweep[1].name", "\"runs\" is already", "tier full"});
  expect_rejected(kStudy + "[[sweep]]\nname = \"other\"\nfile = \"sweep.toml\"\ntier = [\"slow\"]\n",
                  {"sweep[1].tier", "\"slow\"", "\"fast\", \"full\""});
  expect_rejected(kStudy + "[[sweep]]\nname = \"other\"\nfile = \"nope.toml\"\n", {"sweep[1].file", "nope.toml", "not found"});
  expect_rejected(kStudy + "[[sweep]]\nname = \"other\"\nfile = \"sweep.toml\"\nthreads = -1\n", {"sweep[1].threads"});
  expect_rejected(kStudy + "[[post]]\nname = \"p\"\ncommand = [\"x\", \"{sweep:nope}\"]\n", {"post[0].command", "nope"});
  expect_rejected(kStudy + "[[post]]\nname = \"p\"\ncommand = [\"x\", \"{outdir}\"]\n", {"post[0].command", "{outdir}"});
  expect_rejected(kStudy + "[[post]]\nname = \"p\"\ncommand = [\"x\"]\ntable = \"t.csv\"\n", {"post[0].table", "gates"});
  expect_rejected(kStudy + "[report]\nplugin = \"nope.py\"\n", {"report.plugin", "not found"});
  expect_rejected(kStudy + "[[report.section]]\nkind = \"pie\"\n", {"report.section[0].kind", "runs_table"});
}

TEST_F(StudyTest, DiscoversStudiesByOrderThenName) {
  fs::create_directories(dir_ / "studies" / "alpha");
  fs::copy(study(), dir_ / "studies" / "alpha", fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  std::ofstream(dir_ / "studies" / "alpha" / "study.toml") << "title = \"A\"\nsummary = \"s\"\n[[sweep]]\nname = \"r\"\nfile = \"sweep.toml\"\n";
  fs::create_directories(dir_ / "studies" / "not_a_study");
  const std::vector<StudySpec> all = discover_studies(dir_ / "studies");
  ASSERT_EQ(all.size(), 2u);
  EXPECT_EQ(all[0].name, "tiny");  // order = 5 first; alpha has none
  EXPECT_EQ(all[1].name, "alpha");
  EXPECT_EQ(find_study("alpha", dir_ / "studies").name, "alpha");
  EXPECT_EQ(find_study(study().string(), dir_ / "nowhere").name, "tiny");
  EXPECT_THROW(find_study("tinny", dir_ / "studies"), InputError);
}

TEST_F(StudyTest, MeshFileHashesFollowTheFilesBytes) {
  CaseSpec c;
  MeshSpec m;
  m.source = GmshFile{study() / "plate.msh"};
  c.meshes.emplace("g", m);
  ASSERT_EQ(mesh_files(c), (std::vector<fs::path>{study() / "plate.msh"}));
  const std::string before = file_fnv1a(study() / "plate.msh");
  EXPECT_EQ(before.size(), 16u);
  append("plate.msh", "\n");
  EXPECT_NE(file_fnv1a(study() / "plate.msh"), before);
  EXPECT_EQ(file_fnv1a(study() / "missing.msh"), "");
  // The program's build id read from its file is the one it reads from its own image when it runs.
  const std::string id = program_build_id(RICOCHET_BINARY);
  EXPECT_EQ(id.rfind("gnu-build-id:", 0), 0u) << id;
  const Outcome sweep = shell("cd '" + dir_.string() + "' && '" + RICOCHET_BINARY + "' sweep studies/tiny/sweep.toml --out o --quiet");
  ASSERT_EQ(sweep.status, 0) << sweep.output;
  EXPECT_EQ(read_json_file(dir_ / "o/runs/g/000-obstacles.0.friction=0.0_scheme=semi_explicit/overrides.json").at("program_build"), id);
  // A script: its bytes.
  EXPECT_EQ(program_build_id(study() / "case.toml").rfind("fnv1a:", 0), 0u);
}

TEST_F(StudyTest, ReproduceRunsReusesAndRerunsWhatChanged) {
  const std::string args = "tiny --studies studies --out out --tier fast --no-report --quiet";
  Outcome o = reproduce(args);
  ASSERT_EQ(o.status, 0) << o.output;
  Json j = study_json();
  EXPECT_EQ(j.at("study"), "tiny");
  EXPECT_EQ(j.at("title"), "Tiny");
  EXPECT_EQ(j.at("tier"), "fast");
  EXPECT_EQ(j.at("status"), "passed");
  EXPECT_EQ(j.at("folder"), study().string());
  ASSERT_EQ(j.at("sweeps").size(), 1u);
  const Json s = j.at("sweeps")[0];
  EXPECT_EQ(s.at("name"), "runs");
  EXPECT_EQ(s.at("runs"), 4);
  EXPECT_EQ(s.at("reused"), 0);
  EXPECT_EQ(s.at("run_now"), 4);
  EXPECT_EQ(s.at("failed"), 0);
  ASSERT_EQ(s.at("gate_results").size(), 1u);
  EXPECT_EQ(s.at("gate_results")[0].at("name"), "no failed runs");
  EXPECT_EQ(s.at("gate_results")[0].at("passed"), true);
  const Json request = read_json_file(dir_ / "out/tiny/runs/runs/g/000-obstacles.0.friction=0.0_scheme=semi_explicit/overrides.json");
  EXPECT_EQ(request.at("meshes_fnv1a").size(), 1u) << request.dump();
  EXPECT_EQ(request.at("program_build").get<std::string>().rfind("gnu-build-id:", 0), 0u) << request.dump();

  o = reproduce(args);
  ASSERT_EQ(o.status, 0) << o.output;
  EXPECT_NE(o.output.find("runs 4 runs, 4 reused, 0 run now"), std::string::npos) << o.output;
  EXPECT_EQ(study_json().at("sweeps")[0].at("reused"), 4);

  append("case.toml", "# edited\n");
  ASSERT_EQ(reproduce(args).status, 0);
  EXPECT_EQ(study_json().at("sweeps")[0].at("run_now"), 4);

  append("plate.msh", "\n");
  ASSERT_EQ(reproduce(args).status, 0);
  EXPECT_EQ(study_json().at("sweeps")[0].at("run_now"), 4);
  EXPECT_EQ(study_json().at("sweeps")[0].at("reused"), 0);

  // A post step that writes a table checked against its gates, then one that fails.
  write("post_gates.toml", "[[gate]]\nname = \"b small\"\nkind = \"max\"\ncolumn = \"b\"\nlimit = 3\n");
  append("study.toml", "[[post]]\nname = \"table\"\ncommand = [\"sh\", \"-c\", \"printf 'a,b\\\\n1,2\\\\n' > {out}/t.csv\"]\n"
                       "table = \"{out}/t.csv\"\ngates = \"post_gates.toml\"\n");
  o = reproduce(args);
  ASSERT_EQ(o.status, 0) << o.output;
  j = study_json();
  ASSERT_EQ(j.at("post").size(), 1u);
  EXPECT_EQ(j.at("post")[0].at("exit"), 0);
  EXPECT_EQ(j.at("post")[0].at("gate_results")[0].at("passed"), true) << j.dump();
  EXPECT_EQ(j.at("sweeps")[0].at("reused"), 4);

  append("study.toml", "[[post]]\nname = \"boom\"\ncommand = [\"sh\", \"-c\", \"echo broken >&2; exit 3\"]\n");
  o = reproduce(args);
  EXPECT_EQ(o.status, 1) << o.output;
  j = study_json();
  EXPECT_EQ(j.at("status"), "failed");
  EXPECT_EQ(j.at("post")[1].at("exit"), 3);
  EXPECT_NE(j.at("reason").get<std::string>().find("broken"), std::string::npos) << j.dump();
}

TEST_F(StudyTest, TheReportIsDrawnOnlyWhenSomethingChanged) {
  // A stand-in for reports/make_report.py that records its arguments.
  fs::create_directories(dir_ / "reports");
  std::ofstream(dir_ / "reports" / "make_report.py")
      << "import sys\nopen('" << (dir_ / "calls.txt").string() << "', 'a').write(' '.join(sys.argv[1:]) + '\\n')\n"
      << "if sys.argv[1] == '--index':\n    open(sys.argv[2] + '/index.html', 'w').write('index')\n";
  const std::string env = "RICOCHET_REPORTS='" + (dir_ / "reports").string() + "'";
  const std::string args = "tiny --studies studies --out out --tier fast --quiet";
  ASSERT_EQ(reproduce(args, env).status, 0);
  ASSERT_EQ(reproduce(args, env).status, 0);
  std::ifstream in(dir_ / "calls.txt");
  std::vector<std::string> calls;
  for (std::string line; std::getline(in, line);) calls.push_back(line);
  ASSERT_EQ(calls.size(), 2u);  // the second invocation changed nothing: nothing redrawn
  EXPECT_EQ(calls[0], "--study " + (dir_ / "out" / "tiny").string());
  EXPECT_EQ(calls[1], "--index " + (dir_ / "out").string());
  // A failing report is reported, and the study's own outcome stands.
  std::ofstream(dir_ / "reports" / "make_report.py") << "import sys\nsys.exit('no such flag')\n";
  const Outcome o = reproduce(args + " --force", env);
  EXPECT_EQ(o.status, 1) << o.output;
  EXPECT_NE(o.output.find("report tiny: failed: exit 1: no such flag"), std::string::npos) << o.output;
  EXPECT_EQ(study_json().at("status"), "passed");
}

}  // namespace
