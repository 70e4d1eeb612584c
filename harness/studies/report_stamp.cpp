#include "harness/studies/report_stamp.hpp"

#include "harness/outputs/atomic_file.hpp"
#include "harness/sweeps/sweep_plan.hpp"

namespace ricochet {
namespace {

namespace fs = std::filesystem;

// Each part with its length first, so that no two lists of parts give the same text.
void add(std::string& all, const std::string& part) { all += std::to_string(part.size()) + ":" + part + "\n"; }

Json key(const Json& j, const char* k) { return j.is_object() && j.contains(k) ? j.at(k) : Json(); }

}  // namespace

std::string report_stamp(const StudySpec& spec, const Json& study) {
  std::string all;
  add(all, read_text(spec.file));
  add(all, spec.plugin.empty() ? std::string() : read_text(spec.plugin));
  for (const Json& s : key(study, "sweeps")) {
    add(all, compact_json(key(s, "name")));
    add(all, key(s, "dir").is_string() ? read_text(fs::path(key(s, "dir").get<std::string>()) / "summary.csv") : "");
    add(all, compact_json(key(s, "gate_results")));
  }
  for (const Json& p : key(study, "post")) {
    add(all, compact_json(key(p, "name")));
    add(all, compact_json(key(p, "exit")));
    add(all, compact_json(key(p, "gate_results")));
  }
  add(all, compact_json(key(study, "status")));
  return fnv1a_hex(all);
}

std::string read_report_stamp(const fs::path& out) {
  std::string s = read_text(out / "report" / ".stamp");
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}

void write_report_stamp(const fs::path& out, const std::string& stamp) {
  fs::create_directories(out / "report");
  write_file_atomic(out / "report" / ".stamp", stamp + "\n");
}

}  // namespace ricochet
