// Replays the inputs of tests/fuzz/regressions/TARGET/ (findings of the fuzz targets, kept once
// fixed) through the targets' own entry functions (tests/fuzz/fuzz_entries.hpp), so the normal
// build (and its sanitizer build) checks them too: each must be accepted or rejected with an
// InputError, nothing else. Also checks the input formats of the entries. docs/reliability.md,
// Fuzzing.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "tests/fuzz/fuzz_entries.hpp"

namespace fs = std::filesystem;
using namespace ricochet;

namespace {

const fs::path kRegressions = fs::path(RICOCHET_SOURCE_DIR) / "tests/fuzz/regressions";

std::vector<fs::path> inputs_of(const std::string& target) {
  std::vector<fs::path> files;
  if (fs::is_directory(kRegressions / target))
    for (const auto& e : fs::directory_iterator(kRegressions / target))
      if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

std::string contents(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

template <class Entry>
void replay(const std::string& target, Entry entry) {
  for (const fs::path& file : inputs_of(target)) {
    SCOPED_TRACE(file.string());
    const auto start = std::chrono::steady_clock::now();
    EXPECT_NO_THROW(entry(contents(file)));
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_LT(seconds, 10.0) << "slower than the fuzzer's -timeout";
  }
}

}  // namespace

TEST(FuzzRegressions, Case) { replay("case", fuzz::case_entry); }
TEST(FuzzRegressions, Gmsh) { replay("gmsh", fuzz::gmsh_entry); }
TEST(FuzzRegressions, Csv) { replay("csv", fuzz::csv_entry); }
TEST(FuzzRegressions, Gates) { replay("gates", fuzz::gates_entry); }

TEST(FuzzEntries, CaseInputSplitsLeadingSetLines) {
  const fuzz::CaseInput in = fuzz::split_case_input("--set time.dt=1e-6\r\n--set mesh=M2\nname = \"x\"\n--set a=1\n");
  ASSERT_EQ(in.overrides.size(), 2u);
  EXPECT_EQ(in.overrides[0], "time.dt=1e-6");
  EXPECT_EQ(in.overrides[1], "mesh=M2");
  EXPECT_EQ(in.text, "name = \"x\"\n--set a=1\n");
  EXPECT_EQ(fuzz::split_case_input("--set x=1").overrides.size(), 1u);
  EXPECT_TRUE(fuzz::split_case_input("--set x=1").text.empty());
}

TEST(FuzzEntries, AcceptsTheRepositoryFilesAndRejectsGarbage) {
  EXPECT_TRUE(fuzz::case_entry("--set time.end=1e-5\n" + contents(fs::path(RICOCHET_SOURCE_DIR) / "cases/verification/sliding_block.toml")));
  EXPECT_FALSE(fuzz::case_entry("--set time.dtt=1\n" + contents(fs::path(RICOCHET_SOURCE_DIR) / "cases/verification/sliding_block.toml")));
  EXPECT_FALSE(fuzz::case_entry("[meshes"));
  EXPECT_TRUE(fuzz::gmsh_entry(contents(fs::path(RICOCHET_SOURCE_DIR) / "tests/data/gmsh_quad_2x1_v41.msh")));
  EXPECT_FALSE(fuzz::gmsh_entry("$MeshFormat\n2.2 0 8\n"));
  EXPECT_TRUE(fuzz::csv_entry("a,b\n1,\"x,y\"\n"));
  EXPECT_FALSE(fuzz::csv_entry("a,b\n1\n"));
  // Gates: on the built-in table, or on the table after "%%csv" (the gate fails there: still accepted).
  const std::string gate = "[[gate]]\nname = \"g\"\nkind = \"max\"\ncolumn = \"v\"\nlimit = 1.0\n";
  EXPECT_TRUE(fuzz::gates_entry(contents(fs::path(RICOCHET_SOURCE_DIR) / "cases/verification/gates_fast.toml")));
  EXPECT_TRUE(fuzz::gates_entry(gate + "%%csv\nv\n2\n"));
  EXPECT_TRUE(fuzz::gates_entry(gate + "%%csv\r\n"));
  EXPECT_FALSE(fuzz::gates_entry(gate + "%%csvx\nv\n2\n"));  // not the separator: TOML syntax error
  EXPECT_FALSE(fuzz::gates_entry("[[gate]]\nkind = \"maximum\"\n"));
}
