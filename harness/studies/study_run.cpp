#include "harness/studies/study_run.hpp"

#include <chrono>
#include <cstdio>
#include <ostream>
#include <sstream>

#include "harness/input/input_error.hpp"
#include "harness/outputs/atomic_file.hpp"
#include "harness/outputs/csv_reader.hpp"
#include "harness/outputs/run_outputs.hpp"
#include "harness/studies/study_placeholders.hpp"
#include "harness/studies/study_post.hpp"
#include "harness/sweeps/sweep_slurm.hpp"
#include "harness/sweeps/sweep.hpp"

namespace ricochet {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// A study's sweep file as `ricochet sweep` run from here would name it: relative to the current
// folder when it lies below it, so the case paths the sweep records (summary.csv's case_file) are
// the same whichever command ran it; absolute otherwise.
fs::path as_named_from_here(const fs::path& file) {
  std::error_code ec;
  const fs::path here = fs::current_path(ec);
  if (ec || !file.is_absolute()) return file;
  const fs::path rel = file.lexically_relative(here);
  if (rel.empty() || *rel.begin() == "..") return file;
  return rel;
}

std::string seconds_text(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f s", s);
  return buf;
}

// Discards what is written to it (--quiet).
struct NullStream : std::ostream {
  NullStream() : std::ostream(nullptr) {}
};

std::string gate_counts(const std::vector<GateResult>& results) {
  std::size_t failed = 0;
  for (const GateResult& r : results) failed += r.passed ? 0 : 1;
  return "gates: " + std::to_string(results.size() - failed) + " passed, " + std::to_string(failed) + " failed";
}

// One sweep of the study: study.json's entry; `failed` / `gates_failed` as for the study.
Json run_one_sweep(const PreparedSweep& s, const StudyRunOptions& opt, const std::string& study, std::ostream& lines,
                   std::ostream& log, bool& failed, bool& gates_failed) {
  const StudySweep& e = s.entry;
  const auto start = Clock::now();
  const fs::path dir = opt.out / e.name;
  Json j = Json::object();
  j["name"] = e.name;
  j["file"] = e.file.string();
  j["dir"] = dir.string();
  j["gates"] = e.gates.empty() ? Json() : Json(e.gates.string());
  j["gate_results"] = Json::array();
  j["repeat"] = e.repeat;
  j["jobs"] = e.jobs;
  j["threads"] = e.threads;
  j["runs"] = s.runs.size();
  j["reused"] = nullptr;
  j["run_now"] = nullptr;
  j["failed"] = nullptr;
  j["status"] = "failed";
  j["reason"] = nullptr;
  NullStream null;
  try {
    SweepOptions o;
    o.out_dir = dir;
    o.jobs = e.jobs;
    o.repeat = e.repeat;
    o.threads = e.threads;
    o.force = opt.force;
    o.quiet = opt.quiet;
    o.log = &log;
    const SweepOutcome out = run_sweep(s.spec, s.runs, o);
    j["reused"] = out.resumed;
    j["run_now"] = out.executed;
    j["failed"] = out.failed;
    std::string line = "study " + study + ": " + e.name + " " + std::to_string(out.total) + " runs, " +
                       std::to_string(out.resumed) + " reused, " + std::to_string(out.executed) + " run now";
    if (out.failed) line += ", " + std::to_string(out.failed) + " failed";
    std::vector<GateResult> results;
    if (s.gates) {
      results = check_gates(read_csv(dir / "summary.csv"), *s.gates, dir / "gates-junit.xml", opt.quiet ? null : lines);
      j["gate_results"] = gate_results_json(results);
      line += "; " + gate_counts(results);
    }
    lines << line << " (" << seconds_text(since(start)) << ")" << std::endl;
    bool gates_ok = true;
    for (const GateResult& r : results) gates_ok = gates_ok && r.passed;
    if (out.failed) {
      j["reason"] = std::to_string(out.failed) + " of " + std::to_string(out.total) + " runs failed (their reasons: " +
                    (dir / "summary.csv").string() + ", column reason)";
      failed = true;
    } else {
      j["status"] = gates_ok ? "passed" : "gates failed";
    }
    gates_failed = gates_failed || !gates_ok;
  } catch (const std::exception& err) {
    j["reason"] = one_line(err.what());
    lines << "study " << study << ": " << e.name << " failed: " << one_line(err.what()) << std::endl;
    failed = true;
  }
  j["seconds"] = since(start);
  return j;
}

}  // namespace

PreparedStudy prepare_study(StudySpec spec, const std::string& tier) {
  PreparedStudy p;
  p.spec = std::move(spec);
  p.tier = tier;
  for (const StudySweep* e : p.spec.sweeps_of(tier)) {
    PreparedSweep s;
    s.entry = *e;
    s.spec = read_sweep(as_named_from_here(e->file).string());
    s.runs = expand(s.spec);
    check_runs(s.spec, s.runs);
    if (!e->gates.empty()) s.gates = read_gates(e->gates);
    p.sweeps.push_back(std::move(s));
  }
  for (const StudyPost* post : p.spec.posts_of(tier))
    if (!post->gates.empty()) read_gates(post->gates);
  return p;
}

// study.json's keys that say which study ran where.
Json study_header(const PreparedStudy& study, const StudyRunOptions& opt) {
  const StudySpec& spec = study.spec;
  Json j = Json::object();
  j["ricochet_version"] = RICOCHET_VERSION;
  j["study"] = spec.name;
  j["title"] = spec.title;
  j["summary"] = spec.summary;
  j["folder"] = spec.folder.string();
  j["study_file"] = spec.file.string();
  j["tier"] = study.tier;
  j["out"] = opt.out.string();
  return j;
}

std::vector<std::string> missing_requirements(const StudySpec& spec) {
  std::vector<std::string> missing;
  for (const std::string& prog : spec.required_programs)
    if (find_on_path(prog).empty()) missing.push_back("program " + prog);
  for (const std::string& mod : spec.required_python_modules) {
    ProgramOutput r;
    try {
      r = run_program({report_python(), "-c", "import " + mod});
    } catch (const std::exception&) {
      r.status = -1;
    }
    if (r.status != 0) missing.push_back("Python module " + mod + " (" + report_python() + ")");
  }
  return missing;
}

StudyOutcome skip_study(const PreparedStudy& study, const StudyRunOptions& opt, const std::vector<std::string>& missing,
                        std::ostream& lines) {
  const StudySpec& spec = study.spec;
  std::string what;
  for (const std::string& m : missing) what += (what.empty() ? "" : ", ") + m;
  Json j = study_header(study, opt);
  j["status"] = "skipped";
  j["reason"] = "missing " + what + " ([requires] of " + spec.file.filename().string() + ")";
  j["sweeps"] = Json::array();
  j["post"] = Json::array();
  j["finished_at"] = utc_now();
  fs::create_directories(opt.out);
  write_file_atomic(opt.out / "study.json", dump_json(j));
  lines << "study " << spec.name << ": skipped (" << j["reason"].get<std::string>() << ")" << std::endl;
  StudyOutcome out;
  out.status = "skipped";
  out.json = std::move(j);
  return out;
}

StudyOutcome run_study(const PreparedStudy& study, const StudyRunOptions& opt, std::ostream& lines, std::ostream& log) {
  const StudySpec& spec = study.spec;
  const auto start = Clock::now();
  Json j = study_header(study, opt);
  j["started_at"] = utc_now();

  std::string names;
  for (const PreparedSweep& s : study.sweeps) names += (names.empty() ? "" : ", ") + s.entry.name;
  lines << "study " << spec.name << " (" << study.tier << "): sweeps " << (names.empty() ? "none" : names) << std::endl;

  bool failed = false, gates_failed = false;
  std::string reason;
  Json sweeps = Json::array();
  Placeholders values{spec.folder.string(), opt.out.string(), report_python(), this_program().string(), {}};
  for (const PreparedSweep& s : study.sweeps) {
    const bool before = failed;
    sweeps.push_back(run_one_sweep(s, opt, spec.name, lines, log, failed, gates_failed));
    if (failed && !before) reason = "sweep " + s.entry.name + ": " + sweeps.back()["reason"].get<std::string>();
    values.sweeps[s.entry.name] = (opt.out / s.entry.name).string();
  }
  j["sweeps"] = sweeps;

  Json posts = Json::array();
  const bool sweep_failed = failed;
  for (const StudyPost* p : spec.posts_of(study.tier)) {
    if (sweep_failed) {
      Json skipped = Json::object();
      skipped["name"] = p->name;
      skipped["status"] = "failed";
      skipped["reason"] = "not run: a sweep of the study failed";
      posts.push_back(skipped);
      continue;
    }
    NullStream null;
    const PostOutcome o = run_post(*p, values, spec.folder, opt.out, opt.quiet ? null : lines);
    std::string line = "study " + spec.name + ": post " + p->name + " " + o.json["status"].get<std::string>();
    if (o.json["reason"].is_string()) line += ": " + o.json["reason"].get<std::string>();
    lines << line << std::endl;
    if (o.failed && !failed) reason = "post " + p->name + ": " + o.json["reason"].get<std::string>();
    failed = failed || o.failed;
    gates_failed = gates_failed || o.gates_failed;
    posts.push_back(o.json);
  }
  j["post"] = posts;

  StudyOutcome out;
  out.status = failed ? "failed" : gates_failed ? "gates failed" : "passed";
  j["status"] = out.status;
  j["reason"] = reason.empty() ? Json() : Json(reason);
  j["finished_at"] = utc_now();
  j["seconds"] = since(start);
  fs::create_directories(opt.out);
  write_file_atomic(opt.out / "study.json", dump_json(j));
  lines << "study " << spec.name << ": " << out.status << (reason.empty() ? "" : " (" + reason + ")") << " in "
        << seconds_text(since(start)) << " -> " << (opt.out / "study.json").string() << std::endl;
  out.json = std::move(j);
  return out;
}

}  // namespace ricochet
