#include "harness/studies/study_post.hpp"

#include <chrono>
#include <stdexcept>
#include <system_error>

#include "harness/gates/gates.hpp"
#include "harness/input/input_error.hpp"
#include "harness/outputs/atomic_file.hpp"
#include "harness/sweeps/sweep_slurm.hpp"

namespace ricochet {
namespace {

namespace fs = std::filesystem;

}  // namespace

Json gate_results_json(const std::vector<GateResult>& results) {
  Json list = Json::array();
  for (const GateResult& r : results) {
    Json g = Json::object();
    g["name"] = r.name;
    g["passed"] = r.passed;
    g["detail"] = gate_detail(r);
    list.push_back(g);
  }
  return list;
}

PostOutcome run_post(const StudyPost& post, const Placeholders& values, const fs::path& folder, const fs::path& out_dir,
                     std::ostream& lines) {
  const auto start = std::chrono::steady_clock::now();
  PostOutcome o;
  Json& j = o.json;
  j = Json::object();
  j["name"] = post.name;
  j["command"] = Json::array();
  j["exit"] = nullptr;
  j["table"] = nullptr;
  j["gates"] = post.gates.empty() ? Json() : Json(post.gates.string());
  j["gate_results"] = Json::array();
  auto fail = [&](const std::string& why) {
    o.failed = true;
    j["status"] = "failed";
    j["reason"] = why;
  };
  try {
    std::vector<std::string> argv;
    for (const std::string& a : post.command) argv.push_back(expand_placeholders(a, values));
    j["command"] = argv;
    if (argv[0].find('/') == std::string::npos) {
      const fs::path found = find_on_path(argv[0]);
      if (found.empty()) throw std::runtime_error("cannot start '" + argv[0] + "': not found on PATH");
      argv[0] = found.string();
    }
    const fs::path logs = out_dir / "post" / post.name;
    fs::create_directories(logs);
    const ProgramOutput r = run_program(argv, folder);
    write_file_atomic(logs / "stdout.txt", r.out);
    write_file_atomic(logs / "stderr.txt", r.err);
    j["exit"] = r.status;
    if (r.status != 0) {
      const std::string line = one_line(first_line(r.err));
      fail("exit " + std::to_string(r.status) + (line.empty() ? std::string() : ": " + line));
    } else if (!post.table.empty()) {
      fs::path table = expand_placeholders(post.table, values);
      if (table.is_relative()) table = folder / table;
      j["table"] = table.string();
      const std::vector<GateResult> results =
          check_gates(read_csv(table), read_gates(post.gates), logs / "gates-junit.xml", lines);
      j["gate_results"] = gate_results_json(results);
      for (const GateResult& g : results) o.gates_failed = o.gates_failed || !g.passed;
    }
  } catch (const std::exception& e) {
    fail(one_line(e.what()));
  }
  if (!o.failed) {
    j["status"] = o.gates_failed ? "gates failed" : "passed";
    j["reason"] = nullptr;
  }
  j["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return o;
}

}  // namespace ricochet
