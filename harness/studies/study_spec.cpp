#include "harness/studies/study_spec.hpp"

#include <algorithm>
#include <cstdlib>
#include <map>
#include <set>
#include <system_error>

#include "harness/input/input_error.hpp"
#include "harness/input/suggest.hpp"
#include "harness/input/toml_reader.hpp"
#include "harness/studies/study_placeholders.hpp"
#include "harness/sweeps/sweep.hpp"
#include "solver/schemes/threads.hpp"

namespace ricochet {
namespace {

namespace fs = std::filesystem;

// The report's section kinds (docs/studies.md, `[report]`); their own keys are the report's.
const std::vector<std::string> kSectionKinds = {"runs_table", "metric", "work_precision", "histories",
                                                "fields", "stability", "plugin"};

std::string line_of(const toml::node& n, const fs::path& file) {
  std::string s = file.string();
  if (const auto line = n.source().begin.line; line > 0) s += ':' + std::to_string(line);
  return s;
}

// A file named relative to the study folder (or absolute) that must exist.
fs::path existing_file(const TableReader& t, const std::string& key, const fs::path& folder, const std::string& what) {
  fs::path p = t.text(key);
  if (p.empty()) t.fail(key, "expected the path of " + what + "; got \"\"");
  if (p.is_relative()) p = folder / p;
  std::error_code ec;
  if (!fs::is_regular_file(p, ec)) t.fail(key, what + " '" + p.string() + "' not found");
  return p;
}

// An optional file: empty when `key` is absent.
fs::path optional_file(const TableReader& t, const std::string& key, const fs::path& folder, const std::string& what) {
  if (!t.has(key)) {
    t.text(key, "");  // marks the key as allowed here
    return {};
  }
  return existing_file(t, key, folder, what);
}

// `name` of a sweep entry or a post step: it names a folder.
std::string read_name(const TableReader& t) {
  std::string name = t.text("name");
  if (!valid_name(name))
    t.fail("name", "\"" + name + "\": allowed: letters, digits, '_', '-', '.' (not first); at most 64 characters");
  return name;
}

// `tier`: a string or an array of strings from kStudyTiers, each once; default both.
std::vector<std::string> read_tiers(const TableReader& t) {
  if (!t.has("tier")) {
    t.texts("tier");
    return kStudyTiers;
  }
  const std::vector<std::string> given = t.texts("tier");
  if (given.empty()) t.fail("tier", "empty; allowed: \"fast\", \"full\" or both (leave it out for both)");
  std::vector<std::string> out;
  for (const std::string& g : given) {
    if (std::find(kStudyTiers.begin(), kStudyTiers.end(), g) == kStudyTiers.end())
      t.fail("tier", "\"" + g + "\": allowed: \"fast\", \"full\"");
    if (std::count(given.begin(), given.end(), g) > 1) t.fail("tier", "\"" + g + "\" given twice");
  }
  for (const std::string& k : kStudyTiers)
    if (std::count(given.begin(), given.end(), k)) out.push_back(k);
  return out;
}

StudySweep read_sweep_entry(const TableReader& t, const toml::table& raw, const StudySpec& s) {
  StudySweep e;
  e.where = line_of(raw, s.file) + ": " + t.path();
  e.name = read_name(t);
  e.file = existing_file(t, "file", s.folder, "sweep file");
  e.tiers = read_tiers(t);
  e.gates = optional_file(t, "gates", s.folder, "gate file");
  e.repeat = static_cast<int>(t.integer("repeat", 1, 1, 1000));
  e.jobs = static_cast<int>(t.integer("jobs", 1, 1, kMaxSweepJobs));
  e.threads = static_cast<int>(t.integer("threads", 1, 0, kMaxThreads));
  t.finish();
  return e;
}

StudyPost read_post(const TableReader& t, const toml::table& raw, const StudySpec& s) {
  StudyPost p;
  p.where = line_of(raw, s.file) + ": " + t.path();
  p.name = read_name(t);
  const toml::node* c = raw.get("command");
  if (c && !c->is_array()) t.fail("command", "expected an array of strings (the program and its arguments); got " + type_name(*c));
  if (!c) t.text("command");  // "missing required key"
  p.command = t.texts("command");
  if (p.command.empty()) t.fail("command", "empty; give the program and its arguments, e.g. [\"{python}\", \"drift.py\"]");
  p.tiers = read_tiers(t);
  p.table = t.text("table", "");
  if (t.has("table") && p.table.empty()) t.fail("table", "expected the path of a CSV file; got \"\"");
  if (t.has("gates") && !t.has("table")) t.fail("gates", "only with `table` (the CSV the step writes, checked against them)");
  if (t.has("table") && !t.has("gates")) t.fail("table", "needs `gates`, the gate file to check it against");
  p.gates = optional_file(t, "gates", s.folder, "gate file");
  // Every placeholder must expand in each of the step's tiers.
  for (const std::string& tier : p.tiers) {
    Placeholders v{"s", "o", "p", "r", {}};
    for (const StudySweep* e : s.sweeps_of(tier)) v.sweeps.emplace(e->name, "sweep");
    auto check = [&](const std::string& key, const std::string& text) {
      try {
        expand_placeholders(text, v);
      } catch (const InputError& err) {
        t.fail(key, std::string(err.what()) + " (tier " + tier + ")");
      }
    };
    for (const std::string& a : p.command) check("command", a);
    check("table", p.table);
  }
  t.finish();
  return p;
}

void read_report(const TableReader& r, const toml::table& raw, StudySpec& s) {
  s.plugin = optional_file(r, "plugin", s.folder, "report plug-in");
  const std::vector<TableReader> sections = r.tables("section");
  const toml::array* arr = raw.get("section") ? raw.get("section")->as_array() : nullptr;
  for (std::size_t i = 0; i < sections.size(); ++i) {
    const TableReader& sec = sections[i];
    sec.choice("kind", "", kSectionKinds);
    if (const toml::node* n = (*arr)[i].as_table()->get("sweep"); n && n->is_string()) {
      const std::string name = n->as_string()->get();
      const bool known = std::any_of(s.sweeps.begin(), s.sweeps.end(), [&](const StudySweep& e) { return e.name == name; });
      if (!known) sec.fail("sweep", "no [[sweep]] named \"" + name + "\" in this study");
    }
    // The other keys of a section are the report's to check (docs/studies.md).
  }
  r.finish();
}

}  // namespace

bool StudySweep::in(const std::string& tier) const { return std::count(tiers.begin(), tiers.end(), tier) > 0; }
bool StudyPost::in(const std::string& tier) const { return std::count(tiers.begin(), tiers.end(), tier) > 0; }

std::vector<const StudySweep*> StudySpec::sweeps_of(const std::string& tier) const {
  std::vector<const StudySweep*> out;
  for (const StudySweep& e : sweeps)
    if (e.in(tier)) out.push_back(&e);
  return out;
}

std::vector<const StudyPost*> StudySpec::posts_of(const std::string& tier) const {
  std::vector<const StudyPost*> out;
  for (const StudyPost& p : posts)
    if (p.in(tier)) out.push_back(&p);
  return out;
}

StudySpec read_study(const fs::path& folder_in) {
  StudySpec s;
  std::error_code ec;
  s.folder = fs::weakly_canonical(fs::absolute(folder_in), ec);
  if (ec) s.folder = fs::absolute(folder_in);
  s.name = s.folder.filename().string();
  s.file = s.folder / "study.toml";
  const toml::table doc = parse_toml_file(s.file.string(), "study file");
  const CaseContext ctx{s.file.string(), {}};
  const TableReader root(doc, "", ctx);
  s.title = root.text("title");
  if (s.title.empty()) root.fail("title", "empty; give the title of the study's page");
  s.summary = root.text("summary");
  if (s.summary.empty()) root.fail("summary", "empty; say in a sentence what the study shows");
  if (root.has("order")) s.order = root.integer("order", 0, -1000000, 1000000);
  else root.integer("order", 0, -1000000, 1000000);

  const std::vector<TableReader> sweeps = root.tables("sweep");
  if (sweeps.empty()) root.fail("sweep", "missing: give at least one [[sweep]] (name, file)");
  for (std::size_t i = 0; i < sweeps.size(); ++i)
    s.sweeps.push_back(read_sweep_entry(sweeps[i], *(*doc.get("sweep")->as_array())[i].as_table(), s));
  for (const std::string& tier : kStudyTiers) {
    std::map<std::string, const StudySweep*> names;
    for (std::size_t i = 0; i < s.sweeps.size(); ++i) {
      const StudySweep& e = s.sweeps[i];
      if (!e.in(tier)) continue;
      if (const auto [it, fresh] = names.emplace(e.name, &e); !fresh)
        sweeps[i].fail("name", "\"" + e.name + "\" is already the name of " + it->second->where + " in tier " + tier +
                                   "; a sweep's name is unique per tier (give variants disjoint `tier` lists)");
    }
  }
  const std::vector<TableReader> posts = root.tables("post");
  std::set<std::string> post_names;
  for (std::size_t i = 0; i < posts.size(); ++i) {
    StudyPost p = read_post(posts[i], *(*doc.get("post")->as_array())[i].as_table(), s);
    if (!post_names.insert(p.name).second) posts[i].fail("name", "\"" + p.name + "\" is already the name of another [[post]]");
    s.posts.push_back(std::move(p));
  }
  if (const auto report = root.table("report")) read_report(*report, *doc.get("report")->as_table(), s);
  if (const auto req = root.table("requires")) {
    auto names = [&](const char* key) {
      std::vector<std::string> v = req->texts(key);
      for (const std::string& n : v)
        if (n.find_first_of(" /;'\"\\") != std::string::npos)
          req->fail(key, "\"" + n + "\": expected a bare name (no path, spaces or quotes)");
      return v;
    };
    s.required_programs = names("programs");
    s.required_python_modules = names("python_modules");
    req->finish();
  }
  root.finish();
  return s;
}

std::vector<StudySpec> discover_studies(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw InputError("ricochet reproduce: --studies " + dir.string() + ": not a folder");
  std::vector<fs::path> folders;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec))
    if (e.is_directory(ec) && fs::is_regular_file(e.path() / "study.toml", ec)) folders.push_back(e.path());
  std::vector<StudySpec> out;
  for (const fs::path& f : folders) out.push_back(read_study(f));
  std::sort(out.begin(), out.end(), [](const StudySpec& a, const StudySpec& b) {
    if (a.order.has_value() != b.order.has_value()) return a.order.has_value();
    if (a.order && *a.order != *b.order) return *a.order < *b.order;
    return a.name < b.name;
  });
  return out;
}

StudySpec find_study(const std::string& arg, const fs::path& dir) {
  std::error_code ec;
  if (!arg.empty() && arg.find('/') == std::string::npos && fs::is_regular_file(dir / arg / "study.toml", ec))
    return read_study(dir / arg);
  if (fs::is_regular_file(fs::path(arg) / "study.toml", ec)) return read_study(arg);
  std::vector<std::string> names;
  if (fs::is_directory(dir, ec))
    for (const fs::directory_entry& e : fs::directory_iterator(dir, ec))
      if (fs::is_regular_file(e.path() / "study.toml", ec)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
  throw InputError("ricochet reproduce: no study '" + arg + "': not a folder of " + dir.string() +
                   " nor a folder holding a study.toml" + did_you_mean(arg, names) + "; studies in " + dir.string() +
                   ": " + (list.empty() ? "none" : list));
}

fs::path default_studies_dir() {
  const char* dir = std::getenv("RICOCHET_CASES");
  return dir && *dir ? fs::path(dir) : fs::path(RICOCHET_CASES_DIR);
}

}  // namespace ricochet
