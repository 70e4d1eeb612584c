#include "harness/studies/reproduce.hpp"

#include <chrono>
#include <cstdio>
#include <ostream>
#include <set>
#include <stdexcept>
#include <system_error>

#include "harness/cli/commands.hpp"
#include "harness/input/input_error.hpp"
#include "harness/outputs/run_outputs.hpp"
#include "harness/studies/report_stamp.hpp"
#include "harness/studies/study_placeholders.hpp"
#include "harness/studies/study_run.hpp"
#include "harness/sweeps/sweep_slurm.hpp"

namespace ricochet {
namespace {

namespace fs = std::filesystem;

// Runs reports/make_report.py with `args`; its stdout goes to `out` (unless quiet), its stderr to
// `err`. Returns an empty string when it succeeded, else why not, in one line.
std::string make_report(const std::vector<std::string>& args, bool quiet, std::ostream& out, std::ostream& err) {
  std::vector<std::string> argv = {report_python(), report_script_path("make_report.py")};
  argv.insert(argv.end(), args.begin(), args.end());
  try {
    const ProgramOutput r = run_program(argv);
    if (!quiet) out << r.out;
    err << r.err;
    if (r.status == 0) return {};
    const std::string line = one_line(first_line(r.err));
    return "exit " + std::to_string(r.status) + (line.empty() ? std::string() : ": " + line);
  } catch (const std::exception& e) {
    return one_line(e.what());
  }
}

// The chosen studies, read and checked, in the order of the arguments (each once), or every
// study of the folder in its order.
std::vector<PreparedStudy> prepare(const ReproduceCommand& c) {
  const fs::path dir = c.studies_dir.empty() ? default_studies_dir() : fs::path(c.studies_dir);
  std::vector<StudySpec> specs;
  if (c.studies.empty()) {
    specs = discover_studies(dir);
    if (specs.empty())
      throw InputError("ricochet reproduce: no study in " + dir.string() +
                       " (a study is a folder holding a study.toml; docs/studies.md)");
  } else {
    std::set<fs::path> seen;
    for (const std::string& a : c.studies) {
      StudySpec s = find_study(a, dir);
      if (seen.insert(s.folder).second) specs.push_back(std::move(s));
    }
  }
  std::set<std::string> names;
  for (const StudySpec& s : specs)
    if (!names.insert(s.name).second)
      throw InputError("ricochet reproduce: two studies named '" + s.name + "' (their output folder is <out>/" + s.name +
                       "); run them one at a time or rename a folder");
  std::vector<PreparedStudy> out;
  for (StudySpec& s : specs) {
    if (s.sweeps_of(c.tier).empty()) {
      // Every study of the folder: those without the tier are not part of it. A named one must have it.
      if (c.studies.empty()) continue;
      throw InputError("ricochet reproduce: study " + s.name + " (" + s.file.string() + ") has no [[sweep]] of tier " +
                       c.tier + "; run it with --tier " + (c.tier == "fast" ? "full" : "fast"));
    }
    out.push_back(prepare_study(std::move(s), c.tier));
  }
  if (out.empty()) throw InputError("ricochet reproduce: no study in " + dir.string() + " has a [[sweep]] of tier " + c.tier);
  return out;
}

}  // namespace

int run_command(const ReproduceCommand& c, std::ostream& out, std::ostream& err) {
  if (c.tier != "fast" && c.tier != "full")
    throw InputError("ricochet reproduce: --tier: got '" + c.tier + "'; allowed: fast, full");
  const fs::path root = fs::absolute(c.out_dir.empty() ? fs::path("results") / c.tier : fs::path(c.out_dir));
  if (const std::string problem = output_folder_problem(root); !problem.empty())
    throw InputError("ricochet reproduce: --out " + root.string() + ": " + problem);
  const std::vector<PreparedStudy> studies = prepare(c);

  const auto start = std::chrono::steady_clock::now();
  int passed = 0, gates_failed = 0, failed = 0, skipped = 0, report_failures = 0, drawn = 0;
  for (const PreparedStudy& s : studies) {
    StudyRunOptions opt;
    opt.out = root / s.spec.name;
    opt.force = c.force;
    opt.quiet = c.quiet;
    StudyOutcome o;
    try {
      if (const std::vector<std::string> missing = missing_requirements(s.spec); !missing.empty()) {
        skip_study(s, opt, missing, out);
        ++skipped;
        continue;
      }
      o = run_study(s, opt, out, err);
    } catch (const std::exception& e) {
      out << "study " << s.spec.name << ": failed: " << one_line(e.what()) << std::endl;
      ++failed;
      continue;
    }
    (o.status == "passed" ? passed : o.status == "gates failed" ? gates_failed : failed)++;
    if (c.no_report) continue;
    const std::string stamp = report_stamp(s.spec, o.json);
    if (!c.force && stamp == read_report_stamp(opt.out)) {
      out << "report " << s.spec.name << ": reused (nothing it shows changed) -> " << (opt.out / "report").string()
          << std::endl;
      continue;
    }
    if (const std::string why = make_report({"--study", opt.out.string()}, c.quiet, out, err); why.empty()) {
      write_report_stamp(opt.out, stamp);
      ++drawn;
      out << "report " << s.spec.name << ": drawn -> " << (opt.out / "report" / "index.html").string() << std::endl;
    } else {
      ++report_failures;
      out << "report " << s.spec.name << ": failed: " << why << std::endl;
    }
  }
  if (!c.no_report) {
    std::error_code ec;
    if (!c.force && drawn == 0 && skipped == 0 && report_failures == 0 && fs::is_regular_file(root / "index.html", ec)) {
      out << "report index: reused -> " << (root / "index.html").string() << std::endl;
    } else if (const std::string why = make_report({"--index", root.string()}, c.quiet, out, err); why.empty()) {
      out << "report index: drawn -> " << (root / "index.html").string() << std::endl;
    } else {
      ++report_failures;
      out << "report index: failed: " << why << std::endl;
    }
  }
  char secs[32];
  std::snprintf(secs, sizeof secs, "%.1f", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  out << "reproduce " << c.tier << ": " << studies.size() << (studies.size() == 1 ? " study: " : " studies: ") << passed
      << " passed, " << gates_failed << " gates failed, " << failed << " failed";
  if (skipped) out << ", " << skipped << " skipped";
  if (report_failures) out << "; " << report_failures << " report(s) failed";
  out << " in " << secs << " s -> " << root.string() << std::endl;
  if (failed || report_failures) return 1;
  return gates_failed ? kExitReproduceGates : 0;
}

}  // namespace ricochet
